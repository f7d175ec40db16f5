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

#[cfg(test)]
mod tests {
    use super::lowest;
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
}
