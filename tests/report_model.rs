//! The closed-form crest model of `crest report` against model.md R2 and R3 and the 002
//! case study (§3.3): presetter radii 4.990/4.985/4.976/4.975 mm make fz_eff = 0.2 mm and
//! hc = 1.0001 µm.

use approx::assert_relative_eq;
use crest::study::measured::Side;
use crest::study::regression::{crest_model, profile_roughness};
use crest::tool::Rule;
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
            let p = crest_model(&c, lead, 0.4, 0.05, Rule::Paper, side, None).unwrap();
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
    let p = crest_model(&c, 15.0, 0.4, 0.05, Rule::Paper, Side::Plane, None).unwrap();
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
        let p = crest_model(&c, 15.0, 0.4, fz, Rule::Paper, Side::Plane, None).unwrap();
        assert_eq!(p.teeth, [1, 2, 3, 4]);
        assert_relative_eq!(p.fz_eff_mm, fz, epsilon = 1e-12);
        assert_relative_eq!(p.crest_um, hc, epsilon = 1e-5);
    }
}

#[test]
fn r3_teeth_sets_and_exact_crests() {
    // model.md R3 lists ρ_j at the tooth pitch angles (no helix lag), so helix = 0 here;
    // lead 15°, ap 0.4 mm, fz 0.05 mm.
    let offset = |e0_um: f64, phase_deg: f64| Runout {
        offset_mm: e0_um * 1e-3,
        offset_phase_rad: phase_deg.to_radians(),
        ..Runout::default()
    };
    // (run-out, paper teeth, paper fz_eff, exact teeth, exact crest µm)
    type Row = (Runout, Vec<usize>, f64, Vec<usize>, f64);
    let rows: Vec<Row> = vec![
        (presetter(), vec![1], 0.2, vec![1], 1.0021),
        (offset(5.0, 0.0), vec![1], 0.2, vec![1], 0.9998),
        (offset(10.0, 0.0), vec![1], 0.2, vec![1], 0.9996),
        (offset(15.0, 0.0), vec![1], 0.2, vec![1], 0.9993),
        (offset(5.0, 45.0), vec![1, 4], 0.1, vec![1, 4], 0.5624),
        (offset(10.0, 45.0), vec![1, 4], 0.1, vec![1, 4], 0.5623),
        (offset(15.0, 45.0), vec![1, 4], 0.1, vec![1, 4], 0.5622),
        // The paper rule under-counts here (the exact check finds [1,4]); paper mode gives [1].
        (offset(5.0, 30.0), vec![1], 0.2, vec![1, 4], 0.8242),
        (
            offset(0.05, 0.0),
            vec![1, 2, 4],
            0.2 / 3.0,
            vec![1, 2, 3, 4],
            0.0821,
        ),
    ];
    for (runout, paper, fz_eff, exact, crest) in rows {
        let c = ball(0.0, runout.clone());
        let p = crest_model(&c, 15.0, 0.4, 0.05, Rule::Paper, Side::Plane, None).unwrap();
        assert_eq!(p.teeth, paper, "{runout:?}");
        assert_eq!(p.zc, paper.len());
        assert_relative_eq!(p.fz_eff_mm, fz_eff, epsilon = 1e-12);
        let hc = crest::tool::crest_height_mm(5.0, fz_eff) * 1e3;
        assert_relative_eq!(p.crest_um, hc, epsilon = 1e-9);
        // Uniform marks: the profile's Rz is the crest.
        assert_relative_eq!(p.rz_um, hc, epsilon = 1e-6);

        let e = crest_model(&c, 15.0, 0.4, 0.05, Rule::Exact, Side::Plane, None).unwrap();
        assert_eq!(e.teeth, exact, "{runout:?}");
        assert_relative_eq!(e.crest_um, crest, epsilon = 1e-4);
        // The sampled envelope profile (0.5 µm steps) finds the same peak-to-valley height
        // to within the kink between two arcs.
        assert_relative_eq!(e.rz_um, e.crest_um, epsilon = 5e-3);
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
fn curvature_needs_a_ball_and_a_wide_concave_radius() {
    let flat = Cutter::new(Shape::Flat, 5.0, 4, 0.0);
    assert!(
        crest_model(
            &flat,
            15.0,
            0.4,
            0.05,
            Rule::Paper,
            Side::Convex,
            Some(20.0)
        )
        .is_err()
    );
    let c = ball(30.0, presetter());
    assert!(crest_model(&c, 15.0, 0.4, 0.05, Rule::Paper, Side::Concave, Some(5.0)).is_err());
}

#[test]
fn torus_on_a_plane_uses_the_section_profile() {
    // model.md §7: at tilt 10° the generating radius is rc on both sides, so the cusp is
    // fz²/(8 rc) = 5.9 µm at fz = 0.267 mm (one tooth).
    let c = Cutter::new(
        Shape::Torus {
            corner_radius_mm: 1.5,
        },
        5.0,
        1,
        0.0,
    );
    let p = crest_model(&c, 10.0, 0.4, 0.8 / 3.0, Rule::Paper, Side::Plane, None).unwrap();
    let hc = crest::tool::crest_height_mm(1.5, 0.8 / 3.0) * 1e3;
    assert_relative_eq!(p.crest_um, hc, max_relative = 1e-6);
    assert_relative_eq!(p.rz_um, hc, max_relative = 1e-4);
}

#[test]
fn effective_radius_matches_r1() {
    // model.md R1 (002 Table 3): R_ef,max 2.35305 / 3.08339 / 3.72004 mm at ap 0.4 mm.
    let c = ball(30.0, presetter());
    for (lead, r_ef) in [(5.0, 2.35305), (15.0, 3.08339), (25.0, 3.72004)] {
        let p = crest_model(&c, lead, 0.4, 0.05, Rule::Paper, Side::Plane, None).unwrap();
        assert_relative_eq!(p.effective_radius_mm, r_ef, epsilon = 1e-5);
        assert_relative_eq!(p.cutting_speed_ratio, r_ef / 5.0, epsilon = 1e-6);
    }
}
