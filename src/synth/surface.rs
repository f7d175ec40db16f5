//! The known surfaces synthetic paths are made for, all graphs z = F(x, y) in the WCS
//! (cylinders and spheres over their upper or lower half, |y| (and |x|) < radius).

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
    /// A convex cylinder of radius R about the x axis, top line on z = 0:
    /// z = √(R² − y²) − R.
    ConvexCylinder {
        /// R, mm.
        radius_mm: f64,
    },
    /// A concave cylinder (a trough) of radius R about the x axis, bottom line on z = 0:
    /// z = R − √(R² − y²).
    ConcaveCylinder {
        /// R, mm.
        radius_mm: f64,
    },
    /// A convex sphere of radius R, top on the origin: z = √(R² − x² − y²) − R.
    Sphere {
        /// R, mm.
        radius_mm: f64,
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
            Surface::ConvexCylinder { .. } => "convex-cylinder",
            Surface::ConcaveCylinder { .. } => "concave-cylinder",
            Surface::Sphere { .. } => "sphere",
        }
    }

    /// The surface's radius when it is a cylinder or sphere, mm.
    pub fn radius_mm(&self) -> Option<f64> {
        match *self {
            Surface::ConvexCylinder { radius_mm }
            | Surface::ConcaveCylinder { radius_mm }
            | Surface::Sphere { radius_mm } => Some(radius_mm),
            _ => None,
        }
    }

    /// Whether (x, y) lies where the graph is defined (inside a cylinder's or sphere's
    /// radius, with a margin so that slopes stay finite).
    pub fn covers(&self, x: f64, y: f64) -> bool {
        match *self {
            Surface::ConvexCylinder { radius_mm } | Surface::ConcaveCylinder { radius_mm } => {
                y.abs() < 0.98 * radius_mm
            }
            Surface::Sphere { radius_mm } => x.hypot(y) < 0.98 * radius_mm,
            _ => true,
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
            Surface::ConvexCylinder { radius_mm: r } => (r * r - y * y).sqrt() - r,
            Surface::ConcaveCylinder { radius_mm: r } => r - (r * r - y * y).sqrt(),
            Surface::Sphere { radius_mm: r } => (r * r - x * x - y * y).sqrt() - r,
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
            Surface::ConvexCylinder { radius_mm: r } => (0.0, -y / (r * r - y * y).sqrt()),
            Surface::ConcaveCylinder { radius_mm: r } => (0.0, y / (r * r - y * y).sqrt()),
            Surface::Sphere { radius_mm: r } => {
                let w = (r * r - x * x - y * y).sqrt();
                (-x / w, -y / w)
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
            Surface::ConvexCylinder { radius_mm: r } => {
                let w = (r * r - y * y).sqrt();
                (0.0, 0.0, -r * r / (w * w * w))
            }
            Surface::ConcaveCylinder { radius_mm: r } => {
                let w = (r * r - y * y).sqrt();
                (0.0, 0.0, r * r / (w * w * w))
            }
            Surface::Sphere { radius_mm: r } => {
                let w2 = r * r - x * x - y * y;
                let w3 = w2 * w2.sqrt();
                (-(r * r - y * y) / w3, -x * y / w3, -(r * r - x * x) / w3)
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

    fn all() -> [Surface; 7] {
        [
            Surface::Plane,
            Surface::paper_parabola(),
            Surface::paper_hyperbolic_paraboloid(),
            Surface::default_blade(),
            Surface::ConvexCylinder { radius_mm: 20.0 },
            Surface::ConcaveCylinder { radius_mm: 20.0 },
            Surface::Sphere { radius_mm: 20.0 },
        ]
    }

    #[test]
    fn cylinders_and_sphere_have_their_radius_of_curvature() {
        let r = 20.0;
        let t = Vec3::y();
        assert_relative_eq!(
            Surface::ConvexCylinder { radius_mm: r }.normal_curvature(0.0, 0.0, &t),
            -1.0 / r
        );
        let cave = Surface::ConcaveCylinder { radius_mm: r };
        let t = Vec3::new(0.0, 1.0, cave.gradient(0.0, 3.0).1).normalize();
        assert_relative_eq!(
            cave.normal_curvature(0.0, 3.0, &t),
            1.0 / r,
            epsilon = 1e-12
        );
        let s = Surface::Sphere { radius_mm: r };
        let (x, y) = (3.0, -4.0);
        let n = s.normal(x, y);
        let p = Vec3::new(x, y, s.height(x, y) + r);
        assert!(n.angle(&p) < 1e-12);
        assert!(s.covers(3.0, 4.0) && !s.covers(19.9, 0.0));
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let e = 1e-5;
        for s in all() {
            for &(x, y) in &[(0.3, -1.7), (7.0, 4.0), (-9.0, 9.5)] {
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
