//! The swept envelope of a cutter across the feed, the scallop it leaves between two
//! parallel passes, and the path interval for a target scallop (model.md §7, R6).
//!
//! Everything here holds for a plane, a straight pass and a fixed orientation. Directions
//! are given in the local frame (f, g, n): `x` = feed f, `y` = lateral g, `z` = normal n.
//!
//! Seen along f, the end disk of radius Rd = R − rc (centre rc above the tip on the axis)
//! projects onto an ellipse; the corner ball of radius rc projects onto a disk, so the
//! cross-section of the swept solid is the ellipse dilated by rc. Its lower boundary z(y)
//! is traced by the support point for the outward normal m(φ) = (sin φ, −cos φ), φ from
//! −90° (left) through 0 (down) to +90° (right); y grows monotonically with φ, so z(y) is
//! found by bisection on φ. This covers the ball (Rd = 0), the torus and the flat end
//! (rc = 0) with one code path, and the round insert (its insert circle is the corner).
//!
//! For a profile (circle-segment tools, APT cutters) the boundary point for the normal m is
//! the projection of the body's support point: the meridian's point farthest along the
//! axial and radial parts of m, placed at the radial direction of m. A barrel tilted across
//! the feed shows its segment radius Rs here, and its scallop is `Rs − √(Rs² − s²/4)`.

use super::SynthError;
use crate::math::{Vec3, any_perpendicular};
use crate::tool::{Cutter, Meridian, Shape};
use std::f64::consts::FRAC_PI_2;

/// Unit tool axis in (f, g, n) from tilt λ and yaw ψ by convention A of model.md §7:
/// `a = sin λ cos ψ f + sin λ sin ψ g + cos λ n`.
pub fn axis_convention_a(tilt_rad: f64, yaw_rad: f64) -> Vec3 {
    let (sl, cl) = tilt_rad.sin_cos();
    let (sy, cy) = yaw_rad.sin_cos();
    Vec3::new(sl * cy, sl * sy, cl)
}

/// Closed-form effective radius across the feed at the lowest point (model.md §7):
/// `R_eff = rc + A²B²/H³`, with A = Rd, B = Rd |a·f|, γ = atan2(a·g, a·n) and
/// `H = √(A² sin²γ + B² cos²γ)`. Infinite for a flat bottom lying on the plane.
pub fn effective_radius_mm(cutter: &Cutter, axis_fgn: &Vec3) -> f64 {
    if let Shape::Profile(_) = cutter.shape {
        // No closed form: the curvature of the lower boundary at the bottom.
        return CrossSection::new(cutter, axis_fgn).map_or(f64::NAN, |cs| cs.bottom_radius_mm());
    }
    let rc = cutter.corner_radius_mm();
    let rd = cutter.radius_mm - rc;
    if rd <= 0.0 {
        return rc;
    }
    let a = axis_fgn.normalize();
    let big_a = rd;
    let big_b = rd * a.x.abs();
    let gamma = a.y.atan2(a.z);
    let h = (big_a * big_a * gamma.sin().powi(2) + big_b * big_b * gamma.cos().powi(2)).sqrt();
    if h <= 0.0 {
        return f64::INFINITY;
    }
    rc + big_a * big_a * big_b * big_b / h.powi(3)
}

/// The usual approximation of the step for scallop height `h`: `s ≈ 2√(2 R_eff h − h²)`.
pub fn approx_step_mm(r_eff_mm: f64, scallop_mm: f64) -> f64 {
    2.0 * (2.0 * r_eff_mm * scallop_mm - scallop_mm * scallop_mm)
        .max(0.0)
        .sqrt()
}

/// The lower boundary of the swept cross-section of a cutter with a fixed axis.
#[derive(Debug, Clone)]
pub struct CrossSection {
    /// Centre of the end disk projected on (g, n), relative to the tip.
    centre: [f64; 2],
    /// Ellipse matrix: columns are the projections of Rd·u and Rd·v (u, v ⊥ axis).
    m: [[f64; 2]; 2],
    /// Corner radius rc.
    rc: f64,
    /// The axis in (f, g, n).
    axis: Vec3,
    /// Lowest point (y, z).
    bottom: [f64; 2],
    /// y range of the lower boundary.
    y_range: [f64; 2],
    /// A profile's meridian: support points replace the dilated ellipse.
    meridian: Option<Meridian>,
}

