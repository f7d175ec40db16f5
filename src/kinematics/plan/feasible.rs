//! The verdict of the Level 2 interpolator on a next state: its tier (rejected, feasible,
//! releasable), the constraints that bind it, and their slack as a function of the jerk.

use super::REL;
use super::cycle::{crossing_time, interior_peak, peak_discrete, step};
use super::sim::{Sim, State};
use super::skip::CHUNK;
use super::stop::{Stop, brake_dist};

/// How acceptable a next state is.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Debug)]
pub(super) enum Tier {
    Rejected = 0,
    Feasible = 1,
    Releasable = 2,
}

/// What a caller of [`Sim::evaluate`] needs to know.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Need {
    /// The tier, whatever it is (the candidate jerks).
    Classify,
    /// Only whether the state is feasible (releasability is not tested).
    Feasible,
    /// Only whether it is releasable (stops at the first ceiling that is not).
    Releasable,
}

/// The constraints that keep a state below the tier asked for. Every constraint is
/// monotone in the jerk (met at a jerk, met at every lower one), so the boundary jerk is
/// set by one of those violated at the rejected end of the bracket; the search solves their
/// slacks together ([`Sim::slack`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub(super) struct Bind {
    /// A constraint without a slack function was violated (the search bisects).
    pub(super) other: bool,
    /// The speed inside the step against the lowest v̄ of the step's blocks.
    pub(super) step_speed: bool,
    /// The speed at the crossing of posture p during the step against its ceiling.
    pub(super) crossing: Option<usize>,
    /// The stop's end against the end of the look-ahead window or of the segment.
    pub(super) window: bool,
    /// The peak speed ahead against v̄ of the blocks m0..=m1 that it reaches.
    pub(super) peak: Option<(usize, usize)>,
    /// The full stop passing postures p0..=p1 under their ceilings.
    pub(super) under: Option<(usize, usize)>,
    /// Braking to the ceilings of postures p0..=p1 with zero acceleration before them
    /// (releasable).
    pub(super) release: Option<(usize, usize)>,
}

/// Widen an index range to include `i`.
fn widen(r: Option<(usize, usize)>, i: usize) -> Option<(usize, usize)> {
    Some(r.map_or((i, i), |(a, b)| (a.min(i), b.max(i))))
}

/// The verdict of [`Sim::evaluate`]: the tier, the constraints that keep the state below
/// the tier asked for, and the limits (A, J) of the state's stop profile.
#[derive(Clone, Copy, Debug)]
pub(super) struct Eval {
    pub(super) tier: Tier,
    pub(super) bind: Bind,
    pub(super) lim: (f64, f64),
    /// Length of the stop profile from the state (`NAN` when the evaluation stopped
    /// before building it).
    pub(super) dist: f64,
}

impl Eval {
    pub(super) fn rejected(bind: Bind, lim: (f64, f64)) -> Eval {
        Eval {
            tier: Tier::Rejected,
            bind,
            lim,
            dist: f64::NAN,
        }
    }
}

