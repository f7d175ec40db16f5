//! Closed-form bounds of the dome model's revolved body, so that the engine need not mesh a
//! strip to know where it can matter: the node-space box of a strip (for binning it into
//! tiles) and, for one tile, the angles and levels of the strip that can come below the
//! tile's cull height. Both are conservative (a little wider than the mesh), so they change
//! which triangles are looked at, never the lowest height a node keeps.
//!
//! A body point (0, r, z) of the tool frame turned by the spindle angle θ lands at
//! `b + M (r sin θ, r cos θ, z)`: each coordinate is `b_k + M_k2 z + r (M_k0 sin θ + M_k1 cos θ)`,
//! a sinusoid in θ whose bounds over an interval of angles are known.

use crate::math::Vec3;
use nalgebra::Matrix3;
use std::f64::consts::{PI, TAU};

/// Slack of the bounds for the rounding of the mesh's own evaluation (node units or mm).
const SLACK_ABS: f64 = 1e-6;
const SLACK_REL: f64 = 1e-9;

/// Bounds of cos(θ − ψ) for θ in [t0, t1] (t1 − t0 < 2π).
fn cos_range(t0: f64, t1: f64, psi: f64) -> (f64, f64) {
    let (c0, c1) = ((t0 - psi).cos(), (t1 - psi).cos());
    let (mut lo, mut hi) = (c0.min(c1), c0.max(c1));
    // Does [t0, t1] hold ψ + 2πj (a maximum) or ψ + π + 2πj (a minimum)?
    let holds = |at: f64| {
        let j = ((t0 - at) / TAU).ceil();
        at + j * TAU <= t1
    };
    if holds(psi) {
        hi = 1.0;
    }
    if holds(psi + PI) {
        lo = -1.0;
    }
    (lo, hi)
}

/// The node-space box (X0, Y0, X1, Y1) holding every point `b + M rot(θ) e` of the body
/// points `body` (each (0, r, z)) for the spindle angles θ in [t0, t1]: a box at least as
/// large as the one of the meshed points at the angles of the mesh within that interval.
#[cfg(test)]
pub(crate) fn dome_box(m: &Matrix3<f64>, b: &Vec3, body: &[Vec3], t0: f64, t1: f64) -> [f64; 4] {
    DomeSweep::new(m, b, body).dome_box(t0, t1)
}

/// One pose's revolved body points, for the boxes of many angle intervals ([`dome_box`]):
/// what does not depend on the interval is worked out once.
pub(crate) struct DomeSweep<'a> {
    m: &'a Matrix3<f64>,
    b: &'a Vec3,
    body: &'a [Vec3],
    /// Per coordinate X, Y: the amplitude and phase of `a sin θ + c cos θ = amp cos(θ − ψ)`.
    wave: [(f64, f64); 2],
}

