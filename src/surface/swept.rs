//! The swept model's one formula: the lowest point, over a node, of a ball of radius R whose
//! centre moves straight from c0 to c1 (the lower envelope of a capsule), in closed form.
//!
//! Over the node at (x, y) the ball's surface is at z(t) = w(t) − √(R² − q(t)), with the
//! centre (u(t), v(t), w(t)) = c0 + t (c1 − c0) and q(t) its squared horizontal distance to
//! the node. q is a convex quadratic and −√(R² − q) a convex increasing function of it, so
//! z is convex in t on the interval where q ≤ R²: its minimum on [0, 1] is the stationary
//! point clamped to that interval. Setting z'(t) = 0, with e the horizontal step, E = |e|²,
//! r = node − c0 (horizontal), m = e·r and b the vertical step: (E t − m)² = b² (R² − q(t)),
//! a quadratic in t whose root on the side where E t − m has the sign of −b is the minimum.
//! The engine sweeps the ball along straight stretches of samples ([`straight_stretches`])
//! and lowers its tiles with [`lower_tile`].

use super::raster::Tile;
use crate::math::Vec3;

/// The lowest height of the swept ball over the node `p` = (x, y), or `None` when the ball
/// never covers the node (its centre stays farther than R horizontally). `c0`, `c1`: the
/// centre at both ends (x, y, z), all in mm.
pub(crate) fn lowest(c0: [f64; 3], c1: [f64; 3], p: (f64, f64), r: f64) -> Option<f64> {
    let (ex, ey, b) = (c1[0] - c0[0], c1[1] - c0[1], c1[2] - c0[2]);
    let (rx, ry) = (p.0 - c0[0], p.1 - c0[1]);
    let e2 = ex * ex + ey * ey;
    let m = ex * rx + ey * ry;
    let r2 = rx * rx + ry * ry;
    let rr = r * r;
    let at = |t: f64| {
        let q = e2 * t * t - 2.0 * m * t + r2;
        (q <= rr).then(|| c0[2] + b * t - (rr - q).max(0.0).sqrt())
    };
    if e2 <= 1e-24 * rr.max(1e-300) {
        // A vertical (or no) move: the lower end of the two.
        return if b > 0.0 { at(0.0) } else { at(1.0) };
    }
    // Where the ball covers the node: q(t) ≤ R², t in [ta, tb].
    let disc = m * m - e2 * (r2 - rr);
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let (ta, tb) = ((m - s) / e2, (m + s) / e2);
    let (lo, hi) = (ta.max(0.0), tb.min(1.0));
    if lo > hi {
        return None;
    }
    // The stationary point: E t − m = −b √(R² − q) / … squared gives
    // E (E + b²) t² − 2 m (E + b²) t + m² + b² (|r|² − R²) = 0.
    let k = e2 + b * b;
    let c = (m * m + b * b * (r2 - rr)) / k;
    let d = (m * m - e2 * c).max(0.0).sqrt();
    let t = if b > 0.0 { (m - d) / e2 } else { (m + d) / e2 };
    at(t.clamp(lo, hi))
}

/// The swept model's plan of `samples` for a ball of radius `r_mm`: the ball centres in
/// node space (`g` the grid rows scaled to nodes of `d` mm, `shift` node (0, 0)'s offset; i,
/// j in nodes, w in mm) and their [`straight_stretches`].
pub(crate) fn plan(
    samples: &[crate::resample::Sample],
    r_mm: f64,
    g: &nalgebra::Matrix3<f64>,
    frame: &super::GridFrame,
    shift: Vec3,
    d: f64,
) -> (Vec<Vec3>, Vec<u32>) {
    let centres: Vec<Vec3> = samples
        .iter()
        .map(|a| g * (a.position + a.axis.normalize() * r_mm - frame.origin) - shift)
        .collect();
    let runs: Vec<usize> = samples.iter().map(|s| s.run).collect();
    let end = straight_stretches(&centres, &runs, d);
    (centres, end)
}

