//! Patch grids (N-buffer along the surface normal) on curved and tilted surfaces.

use crest::math::{Point3, Vec3};
use crest::resample::Sample;
use crest::surface::{GridSpec, Model, Options, SurfaceError, simulate};
use crest::tool::{Cutter, Shape};

fn no_progress(_: usize, _: usize) {}

/// Ball-end passes along x over the convex cylinder y² + (z + ρ)² = ρ², 3-axis (axis z),
/// at surface intervals `s`, one sample per fz (dome model).
fn cylinder_raster(cutter: &Cutter, rho: f64, s: f64, fz: f64) -> Vec<Sample> {
    let r = cutter.radius_mm;
    let mut out = Vec::new();
    for (run, m) in (-2..=2).enumerate() {
        let phi = m as f64 * s / rho;
        let n = Vec3::new(0.0, phi.sin(), phi.cos());
        for k in -30..=30 {
            let x = k as f64 * fz;
            let c = Point3::new(x, rho * phi.sin(), rho * phi.cos() - rho);
            let centre = c + n * r;
            out.push(Sample {
                run,
                s_mm: 100.0 * run as f64 + x + 1.5,
                t_s: 0.0,
                theta_rad: 0.0,
                position: centre - Vec3::z() * r,
                axis: Vec3::z(),
                contact: Some(c),
                normal: Some(n),
                feed_dir: Vec3::x(),
                feed_mm_min: 1000.0,
            });
        }
    }
    out
}

#[test]
fn patch_on_a_convex_cylinder_gives_the_exact_scallop_along_the_normal() {
    let cutter = Cutter::new(Shape::Ball, 5.0, 1, 0.0);
    let (rho, s, fz) = (20.0, 0.2, 0.05);
    let samples = cylinder_raster(&cutter, rho, s, fz);
    // Patch centred on pass 0 at x = 0 (s_mm = 200 + 0 + 1.5 on run 2).
    let grid = GridSpec::Patch {
        s_mm: 201.5,
        length_mm: 0.1,
        width_mm: 0.4,
    };
    let sim = simulate(
        &samples,
        &cutter,
        &Options::new(Model::Dome, grid, 0.005),
        &no_progress,
    )
    .unwrap();
    let m = &sim.map;
    assert!(sim.nominal_from_contacts);
    assert_eq!((m.nx, m.ny), (21, 81));
    assert_eq!(sim.nodes_cut, m.nx * m.ny);
    // Exact cusp: ball centres on the circle of radius ρ + R at ±φ, φ = s/(2ρ).
    let (r, phi) = (5.0, s / (2.0 * rho));
    let d = (rho + r) * phi.cos() - (r * r - (rho + r).powi(2) * phi.sin().powi(2)).sqrt();
    let h_um = (d - rho) * 1e3;
    // Column 10 is x = 0, a stamp centre; rows 0 and 80 are v = ∓0.2 (passes ∓1), the
    // cusps lie at v ≈ ±0.1.
    let col: Vec<f64> = (0..m.ny).map(|j| m.get(10, j)).collect();
    let max = col.iter().copied().fold(f64::MIN, f64::max);
    let min = col.iter().copied().fold(f64::MAX, f64::min);
    assert!((h_um - 1.25).abs() < 0.01, "closed form {h_um}");
    assert!(
        ((max - min) - h_um).abs() < 0.02 * h_um,
        "scallop {} vs {h_um}",
        max - min
    );
    assert!(col[40].abs() < 0.01, "on the pass: {}", col[40]);
    // A plane window would instead see the cylinder's own drop: 0.2² / (2·20) mm = 1 µm
    // at the patch edge, so the normal-line heights must not show it.
    assert!(
        col[0].abs() < 0.02 && col[80].abs() < 0.02,
        "{} {}",
        col[0],
        col[80]
    );
}

#[test]
fn patch_needs_contact_data() {
    let cutter = Cutter::new(Shape::Ball, 5.0, 1, 0.0);
    let mut samples = cylinder_raster(&cutter, 20.0, 0.2, 0.05);
    for s in &mut samples {
        s.contact = None;
        s.normal = None;
    }
    let grid = GridSpec::Patch {
        s_mm: 1.0,
        length_mm: 0.1,
        width_mm: 0.1,
    };
    let err = simulate(
        &samples,
        &cutter,
        &Options::new(Model::Dome, grid, 0.005),
        &no_progress,
    )
    .unwrap_err();
    assert_eq!(err, SurfaceError::NoContactData);
}