impl Sim<'_> {
    /// The least margin, in mm/s, between the speed during one cycle of jerk j from `st`
    /// and the v̄ of the block the path is in at that moment, at the three points where the
    /// speed inside a block can peak that are not posture crossings: the start of the step
    /// (block k), its end (block k1) and the interior maximum of the speed. The crossings of
    /// the postures in between are held to their ceilings (≤ the v̄ of the blocks on either
    /// side) by the crossing test, so together they bound the speed in every block the step
    /// passes. (Testing the step's highest speed against the lowest v̄ of all its blocks
    /// instead rejects a state cruising at the v̄ of its block just before a block with a
    /// lower v̄, whatever the jerk, although the stop profile from it stays under every
    /// ceiling: the interpolator then had no feasible successor and stopped.)
    /// `k1` and `v1` are the block and the speed (≥ 0) at the end of the step, which both
    /// callers have at hand.
    fn step_speed_slack(&self, st: State, j: f64, k1: usize, v1: f64) -> f64 {
        let State { k, s, v, a } = st;
        let b = self.b;
        let t = self.cycle;
        let cap = |m: usize| b.vbar[m] * (1.0 + REL);
        let mut slack = (cap(k) - v).min(cap(k1) - v1);
        if let Some((tau, vp)) = interior_peak(v, a, j, t) {
            let m = self.block_at(k, (s + step(v, a, j, tau).0).min(b.start[self.end]));
            slack = slack.min(cap(m) - vp);
        }
        slack
    }

    /// Classify the state after one cycle of jerk j from (s, v, a) in block k, and name the
    /// constraints that keep it below the tier asked for (see [`Eval`]). `need` says what
    /// the caller asks: [`Need::Classify`] and [`Need::Releasable`] compute the full tier,
    /// [`Need::Feasible`] skips the releasability tests.
    pub(super) fn evaluate(&self, st: State, j: f64, need: Need) -> Eval {
        let State { k, s, v, a } = st;
        let b = self.b;
        let t = self.cycle;
        let mut bind = Bind::default();
        let mut lim = (0.0, 0.0);
        let reject = Eval::rejected;
        let (ds, v1, a1) = step(v, a, j, t);
        let s1 = s + ds;
        let s_end = b.start[self.end];
        if v1 < -1e-12 * (1.0 + v.abs()) || s1 >= s_end {
            bind.other = true;
            return reject(bind, lim);
        }
        let v1 = v1.max(0.0);
        let k1 = self.block_at(k, s1);
        // Speed inside the step against the v̄ of the blocks it passes through.
        let vmax = v
            .max(v1)
            .max(interior_peak(v, a, j, t).map_or(0.0, |(_, vp)| vp));
        if vmax > self.min_vbar(k, k1) * (1.0 + REL) && self.step_speed_slack(st, j, k1, v1) < 0.0 {
            bind.step_speed = true;
            return reject(bind, lim);
        }
        if a1.abs() > b.abar[k1] * (1.0 + REL) {
            bind.other = true;
            return reject(bind, lim);
        }
        // Ceilings of postures crossed during the step, at the crossing instant.
        for p in (k + 1)..=k1 {
            let sp = b.start[p];
            if sp <= s {
                continue;
            }
            let c = b.ceil[p];
            let amax_step = a.abs().max(a1.abs());
            if vmax <= c * (1.0 + REL) && amax_step <= b.abar[p] {
                continue;
            }
            let tau = crossing_time(v, a, j, t, sp - s);
            let vc = v + a * tau + j * tau * tau / 2.0;
            if vc > c * (1.0 + REL) + 1e-12 {
                bind.crossing = Some(p);
                return reject(bind, lim);
            }
            // Entering block p: the acceleration must be within its ā from here on.
            if (a + j * tau).abs() > b.abar[p] * (1.0 + REL) {
                bind.other = true;
                return reject(bind, lim);
            }
        }
        let Some(prof) = self.stop_from(k1, s1, v1, a1) else {
            bind.other = true;
            return reject(bind, lim);
        };
        lim = (prof.amax, prof.j);
        // The peak speed ahead: the positive acceleration released in whole cycles at the
        // stop profile's jerk, the least j̄ of the blocks ahead. (At the j̄ of the state's
        // own block, a state could pass that none of its successors, ramping down at the
        // lower j̄ of the blocks they reach, can: its peak would be higher than foreseen.
        // Along the stop profile the discrete peak is the same from every cycle's state.)
        if a1 > 0.0 {
            let jk = prof.j;
            let tp = a1 / jk;
            let vpk = peak_discrete(v1, a1, jk, t);
            let dpk = v1 * tp + a1 * tp * tp / 2.0 - jk * tp.powi(3) / 6.0;
            let mut m = k1;
            while m < self.end && b.start[m] < s1 + dpk {
                if vpk > b.vbar[m] * (1.0 + REL) {
                    bind.peak = widen(bind.peak, m);
                }
                m += 1;
            }
        }
        let dist = prof.distance();
        let limit = self.window_end(k1).min(s_end);
        if s1 + dist > limit + 1e-12 * (1.0 + limit.abs()) {
            bind.window = true;
            return reject(bind, lim);
        }
        // Acceleration on entering later blocks (only matters when |a'| exceeds their ā).
        let pk = prof.peak();
        let check_release = need != Need::Feasible;
        let a_stop = b.abar[k1].min(prof.ap.max(a1.abs()));
        let mut p = k1 + 1;
        // Dominance (exact, the tests are monotone in the ceiling): a posture whose ceiling
        // is at least that of an earlier posture that passed `under` after the peak passes
        // too, and one whose ceiling and braking deceleration are at least those of an
        // earlier releasable posture is releasable too (brake_dist falls with c and A, the
        // room grows with x). Only the running minima of the ceilings cost an evaluation.
        // Once a test has failed, the scan goes on to find every posture that fails it.
        let mut under_ok = f64::INFINITY;
        let (mut rel_c, mut rel_a) = (f64::INFINITY, f64::INFINITY);
        while p < self.end && b.start[p] <= s1 + dist {
            // Skip a chunk where no ceiling is below the peak and no ā below the stop's
            // deceleration: none of the tests below can fire there.
            if p.is_multiple_of(CHUNK) {
                let c = p / CHUNK;
                if self.ch.ceil[c] >= pk
                    && self
                        .ch
                        .abar
                        .get(c)
                        .is_some_and(|&am| am * (1.0 + REL) >= a_stop)
                {
                    p += CHUNK;
                    continue;
                }
            }
            let x = b.start[p] - s1;
            let c = b.ceil[p];

            if c < pk && c < under_ok {
                match prof.under_kind(x, c).0 {
                    None => bind.under = widen(bind.under, p),
                    Some(true) if bind.under.is_none() => under_ok = c,
                    Some(_) => {}
                }
            }
            if a_stop > b.abar[p] * (1.0 + REL) {
                let (_, _, ae) = prof.at(prof.time_at(x));
                if ae.abs() > b.abar[p] * (1.0 + REL) {
                    bind.other = true;
                    return reject(bind, lim);
                }
            }
            if check_release && c < pk {
                let (am, jm) = (prof.ap.max(1e-300).max(b.abar[p].min(b.abar[k1])), prof.j);
                if !(c >= rel_c && am >= rel_a) {
                    if brake_dist(v1, a1, c, am, jm) > x * (1.0 + 1e-12) + 1e-12 {
                        bind.release = widen(bind.release, p);
                    } else if bind.release.is_none() && c < rel_c {
                        (rel_c, rel_a) = (c, am);
                    }
                }
            }
            p += 1;
        }
        let tier = if bind.peak.is_some() || bind.under.is_some() {
            Tier::Rejected
        } else if check_release && bind.release.is_none() {
            Tier::Releasable
        } else {
            Tier::Feasible
        };
        if tier == Tier::Rejected {
            // The releasability of a rejected state does not matter.
            bind.release = None;
        }
        Eval {
            tier,
            bind,
            lim,
            dist,
        }
    }

    /// The slack of the constraints `bind` after a cycle of jerk j from (s, v, a) in block
    /// k, with the stop profile's limits `lim` = (A, J) held fixed: the least over them,
    /// each in its own units, positive when all are met. It is continuous in j and costs
    /// no look-ahead scan, so the boundary search can solve on it and keep the full
    /// evaluations for the verdicts. `NAN` when it cannot say.
    pub(super) fn slack(&self, st: State, j: f64, bind: Bind, lim: Option<(f64, f64)>) -> f64 {
        let State { k, s, v, a } = st;
        if bind.other {
            return f64::NAN;
        }
        let b = self.b;
        let t = self.cycle;
        let (ds, v1, a1) = step(v, a, j, t);
        let s1 = s + ds;
        let v1 = v1.max(0.0);
        let k1 = self.block_at(k, s1.min(b.start[self.end]));
        let mut slack = f64::INFINITY;
        if bind.step_speed {
            slack = slack.min(self.step_speed_slack(st, j, k1, v1));
        }
        if let Some(p) = bind.crossing.filter(|&p| b.start[p] > s) {
            // (A crossing carried by a hint may lie behind the state: then it is met.)
            let x = b.start[p] - s;
            if x > ds {
                return f64::NAN;
            }
            let tau = crossing_time(v, a, j, t, x);
            let vc = v + a * tau + j * tau * tau / 2.0;
            slack = slack.min(b.ceil[p] * (1.0 + REL) + 1e-12 - vc);
        }
        if !(bind.window || bind.peak.is_some() || bind.under.is_some() || bind.release.is_some()) {
            return slack;
        }
        let stop = match lim {
            Some((am, jm)) => Stop::new(v1, a1, am, jm),
            None => self.stop_from(k1, s1, v1, a1),
        };
        let Some(pr) = stop else {
            return f64::NAN;
        };
        if let Some((m0, m1)) = bind.peak {
            // A block only counts when the peak is reached inside or after it.
            let jk = pr.j;
            let tp = a1.max(0.0) / jk;
            let dpk = v1 * tp + a1 * tp * tp / 2.0 - jk * tp.powi(3) / 6.0;
            let vpk = peak_discrete(v1, a1, jk, t);
            for m in m0.max(k1)..=m1 {
                slack = slack.min((b.vbar[m] * (1.0 + REL) - vpk).max(b.start[m] - s1 - dpk));
            }
        }
        let (dist, pk) = (pr.distance(), pr.peak());
        if bind.window {
            let limit = self.window_end(k1).min(b.start[self.end]);
            slack = slack.min(limit + 1e-12 * (1.0 + limit.abs()) - s1 - dist);
        }
        // A posture only counts inside the stopping distance and below the peak. The
        // dominance of `evaluate` holds for the slacks too: a posture dominated by an earlier
        // one that passes has the larger slack, so it is skipped.
        if let Some((p0, p1)) = bind.under {
            let mut under_ok = f64::INFINITY;
            for p in p0.max(k1 + 1)..=p1 {
                let (x, c) = (b.start[p] - s1, b.ceil[p]);
                if b.start[p] > s1 + dist {
                    break;
                }
                if c < pk && c < under_ok {
                    let (kind, sl) = pr.under_kind(x, c);
                    if kind == Some(true) {
                        under_ok = c;
                    }
                    slack = slack.min(sl);
                }
            }
        }
        if let Some((p0, p1)) = bind.release {
            let (mut rel_c, mut rel_a) = (f64::INFINITY, f64::INFINITY);
            for p in p0.max(k1 + 1)..=p1 {
                let (x, c) = (b.start[p] - s1, b.ceil[p]);
                if b.start[p] > s1 + dist {
                    break;
                }
                let am = pr.ap.max(1e-300).max(b.abar[p].min(b.abar[k1]));
                if c < pk && !(c >= rel_c && am >= rel_a) {
                    let room = x * (1.0 + 1e-12) + 1e-12;
                    let sl = room - brake_dist(v1, a1, c, am, pr.j);
                    if sl >= 0.0 && c < rel_c {
                        (rel_c, rel_a) = (c, am);
                    }
                    slack = slack.min(sl);
                }
            }
        }
        slack
    }
}

