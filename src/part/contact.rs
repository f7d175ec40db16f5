//! Contact data for centre-line paths from the design surface: where the cutter touches the
//! surface and the surface normal there ([`touch`]); with no part they are derived from the
//! path itself ([`super::derive`]).
//!
//! The cutter body is the set of points within the tube radius of its *core*: the ball's
//! centre (radius R), the torus's corner-centre circle (radius rd = R − rc at height rc above
//! the tip, tube rc) or the flat end's bottom disk (tube 0).
//!
//! The contact is the part point nearest the core (for a ball: nearest the centre); the
//! clearance is that distance less the tube radius (negative = gouge).
//!
//! [`touch`] knows the cores of the ball, torus, flat end and round insert only; for a
//! profile [`touch_supported`] says no and the caller must not ask.

use super::Part;
use super::derive::basis;
use crate::math::{Point3, Vec3};
use crate::tool::Cutter;

/// Where a cutter touches the part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Touch {
    /// The part point the cutter is nearest to (the CC point when it touches), mm.
    pub cc: Point3,
    /// The part's unit normal there.
    pub normal: Vec3,
    /// Distance from the cutter body to the part, mm: positive = clearance (air), negative =
    /// penetration (gouge).
    pub clearance_mm: f64,
}

/// Whether [`touch`] knows the cutter's core (every shape but a profile).
pub fn touch_supported(cutter: &Cutter) -> bool {
    !matches!(cutter.shape, crate::tool::Shape::Profile(_))
}

/// Where `cutter` at tip `tip`, unit axis `axis`, touches `part` (a profile is treated as
/// its corner radius about its end: see [`touch_supported`]).
pub fn touch(part: &Part, cutter: &Cutter, tip: &Point3, axis: &Vec3) -> Touch {
    let r = cutter.radius_mm;
    let rc = cutter.corner_radius_mm();
    let rd = r - rc;
    let centre = tip + axis * rc;
    let at = |p: &Point3| {
        let c = part.closest(p);
        (c.signed_distance - rc, c)
    };
    if rd <= 1e-12 {
        let (clear, c) = at(&centre);
        return Touch {
            cc: c.point,
            normal: c.normal,
            clearance_mm: clear,
        };
    }
    let (e1, e2) = basis(axis);
    // Core points: the corner-centre circle (and, for a flat end, rings of its disk).
    let point = |rho: f64, phi: f64| centre + (e1 * phi.cos() + e2 * phi.sin()) * rho;
    let rings: &[f64] = if rc <= 1e-12 {
        &[0.0, 0.25, 0.5, 0.75, 1.0]
    } else {
        &[1.0]
    };
    const N: usize = 72;
    let mut best = (f64::INFINITY, 1.0, 0.0);
    for &k in rings {
        let n = if k == 0.0 { 1 } else { N };
        for i in 0..n {
            let phi = std::f64::consts::TAU * i as f64 / N as f64;
            let (d, _) = at(&point(k * rd, phi));
            if d < best.0 {
                best = (d, k, phi);
            }
        }
    }
    // Refine the angle (golden section) on the best ring, then the radius for a flat end.
    let (_, k, phi) = best;
    let step = std::f64::consts::TAU / N as f64;
    let f = |phi: f64| at(&point(k * rd, phi)).0;
    let phi = golden(&f, phi - step, phi + step, 40);
    let rho = if rc <= 1e-12 {
        let g = |rho: f64| at(&point(rho, phi)).0;
        golden(&g, 0.0, rd, 40)
    } else {
        k * rd
    };
    let (clear, c) = at(&point(rho, phi));
    let (clear, c) = if clear <= best.0 {
        (clear, c)
    } else {
        at(&point(best.1 * rd, best.2))
    };
    Touch {
        cc: c.point,
        normal: c.normal,
        clearance_mm: clear,
    }
}

/// [`touch`] for every pose given (tip, unit axis), in parallel; the order is kept.
pub fn touch_all(
    part: &Part,
    cutter: &Cutter,
    poses: &[Option<(Point3, Vec3)>],
) -> Vec<Option<Touch>> {
    use rayon::prelude::*;
    poses
        .par_iter()
        .map(|p| p.map(|(tip, axis)| touch(part, cutter, &tip, &axis)))
        .collect()
}

/// Golden-section minimum of `f` on [a, b].
fn golden(f: &dyn Fn(f64) -> f64, mut a: f64, mut b: f64, iters: usize) -> f64 {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..iters {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::Shape;
    use approx::assert_relative_eq;

    #[test]
    fn touch_finds_the_contact_and_the_gouge() {
        let part = Part::new(super::super::tests::half_cylinder(20.0, 5.0, 2000)).unwrap();
        let ball = Cutter::new(Shape::Ball, 5.0, 2, 0.0);
        // Convex cylinder of radius 20 about x (top at z = 20); 3-axis ball 2 µm deep.
        let phi = 0.3f64;
        let n = Vec3::new(0.0, -phi.cos(), phi.sin());
        let cc = Point3::new(0.0, -20.0 * phi.cos(), 20.0 * phi.sin());
        let tip = crate::synth::tool_tip(&ball, &cc, &n, &Vec3::z()) - n * 0.002;
        let t = touch(&part, &ball, &tip, &Vec3::z());
        assert_relative_eq!(t.clearance_mm, -0.002, epsilon = 1e-5);
        assert!((t.cc - cc).norm() < 1e-4, "{:?}", t.cc);
        let torus = Cutter::new(
            Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            2,
            0.0,
        );
        let tip = crate::synth::tool_tip(&torus, &cc, &n, &Vec3::z());
        let t = touch(&part, &torus, &tip, &Vec3::z());
        assert!(t.clearance_mm.abs() < 1e-5, "{}", t.clearance_mm);
        assert!((t.cc - cc).norm() < 1e-3, "{:?}", t.cc);
        assert!(t.normal.angle(&n) < 1e-3);
    }
}