/// Lower `tile` to the ball of radius `r` mm swept from centre `c0` to `c1` (node space: x,
/// y in nodes of `d` mm, z in mm) at the nodes where it can come below `cull`.
pub(crate) fn lower_tile(tile: &mut Tile, c0: Vec3, c1: Vec3, r: f64, d: f64, cull: f64) {
    // Horizontal reach of the ball's cap below `cull`, nodes (+1 for rounding).
    let h = cull - (c0.z.min(c1.z) - r);
    if h < 0.0 {
        return;
    }
    let reach = if h >= r {
        r
    } else {
        (h * (2.0 * r - h)).sqrt()
    } / d
        + 1.0;
    let lo_i = (c0.x.min(c1.x) - reach).floor().max(tile.i0 as f64) as usize;
    let lo_j = (c0.y.min(c1.y) - reach).floor().max(tile.j0 as f64) as usize;
    let hi_i = (c0.x.max(c1.x) + reach)
        .ceil()
        .min((tile.i0 + tile.w) as f64 - 1.0);
    let hi_j = (c0.y.max(c1.y) + reach)
        .ceil()
        .min((tile.j0 + tile.h) as f64 - 1.0);
    if hi_i < lo_i as f64 || hi_j < lo_j as f64 {
        return;
    }
    let to_mm = |c: Vec3| [c.x * d, c.y * d, c.z];
    let (a, b) = (to_mm(c0), to_mm(c1));
    for j in lo_j..=hi_j as usize {
        for i in lo_i..=hi_i as usize {
            if let Some(z) = lowest(a, b, (i as f64 * d, j as f64 * d), r) {
                let cell = &mut tile.z[(j - tile.j0) * tile.w + (i - tile.i0)];
                if z < *cell {
                    *cell = z;
                }
            }
        }
    }
}

/// Most moves (sample to sample) in one straight stretch of the swept model (bounds the work of finding
/// them).
const STRETCH_MAX: usize = 512;

/// Largest distance of a ball centre from the straight stretch that replaces it, mm: the
/// heights move by at most this much.
const STRETCH_TOL_MM: f64 = 1e-7;

/// The swept model's straight stretches: for each sample, the last sample of the stretch
/// that starts there, `u32::MAX` for samples inside one. A stretch follows its run while
/// every ball centre it passes lies within [`STRETCH_TOL_MM`] of the chord from its first
/// to its last centre (and forward along it), at most [`STRETCH_MAX`] moves; the ball
/// swept along the chord then covers what the samples' moves cover. `centres` in node
/// space (x, y in nodes of `d` mm, z in mm).
pub(crate) fn straight_stretches(centres: &[Vec3], runs: &[usize], d: f64) -> Vec<u32> {
    let mm = |c: &Vec3| Vec3::new(c.x * d, c.y * d, c.z);
    let n = centres.len();
    let mut end = vec![u32::MAX; n];
    let mut k = 0;
    while k < n {
        let a = mm(&centres[k]);
        let mut m = k;
        while m + 1 < n && runs[m + 1] == runs[k] && m + 1 - k <= STRETCH_MAX {
            let b = mm(&centres[m + 1]);
            let chord = b - a;
            let len = chord.norm();
            let ok = len > 0.0
                && (k + 1..=m).all(|i| {
                    let p = mm(&centres[i]) - a;
                    let t = p.dot(&chord) / len;
                    t >= -STRETCH_TOL_MM
                        && t <= len + STRETCH_TOL_MM
                        && (p - chord * (t / len)).norm() <= STRETCH_TOL_MM
                });
            if !ok {
                break;
            }
            m += 1;
        }
        end[k] = m as u32;
        // The next stretch starts where this one ends, unless the run ended here.
        k = if m > k && m + 1 < n && runs[m + 1] == runs[m] {
            m
        } else {
            m + 1
        };
    }
    end
}

#[cfg(test)]
mod tests {
    use super::{STRETCH_MAX, lowest, straight_stretches};
    use crate::math::Vec3;
    use proptest::prelude::*;

    /// The minimum over a fine sampling of t (the reference the closed form must meet).
    fn brute(c0: [f64; 3], c1: [f64; 3], p: (f64, f64), r: f64) -> Option<f64> {
        let n = 200_000;
        (0..=n)
            .filter_map(|i| {
                let t = i as f64 / n as f64;
                let c = [
                    c0[0] + (c1[0] - c0[0]) * t,
                    c0[1] + (c1[1] - c0[1]) * t,
                    c0[2] + (c1[2] - c0[2]) * t,
                ];
                let q = (p.0 - c[0]).powi(2) + (p.1 - c[1]).powi(2);
                (q <= r * r).then(|| c[2] - (r * r - q).sqrt())
            })
            .reduce(f64::min)
    }