impl CrossSection {
    /// The cross-section of `cutter` with unit axis `axis_fgn` in (f, g, n).
    pub fn new(cutter: &Cutter, axis_fgn: &Vec3) -> Result<CrossSection, SynthError> {
        let a = crate::math::normalize_or_none(axis_fgn, 1e-12)
            .ok_or_else(|| SynthError::Invalid("the tool axis has zero length".to_string()))?;
        if a.z <= 0.0 {
            return Err(SynthError::Invalid(
                "the tool axis must point out of the surface (tilt below 90°)".to_string(),
            ));
        }
        let meridian = match &cutter.shape {
            Shape::Profile(m) => {
                if !m.is_convex() {
                    return Err(SynthError::Invalid(
                        "the swept cross-section needs a convex cutter profile".to_string(),
                    ));
                }
                Some(m.clone())
            }
            _ => None,
        };
        let rc = if meridian.is_some() {
            0.0
        } else {
            cutter.corner_radius_mm()
        };
        let rd = if meridian.is_some() {
            0.0
        } else {
            cutter.radius_mm - rc
        };
        if cutter.radius_mm.is_nan() || cutter.radius_mm <= 0.0 || rc < 0.0 || rd < 0.0 {
            return Err(SynthError::Invalid(format!(
                "invalid cutter: radius {} mm, corner radius {} mm",
                cutter.radius_mm, rc
            )));
        }
        let u = any_perpendicular(&a);
        let v = a.cross(&u);
        let c = a * rc;
        let mut cs = CrossSection {
            centre: [c.y, c.z],
            m: [[rd * u.y, rd * v.y], [rd * u.z, rd * v.z]],
            rc,
            axis: a,
            bottom: [0.0, 0.0],
            y_range: [0.0, 0.0],
            meridian,
        };
        cs.bottom = cs.point(0.0);
        cs.y_range = [cs.point(-FRAC_PI_2)[0], cs.point(FRAC_PI_2)[0]];
        Ok(cs)
    }

    /// Boundary point (y, z) whose outward normal is m(φ) = (sin φ, −cos φ).
    fn point(&self, phi: f64) -> [f64; 2] {
        let (s, c) = phi.sin_cos();
        if let Some(m) = &self.meridian {
            let dir = Vec3::new(0.0, s, -c);
            let m_a = dir.dot(&self.axis);
            let radial = dir - self.axis * m_a;
            let m_r = radial.norm();
            let w = if m_r > 1e-15 {
                radial / m_r
            } else {
                Vec3::zeros()
            };
            let p = m.support(m_r, m_a);
            let q = self.axis * p[1] + w * p[0];
            return [q.y, q.z];
        }
        let dir = [s, -c];
        // Mᵀ m
        let mt = [
            self.m[0][0] * dir[0] + self.m[1][0] * dir[1],
            self.m[0][1] * dir[0] + self.m[1][1] * dir[1],
        ];
        let len = (mt[0] * mt[0] + mt[1] * mt[1]).sqrt();
        let (ey, ez) = if len > 1e-300 {
            (
                (self.m[0][0] * mt[0] + self.m[0][1] * mt[1]) / len,
                (self.m[1][0] * mt[0] + self.m[1][1] * mt[1]) / len,
            )
        } else {
            (0.0, 0.0)
        };
        [
            self.centre[0] + ey + self.rc * dir[0],
            self.centre[1] + ez + self.rc * dir[1],
        ]
    }

    /// The lowest point (y, z) of the cross-section, relative to the tip.
    pub fn bottom(&self) -> [f64; 2] {
        self.bottom
    }

    /// Radius of curvature of the lower boundary at its lowest point (the mean of both
    /// sides over 0.5 % of the cutter's width), mm; infinite where it is flat.
    pub fn bottom_radius_mm(&self) -> f64 {
        let d = 0.005 * (self.y_range[1] - self.y_range[0]);
        let [y0, z0] = self.bottom;
        let rise = |y: f64| self.lower(y).map_or(f64::NAN, |z| z - z0);
        let h = 0.5 * (rise(y0 - d) + rise(y0 + d));
        if h > 0.0 {
            d * d / (2.0 * h)
        } else {
            f64::INFINITY
        }
    }

    /// Lower boundary z(y) relative to the tip, or `None` outside the cutter's width.
    pub fn lower(&self, y: f64) -> Option<f64> {
        self.lower_with_phi(y).map(|(z, _)| z)
    }