#[cfg(test)]
mod tests {
    use super::super::{plan_acc_only, plan_jerk};
    use crate::kinematics::blocks::{Blocks, Limit};

    /// A straight path whose v̄ falls slowly block by block (as the rotary axes' share grows
    /// towards a tilt change), with lower ā and j̄ towards the end.
    fn falling_cap_blocks(n: usize) -> Blocks {
        let len = vec![0.1; n];
        let start: Vec<f64> = (0..=n).map(|p| p as f64 * 0.1).collect();
        let vbar: Vec<f64> = (0..n).map(|k| 34.0 - 0.006 * k as f64).collect();
        let abar: Vec<f64> = (0..n)
            .map(|k| 5000.0 - 4000.0 * k as f64 / n as f64)
            .collect();
        let jbar: Vec<f64> = (0..n)
            .map(|k| 80000.0 - 48000.0 * k as f64 / n as f64)
            .collect();
        let mut ceil = vec![0.0; n + 1];
        for p in 1..n {
            ceil[p] = vbar[p - 1].min(vbar[p]);
        }
        Blocks {
            len,
            start,
            g: vec![[0.0; 5]; n],
            vaxis: vbar.clone(),
            vbar_by: vec![Limit::Feed; n],
            jbar_by: vec![0; n],
            ceil_junction: vec![false; n + 1],
            vbar,
            abar,
            jbar,
            ceil,
        }
    }

