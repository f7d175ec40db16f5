//! Properties of the cutter model (proptest): edges lie on the dome, zero run-out lets every
//! tooth cut, and raising one tooth's radius never brings other teeth into the cut.

use crest::tool::{Cutter, Rule, Shape, analyse};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Without run-out every ICE point of a ball end lies on the dome (002 Eq 1), whatever
    /// the helix, tooth and spindle angle; on a torus it lies on the torus.
    #[test]
    fn edges_lie_on_the_dome(
        radius in 0.5f64..12.0,
        teeth in 1usize..9,
        helix_deg in 0.0f64..50.0,
        u in 0.0f64..=1.0,
        theta in -10.0f64..10.0,
        tooth_seed in 0usize..64,
        corner_share in 0.05f64..0.95,
    ) {
        let j = tooth_seed % teeth;
        let ball = Cutter::new(Shape::Ball, radius, teeth, helix_deg.to_radians());
        let z = u * radius;
        let p = ball.edge_point(j, z, theta);
        let centre_distance = (p - nalgebra::Vector3::new(0.0, 0.0, radius)).norm();
        prop_assert!((centre_distance - radius).abs() < 1e-10 * radius.max(1.0));
        prop_assert!((p.z - z).abs() < 1e-12);
        let rc = corner_share * radius;
        let torus = Cutter::new(Shape::Torus { corner_radius_mm: rc }, radius, teeth, helix_deg.to_radians());
        let zt = u * rc;
        let q = torus.edge_point(j, zt, theta);
        let rho = q.xy().norm() - (radius - rc);
        prop_assert!((rho * rho + (zt - rc) * (zt - rc) - rc * rc).abs() < 1e-9 * radius.max(1.0));
    }

    /// With zero run-out every tooth cuts under both rules and the marks are fz apart.
    #[test]
    fn zero_runout_every_tooth_participates(
        radius in 1.0f64..10.0,
        teeth in 1usize..9,
        helix_deg in 0.0f64..45.0,
        lead_deg in -60.0f64..60.0,
        fz in 0.005f64..0.3,
        torus in any::<bool>(),
    ) {
        let shape = if torus { Shape::Torus { corner_radius_mm: 0.3 * radius } } else { Shape::Ball };
        let c = Cutter::new(shape, radius, teeth, helix_deg.to_radians());
        for rule in [Rule::Paper, Rule::Exact] {
            let a = analyse(&c, lead_deg, 0.3, fz, rule).unwrap();
            prop_assert_eq!(a.zc, teeth);
            prop_assert!(a.teeth.iter().all(|t| t.participates));
            prop_assert!((a.fz_effective_mm - fz).abs() < 1e-12);
        }
    }

    /// Raising one tooth's radius never brings another tooth into the cut (either rule),
    /// and when that tooth already cut, zc does not grow.
    #[test]
    fn raising_one_tooth_never_adds_teeth(
        teeth in 2usize..7,
        offset_um in 0.0f64..20.0,
        phase_deg in 0.0f64..360.0,
        devs in proptest::collection::vec(-20.0f64..20.0, 6),
        raise_um in 0.001f64..30.0,
        tooth_seed in 0usize..64,
        lead_deg in 1.0f64..40.0,
        fz in 0.01f64..0.2,
        helix_deg in 0.0f64..40.0,
    ) {
        let j = tooth_seed % teeth;
        let mut c = Cutter::new(Shape::Ball, 5.0, teeth, helix_deg.to_radians());
        c.runout.offset_mm = offset_um * 1e-3;
        c.runout.offset_phase_rad = phase_deg.to_radians();
        c.runout.tooth_radius_dev_mm = devs[..teeth].iter().map(|d| d * 1e-3).collect();
        let mut raised = c.clone();
        raised.runout.tooth_radius_dev_mm[j] += raise_um * 1e-3;
        for rule in [Rule::Paper, Rule::Exact] {
            let before = analyse(&c, lead_deg, 0.4, fz, rule).unwrap();
            let after = analyse(&raised, lead_deg, 0.4, fz, rule).unwrap();
            for i in (0..teeth).filter(|&i| i != j) {
                prop_assert!(
                    !after.teeth[i].participates || before.teeth[i].participates,
                    "{:?}: tooth {} joined after raising tooth {}", rule, i + 1, j + 1
                );
            }
            if before.teeth[j].participates {
                prop_assert!(after.zc <= before.zc);
            }
        }
    }
}