    /// z(y) and the normal angle φ of the boundary there.
    fn lower_with_phi(&self, y: f64) -> Option<(f64, f64)> {
        if !(self.y_range[0]..=self.y_range[1]).contains(&y) {
            return None;
        }
        let (mut lo, mut hi) = (-FRAC_PI_2, FRAC_PI_2);
        let (mut p_lo, mut p_hi) = (self.point(lo), self.point(hi));
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            let p = self.point(mid);
            if p[0] < y {
                lo = mid;
                p_lo = p;
            } else {
                hi = mid;
                p_hi = p;
            }
        }
        // Between the two bracketing points the boundary is a straight segment (a jump in
        // the support point, e.g. a flat end) or a single point.
        let dy = p_hi[0] - p_lo[0];
        let z = if dy > 1e-15 {
            p_lo[1] + (p_hi[1] - p_lo[1]) * (y - p_lo[0]) / dy
        } else {
            0.5 * (p_lo[1] + p_hi[1])
        };
        Some((z, 0.5 * (lo + hi)))
    }

    /// Scallop height (mm) left between two passes `s_mm` apart: the highest point of
    /// min(z(y), z(y − s)) between the two minima, above the minimum. `None` when the
    /// boundaries do not meet (step wider than the cutter) or meet above the lower part
    /// of the tool (where the shank, not the corner, would cut).
    pub fn scallop_mm(&self, s_mm: f64) -> Option<f64> {
        self.scallop_with_phi(s_mm).map(|(h, _)| h)
    }

    fn scallop_with_phi(&self, s_mm: f64) -> Option<(f64, f64)> {
        if s_mm <= 0.0 {
            return Some((0.0, 0.0));
        }
        let y0 = self.bottom[0];
        // g(y) = z(y) − z(y − s) is nondecreasing on [y0, y0 + s]; find its root.
        let (mut lo, mut hi) = (y0, y0 + s_mm);
        if hi > self.y_range[1] || lo - s_mm < self.y_range[0] {
            // Partly outside: shrink to where both boundaries exist.
            lo = lo.max(self.y_range[0] + s_mm);
            hi = hi.min(self.y_range[1]);
            if lo > hi {
                return None;
            }
        }
        let g = |y: f64| -> Option<f64> { Some(self.lower(y)? - self.lower(y - s_mm)?) };
        if g(lo)? > 0.0 || g(hi)? < 0.0 {
            return None;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if g(mid)? < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let y = 0.5 * (lo + hi);
        let (z1, phi1) = self.lower_with_phi(y)?;
        let (z2, phi2) = self.lower_with_phi(y - s_mm)?;
        let z = z1.min(z2);
        // The corner's support direction must point below the tool's equator.
        let below = |phi: f64| phi.sin() * self.axis.y - phi.cos() * self.axis.z < 0.0;
        if !below(phi1) || !below(phi2) {
            return None;
        }
        Some((z - self.bottom[1], phi1.abs().max(phi2.abs())))
    }

    /// The exact path interval for scallop height `h_mm`: solves h(s) = h_target by
    /// bisection (h is nondecreasing in s). Returns the largest s with h(s) ≤ h_target.
    pub fn step_for_scallop(&self, h_mm: f64) -> Result<f64, SynthError> {
        self.step_for_scallop_within(h_mm, 0.0)
    }

    /// [`CrossSection::step_for_scallop`] to a relative tolerance `rel` (0: to the last
    /// bit): a step at most `rel` below the exact one and never above it, so the passes it
    /// gives are never fewer (for budgets, in far fewer evaluations).
    pub fn step_for_scallop_within(&self, h_mm: f64, rel: f64) -> Result<f64, SynthError> {
        if h_mm.is_nan() || h_mm <= 0.0 || !h_mm.is_finite() {
            return Err(SynthError::Invalid(format!(
                "the scallop height must be positive, got {h_mm} mm"
            )));
        }
        let width = self.y_range[1] - self.y_range[0];
        let (mut lo, mut hi) = (0.0, width);
        // h(hi) must exceed the target (or be undefined); otherwise the target is unreachable
        // only in the sense that any step up to the width works — report that as an error.
        match self.scallop_mm(hi) {
            Some(h) if h <= h_mm => {
                return Err(SynthError::Invalid(format!(
                    "a scallop of {:.3} µm is larger than this cutter can leave",
                    h_mm * 1e3
                )));
            }
            _ => {}
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi || hi - lo <= rel * hi {
                break;
            }
            match self.scallop_mm(mid) {
                Some(h) if h <= h_mm => lo = mid,
                _ => hi = mid,
            }
        }
        // The bisection ends at a jump of h only when the target lies above every scallop
        // the corner can leave (h is continuous otherwise).
        if lo <= 0.0 || self.scallop_mm(hi).is_none() {
            return Err(SynthError::Invalid(format!(
                "no step leaves a scallop of {:.3} µm with this cutter and tilt",
                h_mm * 1e3
            )));
        }
        Ok(lo)
    }
}

