//! The cutter as seen by the rasteriser: a meridian polyline ("levels") and, per tooth,
//! the tool-frame points of its edge (ICE) or of its revolved body (dome) at angle 0.
//!
//! Any point at spindle angle θ is the angle-0 point rotated about the tool axis:
//! `edge_point(j, z, θ) = Rot(θ) edge_point(j, z, 0)` with `Rot(θ)(x, y, z) =
//! (x cos θ + y sin θ, −x sin θ + y cos θ, z)`, since d(θ + ψ) = Rot(θ) d(ψ). This turns
//! every pose into one 3×3 matrix and makes each edge element cost a matrix-vector product.
//!
//! Ball, torus and flat ends are discretised by their closed forms; round inserts and
//! profiles by their meridian polyline (which may start off the axis and, for a profile
//! that is not convex, need a full scan of the levels).

use crate::math::Vec3;
use crate::tool::{Cutter, ProfileError, Shape, direction};

/// One meridian sample of the nominal body: local radius `r` at height `z` (tool frame, mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Level {
    pub r: f64,
    pub z: f64,
}

/// Meridian levels and per-tooth points.
#[derive(Debug, Clone)]
pub(crate) struct Profile {
    pub levels: Vec<Level>,
    /// `edge[j][i]`: tooth j's edge element at level i, angle 0 (vector run-out form).
    pub edge: Vec<Vec<Vec3>>,
    /// `body[j][i]`: (0, r_j(z_i), z_i), tooth j's revolved body (radial run-out form).
    pub body: Vec<Vec<Vec3>>,
    /// Upper bound of how far run-out moves any element from the nominal circle, mm.
    pub runout_bound: f64,
    /// `reach[i]`: the largest distance √(r² + z²) from the tip of levels 0..=i, mm.
    pub reach: Vec<f64>,
    /// Whether the levels follow a convex meridian (a linear function of (r, z) is then
    /// unimodal along them).
    pub convex: bool,
    /// Levels `0..flat` lie on the end face, and so does level `flat`: each tooth's body
    /// points `0..=flat` are on one straight segment, so a dome mesh needs only the ends of
    /// the stretch of them it uses (0 when there is no such stretch).
    pub flat: usize,
}

