//! The closed-form crest model of `crest report` against model.md R2 and R3 and the 002
//! case study (§3.3): presetter radii 4.990/4.985/4.976/4.975 mm make fz_eff = 0.2 mm and
//! hc = 1.0001 µm.

use approx::assert_relative_eq;
use crest::report::regression::{Side, crest_model, participating_teeth, profile_roughness};
use crest::tool::{Cutter, Runout, Shape};

fn ball(helix_deg: f64, runout: Runout) -> Cutter {
    let mut c = Cutter::new(Shape::Ball, 5.0, 4, helix_deg.to_radians());
    c.runout = runout;
    c
}

fn presetter() -> Runout {
    Runout {
        tooth_radius_dev_mm: vec![-0.010, -0.015, -0.024, -0.025],
        ..Runout::default()
    }
}

#[test]
fn case_study_presetter_radii_give_one_tooth_and_fz_0_2() {
    let c = ball(30.0, presetter());
    for lead in [5.0, 15.0, 25.0] {
        for side in [Side::Concave, Side::Convex, Side::Plane] {
            let p = crest_model(&c, lead, 0.05, side, None).unwrap();
            assert_eq!(p.teeth, [1]);
            assert_eq!(p.zc, 1);
            assert_relative_eq!(p.fz_eff_mm, 0.2, epsilon = 1e-12);
            // model.md R2: hc(0.2) = 1.0001000 µm; the nominal hc(0.05) = 0.0625004 µm.
            assert_relative_eq!(p.crest_um, 1.0001000, epsilon = 1e-6);
            assert_relative_eq!(p.nominal_crest_um, 0.0625004, epsilon = 1e-6);
            // Rz of the periodic profile = hc (002 §3.3: "Rz = hc").
            assert_relative_eq!(p.rz_um, 1.0001000, epsilon = 1e-6);
            // Generating height R(1 − cos β).
            let z = 5.0 * (1.0 - lead.to_radians().cos());
            assert_relative_eq!(p.generating_height_mm, z, epsilon = 1e-12);
            // Local radius of tooth 1 at z: √(z(2R − z)) − 10 µm.
            assert_relative_eq!(
                p.tooth_radius_mm[0],
                (z * (10.0 - z)).sqrt() - 0.010,
                epsilon = 1e-12
            );
        }
    }
    // model.md §6: the local radius at the generating point is R sin β.
    let p = crest_model(&c, 15.0, 0.05, Side::Plane, None).unwrap();
    assert_relative_eq!(p.tooth_radius_mm[0] + 0.010, 1.294, epsilon = 5e-4);
}

#[test]
fn r2_crest_heights_without_runout() {
    // No run-out: every tooth cuts, fz_eff = fz, hc = Eq 14 (0.13333 = 0.4/3, 0.26667 = 0.8/3).
    let c = ball(30.0, Runout::default());
    for (fz, hc) in [
        (0.05, 0.0625004),
        (0.1, 0.250006),
        (0.4 / 3.0, 0.44446),
        (0.8 / 3.0, 1.77810),
    ] {
        let p = crest_model(&c, 15.0, fz, Side::Plane, None).unwrap();
        assert_eq!(p.teeth, [1, 2, 3, 4]);
        assert_relative_eq!(p.fz_eff_mm, fz, epsilon = 1e-12);
        assert_relative_eq!(p.crest_um, hc, epsilon = 1e-5);
    }
}

#[test]
fn r3_paper_rule_teeth_sets() {
    // model.md R3 lists ρ_j at the tooth pitch angles (no helix lag), so helix = 0 here.
    let z = 5.0 * (1.0 - 15f64.to_radians().cos());
    let offset = |e0_um: f64, phase_deg: f64| Runout {
        offset_mm: e0_um * 1e-3,
        offset_phase_rad: phase_deg.to_radians(),
        ..Runout::default()
    };
    let rows: Vec<(Runout, Vec<usize>, f64)> = vec![
        (presetter(), vec![0], 0.2),
        (offset(5.0, 0.0), vec![0], 0.2),
        (offset(10.0, 0.0), vec![0], 0.2),
        (offset(15.0, 0.0), vec![0], 0.2),
        (offset(5.0, 45.0), vec![0, 3], 0.1),
        (offset(10.0, 45.0), vec![0, 3], 0.1),
        (offset(15.0, 45.0), vec![0, 3], 0.1),
        // The paper rule under-counts here (the exact check finds [1,4]); paper mode gives [1].
        (offset(5.0, 30.0), vec![0], 0.2),
        (offset(0.05, 0.0), vec![0, 1, 3], 0.2 / 3.0),
    ];
    for (runout, teeth, fz_eff) in rows {
        let c = ball(0.0, runout.clone());
        assert_eq!(participating_teeth(&c, z, 0.05), teeth, "{runout:?}");
        let p = crest_model(&c, 15.0, 0.05, Side::Plane, None).unwrap();
        assert_eq!(p.zc, teeth.len());
        assert_eq!(p.teeth, teeth.iter().map(|j| j + 1).collect::<Vec<_>>());
        assert_relative_eq!(p.fz_eff_mm, fz_eff, epsilon = 1e-12);
        assert_relative_eq!(
            p.crest_um,
            crest::tool::crest_height_mm(5.0, fz_eff) * 1e3,
            epsilon = 1e-12
        );
    }
}

#[test]
fn simulated_ra_of_the_case_study() {
    // Arcs of R = 5 mm spaced 0.2 mm: Ra = 0.2566 µm, i.e. 4/(9√3)·hc to first order.
    let (rz, ra, lc) = profile_roughness(5.0, 0.2);
    assert_eq!(lc, 0.8);
    assert_relative_eq!(rz, 1.0001000, epsilon = 1e-6);
    assert_relative_eq!(ra, 0.2566, epsilon = 1e-4);
    // Spacings that do not divide the sampling length still give Rz = hc (each of the five
    // sampling lengths holds a whole crest) and Ra close to the closed form.
    let (rz, ra, _) = profile_roughness(5.0, 0.3);
    let hc = crest::tool::crest_height_mm(5.0, 0.3) * 1e3;
    assert_relative_eq!(rz, hc, epsilon = 1e-6);
    assert_relative_eq!(ra, 4.0 / (9.0 * 3f64.sqrt()) * hc, max_relative = 0.02);
}

#[test]
fn non_ball_tools_are_refused() {
    let c = Cutter::new(Shape::Flat, 5.0, 4, 0.0);
    assert!(crest_model(&c, 15.0, 0.05, Side::Plane, None).is_err());
}