/// The exact transversal step for scallop `h_mm` of `cutter` with axis `axis_fgn` on a
/// plane (model.md §7, oracle `transversal_step`).
pub fn exact_step_mm(cutter: &Cutter, axis_fgn: &Vec3, h_mm: f64) -> Result<f64, SynthError> {
    CrossSection::new(cutter, axis_fgn)?.step_for_scallop(h_mm)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::Shape;
    use approx::assert_relative_eq;

    fn torus() -> Cutter {
        Cutter::new(
            Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            1,
            0.0,
        )
    }

    #[test]
    fn r6_exact_steps_and_effective_radii() {
        // model.md R6: R = 5, rc = 1.5; (yaw, tilt, h) → R_eff, s approx, s exact.
        let cases = [
            (0.0, 1.0, 0.005, 202.045, 2.8428, 2.7850),
            (0.0, 10.0, 0.010, 21.656, 1.3161, 1.3115),
            (20.0, 10.0, 0.010, 19.298, 1.2424, 1.2385),
        ];
        let c = torus();
        for (yaw, tilt, h, r_eff, approx, exact) in cases {
            let a = axis_convention_a(f64::to_radians(tilt), f64::to_radians(yaw));
            let r = effective_radius_mm(&c, &a);
            assert!((r - r_eff).abs() < 1e-3, "R_eff {r} vs {r_eff}");
            assert!((approx_step_mm(r, h) - approx).abs() < 1e-4);
            let s = exact_step_mm(&c, &a, h).unwrap();
            assert!((s - exact).abs() < 1e-3, "step {s} vs {exact}");
        }
    }

    #[test]
    fn r6_convention_b_effective_radius() {
        // Convention B of R6 row 4: lead 10° about g, then side tilt 20° about f.
        let (l, p) = (10f64.to_radians(), 20f64.to_radians());
        let a0 = Vec3::new(l.sin(), 0.0, l.cos());
        let a = Vec3::new(
            a0.x,
            a0.y * p.cos() - a0.z * p.sin(),
            a0.y * p.sin() + a0.z * p.cos(),
        );
        let r = effective_radius_mm(&torus(), &a);
        assert!((r - 3.439).abs() < 1e-3, "{r}");
        let s = exact_step_mm(&torus(), &a, 0.010).unwrap();
        assert!((s - 0.5259).abs() < 1e-3, "{s}");
    }

    #[test]
    fn ball_scallop_is_the_circle_crest() {
        let ball = Cutter::new(Shape::Ball, 5.0, 2, 0.0);
        let cs = CrossSection::new(&ball, &axis_convention_a(0.3, 0.7)).unwrap();
        for s in [0.1, 0.5, 1.0, 3.0] {
            let h = cs.scallop_mm(s).unwrap();
            assert_relative_eq!(h, crate::tool::crest_height_mm(5.0, s), epsilon = 1e-12);
        }
        let s = cs.step_for_scallop(0.001).unwrap();
        assert_relative_eq!(crate::tool::crest_height_mm(5.0, s), 0.001, epsilon = 1e-12);
        assert_relative_eq!(effective_radius_mm(&ball, &Vec3::z()), 5.0);
    }

    #[test]
    fn scallop_is_monotone_in_the_step() {
        let cs = CrossSection::new(&torus(), &axis_convention_a(0.2, 0.5)).unwrap();
        let mut last = 0.0;
        for k in 1..60 {
            let h = cs.scallop_mm(0.05 * k as f64).unwrap();
            assert!(h >= last - 1e-12);
            last = h;
        }
    }

    #[test]
    fn flat_bottom_leaves_no_scallop_within_its_width() {
        let cs = CrossSection::new(&torus(), &Vec3::z()).unwrap();
        assert_relative_eq!(cs.scallop_mm(6.9).unwrap(), 0.0, epsilon = 1e-12);
        assert!(cs.scallop_mm(7.5).unwrap() > 0.0);
        assert!(effective_radius_mm(&torus(), &Vec3::z()).is_infinite());
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert!(exact_step_mm(&torus(), &Vec3::new(1.0, 0.0, -0.1), 0.01).is_err());
        assert!(exact_step_mm(&torus(), &Vec3::z(), -1.0).is_err());
        assert!(exact_step_mm(&torus(), &Vec3::z(), 10.0).is_err());
    }
}
