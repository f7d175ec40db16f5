//! Trochoidal paths of the infinitesimal cutting-edge (ICE) elements along a straight pass
//! (002 Fig 14a/b) and the crest height between consecutive marks of one element.
//!
//! The pass is straight along +x on the plane z = 0 with the tip on it; the tool axis leans
//! by the lead β into the feed, `z_t = (sin β, 0, cos β)`, `x_t = (cos β, 0, −sin β)`,
//! `y_t = (0, 1, 0)` (model.md §1.3). The spindle turns θ while the tip advances
//! `Z fz θ / 2π`; the ICE point of tooth j at height z is `P + [x_t y_t z_t] E_j(z, θ)`
//! with `E_j` = [`Cutter::edge_point`] (helix lag and run-out included).
//!
//! **Crest between consecutive marks (top view).** Seen along the surface normal, the ICE
//! at height z (radius r) of consecutive teeth leaves marks fz apart. Their lateral
//! envelope dips between two marks to the point where the outer arcs cross, at spindle
//! angle θ* from the mark's apex solving `v θ + r cos β sin θ = fz/2` with `v = Z fz/2π`
//! per radian; the crest is `r (1 − cos θ*)`. When v ≪ r this is 002 Eq 14 with the
//! projected spacing, `r − √(r² − (fz/2 cos β)²)`. Nominal radii (no run-out): a run-out
//! that leaves one tooth cutting is modelled by passing the effective fz (002: 0.05 → 0.2).

use super::Cutter;
use crate::math::{Point3, Vec3};
use std::f64::consts::TAU;

/// The ICE path of tooth `j` at height `z_mm` along a straight pass at lateral offset
/// `y_mm`, lead `lead_rad`, feed per tooth `fz_mm`, for spindle angles θ = 0 … 2π·revs in
/// `n` + 1 samples. Points in the part frame (x feed, y lateral, z normal), mm.
#[allow(clippy::too_many_arguments)]
pub fn trochoid(
    cutter: &Cutter,
    j: usize,
    z_mm: f64,
    lead_rad: f64,
    fz_mm: f64,
    y_mm: f64,
    revolutions: f64,
    n: usize,
) -> Vec<Point3> {
    let (sb, cb) = lead_rad.sin_cos();
    let xt = Vec3::new(cb, 0.0, -sb);
    let yt = Vec3::new(0.0, 1.0, 0.0);
    let zt = Vec3::new(sb, 0.0, cb);
    let advance_per_rad = cutter.teeth() as f64 * fz_mm / TAU;
    (0..=n)
        .map(|i| {
            let theta = TAU * revolutions * i as f64 / n.max(1) as f64;
            let e = cutter.edge_point(j, z_mm, theta);
            Point3::new(advance_per_rad * theta, y_mm, 0.0) + xt * e.x + yt * e.y + zt * e.z
        })
        .collect()
}

/// Crest height between consecutive marks of the ICE at height `z_mm`, in the top view,
/// for feed per tooth `fz_mm` and lead `lead_rad` (nominal radii; see the module docs), mm.
pub fn crest_between_marks_mm(cutter: &Cutter, z_mm: f64, fz_mm: f64, lead_rad: f64) -> f64 {
    let r = cutter.profile_radius(z_mm);
    let rp = r * lead_rad.cos();
    let v = cutter.teeth().max(1) as f64 * fz_mm / TAU;
    let target = 0.5 * fz_mm;
    // v θ + r' sin θ is increasing on [0, π]; bisection.
    let f = |t: f64| v * t + rp * t.sin() - target;
    let (mut lo, mut hi) = (0.0, std::f64::consts::PI);
    if f(hi) <= 0.0 {
        return 2.0 * r;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t = 0.5 * (lo + hi);
    // r (1 − cos θ) = 2 r sin²(θ/2), without cancellation.
    2.0 * r * (0.5 * t).sin().powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::Shape;
    use approx::assert_relative_eq;

    #[test]
    fn crest_matches_eq14_when_the_advance_is_small() {
        // v ≪ r: the crest tends to Eq 14 with the projected spacing fz / cos β.
        let c = Cutter::new(Shape::Ball, 5.0, 1, 0.0);
        let (z, fz, lead): (f64, f64, f64) = (2.5, 0.001, 0.3);
        let r = c.profile_radius(z);
        let eq14 = crate::tool::crest_height_mm(r, fz / lead.cos());
        assert_relative_eq!(
            crest_between_marks_mm(&c, z, fz, lead),
            eq14,
            max_relative = 1e-3
        );
    }

    #[test]
    fn crest_matches_the_traced_envelope() {
        // One straight tooth, z = 1 mm (r = 3 mm), fz = 0.2, lead 15°: the lateral envelope
        // of the traced ICE path dips between two marks by the closed-form crest.
        let c = Cutter::new(Shape::Ball, 5.0, 1, 0.0);
        let (z, fz, lead) = (1.0, 0.2, 15f64.to_radians());
        let expect = crest_between_marks_mm(&c, z, fz, lead);
        let pts = trochoid(&c, 0, z, lead, fz, 0.0, 3.0, 3 * 20_000);
        // Mark apexes (max y) lie at x = k fz + z sin β; the envelope at the midpoint
        // between the second and third marks is the highest crossing of that abscissa.
        let x_mid = 1.5 * fz + z * lead.sin();
        let r = c.profile_radius(z);
        let y_valley = pts
            .windows(2)
            .filter(|w| w[0].y > 0.0 && (w[0].x - x_mid) * (w[1].x - x_mid) <= 0.0)
            .map(|w| w[0].y + (w[1].y - w[0].y) * (x_mid - w[0].x) / (w[1].x - w[0].x))
            .fold(f64::NEG_INFINITY, f64::max);
        let y_peak = pts.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
        assert_relative_eq!(y_peak, r, epsilon = 1e-6);
        assert_relative_eq!(r - y_valley, expect, epsilon = 2e-6);
        assert!(expect > 1.5e-3 && expect < 2.0e-3, "{expect}");
    }

    #[test]
    fn trochoid_advances_by_z_fz_per_turn() {
        let c = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        let p = trochoid(&c, 2, 1.0, 0.0, 0.05, 0.0, 1.0, 360);
        let d = p[360] - p[0];
        assert_relative_eq!(d, Vec3::new(0.2, 0.0, 0.0), epsilon = 1e-12);
    }
}
