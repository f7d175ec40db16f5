//! Straight passes over the plane z = 0 built by hand, and the mean-plane height statistics
//! of a map: shared by the surface tests and `benches/surface.rs`.

use std::f64::consts::TAU;

use crest::math::{Point3, Vec3};
use crest::resample::Sample;
use crest::tool::Cutter;

/// Tool tip that puts the cutter's lowest point on the plane z = 0 at contact `c`
/// (tool axis `a`, unit), for ball, torus and flat ends.
pub fn tip_for_contact(cutter: &Cutter, c: Point3, a: Vec3) -> Point3 {
    let rc = cutter.corner_radius_mm();
    let rd = cutter.radius_mm - rc;
    let z = Vec3::z();
    let down = -(z - a * a.z);
    let e = if down.norm() < 1e-12 {
        Vec3::zeros()
    } else {
        down.normalize()
    };
    c - a * rc - e * rd + z * rc
}

/// One straight pass over the plane z = 0: contact points from `c0` along `dir` (unit, in
/// the plane) for `length_mm`, sampled every `ds_mm`; spindle angle advances by
/// 2π ds/(Z fz) from `theta0`.
#[allow(clippy::too_many_arguments)]
pub fn pass(
    cutter: &Cutter,
    run: usize,
    c0: Point3,
    dir: Vec3,
    axis: Vec3,
    length_mm: f64,
    ds_mm: f64,
    fz_mm: f64,
    theta0: f64,
) -> Vec<Sample> {
    let n = (length_mm / ds_mm).round() as usize;
    let z = cutter.teeth() as f64;
    (0..=n)
        .map(|k| {
            let s = k as f64 * ds_mm;
            let c = c0 + dir * s;
            Sample {
                run,
                s_mm: s,
                t_s: s / 1000.0,
                theta_rad: theta0 + TAU * s / (z * fz_mm),
                position: tip_for_contact(cutter, c, axis),
                axis,
                contact: Some(c),
                normal: Some(Vec3::z()),
                feed_dir: dir,
                feed_mm_min: 1000.0,
            }
        })
        .collect()
}

/// Mean-plane statistics of finite heights: (Sz, Sq, Sa), µm.
pub fn height_stats(z: &[f64]) -> (f64, f64, f64) {
    let v: Vec<f64> = z.iter().copied().filter(|x| x.is_finite()).collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    let sq = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    let sa = v.iter().map(|x| (x - mean).abs()).sum::<f64>() / n;
    (max - min, sq, sa)
}
