//! One cycle of constant jerk: the state after it, the interior speed peak, the instant
//! a position is crossed, the discrete peak speed ahead and the largest jerk that keeps it
//! under a cap.

use super::root::solve_monotone;

/// The interior maximum of the speed during a cycle of jerk j from (v, a) when the
/// acceleration turns from positive to negative inside it: (time, speed).
pub(super) fn interior_peak(v: f64, a: f64, j: f64, t: f64) -> Option<(f64, f64)> {
    (a > 0.0 && a + j * t < 0.0).then(|| (-a / j, v - a * a / (2.0 * j)))
}

/// One cycle of constant jerk from (v, a): (Δs, v', a') after time τ.
pub(super) fn step(v: f64, a: f64, j: f64, tau: f64) -> (f64, f64, f64) {
    (
        v * tau + a * tau * tau / 2.0 + j * tau.powi(3) / 6.0,
        v + a * tau + j * tau * tau / 2.0,
        a + j * tau,
    )
}

/// Time τ in [0, T] at which a constant-jerk step from (v, a) has advanced by x.
pub(super) fn crossing_time(v: f64, a: f64, j: f64, t: f64, x: f64) -> f64 {
    // First guess: at the start speed (exact for a constant speed).
    solve_monotone(0.0, t, if v > 0.0 { x / v } else { 0.5 * t }, x, |tau| {
        let (ds, vs, _) = step(v, a, j, tau);
        (ds, vs)
    })
}

/// Highest speed reached from (v, a > 0) when the acceleration is ramped down at −J in
/// whole cycles of length T, the last one with the jerk −a/T that ends at a = 0. It is the
/// discrete counterpart of v + a²/(2J), never lower, so that a greedy interpolator can
/// settle exactly on a speed cap instead of oscillating around it.
pub(super) fn peak_discrete(v: f64, a: f64, jm: f64, t: f64) -> f64 {
    if a <= 0.0 {
        return v;
    }
    let n = (a / (jm * t)).floor();
    let r = a - n * jm * t;
    v + n * n * jm * t * t / 2.0 + n * r * t + r * t / 2.0
}

