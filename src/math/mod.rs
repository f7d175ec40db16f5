//! Shared numerics: vector aliases, angle helpers and frames.
//!
//! Lengths are mm and angles radians everywhere inside the library; conversion to µm,
//! degrees and mm/min happens only at the interface (`cli`, `io`, `report`).

pub mod limits;

use nalgebra as na;

pub mod rng;
pub mod wide;

/// A point in a Cartesian frame, mm.
pub type Point3 = na::Point3<f64>;
/// A vector in a Cartesian frame.
pub type Vec3 = na::Vector3<f64>;

/// Normalise `v`, or return `None` when it is shorter than `eps`.
pub fn normalize_or_none(v: &Vec3, eps: f64) -> Option<Vec3> {
    let n = v.norm();
    if n > eps && n.is_finite() {
        Some(v / n)
    } else {
        None
    }
}

/// Normalised linear interpolation of two unit vectors (model.md §5.1, "nlerp").
/// Falls back to `a` when the chord passes through the origin (antipodal vectors).
pub fn nlerp(a: &Vec3, b: &Vec3, u: f64) -> Vec3 {
    let v = a * (1.0 - u) + b * u;
    normalize_or_none(&v, 1e-12).unwrap_or(*a)
}

/// Spherical linear interpolation of two unit vectors. For antipodal vectors the
/// great circle is not unique and the result rotates about an axis normal to `a`.
pub fn slerp(a: &Vec3, b: &Vec3, u: f64) -> Vec3 {
    let cos = a.dot(b).clamp(-1.0, 1.0);
    let angle = cos.acos();
    if angle < 1e-9 {
        return nlerp(a, b, u);
    }
    let axis_in_plane = if (std::f64::consts::PI - angle) < 1e-9 {
        any_perpendicular(a)
    } else {
        (b - a * cos).normalize()
    };
    let t = angle * u;
    (a * t.cos() + axis_in_plane * t.sin()).normalize()
}

/// A unit vector perpendicular to the unit vector `a`.
pub fn any_perpendicular(a: &Vec3) -> Vec3 {
    let trial = if a.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    (trial - a * a.dot(&trial)).normalize()
}

/// `x.floor()` for the hot loops: exact (the same value as `f64::floor` up to the sign of
/// a zero result) without the library call that targets lacking SSE4.1 make.
#[inline]
pub fn floor_fast(x: f64) -> f64 {
    if x.abs() < 4.0e15 {
        let t = x as i64 as f64;
        if t > x { t - 1.0 } else { t }
    } else {
        x.floor()
    }
}

/// `x.ceil()` for the hot loops, see [`floor_fast`].
#[inline]
pub fn ceil_fast(x: f64) -> f64 {
    if x.abs() < 4.0e15 {
        let t = x as i64 as f64;
        if t < x { t + 1.0 } else { t }
    } else {
        x.ceil()
    }
}

/// Wrap an angle to (−π, π].
pub fn wrap_pi(a: f64) -> f64 {
    if a > -std::f64::consts::PI && a <= std::f64::consts::PI {
        return a;
    }
    let two_pi = std::f64::consts::TAU;
    let mut r = a.rem_euclid(two_pi);
    if r > std::f64::consts::PI {
        r -= two_pi;
    }
    r
}

/// An orthonormal right-handed frame: `x`, `y`, `z` unit vectors with `z = x × y`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// First axis.
    pub x: Vec3,
    /// Second axis.
    pub y: Vec3,
    /// Third axis, `x × y`.
    pub z: Vec3,
}

impl Frame {
    /// The tool frame of model.md §1.3: `z = axis`, `x` = `feed` projected normal to the axis,
    /// `y = z × x`. When the feed is parallel to the axis, `x` is any perpendicular.
    pub fn tool(axis: &Vec3, feed: &Vec3) -> Frame {
        let z = axis.normalize();
        let x = normalize_or_none(&(feed - z * feed.dot(&z)), 1e-12)
            .unwrap_or_else(|| any_perpendicular(&z));
        let y = z.cross(&x);
        Frame { x, y, z }
    }

    /// Map frame coordinates to the parent frame (a direction, no translation).
    pub fn to_parent(&self, local: &Vec3) -> Vec3 {
        self.x * local.x + self.y * local.y + self.z * local.z
    }

    /// Map a parent-frame direction into frame coordinates.
    pub fn to_local(&self, v: &Vec3) -> Vec3 {
        Vec3::new(self.x.dot(v), self.y.dot(v), self.z.dot(v))
    }
}

/// `v` with `decimals` decimals, trailing zeros (and a trailing point) removed, and `-0`
/// written `0`: the one way numbers are trimmed for titles, labels, names and reports.
pub fn trim_decimals(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s.as_str()
    };
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trim_decimals_drops_zeros_and_negative_zero() {
        assert_eq!(trim_decimals(1.5, 4), "1.5");
        assert_eq!(trim_decimals(2.0, 3), "2");
        assert_eq!(trim_decimals(-0.00001, 3), "0");
        assert_eq!(trim_decimals(120.0, 0), "120");
        assert_eq!(trim_decimals(0.123456, 4), "0.1235");
    }
    use approx::assert_relative_eq;

    #[test]
    fn nlerp_and_slerp_match_model_r4() {
        // model.md R4: axes 0 and 0.2 rad apart, u = 0.25: nlerp 0.049875 rad, slerp 0.05 rad.
        let a = Vec3::z();
        let b = Vec3::new(0.2f64.sin(), 0.0, 0.2f64.cos());
        let n = nlerp(&a, &b, 0.25);
        let s = slerp(&a, &b, 0.25);
        assert_relative_eq!(n.x.atan2(n.z), 0.049875, epsilon = 1e-6);
        assert_relative_eq!(s.x.atan2(s.z), 0.05, epsilon = 1e-12);
    }

    #[test]
    fn tool_frame_is_orthonormal() {
        let f = Frame::tool(&Vec3::new(0.1, 0.2, 1.0), &Vec3::new(1.0, 0.0, 0.3));
        assert_relative_eq!(f.x.norm(), 1.0, epsilon = 1e-12);
        assert_relative_eq!(f.x.dot(&f.z), 0.0, epsilon = 1e-12);
        assert_relative_eq!(f.x.cross(&f.y), f.z, epsilon = 1e-12);
    }

    #[test]
    fn wrap_pi_range() {
        assert_relative_eq!(
            wrap_pi(3.0 * std::f64::consts::PI),
            std::f64::consts::PI,
            epsilon = 1e-12
        );
        assert_relative_eq!(wrap_pi(-0.5), -0.5, epsilon = 1e-12);
    }
}