    #[test]
    fn a_slowly_falling_cap_is_followed_without_unplanned_stops() {
        // Cruising at v̄ of its block, the interpolator must be able to enter the next
        // block, whose v̄ is a little lower: the speed at the crossing, not the highest speed
        // of the step, is what the lower v̄ bounds.
        let b = falling_cap_blocks(1000);
        let l2 = plan_jerk(&b, 0.003, 0);
        let l1 = plan_acc_only(&b);
        assert_eq!(l2.stop_recoveries, 0);
        assert_eq!(l2.fallbacks, 0);
        assert!(
            l2.max_ceiling_ratio <= 1.0 + 1e-6,
            "{}",
            l2.max_ceiling_ratio
        );
        assert!(l2.max_axis_ratio <= 1.0 + 1e-6, "{}", l2.max_axis_ratio);
        // Jerk-limited, never faster than Level 1; with no stops on the way, only the ramps
        // at both ends cost more than Level 1's. Each is triangular (v < A²/J): 2·√(v/J)
        // over v·√(v/J), where Level 1 ramps in v/A and cruises the rest at v. Their extra
        // time in closed form (about 0.017 s + 0.016 s), plus a cycle each for rounding.
        let extra = |v: f64, a: f64, j: f64| {
            assert!(v < a * a / j, "triangular ramp");
            let (t, d) = (2.0 * (v / j).sqrt(), v * (v / j).sqrt());
            t - (v / a + (d - v * v / (2.0 * a)) / v)
        };
        let last = b.n() - 1;
        let ramps = extra(b.vbar[0], b.abar[0], b.jbar[0])
            + extra(b.vbar[last], b.abar[last], b.jbar[last]);
        assert!(l2.total >= l1.total, "{} < {}", l2.total, l1.total);
        assert!(
            l2.total <= l1.total + ramps + 2.0 * 0.003,
            "{} vs {} + {ramps}",
            l2.total,
            l1.total
        );
    }
}
