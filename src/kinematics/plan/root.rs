//! Root finders of the planner: a safeguarded Newton iteration for monotone positions
//! and Brent's method for the boundary jerk.

/// Root of `pos(t) = x` on `[lo, hi]` for a non-decreasing position with derivative `vel`
/// (`f(t)` returns both), from a first guess: safeguarded Newton, falling back to bisection
/// when a step leaves the bracket. Converges to the last few ULP; the same answer as a
/// 60-step bisection in a few evaluations.
#[inline]
pub(super) fn solve_monotone(
    mut lo: f64,
    mut hi: f64,
    guess: f64,
    x: f64,
    f: impl Fn(f64) -> (f64, f64),
) -> f64 {
    if hi <= lo {
        return lo;
    }
    let mut t = if guess > lo && guess < hi {
        guess
    } else {
        0.5 * (lo + hi)
    };
    for _ in 0..100 {
        let (p, v) = f(t);
        if p < x {
            lo = t;
        } else {
            hi = t;
        }
        let mut tn = if v > 0.0 { t - (p - x) / v } else { f64::NAN };
        // Converged: the Newton step is at the rounding level (checked before the bracket
        // safeguard, which would otherwise answer a step onto the bracket's end with a
        // bisection step away from the root).
        if (tn - t).abs() <= 2.0 * f64::EPSILON * t.abs() {
            return tn.clamp(lo, hi);
        }
        if !(tn > lo && tn < hi) {
            tn = 0.5 * (lo + hi);
        }
        if hi - lo <= 4.0 * f64::EPSILON * hi {
            return tn;
        }
        t = tn;
    }
    0.5 * (lo + hi)
}

/// Brent's method (zeroin: inverse quadratic interpolation, secant and bisection steps)
/// for a root of f on a bracket with f(g) ≥ 0 > f(b). Returns the end of the final
/// bracket where f ≥ 0; the bracket is then at most `tol` wide.
pub(super) fn brent(
    g: f64,
    fg: f64,
    b: f64,
    fb: f64,
    tol: f64,
    mut f: impl FnMut(f64) -> f64,
) -> f64 {
    // b: best estimate, a: previous, c: the other end of the bracket.
    let (mut a, mut fa, mut b, mut fb) = (g, fg, b, fb);
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    for _ in 0..100 {
        if (fb >= 0.0) == (fc >= 0.0) {
            (c, fc) = (a, fa);
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            (a, fa) = (b, fb);
            (b, fb) = (c, fc);
            (c, fc) = (a, fa);
        }
        let tol1 = 2.0 * f64::EPSILON * b.abs() + 0.25 * tol;
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol1 || fb == 0.0 {
            break;
        }
        if e.abs() >= tol1 && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * xm * q - (tol1 * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        (a, fa) = (b, fb);
        b += if d.abs() > tol1 { d } else { tol1.copysign(xm) };
        fb = f(b);
    }
    if fb >= 0.0 { b } else { c }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brent_closes_the_bracket_on_the_passing_side() {
        // f(j) = 2 − j (root 2) and a kinked one; the answer passes and lies within tol.
        for f in [(|j: f64| 2.0 - j) as fn(f64) -> f64, |j: f64| {
            if j < 2.0 {
                (2.0 - j).powi(3)
            } else {
                -(j - 2.0).sqrt()
            }
        }] {
            let r = brent(-5.0, f(-5.0), 7.0, f(7.0), 1e-9, f);
            assert!(f(r) >= 0.0 && (r - 2.0).abs() <= 1e-9, "{r}");
        }
    }
}