impl<'a> DomeSweep<'a> {
    pub(crate) fn new(m: &'a Matrix3<f64>, b: &'a Vec3, body: &'a [Vec3]) -> DomeSweep<'a> {
        let wave = [0, 1].map(|k| {
            let (a, c) = (m[(k, 0)], m[(k, 1)]);
            (a.hypot(c), a.atan2(c))
        });
        DomeSweep { m, b, body, wave }
    }

    /// [`dome_box`] of angles [t0, t1].
    pub(crate) fn dome_box(&self, t0: f64, t1: f64) -> [f64; 4] {
        let (m, b) = (self.m, self.b);
        let mut bb = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for k in 0..2 {
            let (amp, psi) = self.wave[k];
            let (lo, hi) = cos_range(t0, t1, psi);
            for e in self.body {
                let centre = b[k] + m[(k, 2)] * e.z;
                let r = e.y.max(0.0) * amp;
                bb[k] = bb[k].min(centre + r * lo);
                bb[k + 2] = bb[k + 2].max(centre + r * hi);
            }
        }
        for k in 0..2 {
            bb[k] -= SLACK_ABS + SLACK_REL * bb[k].abs();
            bb[k + 2] += SLACK_ABS + SLACK_REL * bb[k + 2].abs();
        }
        bb
    }
}

/// Of a dome strip (mesh angles `a..=b` of `step`, body points `body`, pose `m`, `bz`), the
/// angles and the levels (indices into `body`) of the quads that have a corner at or below
/// `cull`: every other quad's triangles lie wholly above `cull`, which the rasteriser skips
/// anyway. `None` when no corner is that low. The first `face` points of `body` lie on the
/// end face with the one after them, at growing radii (0 when there are none). Corners are
/// judged from the closed form with a slack for rounding, so the ranges hold every quad the
/// mesh would find low.
pub(crate) fn dome_low(
    m: &Matrix3<f64>,
    bz: f64,
    body: &[Vec3],
    (a, b): (i64, i64),
    step: f64,
    cull: f64,
    face: usize,
) -> Option<((i64, i64), (usize, usize))> {
    let (ma, mb) = (m[(2, 0)], m[(2, 1)]);
    let amp = ma.hypot(mb);
    let m22 = m[(2, 2)];
    // W(θ) = c + r amp cos(θ − ψ) with ψ = atan2(ma, mb); lowest at θ = ψ + π.
    let lowest = ma.atan2(mb) + PI;
    let cull = cull + SLACK_ABS + SLACK_REL * cull.abs();
    let mut levels: Option<(usize, usize)> = None;
    let mut half = -1.0f64;
    for (i, e) in body.iter().enumerate() {
        let c = bz + e.z * m22;
        let ra = e.y.max(0.0) * amp;
        if c - ra > cull {
            continue;
        }
        // Levels `0..face` share `c` with level `face` and their radii grow: those below
        // the cull form a run whose half-widths lie between its ends' (the first, and the
        // rim or the last level), so only the ends need one.
        let inner = levels.is_some() && i < face && i + 1 < body.len();
        levels = Some(levels.map_or((i, i), |(lo, _)| (lo, i)));
        if inner {
            continue;
        }
        let h = if c + ra <= cull || ra < 1e-12 {
            PI
        } else {
            ((c - cull) / ra).clamp(-1.0, 1.0).acos()
        };
        half = half.max(h);
    }
    let (l0, l1) = levels?;
    let half = half + 1e-6;
    let mut cols: Option<(i64, i64)> = None;
    for k in a..=b {
        let d = (k as f64 * step - lowest).rem_euclid(TAU);
        if d.min(TAU - d) <= half {
            cols = Some(cols.map_or((k, k), |(lo, _)| (lo, k)));
        }
    }
    let (c0, c1) = cols?;
    Some((
        ((c0 - 1).max(a), (c1 + 1).min(b)),
        (l0.saturating_sub(1), (l1 + 1).min(body.len() - 1)),
    ))
}

/// The node-space (X, Y) of the lowest point of the revolved body points `body` (each
/// (0, r, z)) at pose `m`, `b`: where the body touches first (a key to order strips by).
pub(crate) fn lowest_xy(m: &Matrix3<f64>, b: &Vec3, body: &[Vec3]) -> [f64; 2] {
    let (ma, mb) = (m[(2, 0)], m[(2, 1)]);
    let amp = ma.hypot(mb);
    let t = ma.atan2(mb) + PI;
    let (s, c) = t.sin_cos();
    let mut best = (f64::INFINITY, [b.x, b.y]);
    for e in body {
        let w = b.z + e.z * m[(2, 2)] - e.y.max(0.0) * amp;
        if w < best.0 {
            let at = |k: usize| b[k] + m[(k, 2)] * e.z + e.y * (m[(k, 0)] * s + m[(k, 1)] * c);
            best = (w, [at(0), at(1)]);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose() -> (Matrix3<f64>, Vec3) {
        let m = Matrix3::new(40.0, 3.0, -5.0, -2.0, 38.0, 7.0, 0.2, -0.15, 0.97);
        (m, Vec3::new(12.0, -30.0, 0.4))
    }

    fn body() -> Vec<Vec3> {
        (0..40)
            .map(|i| {
                let a = i as f64 * 0.04;
                Vec3::new(0.0, 1.0 + 5.0 * a.sin(), 5.0 - 5.0 * a.cos())
            })
            .collect()
    }

    fn point(m: &Matrix3<f64>, b: &Vec3, e: &Vec3, t: f64) -> Vec3 {
        let (s, c) = t.sin_cos();
        b + m * Vec3::new(e.y * s, e.y * c, e.z)
    }

    #[test]
    fn the_box_holds_every_meshed_point() {
        let (m, b) = pose();
        let body = body();
        let step = TAU / 284.0;
        for (a, z) in [(-40i64, -8i64), (0, 32), (250, 282), (100, 132), (-3, 29)] {
            let bb = dome_box(&m, &b, &body, a as f64 * step, z as f64 * step);
            for k in a..=z {
                for e in &body {
                    let p = point(&m, &b, e, k as f64 * step);
                    assert!(p.x >= bb[0] && p.y >= bb[1] && p.x <= bb[2] && p.y <= bb[3]);
                }
            }
        }
    }

    /// [`body`] behind an end face: 12 points at its height, radii 0 to 1.
    fn faced() -> (Vec<Vec3>, usize) {
        let tail = body();
        let mut face: Vec<Vec3> = (0..12)
            .map(|i| Vec3::new(0.0, i as f64 / 12.0, tail[0].z))
            .collect();
        let n = face.len();
        face.extend(tail);
        (face, n)
    }

    #[test]
    fn every_low_corner_is_in_the_low_ranges() {
        let (m, b) = pose();
        let step = TAU / 284.0;
        let (with_face, n) = faced();
        let bodies = [
            (body(), 0),
            (with_face.clone(), n),
            // A strip that starts inside the end face, and one that ends there.
            (with_face[5..].to_vec(), n - 5),
            (with_face[..8].to_vec(), 8),
        ];
        for (body, face) in bodies {
            low_corners_in_the_low_ranges(&m, &b, &body, face, step);
        }
    }

    fn low_corners_in_the_low_ranges(
        m: &Matrix3<f64>,
        b: &Vec3,
        body: &[Vec3],
        face: usize,
        step: f64,
    ) {
        let (m, b) = (*m, *b);
        for cull in [0.3, 0.4, 0.6, 1.0, 3.0] {
            for (a, z) in [(-40i64, -8i64), (0, 32), (250, 282), (100, 132), (-3, 29)] {
                let got = dome_low(&m, b.z, body, (a, z), step, cull, face);
                for k in a..=z {
                    for (i, e) in body.iter().enumerate() {
                        if point(&m, &b, e, k as f64 * step).z <= cull {
                            let ((c0, c1), (l0, l1)) = got.expect("a low corner");
                            assert!((c0..=c1).contains(&k) && (l0..=l1).contains(&i));
                            assert!(c0 < k || c0 == a);
                            assert!(k < c1 || c1 == z);
                        }
                    }
                }
            }
        }
    }
}