    #[test]
    fn horizontal_pass_gives_the_ball_section() {
        // A pass along x at height R: over a node at distance y the ball is R − √(R² − y²).
        let r = 3.0;
        for y in [0.0, 0.1, 0.25, 1.0, 2.9] {
            let z = lowest([0.0, 0.0, r], [10.0, 0.0, r], (5.0, y), r).unwrap();
            let want = r - (r * r - y * y).sqrt();
            assert!((z - want).abs() < 1e-12, "y {y}: {z} vs {want}");
        }
        assert_eq!(lowest([0.0, 0.0, r], [10.0, 0.0, r], (5.0, 3.1), r), None);
        // Beyond the end: the end ball.
        let z = lowest([0.0, 0.0, r], [10.0, 0.0, r], (10.5, 0.0), r).unwrap();
        assert!((z - (r - (r * r - 0.25f64).sqrt())).abs() < 1e-12);
    }

    #[test]
    fn vertical_move_is_its_lower_end() {
        let z = lowest([1.0, 1.0, 5.0], [1.0, 1.0, 2.0], (1.5, 1.0), 1.0).unwrap();
        assert!((z - (2.0 - 0.75f64.sqrt())).abs() < 1e-12);
    }

    proptest! {
        #[test]
        fn closed_form_is_the_minimum_over_the_move(
            x0 in -2.0..2.0f64, y0 in -2.0..2.0f64, z0 in -1.0..1.0f64,
            x1 in -2.0..2.0f64, y1 in -2.0..2.0f64, z1 in -1.0..1.0f64,
            px in -3.0..3.0f64, py in -3.0..3.0f64, r in 0.2..3.0f64,
        ) {
            let (c0, c1) = ([x0, y0, z0], [x1, y1, z1]);
            let got = lowest(c0, c1, (px, py), r);
            let want = brute(c0, c1, (px, py), r);
            match (got, want) {
                (Some(g), Some(w)) => {
                    // The sampling misses the true minimum by at most the curve's change
                    // over one step (and finds nothing where the ball only grazes).
                    prop_assert!(g <= w + 1e-9, "closed form {g} above sampled {w}");
                    prop_assert!(w - g < 1e-3 * r, "closed form {g} far below sampled {w}");
                }
                (None, Some(w)) => prop_assert!(false, "missed a covered node ({w})"),
                (Some(g), None) => {
                    // Covered only between samples: at the very rim.
                    let rim = [z0, z1].iter().cloned().fold(f64::INFINITY, f64::min) - 1e-6;
                    prop_assert!(g >= rim - r, "{g}");
                }
                (None, None) => {}
            }
        }
    }

    #[test]
    fn straight_stretches_follow_lines_and_break_at_corners_runs_and_curves() {
        // Two runs: a line of 1200 samples with a corner after 700, then a circle arc.
        let d = 0.01;
        let mut c = Vec::new();
        let mut runs = Vec::new();
        for i in 0..700 {
            c.push(Vec3::new(i as f64 * 0.5, 0.0, 3.0)); // node space: 0.005 mm steps
            runs.push(0);
        }
        for i in 1..=500 {
            c.push(Vec3::new(699.0 * 0.5, i as f64 * 0.5, 3.0));
            runs.push(0);
        }
        for i in 0..100 {
            let a = i as f64 * 0.01; // R 5 mm = 500 nodes, 0.05 mm steps
            c.push(Vec3::new(500.0 * a.cos(), 500.0 * a.sin(), 3.0));
            runs.push(1);
        }
        let end = straight_stretches(&c, &runs, d);
        let starts: Vec<(usize, u32)> = end
            .iter()
            .enumerate()
            .filter(|(_, e)| **e != u32::MAX)
            .map(|(k, e)| (k, *e))
            .collect();
        // The first leg in stretches of at most STRETCH_MAX moves, ending at the corner.
        assert_eq!(starts[0], (0, STRETCH_MAX as u32));
        assert_eq!(starts[1], (STRETCH_MAX, 699));
        assert_eq!(starts[2], (699, 1199));
        // Consecutive stretches share their ends; the arc's sagitta over one 0.05 mm step
        // already exceeds the tolerance, so each of its moves is its own stretch, and the
        // second run starts afresh.
        for w in starts.windows(2) {
            if runs[w[1].0] == runs[w[0].0] {
                assert_eq!(w[0].1 as usize, w[1].0);
            }
        }
        let arc: Vec<_> = starts.iter().filter(|(k, _)| *k >= 1200).collect();
        assert_eq!(arc.len(), 99);
        assert!(arc.iter().all(|(k, e)| *e as usize == k + 1 || *k == 1299));
        assert!(starts.iter().all(|(k, e)| *e as usize >= *k));
    }
}
