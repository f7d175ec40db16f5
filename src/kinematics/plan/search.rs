//! The jerk of each Level 2 cycle: the candidates, the boundary search between them
//! (slack roots checked by full evaluations, then the bisection replayed), the hint carried
//! from the last braking cycle, and the least-violating fallback.

use super::cycle::{jerk_cap, step};
use super::feasible::{Bind, Eval, Need, Tier};
use super::root::brent;
use super::sim::{Sim, State};
use super::stop::Stop;

/// Bisection steps on the jerk (§6.3 step 2).
const BISECT: usize = 30;

/// The constraints (and stop limits) that bounded the last cycle's jerk from above, for
/// the next cycle's [`Sim::follow_hint`].
pub(super) type Hint = Option<(Bind, (f64, f64))>;

/// The jerk [`Sim::choose`] takes for a cycle.
pub(super) struct Choice {
    pub(super) j: f64,
    /// No candidate was acceptable: `j` is the least-violating jerk.
    pub(super) fell: bool,
    /// `j` was found by the boundary search between two candidates.
    pub(super) searched: bool,
    /// The constraints that bound `j`, for the next cycle.
    pub(super) hint: Hint,
    /// Length of the stop profile from the next state, when `j` was evaluated in full
    /// (`NAN` otherwise): it tells [`Sim::run`] whether the final stop is due.
    pub(super) dist: f64,
}

impl Choice {
    fn new(j: f64, searched: bool, hint: Hint, dist: f64) -> Choice {
        Choice {
            j,
            fell: false,
            searched,
            hint,
            dist,
        }
    }
}