/// Largest jerk j in [j_lo, j_hi] such that, after one cycle, the discrete peak speed is
/// ≤ vcap (`NEG_INFINITY` if none).
pub(super) fn jerk_cap(v: f64, a: f64, t: f64, jm: f64, vcap: f64, j_lo: f64, j_hi: f64) -> f64 {
    let ok = |j: f64| {
        let (_, v1, a1) = step(v, a, j, t);
        peak_discrete(v1, a1, jm, t) <= vcap
    };
    if ok(j_hi) {
        return j_hi;
    }
    if !ok(j_lo) {
        return f64::NEG_INFINITY;
    }
    // Closed form: with u = a' = a + jT > 0 the discrete peak is piecewise linear in u, with
    // slope T(n + 1) on [n·jm·T, (n + 1)·jm·T); for a' ≤ 0 it is v' itself, linear in j. The
    // answer is accepted when it passes and a step of the search's resolution above it does
    // not; rounding aside it always is, and the search below is the fallback.
    let tol = (j_hi - j_lo) * f64::EPSILON * 4.0;
    let j_closed = {
        let q = jm * t;
        let v_at_zero = v + a * t / 2.0; // a' = 0
        if v_at_zero > vcap {
            2.0 * (vcap - v - a * t) / (t * t)
        } else {
            let n = (-1.0 + (1.0 - 8.0 * (v_at_zero - vcap) / (q * t)).max(0.0).sqrt()) / 2.0;
            let n = n.floor().max(0.0);
            let p_n = v_at_zero + n * q * t / 2.0 + n * n * q * t / 2.0;
            let u = n * q + (vcap - p_n) / (t * (n + 1.0));
            (u - a) / t
        }
    };
    let mut jc = j_closed.clamp(j_lo, j_hi);
    for _ in 0..4 {
        if !jc.is_finite() || ok(jc) {
            break;
        }
        jc -= tol;
    }
    // Newton steps up on the rounding residual (slope of the peak in j: T² (n + 1)), so
    // that the answer is the largest passing jerk to the last bits, as the search finds.
    for _ in 0..3 {
        let (_, v1, a1) = step(v, a, jc, t);
        let r = vcap - peak_discrete(v1, a1, jm, t);
        if r.is_nan() || r <= 0.0 {
            break;
        }
        let n = if a1 > 0.0 {
            (a1 / (jm * t)).floor()
        } else {
            0.0
        };
        let slope = if a1 > 0.0 {
            t * t * (n + 1.0)
        } else {
            t * t / 2.0
        };
        let jn = (jc + r / slope).min(j_hi);
        if jn > jc && ok(jn) {
            jc = jn;
        } else {
            break;
        }
    }
    // Above the boundary by 2⁻³⁶ of the range (a speed change of about 1e-11 mm/s, well
    // above the rounding of the peak) must fail.
    let above = jc + (j_hi - j_lo) * 0.5f64.powi(36);
    if jc.is_finite() && jc >= j_lo && ok(jc) && (above > j_hi || !ok(above)) {
        return jc;
    }

    // The peak is continuous and increasing in j: Illinois false position on
    // f(j) = peak − vcap, with a bisection step whenever the bracket fails to halve, down to
    // a bracket of 2⁻⁵⁰ of the range (the 60-step bisection this replaces stopped at 2⁻⁶⁰:
    // the difference in speed after a cycle is below 1e-15 mm/s).
    let f = |j: f64| {
        let (_, v1, a1) = step(v, a, j, t);
        peak_discrete(v1, a1, jm, t) - vcap
    };
    let (mut lo, mut hi) = (j_lo, j_hi);
    let (mut flo, mut fhi) = (f(lo), f(hi));
    let mut width = hi - lo;
    let mut side = 0i32;
    for _ in 0..120 {
        if hi - lo <= tol {
            break;
        }
        let mut mid = if fhi > flo {
            (lo * fhi - hi * flo) / (fhi - flo)
        } else {
            f64::NAN
        };
        if !(mid > lo && mid < hi) {
            mid = 0.5 * (lo + hi);
        }
        let fm = f(mid);
        if fm <= 0.0 {
            lo = mid;
            flo = fm;
            if side == -1 {
                fhi *= 0.5;
            }
            side = -1;
        } else {
            hi = mid;
            fhi = fm;
            if side == 1 {
                flo *= 0.5;
            }
            side = 1;
        }
        if hi - lo > 0.5 * width {
            // Slow progress: force a bisection step.
            let m = 0.5 * (lo + hi);
            if m > lo && m < hi {
                let fm = f(m);
                if fm <= 0.0 {
                    lo = m;
                    flo = fm;
                } else {
                    hi = m;
                    fhi = fm;
                }
            }
        }
        width = hi - lo;
    }
    lo
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn jerk_cap_hits_the_cap() {
        let (t, jm, vcap) = (0.003, 40000.0, 83.0);
        for &(v, a) in &[(82.8, 0.0), (82.0, 200.0), (82.95, -30.0)] {
            let j = jerk_cap(v, a, t, jm, vcap, -jm, jm);
            let (_, v1, a1) = step(v, a, j, t);
            assert_relative_eq!(peak_discrete(v1, a1, jm, t), vcap, max_relative = 1e-9);
        }
    }

    #[test]
    fn discrete_peak_bounds_the_continuous_one() {
        let (t, jm) = (0.003, 40000.0);
        for &a in &[0.0, 10.0, 120.0, 121.0, 1000.0, 4999.0] {
            let d = peak_discrete(50.0, a, jm, t);
            assert!(d >= 50.0 + a * a / (2.0 * jm) - 1e-12);
            assert!(d <= 50.0 + a * a / (2.0 * jm) + a * t / 2.0 + 1e-12);
        }
    }
}
