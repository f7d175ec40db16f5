//! The closed-form stop profiles of the planner: the three-phase full stop (and brake to
//! a speed) with its crossings of a ceiling, and the rest-to-rest move built from it.

use super::REL;
use super::root::solve_monotone;

/// The three-phase braking profile from (v, a) with limits A, J: jerk −J until the
/// acceleration is −a_p, hold, then +J back to zero acceleration (§6.3 "full stop").
/// With a speed offset it is also the brake-to-c profile of `brake_dist`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Stop {
    v0: f64,
    a0: f64,
    /// The limits the profile was built with: A and J.
    pub(super) amax: f64,
    pub(super) j: f64,
    pub(super) ap: f64,
    t1: f64,
    t2: f64,
    t3: f64,
}

impl Stop {
    /// The profile, or `None` when the speed would reach zero before the deceleration is
    /// released (the state cannot stop without reversing).
    pub(super) fn new(v: f64, a: f64, amax: f64, jmax: f64) -> Option<Stop> {
        let d = v + a * a / (2.0 * jmax);
        if a < 0.0 && a * a / (2.0 * jmax) > v * (1.0 + 1e-9) + 1e-15 {
            return None;
        }
        if d <= 0.0 {
            return Some(Stop {
                v0: v,
                a0: a,
                amax,
                j: jmax,
                ap: 0.0,
                t1: 0.0,
                t2: 0.0,
                t3: 0.0,
            });
        }
        let ap = amax.min((jmax * d).sqrt()).max(-a);
        let t1 = ((a + ap) / jmax).max(0.0);
        let t2 = if ap > 0.0 {
            ((d - ap * ap / jmax) / ap).max(0.0)
        } else {
            0.0
        };
        let t3 = ap / jmax;
        Some(Stop {
            v0: v,
            a0: a,
            amax,
            j: jmax,
            ap,
            t1,
            t2,
            t3,
        })
    }

    pub(super) fn duration(&self) -> f64 {
        self.t1 + self.t2 + self.t3
    }

    /// (position, speed, acceleration) at time t from the start (clamped at the end).
    pub(super) fn at(&self, t: f64) -> (f64, f64, f64) {
        let j = self.j;
        let t = t.max(0.0);
        let tau = t.min(self.t1);
        let mut s = self.v0 * tau + self.a0 * tau * tau / 2.0 - j * tau.powi(3) / 6.0;
        let mut v = self.v0 + self.a0 * tau - j * tau * tau / 2.0;
        let mut a = self.a0 - j * tau;
        if t <= self.t1 {
            return (s, v, a);
        }
        let tau = (t - self.t1).min(self.t2);
        s += v * tau + a * tau * tau / 2.0;
        v += a * tau;
        if t <= self.t1 + self.t2 {
            return (s, v, a);
        }
        let tau = (t - self.t1 - self.t2).min(self.t3);
        s += v * tau + a * tau * tau / 2.0 + j * tau.powi(3) / 6.0;
        v += a * tau + j * tau * tau / 2.0;
        a += j * tau;
        (s, v, a)
    }

    pub(super) fn distance(&self) -> f64 {
        self.at(self.duration()).0
    }

    /// Peak speed (reached when a positive initial acceleration has been ramped down).
    pub(super) fn peak(&self) -> f64 {
        if self.a0 > 0.0 {
            self.v0 + self.a0 * self.a0 / (2.0 * self.j)
        } else {
            self.v0
        }
    }

    /// Does the profile pass position `x` (from its start) at a speed ≤ `c`?
    #[cfg(test)]
    fn under(&self, x: f64, c: f64) -> bool {
        self.under_kind(x, c).0.is_some()
    }

    /// [`Stop::under`] telling how it passes: `None` = it does not, `Some(true)` = the peak
    /// is below `c` or `x` lies after the falling crossing of `c` (then every later position
    /// with a ceiling ≥ `c` passes too: the speed only falls after the peak),
    /// `Some(false)` = `x` lies before the rising crossing (no such implication). The second
    /// value is the slack in mm: the distance from `x` to the nearer crossing on the
    /// passing side (negative when `x` lies between the crossings), infinite when the peak
    /// is below `c`.
    pub(super) fn under_kind(&self, x: f64, c: f64) -> (Option<bool>, f64) {
        let c = c * (1.0 + REL) + 1e-12;
        let pk = self.peak();
        if pk <= c {
            return (Some(true), f64::INFINITY);
        }
        let j = self.j;
        // Falling crossing: first time after the peak at which the speed is ≤ c.
        let t_pk = (self.a0 / j).max(0.0).min(self.t1);
        let v1 = self.at(self.t1).1;
        let v2 = v1 - self.ap * self.t2;
        let tf = if c >= v1 {
            let disc = (self.a0 * self.a0 + 2.0 * j * (self.v0 - c)).max(0.0);
            ((self.a0 + disc.sqrt()) / j).clamp(t_pk, self.t1)
        } else if c >= v2 && self.ap > 0.0 {
            self.t1 + (v1 - c) / self.ap
        } else {
            let disc = (self.ap * self.ap - 2.0 * j * (v2 - c)).max(0.0);
            self.t1 + self.t2 + ((self.ap - disc.sqrt()) / j).clamp(0.0, self.t3)
        };
        let df = self.at(tf).0 * (1.0 - 1e-12) - 1e-12;
        if x >= df {
            return (Some(true), x - df);
        }
        if self.v0 <= c {
            // Rising crossing inside phase 1.
            let disc = (self.a0 * self.a0 - 2.0 * j * (c - self.v0)).max(0.0);
            let tr = ((self.a0 - disc.sqrt()) / j).clamp(0.0, t_pk);
            let dr = self.at(tr).0;
            let slack = (dr - x).max(x - df);
            return ((x <= dr).then_some(false), slack);
        }
        (None, x - df)
    }

