//! The known surfaces synthetic paths are made for, all graphs z = F(x, y) in the WCS.

use crate::math::Vec3;
use std::f64::consts::TAU;

/// A surface z = F(x, y), mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Surface {
    /// The plane z = 0.
    Plane,
    /// The extruded parabola z = −a·x² + d of 001 Fig 7, extruded along y.
    ExtrudedParabola {
        /// a, 1/mm (001: 0.004).
        a_per_mm: f64,
        /// d, mm (001: 0.1).
        d_mm: f64,
    },
    /// The hyperbolic paraboloid z = x·y / c (000 Fig 10). Its rulings are the lines
    /// x = const and y = const, so passes along x or y have straight CC loci, as in 000
    /// ("trajectories defined according to the surface rules").
    HyperbolicParaboloid {
        /// c, mm.
        c_mm: f64,
    },
    /// A blade-like free-form patch with concave and convex regions: a camber wave along
    /// x, a smaller wave across y and a twist,
    /// z = A sin(2πx/λx) + B sin(2πy/λy) + τ·x·y.
    BladePatch {
        /// A, mm.
        amplitude_x_mm: f64,
        /// λx, mm.
        wavelength_x_mm: f64,
        /// B, mm.
        amplitude_y_mm: f64,
        /// λy, mm.
        wavelength_y_mm: f64,
        /// τ, 1/mm.
        twist_per_mm: f64,
    },
}

impl Surface {
    /// The extruded parabola of 001 Fig 7: a = 0.004 mm⁻¹, d = 0.1 mm.
    pub fn paper_parabola() -> Surface {
        Surface::ExtrudedParabola {
            a_per_mm: 0.004,
            d_mm: 0.1,
        }
    }

    /// The hyperbolic paraboloid used for 000 Fig 10: z = x·y / 200 mm. The paper prints no
    /// parameters; over the default 40 × 40 mm field this rises ±2 mm with slopes up to
    /// 0.1 (5.7°), so the tool axis turns along every ruling, as in 000.
    pub fn paper_hyperbolic_paraboloid() -> Surface {
        Surface::HyperbolicParaboloid { c_mm: 200.0 }
    }

    /// The blade-like patch: A = 1 mm, λx = 40 mm, B = 0.5 mm, λy = 30 mm, τ = 0.002 mm⁻¹.
    /// Its smallest radii of curvature are about 40 mm (along x) and 46 mm (across).
    pub fn default_blade() -> Surface {
        Surface::BladePatch {
            amplitude_x_mm: 1.0,
            wavelength_x_mm: 40.0,
            amplitude_y_mm: 0.5,
            wavelength_y_mm: 30.0,
            twist_per_mm: 0.002,
        }
    }

