//! Acceptance of the surface models against closed forms and model.md R2/R3.

mod surface_common;

use crest::math::{Point3, Vec3};
use crest::surface::{GridSpec, Model, Options, simulate};
use crest::tool::{Cutter, Shape, crest_height_mm};
use surface_common::pass;

fn no_progress(_: usize, _: usize) {}

#[test]
fn dome_raster_lateral_crest_matches_closed_form() {
    // 3-axis ball-end raster, R 5, stepover 0.2 mm, fz 0.05 mm, 2 teeth.
    let cutter = Cutter::new(Shape::Ball, 5.0, 2, 0.0);
    let fz = 0.05;
    let mut samples = Vec::new();
    for (run, y) in [-0.2, 0.0, 0.2, 0.4, 0.6].iter().enumerate() {
        samples.extend(pass(
            &cutter,
            run,
            Point3::new(-1.2, *y, 0.0),
            Vec3::x(),
            Vec3::z(),
            2.5,
            fz,
            fz,
            0.0,
        ));
    }
    let grid = GridSpec::Window {
        x0_mm: 0.0,
        y0_mm: 0.0,
        x1_mm: 0.1,
        y1_mm: 0.4,
    };
    let sim = simulate(
        &samples,
        &cutter,
        &Options::new(Model::Dome, grid, 0.005),
        &no_progress,
    )
    .unwrap();
    let m = &sim.map;
    assert_eq!((m.nx, m.ny), (21, 81));
    assert_eq!(sim.nodes_cut, m.nx * m.ny);
    // Column x = 0 passes through a stamp centre: the lateral profile is the ball's circle.
    let col: Vec<f64> = (0..m.ny).map(|j| m.get(0, j)).collect();
    let max = col.iter().copied().fold(f64::MIN, f64::max);
    let min = col.iter().copied().fold(f64::MAX, f64::min);
    let want = crest_height_mm(5.0, 0.2) * 1e3;
    assert!((want - 1.0001).abs() < 1e-4);
    assert!(
        ((max - min) - want).abs() < 0.02 * want,
        "crest {} vs {want}",
        max - min
    );
    // Cusps midway between passes, zero on the passes.
    assert!((m.get(0, 20) - want).abs() < 0.02 * want);
    assert!(m.get(0, 40).abs() < 0.01);
}

/// A single pass along +x at 15° lead, 4 teeth, fz 0.05 mm, run-out `e0_mm` at phase
/// `phase_deg`: the height profile along the pass centre (y = 0), µm, at 2 µm spacing.
fn lead_pass_profile(e0_mm: f64, phase_deg: f64) -> Vec<f64> {
    let mut cutter = Cutter::new(Shape::Ball, 5.0, 4, 0.0);
    cutter.runout.offset_mm = e0_mm;
    cutter.runout.offset_phase_rad = phase_deg.to_radians();
    let lead = 15f64.to_radians();
    let axis = Vec3::new(lead.sin(), 0.0, lead.cos());
    let fz = 0.05;
    // Samples every 10° of spindle; the engine subdivides to Δθ = 0.25°.
    let ds = 4.0 * fz * 10.0 / 360.0;
    let samples = pass(
        &cutter,
        0,
        Point3::new(-0.8, 0.0, 0.0),
        Vec3::x(),
        axis,
        2.2,
        ds,
        fz,
        0.0,
    );
    let grid = GridSpec::Window {
        x0_mm: 0.0,
        y0_mm: -0.004,
        x1_mm: 0.6,
        y1_mm: 0.004,
    };
    let opts = Options::new(
        Model::Ice {
            dtheta_rad: 0.25f64.to_radians(),
        },
        grid,
        0.002,
    );
    let sim = simulate(&samples, &cutter, &opts, &no_progress).unwrap();
    assert_eq!(sim.nodes_cut, sim.map.nx * sim.map.ny);
    sim.map.row(2).to_vec()
}

/// Positions (node indices) of the strict local minima of a profile.
fn minima(p: &[f64]) -> Vec<usize> {
    (1..p.len() - 1)
        .filter(|&i| p[i] < p[i - 1] && p[i] <= p[i + 1])
        .collect()
}

#[test]
fn ice_single_pass_with_runout_leaves_one_mark_per_revolution() {
    // model.md R3: e0 = 10 µm, φe = 0: only tooth 1 cuts, marks 0.2 mm apart, crest 0.9996 µm.
    let p = lead_pass_profile(0.010, 0.0);
    let max = p.iter().copied().fold(f64::MIN, f64::max);
    let min = p.iter().copied().fold(f64::MAX, f64::min);
    assert!(((max - min) - 0.9996).abs() < 0.03, "crest {}", max - min);
    let mins = minima(&p);
    assert!(mins.len() >= 2, "{mins:?}");
    for w in mins.windows(2) {
        let spacing_um = (w[1] - w[0]) as f64 * 2.0;
        assert!(
            (spacing_um - 200.0).abs() <= 4.0,
            "spacing {spacing_um} µm in {mins:?}"
        );
    }
}

#[test]
fn ice_runout_at_45_degrees_lets_two_teeth_cut() {
    // model.md R3: e0 = 5 µm, φe = 45°: teeth 1 and 4 cut, crest 0.5624 µm, two marks per
    // revolution (fz and 3 fz apart).
    let p = lead_pass_profile(0.005, 45.0);
    let max = p.iter().copied().fold(f64::MIN, f64::max);
    let min = p.iter().copied().fold(f64::MAX, f64::min);
    assert!(((max - min) - 0.5624).abs() < 0.03, "crest {}", max - min);
    let mins = minima(&p);
    let gaps: Vec<f64> = mins
        .windows(2)
        .map(|w| (w[1] - w[0]) as f64 * 2.0)
        .collect();
    assert!(gaps.len() >= 3, "{gaps:?}");
    for g in &gaps {
        assert!(
            (g - 50.0).abs() <= 4.0 || (g - 150.0).abs() <= 4.0,
            "gaps {gaps:?}"
        );
    }
}