impl Sim<'_> {
    /// A measure of how badly a jerk violates the constraints (for the fallback tier).
    fn violation(&self, st: State, j: f64) -> f64 {
        let State { k, s, v, a } = st;
        let b = self.b;
        let (ds, v1, a1) = step(v, a, j, self.cycle);
        let s1 = s + ds;
        let mut bad = (-v1).max(0.0);
        let s_end = b.start[self.end];
        let k1 = self.block_at(k, s1.min(s_end));
        bad += (v1 - b.vbar[k1]).max(0.0);
        let am = b.abar[k1];
        let jm = b.jbar[k1];
        let dist = Stop::new(v1.max(0.0), a1.max(-v1.max(0.0).sqrt() * jm.sqrt()), am, jm)
            .map_or(0.0, |p| p.distance());
        bad += (s1 + dist - s_end).max(0.0);
        bad
    }

    /// Choose the jerk of the next cycle (§6.3 steps 1–3).
    pub(super) fn choose(&self, st: State, hint: Hint) -> Choice {
        let State { k, s, v, a } = st;
        let b = self.b;
        let t = self.cycle;
        let (a0, j0) = (b.abar[k], b.jbar[k]);
        let jh0 = j0.min((a0 - a) / t);
        let (ds, ..) = step(v, a, jh0.max(0.0), t);
        let k2 = self.block_at(k, s + ds);
        let (mut am, mut jm) = (a0, j0);
        for m in k..=k2 {
            am = am.min(b.abar[m]);
            jm = jm.min(b.jbar[m]);
        }
        let mut j_lo = (-jm).max((-am - a) / t);
        let mut j_hi = jm.min((am - a) / t);
        if j_lo > j_hi {
            // |a| is beyond this block's ā (entering a weaker block): steer back.
            if a > 0.0 {
                j_hi = j_lo;
            } else {
                j_lo = j_hi;
            }
        }
        // Tighten j_hi by the velocity cap of the step's blocks (closed form), so cruising
        // needs one evaluation instead of a bisection.
        let vcap = self.min_vbar(k, k2);
        let j_cap = jerk_cap(v, a, t, jm, vcap, j_lo, j_hi);
        if j_cap > f64::NEG_INFINITY {
            j_hi = j_cap;
        }
        let clip = |x: f64| x.clamp(j_lo, j_hi);
        let mut cands = [j_hi, clip(-a / t), clip(0.0), j_lo];
        cands.sort_by(|x, y| y.total_cmp(x));
        if let Some(h) = hint.filter(|_| !self.bisect_only)
            && let Some(c) = self.follow_hint(st, &cands, h)
        {
            return c;
        }
        let mut evals = [Eval::rejected(Bind::default(), (0.0, 0.0)); 4];
        let mut best = Tier::Rejected;
        for (i, &c) in cands.iter().enumerate() {
            if i > 0 && c == cands[i - 1] {
                evals[i] = evals[i - 1];
            } else {
                evals[i] = self.evaluate(st, c, Need::Classify);
            }
            if evals[i].tier == Tier::Releasable {
                best = Tier::Releasable;
                break;
            }
            best = best.max(evals[i].tier);
        }
        if best == Tier::Rejected {
            // Least violation on a 41-point grid.
            let mut bj = j_lo;
            let mut bv = f64::INFINITY;
            for i in 0..=40 {
                let jj = j_lo + (j_hi - j_lo) * i as f64 / 40.0;
                let viol = self.violation(st, jj);
                if viol < bv {
                    bv = viol;
                    bj = jj;
                }
            }
            return Choice {
                fell: true,
                ..Choice::new(bj, false, None, f64::NAN)
            };
        }
        if best == Tier::Feasible && evals[3].tier == Tier::Feasible {
            // No candidate keeps every ceiling reachable with zero acceleration: the state
            // fell behind a braking profile by less than a cycle (a phase switch inside a
            // cycle). Riding the feasibility boundary from here would leave no feasible
            // successor at the next phase switch, so brake as hard as allowed for a cycle
            // to win the margin back.
            return Choice::new(cands[3], false, None, evals[3].dist);
        }
        let i = evals.iter().position(|e| e.tier >= best).unwrap_or(3);
        if i == 0 {
            return Choice::new(cands[0], false, None, evals[0].dist);
        }
        let good = (cands[i], evals[i]);
        let c = self.boundary(st, best, good, (cands[i - 1], evals[i - 1]));
        // Only a releasable boundary is carried to the next cycle (see `follow_hint`).
        Choice {
            hint: c.hint.filter(|_| best == Tier::Releasable),
            ..c
        }
    }

    /// The largest acceptable jerk (tier ≥ `best`) between `good` (acceptable) and `bad`
    /// (not, with its verdict). The greedy interpolator rides this boundary, so it is found
    /// to the resolution of a 30-step bisection, 2⁻³⁰ of the bracket (stopping at even
    /// 1e-7 of the jerk limit changes the plan of the 001 parabola by 0.2 %).
    ///
    /// Rather than bisecting on full evaluations, each round solves the slack of the
    /// constraint that rejected the upper end ([`Sim::slack`]: no look-ahead scan) for its
    /// root, then checks the root and a point half the tolerance above it with two full
    /// evaluations. Usually that closes the bracket; if the upper check is rejected by
    /// another constraint, the next round solves that one. The bracket only ever moves on
    /// the verdicts of full evaluations, so the answer is acceptable whatever the slack
    /// says; when the slack cannot say (or after a few rounds), the search bisects.
    fn boundary(&self, st: State, best: Tier, good: (f64, Eval), bad: (f64, Eval)) -> Choice {
        let tol = (bad.0 - good.0) * 0.5f64.powi(BISECT as i32);
        let probe =
            |x: f64, lo: &mut (f64, Eval), hi: &mut (f64, Eval)| self.probe(st, best, x, lo, hi);
        let mut rounds = 0;
        let (mut lo, mut hi) = (good, bad);
        while hi.0 - lo.0 > tol {
            let root = if rounds < 4 && !self.bisect_only {
                self.slack_root(st, (lo.0, hi.0), hi.1.bind, [lo.1.lim, hi.1.lim], tol / 4.0)
            } else {
                None
            };
            let Some(r) = root else {
                let mid = 0.5 * (lo.0 + hi.0);
                if mid <= lo.0 || mid >= hi.0 {
                    break;
                }
                probe(mid, &mut lo, &mut hi);
                continue;
            };
            rounds += 1;
            // The root, then just above it: together they close the bracket.
            if r > lo.0 && r < hi.0 && !probe(r, &mut lo, &mut hi) {
                continue;
            }
            if hi.0 - lo.0 > tol {
                let x = (lo.0 + 0.5 * tol).min(0.5 * (lo.0 + hi.0));
                probe(x, &mut lo, &mut hi);
            }
        }
        let j = self.replay(st, best, (good.0, bad.0), &mut lo, &mut hi);
        let dist = if j == lo.0 { lo.1.dist } else { f64::NAN };
        Choice::new(j, true, Some((hi.1.bind, hi.1.lim)), dist)
    }

    /// A full evaluation at x for tier `best`: x becomes the new `lo` if acceptable (true),
    /// else the new `hi`.
    fn probe(
        &self,
        st: State,
        best: Tier,
        x: f64,
        lo: &mut (f64, Eval),
        hi: &mut (f64, Eval),
    ) -> bool {
        let need = if best == Tier::Releasable {
            Need::Releasable
        } else {
            Need::Feasible
        };
        let e = self.evaluate(st, x, need);
        if e.tier >= best {
            *lo = (x, e);
            true
        } else {
            *hi = (x, e);
            false
        }
    }

    /// Replay the 30-step bisection between the candidates `good` and `bad`, knowing a
    /// bracket `lo` (acceptable) .. `hi` (not) from full evaluations: every midpoint at or
    /// below `lo` is acceptable and every one at or above `hi` is not (the tiers are
    /// monotone in the jerk), so only a midpoint inside the bracket needs an evaluation.
    /// The answer is the bisection's own, to the last bit: the greedy plan is sensitive to
    /// differences far below the bisection's resolution (another point of the same bracket
    /// can add unplanned stops).
    fn replay(
        &self,
        st: State,
        best: Tier,
        (good, bad): (f64, f64),
        lo: &mut (f64, Eval),
        hi: &mut (f64, Eval),
    ) -> f64 {
        let (mut g, mut b) = (good, bad);
        for _ in 0..BISECT {
            let mid = 0.5 * (g + b);
            if mid == g || mid == b {
                break;
            }
            let ok = if mid <= lo.0 {
                true
            } else if mid >= hi.0 {
                false
            } else {
                self.probe(st, best, mid, lo, hi)
            };
            if ok {
                g = mid;
            } else {
                b = mid;
            }
        }
        g
    }

    /// The braking cycle after a braking cycle: the constraints that bound the last jerk
    /// (`hint`) usually bound this one too. Solve their slack over the whole jerk range,
    /// check the root and a point just above it with two full evaluations, and if both
    /// agree (releasable, not releasable) the candidate scan and the bisection of
    /// [`Sim::choose`] are replayed on that bracket without evaluating them: the same jerk
    /// to the last bit, for two evaluations instead of six to ten. `None` when the hint
    /// does not hold (then `choose` runs as usual).
    fn follow_hint(
        &self,
        st: State,
        cands: &[f64; 4],
        (bind, lim): (Bind, (f64, f64)),
    ) -> Option<Choice> {
        let (top, bottom) = (cands[0], cands[3]);
        if top.is_nan() || bottom.is_nan() || top <= bottom {
            return None;
        }
        // Most often the hint no longer binds: its constraints hold at the top candidate.
        if self.slack(st, top, bind, Some(lim)) >= 0.0 {
            return None;
        }
        let tol = (top - bottom) * 0.5f64.powi(BISECT as i32 + 2);
        let r = self.slack_root(st, (bottom, top), bind, [lim, lim], tol / 4.0)?;
        if r + tol >= top {
            return None;
        }
        let e_lo = self.evaluate(st, r, Need::Releasable);
        if e_lo.tier != Tier::Releasable {
            return None;
        }
        let e_hi = self.evaluate(st, r + tol, Need::Releasable);
        if e_hi.tier == Tier::Releasable {
            return None;
        }
        let (mut lo, mut hi) = ((r, e_lo), (r + tol, e_hi));
        // The first candidate at or below the boundary is the first releasable one.
        let mut i = cands.iter().position(|&c| c <= lo.0)?;
        while i > 0 && cands[i - 1] < hi.0 {
            // A candidate inside the bracket: its verdict narrows the bracket.
            let e = self.evaluate(st, cands[i - 1], Need::Releasable);
            if e.tier == Tier::Releasable {
                lo = (cands[i - 1], e);
                i -= 1;
            } else {
                hi = (cands[i - 1], e);
                break;
            }
        }
        if i == 0 {
            return Some(Choice::new(cands[0], false, None, lo.1.dist));
        }
        // Releasability need not hold all the way down (a hard brake may not stop without
        // reversing), so the candidate that the scan would take is checked too.
        // (and the one above, which the scan would have rejected).
        let releasable = |j: f64| self.evaluate(st, j, Need::Releasable).tier == Tier::Releasable;
        if (cands[i] < lo.0 && !releasable(cands[i]))
            || (cands[i - 1] > hi.0 && releasable(cands[i - 1]))
        {
            return None;
        }
        let j = self.replay(
            st,
            Tier::Releasable,
            (cands[i], cands[i - 1]),
            &mut lo,
            &mut hi,
        );
        let dist = if j == lo.0 { lo.1.dist } else { f64::NAN };
        Some(Choice::new(j, true, Some((hi.1.bind, hi.1.lim)), dist))
    }

    /// Root of [`Sim::slack`] of the constraints `bind` on the bracket `(g, b)`, where a
    /// full evaluation accepted g and rejected b, to `tol`: the end of the final bracket
    /// with slack ≥ 0. The stop profile's limits change in steps with the distance it
    /// covers, so the limits are held at those of the rejected end, then of the accepted
    /// end, then recomputed at every point (exact, but the slack then has jumps); the
    /// first that gives a sign change is used. `None` when none does.
    fn slack_root(
        &self,
        st: State,
        (g, b): (f64, f64),
        bind: Bind,
        [lim_g, lim_b]: [(f64, f64); 2],
        tol: f64,
    ) -> Option<f64> {
        if bind.other {
            return None;
        }
        for (i, lim) in [Some(lim_b), Some(lim_g), None].into_iter().enumerate() {
            if i == 1 && lim_g == lim_b {
                continue;
            }
            let h = |j: f64| self.slack(st, j, bind, lim);
            // The rejected end first: where the constraints hold there, they do not set
            // the boundary (a hint that no longer binds), and the other end is not needed.
            let fb = h(b);
            if fb >= 0.0 || fb.is_nan() {
                continue;
            }
            let fg = h(g);
            if fg >= 0.0 {
                // A point where the slack cannot say counts as rejected.
                return Some(brent(g, fg, b, fb, tol, |j| {
                    let f = h(j);
                    if f.is_nan() { -1.0 } else { f }
                }));
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::super::segment::plan_jerk_with;
    use crate::kinematics::blocks::Blocks;

    /// A 5-axis zigzag in 0.2 mm blocks with the tool axis tilting back and forth (C turns
    /// through 180° where the tilt changes sign), on the Table I AC machine: corners,
    /// rotary-bound blocks, unplanned stops.
    fn zigzag_blocks() -> Blocks {
        use crate::kinematics::machine::{Machine, TABLE_I_AC_TOML};
        use crate::kinematics::{IkTracker, pose_tilt_azimuth};
        let m = Machine::from_toml_str(TABLE_I_AC_TOML).unwrap();
        let mut ik = IkTracker::new(&m);
        let (mut joints, mut pos) = (Vec::new(), Vec::new());
        for i in 0..1500 {
            let (pass, u) = (i / 250, (i % 250) as f64 * 0.2);
            let x = if pass % 2 == 0 { u } else { 50.0 - u };
            let (y, z) = (pass as f64 * 0.5, 2.0 * (x / 8.0).sin());
            let slope = (0.25 * (x / 8.0).cos()).atan().to_degrees();
            let az = if slope >= 0.0 { 180.0 } else { 0.0 };
            let pose = pose_tilt_azimuth([x, y, z], 8.0 + slope.abs(), az);
            joints.push(ik.solve(&pose.tip, &pose.axis.normalize()).unwrap().joints);
            pos.push([x, y, z]);
        }
        let settings = crate::kinematics::Settings {
            cycle_time: m.cycle_time,
            min_block_cycles: m.min_block_cycles,
            lookahead_blocks: 0,
            junction_spacing_rule: true,
        };
        let n = joints.len();
        Blocks::build(
            &joints,
            &pos,
            &vec![5000.0 / 60.0; n - 1],
            &vec![false; n],
            &m.joint_limits(),
            &settings,
        )
    }

    #[test]
    fn slack_search_gives_the_bisection_plan_bit_for_bit() {
        let b = zigzag_blocks();
        let fast = plan_jerk_with(&b, 0.003, 0, false);
        let slow = plan_jerk_with(&b, 0.003, 0, true);
        assert!(
            fast.searches > fast.cycles / 20,
            "the path should keep the search busy (a guard on the test input, not a property)"
        );
        assert_eq!(fast.cycles, slow.cycles);
        assert_eq!(fast.searches, slow.searches);
        assert_eq!(fast.stop_recoveries, slow.stop_recoveries);
        assert_eq!(fast.t, slow.t);
        assert_eq!(fast.v, slow.v);
        assert!(fast.max_axis_ratio <= 1.0 + 1e-6, "{}", fast.max_axis_ratio);
    }
}