    /// Time at which the profile reaches position x (x within the profile): the phase is
    /// found from its end positions, then a safeguarded Newton iteration on the position
    /// (bisection whenever a Newton step leaves the bracket).
    pub(super) fn time_at(&self, x: f64) -> f64 {
        let ta = self.t1;
        let tb = self.t1 + self.t2;
        let (lo, hi) = if x <= self.at(ta).0 {
            (0.0, ta)
        } else if x <= self.at(tb).0 {
            (ta, tb)
        } else {
            (tb, self.duration())
        };
        solve_monotone(lo, hi, 0.5 * (lo + hi), x, |t| {
            let (s, v, _) = self.at(t);
            (s, v)
        })
    }
}

/// Shortest distance to bring the speed from (v, a) down to c with zero final
/// acceleration (§6.3 "brake_dist").
pub(super) fn brake_dist(v: f64, a: f64, c: f64, amax: f64, jmax: f64) -> f64 {
    if (v <= c && a <= 0.0) || (a > 0.0 && v + a * a / (2.0 * jmax) <= c) {
        return 0.0;
    }
    let d = v - c + a * a / (2.0 * jmax);
    if a < 0.0 && d <= a * a / jmax {
        let t = (-a - (a * a - 2.0 * jmax * (v - c)).max(0.0).sqrt()) / jmax;
        return v * t + a * t * t / 2.0 + jmax * t.powi(3) / 6.0;
    }
    match Stop::new(v - c, a, amax, jmax) {
        Some(p) => p.distance() + c * p.duration(),
        None => 0.0,
    }
}

/// Duration of a jerk-limited rest-to-rest move over distance d (speed ≤ vmax): the
/// speed-up mirrors the stop profile from the peak speed.
pub(super) fn rest_to_rest(d: f64, vmax: f64, amax: f64, jmax: f64) -> f64 {
    if d <= 0.0 {
        return 0.0;
    }
    let ramp = |vp: f64| {
        Stop::new(vp, 0.0, amax, jmax).map_or((0.0, 0.0), |p| (p.distance(), p.duration()))
    };
    let (dm, tm) = ramp(vmax);
    if 2.0 * dm <= d {
        return 2.0 * tm + (d - 2.0 * dm) / vmax;
    }
    let (mut lo, mut hi) = (0.0, vmax);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if 2.0 * ramp(mid).0 <= d {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    2.0 * ramp(lo).1
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn stop_profile_ends_at_rest() {
        for &(v, a) in &[(83.0, 0.0), (83.0, 1500.0), (83.0, -1500.0), (1.0, 10.0)] {
            let p = Stop::new(v, a, 5000.0, 40000.0).unwrap();
            let (_, ve, ae) = p.at(p.duration());
            assert!(ve.abs() < 1e-9 && ae.abs() < 1e-9, "{v} {a}: {ve} {ae}");
            assert!(p.distance() > 0.0);
        }
        // Cannot stop without reversing.
        assert!(Stop::new(0.01, -4000.0, 5000.0, 40000.0).is_none());
    }

    #[test]
    fn brake_dist_closed_forms() {
        // From rest-free cruise v to c with a = 0 and A not reached: t = 2 sqrt((v−c)/J),
        // distance = (v + c)/2 · t.
        let (v, c, j): (f64, f64, f64) = (83.333, 20.0, 40000.0);
        let t = 2.0 * ((v - c) / j).sqrt();
        assert_relative_eq!(
            brake_dist(v, 0.0, c, 5000.0, j),
            (v + c) / 2.0 * t,
            max_relative = 1e-9
        );
        assert_eq!(brake_dist(10.0, -5.0, 20.0, 5000.0, j), 0.0);
        assert_eq!(brake_dist(10.0, 5.0, 20.0, 5000.0, j), 0.0);
    }

    #[test]
    fn under_matches_sampling() {
        let p = Stop::new(50.0, 800.0, 3000.0, 40000.0).unwrap();
        let n = 400;
        for i in 1..n {
            let t = p.duration() * i as f64 / n as f64;
            let (x, v, _) = p.at(t);
            assert!(p.under(x, v * 1.001 + 1e-6), "t {t}");
            if v > 1.0 {
                assert!(!p.under(x, v * 0.99), "t {t}");
            }
        }
    }

    #[test]
    fn rest_to_rest_matches_k1_closed_form() {
        // 100 mm at 5 m/min, J = 40 m/s³: L/F + 2 sqrt(F/J).
        let f = 5000.0 / 60.0;
        let t = rest_to_rest(100.0, f, 5000.0, 40000.0);
        assert_relative_eq!(
            t,
            100.0 / f + 2.0 * (f / 40000.0f64).sqrt(),
            max_relative = 1e-9
        );
        // Jerk only, short: four phases of τ with d = 2 J τ³.
        let d = 1e-3;
        let tau = (d / (2.0 * 40000.0f64)).cbrt();
        assert_relative_eq!(
            rest_to_rest(d, 83.0, 5000.0, 40000.0),
            4.0 * tau,
            max_relative = 1e-9
        );
    }
}
