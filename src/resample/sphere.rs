//! Interpolation of unit vectors (tool axis, surface normal) on the sphere within a move:
//! slerp or nlerp with per-move precomputation.

use super::AxisInterpolation;
use crate::math::{Vec3, any_perpendicular, nlerp};
use std::f64::consts::PI;

/// Interpolation of unit vectors with per-move precomputation (one `sin_cos` a sample).
#[derive(Debug, Clone, Copy)]
pub(super) struct SphereInterp {
    a: Vec3,
    b: Vec3,
    perp: Vec3,
    angle: f64,
    slerp: bool,
}

impl SphereInterp {
    /// Returns the interpolator and whether the vectors are antipodal (a 180° flip).
    pub(super) fn new(a: Vec3, b: Vec3, kind: AxisInterpolation) -> (SphereInterp, bool) {
        let cos = a.dot(&b);
        let cross = a.cross(&b);
        // atan2 keeps small angles accurate (acos loses half the digits near 1).
        let angle = cross.norm().atan2(cos);
        let flipped = PI - angle < 1e-6;
        let perp = if angle < 1e-9 {
            Vec3::zeros()
        } else if PI - angle < 1e-9 {
            any_perpendicular(&a)
        } else {
            (b - a * cos).normalize()
        };
        let interp = SphereInterp {
            a,
            b,
            perp,
            angle,
            slerp: kind == AxisInterpolation::Slerp,
        };
        (interp, flipped)
    }

    /// Same values as [`crate::math::slerp`] / [`crate::math::nlerp`].
    pub(super) fn eval(&self, u: f64) -> Vec3 {
        if self.slerp && self.angle >= 1e-9 {
            // `a` and `perp` are orthonormal, so the result is unit to rounding (~1e-16).
            let (s, c) = sin_cos(self.angle * u);
            self.a * c + self.perp * s
        } else {
            nlerp(&self.a, &self.b, u)
        }
    }
}

/// `x.sin_cos()`, by Taylor series for |x| ≤ 0.1 (exact to rounding there: the first
/// omitted terms are below 3e-19), which is most of a 5-axis path's axis changes.
fn sin_cos(x: f64) -> (f64, f64) {
    if x.abs() > 0.1 {
        return x.sin_cos();
    }
    // Taylor coefficients 1/3!, 1/5!, … and 1/2!, 1/4!, … (Horner, no divisions).
    const S: [f64; 4] = [1.0 / 6.0, 1.0 / 120.0, 1.0 / 5040.0, 1.0 / 362_880.0];
    const C: [f64; 5] = [
        1.0 / 2.0,
        1.0 / 24.0,
        1.0 / 720.0,
        1.0 / 40_320.0,
        1.0 / 3_628_800.0,
    ];
    let x2 = x * x;
    let s = x * (1.0 - x2 * (S[0] - x2 * (S[1] - x2 * (S[2] - x2 * S[3]))));
    let c = 1.0 - x2 * (C[0] - x2 * (C[1] - x2 * (C[2] - x2 * (C[3] - x2 * C[4]))));
    (s, c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn series_sin_cos_matches_libm() {
        for k in -1000..=1000 {
            let x = k as f64 * 1e-4;
            let (s, c) = sin_cos(x);
            assert!((s - x.sin()).abs() <= 2.0 * f64::EPSILON * x.abs(), "{x}");
            assert!((c - x.cos()).abs() <= 2.0 * f64::EPSILON, "{x}");
        }
        assert_eq!(sin_cos(0.3), 0.3f64.sin_cos());
    }

    #[test]
    fn sphere_interpolation_matches_math() {
        let a = Vec3::new(0.1, -0.3, 1.0).normalize();
        for b in [
            Vec3::new(0.2, 0.1, 1.0).normalize(),
            Vec3::new(-1.0, 0.5, 0.2).normalize(),
            Vec3::new(1e-7, 0.0, 1.0).normalize(),
        ] {
            for (kind, f) in [
                (
                    AxisInterpolation::Slerp,
                    crate::math::slerp as fn(&Vec3, &Vec3, f64) -> Vec3,
                ),
                (AxisInterpolation::Nlerp, crate::math::nlerp),
            ] {
                let (si, flipped) = SphereInterp::new(a, b, kind);
                assert!(!flipped);
                for u in [0.0, 0.25, 0.5, 0.9, 1.0] {
                    assert_relative_eq!(si.eval(u), f(&a, &b, u), epsilon = 1e-9);
                }
                assert_relative_eq!(si.eval(1.0), b, epsilon = 1e-12);
            }
        }
        let (si, flipped) = SphereInterp::new(a, -a, AxisInterpolation::Slerp);
        assert!(flipped);
        assert_relative_eq!(si.eval(0.5).dot(&a), 0.0, epsilon = 1e-12);
        assert_relative_eq!(si.eval(1.0), -a, epsilon = 1e-12);
    }
}