impl Profile {
    /// Discretise `cutter` with meridian chord error ≤ `chord_tol_mm`, the side modelled up to
    /// `side_mm` above the end of the corner.
    pub fn new(cutter: &Cutter, chord_tol_mm: f64, side_mm: f64) -> Result<Profile, ProfileError> {
        if !cutter.shape.is_classic() {
            return Profile::general(cutter, chord_tol_mm, side_mm);
        }
        let r = cutter.radius_mm;
        let rc = cutter.corner_radius_mm();
        let rd = (r - rc).max(0.0);
        let mut levels = Vec::new();
        // Flat end: radial line from the centre (for a ball Rd = 0: nothing).
        if rd > 0.0 {
            let n = (rd / 0.1).ceil().max(1.0) as usize;
            for i in 0..n {
                levels.push(Level {
                    r: rd * i as f64 / n as f64,
                    z: 0.0,
                });
            }
        }
        // Corner arc κ ∈ [0, π/2].
        let flat_end = levels.len();
        if rc > 0.0 {
            let dk = (8.0 * chord_tol_mm / rc)
                .sqrt()
                .clamp(1e-4, 2f64.to_radians());
            let n = (std::f64::consts::FRAC_PI_2 / dk).ceil() as usize;
            for i in 0..=n {
                let k = std::f64::consts::FRAC_PI_2 * i as f64 / n as f64;
                levels.push(Level {
                    r: rd + rc * k.sin(),
                    z: rc * (1.0 - k.cos()),
                });
            }
        } else {
            levels.push(Level { r, z: 0.0 });
        }
        // Side (cylinder of radius R).
        let n_side = (side_mm / 0.05).ceil().clamp(1.0, 200.0) as usize;
        for i in 1..=n_side {
            levels.push(Level {
                r,
                z: rc + side_mm * i as f64 / n_side as f64,
            });
        }
        let teeth = cutter.teeth();
        let mut edge = Vec::with_capacity(teeth);
        let mut body = Vec::with_capacity(teeth);
        for j in 0..teeth {
            let dev = cutter.tooth_dev_mm(j);
            let eps = cutter.tooth_axial_dev_mm(j);
            let rho0 = cutter.tooth_radius(j, 0.0) - cutter.profile_radius(0.0);
            let mut e = Vec::with_capacity(levels.len());
            let mut b = Vec::with_capacity(levels.len());
            for (i, l) in levels.iter().enumerate() {
                if i < flat_end {
                    // On the end face: the tooth is a radial line; scale the deviations so
                    // that the line meets the corner edge continuously.
                    let f = if rd > 0.0 { l.r / rd } else { 0.0 };
                    let dir = direction(cutter.tooth_angle(j, 0.0));
                    let mut p = cutter.axis_offset(0.0, 0.0) * f + dir * (l.r + dev * f);
                    if eps != 0.0 {
                        p.z += eps;
                    }
                    e.push(p);
                    b.push(Vec3::new(0.0, (l.r + rho0 * f).max(0.0), eps));
                } else {
                    e.push(cutter.edge_point(j, l.z, 0.0));
                    let rj = if matches!(cutter.shape, Shape::Ball) || l.z > 0.0 {
                        cutter.tooth_radius(j, l.z)
                    } else {
                        l.r + rho0
                    };
                    let z = if eps != 0.0 { l.z + eps } else { l.z };
                    b.push(Vec3::new(0.0, rj.max(0.0), z));
                }
            }
            edge.push(e);
            body.push(b);
        }
        let flat = if rd > 0.0 { flat_end } else { 0 };
        Ok(Profile::finish(cutter, levels, edge, body, true, flat))
    }

    /// A round insert or a profile: the meridian polyline, each level's edge point and its
    /// revolved body with the radial run-out of that height.
    fn general(cutter: &Cutter, chord_tol_mm: f64, side_mm: f64) -> Result<Profile, ProfileError> {
        let m = cutter.meridian()?;
        let tol = chord_tol_mm.max(1e-7);
        let levels: Vec<Level> = m
            .polyline(tol, side_mm)
            .into_iter()
            .map(|p| Level { r: p[0], z: p[1] })
            .collect();
        let teeth = cutter.teeth();
        let mut edge = Vec::with_capacity(teeth);
        let mut body = Vec::with_capacity(teeth);
        for j in 0..teeth {
            let eps = cutter.tooth_axial_dev_mm(j);
            edge.push(
                levels
                    .iter()
                    .map(|l| cutter.edge_point_at(j, l.r, l.z, 0.0))
                    .collect(),
            );
            body.push(
                levels
                    .iter()
                    .map(|l| {
                        let rj = l.r + cutter.radial_runout_mm(j, l.z);
                        Vec3::new(0.0, rj.max(0.0), l.z + eps)
                    })
                    .collect(),
            );
        }
        Ok(Profile::finish(
            cutter,
            levels,
            edge,
            body,
            m.is_convex(),
            0,
        ))
    }

    /// Whether a dome mesh of levels `lo..=hi` uses level `i` (the test's plain statement
    /// of [`Profile::dome_levels`]).
    #[cfg(test)]
    fn dome_keeps(&self, i: usize, lo: usize, hi: usize) -> bool {
        i == lo || i == hi || i == 0 || i >= self.flat
    }

    /// The levels a dome mesh of levels `lo..=hi` uses, in order: its ends and every level
    /// off the end face. The end face's levels strictly inside the stretch lie on the
    /// segment between its ends, so their quads are one plane's fan and their points add
    /// nothing to any bound of the mesh; they are not even looked at.
    pub fn dome_levels(&self, lo: usize, hi: usize) -> impl Iterator<Item = usize> {
        let from = (lo + 1).max(self.flat);
        let last = (hi > lo && hi < from).then_some(hi);
        std::iter::once(lo).chain(from..=hi).chain(last)
    }