    /// A short lower-case name.
    pub fn name(&self) -> &'static str {
        match self {
            Surface::Plane => "plane",
            Surface::ExtrudedParabola { .. } => "extruded-parabola",
            Surface::HyperbolicParaboloid { .. } => "hyperbolic-paraboloid",
            Surface::BladePatch { .. } => "blade-patch",
        }
    }

    /// Height F(x, y), mm.
    pub fn height(&self, x: f64, y: f64) -> f64 {
        match *self {
            Surface::Plane => 0.0,
            Surface::ExtrudedParabola { a_per_mm, d_mm } => -a_per_mm * x * x + d_mm,
            Surface::HyperbolicParaboloid { c_mm } => x * y / c_mm,
            Surface::BladePatch {
                amplitude_x_mm,
                wavelength_x_mm,
                amplitude_y_mm,
                wavelength_y_mm,
                twist_per_mm,
            } => {
                amplitude_x_mm * (TAU * x / wavelength_x_mm).sin()
                    + amplitude_y_mm * (TAU * y / wavelength_y_mm).sin()
                    + twist_per_mm * x * y
            }
        }
    }

    /// Gradient (∂F/∂x, ∂F/∂y).
    pub fn gradient(&self, x: f64, y: f64) -> (f64, f64) {
        match *self {
            Surface::Plane => (0.0, 0.0),
            Surface::ExtrudedParabola { a_per_mm, .. } => (-2.0 * a_per_mm * x, 0.0),
            Surface::HyperbolicParaboloid { c_mm } => (y / c_mm, x / c_mm),
            Surface::BladePatch {
                amplitude_x_mm,
                wavelength_x_mm,
                amplitude_y_mm,
                wavelength_y_mm,
                twist_per_mm,
            } => {
                let kx = TAU / wavelength_x_mm;
                let ky = TAU / wavelength_y_mm;
                (
                    amplitude_x_mm * kx * (kx * x).cos() + twist_per_mm * y,
                    amplitude_y_mm * ky * (ky * y).cos() + twist_per_mm * x,
                )
            }
        }
    }

    /// Second derivatives (F_xx, F_xy, F_yy).
    pub fn hessian(&self, x: f64, y: f64) -> (f64, f64, f64) {
        match *self {
            Surface::Plane => (0.0, 0.0, 0.0),
            Surface::ExtrudedParabola { a_per_mm, .. } => (-2.0 * a_per_mm, 0.0, 0.0),
            Surface::HyperbolicParaboloid { c_mm } => (0.0, 1.0 / c_mm, 0.0),
            Surface::BladePatch {
                amplitude_x_mm,
                wavelength_x_mm,
                amplitude_y_mm,
                wavelength_y_mm,
                twist_per_mm,
            } => {
                let kx = TAU / wavelength_x_mm;
                let ky = TAU / wavelength_y_mm;
                (
                    -amplitude_x_mm * kx * kx * (kx * x).sin(),
                    twist_per_mm,
                    -amplitude_y_mm * ky * ky * (ky * y).sin(),
                )
            }
        }
    }

    /// Unit normal (−F_x, −F_y, 1)/√(1 + F_x² + F_y²), pointing up, out of the material.
    pub fn normal(&self, x: f64, y: f64) -> Vec3 {
        let (fx, fy) = self.gradient(x, y);
        Vec3::new(-fx, -fy, 1.0).normalize()
    }

    /// Normal curvature at (x, y) in the unit tangent direction `t` (3-D). Positive when
    /// the surface bends towards the normal (concave, seen from the tool).
    pub fn normal_curvature(&self, x: f64, y: f64, t: &Vec3) -> f64 {
        let (fx, fy) = self.gradient(x, y);
        let (fxx, fxy, fyy) = self.hessian(x, y);
        let w = (1.0 + fx * fx + fy * fy).sqrt();
        (fxx * t.x * t.x + 2.0 * fxy * t.x * t.y + fyy * t.y * t.y) / w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn all() -> [Surface; 4] {
        [
            Surface::Plane,
            Surface::paper_parabola(),
            Surface::paper_hyperbolic_paraboloid(),
            Surface::default_blade(),
        ]
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let e = 1e-5;
        for s in all() {
            for &(x, y) in &[(0.3, -1.7), (7.0, 4.0), (-12.0, 9.5)] {
                let (fx, fy) = s.gradient(x, y);
                let nfx = (s.height(x + e, y) - s.height(x - e, y)) / (2.0 * e);
                let nfy = (s.height(x, y + e) - s.height(x, y - e)) / (2.0 * e);
                assert_relative_eq!(fx, nfx, epsilon = 1e-8);
                assert_relative_eq!(fy, nfy, epsilon = 1e-8);
                let (fxx, fxy, fyy) = s.hessian(x, y);
                let g = |x, y| s.gradient(x, y);
                assert_relative_eq!(
                    fxx,
                    (g(x + e, y).0 - g(x - e, y).0) / (2.0 * e),
                    epsilon = 1e-7
                );
                assert_relative_eq!(
                    fxy,
                    (g(x, y + e).0 - g(x, y - e).0) / (2.0 * e),
                    epsilon = 1e-7
                );
                assert_relative_eq!(
                    fyy,
                    (g(x, y + e).1 - g(x, y - e).1) / (2.0 * e),
                    epsilon = 1e-7
                );
            }
        }
    }

    #[test]
    fn parabola_curvature_is_convex_2a() {
        // z = −a x² + d: at the apex the radius of curvature is 1/(2a) = 125 mm, convex.
        let s = Surface::paper_parabola();
        assert_relative_eq!(s.height(5.0, 3.0), 0.0, epsilon = 1e-15);
        assert_relative_eq!(s.normal_curvature(0.0, 0.0, &Vec3::x()), -0.008);
        assert_relative_eq!(s.normal_curvature(0.0, 0.0, &Vec3::y()), 0.0);
    }

    #[test]
    fn blade_has_concave_and_convex_regions() {
        let s = Surface::default_blade();
        let k1 = s.normal_curvature(-10.0, 0.0, &Vec3::x());
        let k2 = s.normal_curvature(10.0, 0.0, &Vec3::x());
        assert!(k1 > 0.02 && k2 < -0.02, "{k1} {k2}");
    }
}
