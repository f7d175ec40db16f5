//! Effective cutting radius and cutting-speed ratio for a lead angle and a depth of cut
//! (model.md §6, 002 Table 3).
//!
//! The tool is tilted by the lead β against the surface normal and its lowest point touches
//! the plane; everything within `ap` of that point along the normal is engaged. A point of
//! the profile at radius r and height h(r) reaches its lowest normal height
//! `g(r) = h(r) cos β − r sin β` on the side that leans forward, so the engaged radii are
//! `{r : g(r) ≤ min g + ap}`, an interval because g is convex. Its upper end is the largest
//! radius that cuts, R_ef,max; for a ball it is `R sin(β + acos((R − ap)/R))`, capped at R
//! once the equator engages. A round insert's g starts at its inner flank; a profile that
//! is not convex is scanned densely before the same refinement.

use super::cutter::{Cutter, Shape};
use std::f64::consts::FRAC_PI_2;

/// Effective radius of one cutter body at one engagement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffectiveRadius {
    /// R_ef,max: the largest engaged radius, mm.
    pub max_mm: f64,
    /// Radius of the lowest (generating) point, mm (R sin β for a ball).
    pub contact_mm: f64,
}

/// The largest engaged radius R_ef,max and the contact radius of `cutter` (its nominal body,
/// no run-out) at lead `lead_rad` and depth of cut `ap_mm` along the normal.
pub fn effective_radius(cutter: &Cutter, lead_rad: f64, ap_mm: f64) -> EffectiveRadius {
    let r = cutter.radius_mm;
    let b = lead_rad.abs().min(FRAC_PI_2);
    let ap = ap_mm.max(0.0);
    if let Shape::Ball = cutter.shape {
        let kappa_ap = ((r - ap) / r).clamp(-1.0, 1.0).acos();
        return EffectiveRadius {
            max_mm: r * (b + kappa_ap).min(FRAC_PI_2).sin(),
            contact_mm: r * b.sin(),
        };
    }
    let (sb, cb) = b.sin_cos();
    let g = |x: f64| cutter.profile_height(x).unwrap_or(f64::INFINITY) * cb - x * sb;
    if let Shape::Profile(m) = &cutter.shape
        && !m.is_convex()
    {
        return scanned(&g, cutter.min_radius_mm(), r, ap);
    }
    // Minimum of the convex g on [r_min, R] by golden-section search.
    let (mut lo, mut hi) = (cutter.min_radius_mm(), r);
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..100 {
        let c = hi - phi * (hi - lo);
        let d = lo + phi * (hi - lo);
        if g(c) <= g(d) {
            hi = d;
        } else {
            lo = c;
        }
    }
    let r_low = if g(r) <= g(0.5 * (lo + hi)) {
        r
    } else {
        0.5 * (lo + hi)
    };
    let level = g(r_low) + ap;
    let max_mm = if g(r) <= level {
        r
    } else {
        let (mut a, mut z) = (r_low, r);
        for _ in 0..100 {
            let m = 0.5 * (a + z);
            if g(m) <= level {
                a = m;
            } else {
                z = m;
            }
        }
        0.5 * (a + z)
    };
    EffectiveRadius {
        max_mm,
        contact_mm: r_low,
    }
}

/// [`effective_radius`] for a g that need not be convex on [lo, hi]: the lowest of 4001
/// samples refined by golden section, the largest engaged radius by bisection from the
/// last engaged sample.
fn scanned(g: &dyn Fn(f64) -> f64, lo: f64, hi: f64, ap: f64) -> EffectiveRadius {
    const N: usize = 4000;
    let x = |i: usize| lo + (hi - lo) * i as f64 / N as f64;
    let best = (0..=N)
        .min_by(|&a, &b| g(x(a)).total_cmp(&g(x(b))))
        .unwrap_or(0);
    let (mut a, mut b) = (x(best.saturating_sub(1)), x((best + 1).min(N)));
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..100 {
        let c = b - phi * (b - a);
        let d = a + phi * (b - a);
        if g(c) <= g(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let m = 0.5 * (a + b);
    let r_low = if g(m) <= g(x(best)) { m } else { x(best) };
    let level = g(r_low) + ap;
    let last = (0..=N).rev().find(|&i| g(x(i)) <= level).unwrap_or(best);
    let max_mm = if last == N {
        hi
    } else {
        let (mut p, mut q) = (x(last), x(last + 1));
        for _ in 0..100 {
            let mid = 0.5 * (p + q);
            if g(mid) <= level {
                p = mid;
            } else {
                q = mid;
            }
        }
        0.5 * (p + q)
    };
    EffectiveRadius {
        max_mm: max_mm.max(r_low),
        contact_mm: r_low,
    }
}

/// Cutting-speed ratio R_ef,max / R (0..1): the share of the nominal cutting speed that the
/// fastest engaged point sees.
pub fn cutting_speed_ratio(cutter: &Cutter, lead_rad: f64, ap_mm: f64) -> f64 {
    effective_radius(cutter, lead_rad, ap_mm).max_mm / cutter.radius_mm
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn torus_numeric_matches_geometry() {
        // Torus R 5, rc 1.5, lead 0: engaged up to h(r) = ap on the corner arc.
        let c = Cutter::new(
            Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            1,
            0.0,
        );
        let e = effective_radius(&c, 0.0, 0.4);
        // (r − 3.5)² + (0.4 − 1.5)² = 1.5².
        assert_relative_eq!(
            e.max_mm,
            3.5 + (1.5f64 * 1.5 - 1.1 * 1.1).sqrt(),
            epsilon = 1e-9
        );
        // Large ap engages the whole radius.
        assert_relative_eq!(effective_radius(&c, 0.2, 3.0).max_mm, 5.0, epsilon = 1e-12);
        // A torus with rc = R is a ball: both paths agree.
        let t = Cutter::new(
            Shape::Torus {
                corner_radius_mm: 5.0,
            },
            5.0,
            1,
            0.0,
        );
        let b = Cutter::new(Shape::Ball, 5.0, 1, 0.0);
        for lead in [5f64, 15.0, 25.0] {
            let l = lead.to_radians();
            assert_relative_eq!(
                effective_radius(&t, l, 0.4).max_mm,
                effective_radius(&b, l, 0.4).max_mm,
                epsilon = 1e-9
            );
            assert_relative_eq!(
                effective_radius(&t, l, 0.4).contact_mm,
                effective_radius(&b, l, 0.4).contact_mm,
                epsilon = 1e-6
            );
        }
    }

    #[test]
    fn flat_end_at_lead() {
        // Flat end, lead β: g(r) = −r sin β, lowest at r = R, the whole face within ap once
        // R sin β ≤ ap.
        let c = Cutter::new(Shape::Flat, 5.0, 2, 0.0);
        let b = 2f64.to_radians();
        let e = effective_radius(&c, b, 0.4);
        assert_relative_eq!(e.max_mm, 5.0, epsilon = 1e-12);
        assert_relative_eq!(e.contact_mm, 5.0, epsilon = 1e-12);
    }
}