    fn finish(
        cutter: &Cutter,
        levels: Vec<Level>,
        edge: Vec<Vec<Vec3>>,
        body: Vec<Vec<Vec3>>,
        convex: bool,
        flat: usize,
    ) -> Profile {
        let z_top = levels.last().map(|l| l.z).unwrap_or(0.0);
        let ro = &cutter.runout;
        let dev_max = ro
            .tooth_radius_dev_mm
            .iter()
            .fold(0.0f64, |m, d| m.max(d.abs()));
        let mut runout_bound =
            ro.offset_mm.abs() + z_top * ro.tilt_rad.tan().abs() + dev_max + 1e-9;
        let axial_max = ro
            .tooth_axial_dev_mm
            .iter()
            .fold(0.0f64, |m, d| m.max(d.abs()));
        if axial_max > 0.0 {
            runout_bound += axial_max;
        }
        let mut reach = Vec::with_capacity(levels.len());
        let mut top = 0.0f64;
        for l in &levels {
            top = top.max((l.r * l.r + l.z * l.z).sqrt());
            reach.push(top);
        }
        Profile {
            levels,
            edge,
            body,
            runout_bound,
            reach,
            convex,
            flat,
        }
    }
}

/// The engine's candidate levels for levels along a meridian that is not convex: every level is
/// tested, the range runs from the first to the last within `lim` (one more each side).
pub(crate) fn scan_candidates(
    f: &dyn Fn(usize) -> f64,
    n: usize,
    lim: f64,
) -> Option<(usize, usize)> {
    let lo = (0..n).find(|&i| f(i) <= lim)?;
    let hi = (0..n).rev().find(|&i| f(i) <= lim)?;
    Some((lo.saturating_sub(1), (hi + 1).min(n - 1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::tool::Runout;
    use approx::assert_relative_eq;

    #[test]
    fn dome_levels_are_the_kept_ones() {
        let shape = Shape::Torus {
            corner_radius_mm: 5.0,
        };
        let cutter = Cutter::new(shape, 16.0, 2, 30f64.to_radians());
        let p = Profile::new(&cutter, 1e-3, 16.0).unwrap();
        assert!(p.flat > 3);
        let n = p.body[0].len();
        for lo in 0..n {
            for hi in lo..n {
                let want: Vec<usize> = (lo..=hi).filter(|i| p.dome_keeps(*i, lo, hi)).collect();
                assert_eq!(
                    p.dome_levels(lo, hi).collect::<Vec<_>>(),
                    want,
                    "{lo}..={hi}"
                );
            }
        }
    }

    #[test]
    fn rotated_angle_zero_point_is_the_edge_point() {
        let mut c = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        c.runout = Runout {
            offset_mm: 0.01,
            offset_phase_rad: 0.3,
            tilt_rad: 0.001,
            tilt_phase_rad: 1.0,
            tooth_radius_dev_mm: vec![0.0, -0.01, 0.002, 0.0],
            ..Default::default()
        };
        let p = Profile::new(&c, 1e-4, 0.5).unwrap();
        let theta: f64 = 1.234;
        let (s, co) = theta.sin_cos();
        for j in 0..4 {
            for (i, l) in p.levels.iter().enumerate().step_by(7) {
                let e = p.edge[j][i];
                let rot = Vec3::new(e.x * co + e.y * s, -e.x * s + e.y * co, e.z);
                let want = c.edge_point(j, l.z, theta);
                assert_relative_eq!(rot, want, epsilon = 1e-12);
            }
        }
    }

    #[test]
    fn torus_levels_follow_the_profile() {
        let c = Cutter::new(
            Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            1,
            0.0,
        );
        let p = Profile::new(&c, 1e-5, 0.2).unwrap();
        for l in &p.levels {
            if l.r <= 5.0 - 1e-12 {
                assert_relative_eq!(c.profile_height(l.r).unwrap(), l.z, epsilon = 1e-9);
            }
        }
        assert_relative_eq!(p.levels.last().unwrap().r, 5.0);
    }
}
