//! Velocity planning along the blocks (kinematics.md §6): Level 1, the exact
//! acceleration-limited look-ahead (`plan_acc_only`), and Level 2, the jerk-limited
//! look-ahead interpolator simulated at the NC cycle time (`plan_jerk`, "Eq 4").
//!
//! Level 2 is a greedy choice of a constant jerk per cycle: the largest jerk whose next
//! state is *feasible* (the full-stop manoeuvre from it stays under every ceiling ahead and
//! ends before the path end and the look-ahead window) and, if possible, *releasable*
//! (every ceiling ahead can still be met with zero acceleration). The final stop is appended
//! in closed form. The stop profiles are evaluated in closed form, not by integration.

use super::blocks::{Blocks, Limit};
use rayon::prelude::*;

/// Bisection steps on the jerk (§6.3 step 2).
const BISECT: usize = 30;
/// Relative slack on speed checks.
const REL: f64 = 1e-9;
/// The stop and brake profiles of the feasibility tests use this fraction of ā and j̄; 1:
/// the full limits, as the moves themselves. (A fraction below 1 would leave room to catch
/// up where a constant jerk per cycle cannot follow a phase switch inside a cycle; instead
/// the tests of [`Sim::evaluate`] are ones that a state's successors can keep passing by
/// following its stop profile, and the few states left without a feasible successor run
/// that profile in closed form, see [`Sim::run`].)
const MARGIN: f64 = 1.0;
/// The limits of a stop profile are the minimum over the blocks within this multiple of
/// its distance (plus one cycle of travel). With exactly its distance (factor 1), a
/// profile that ends just before a block with a lower jerk limit is feasible, the next
/// one that reaches into it by a hair is not, and the interpolator is caught braking too
/// late; looking half a stop further makes the switch happen while there is room.
const COVER: f64 = 1.5;

/// Result of a planning pass.
#[derive(Debug, Clone, Default)]
pub struct Timing {
    /// Time stamp of every posture, s.
    pub t: Vec<f64>,
    /// Path speed ṡ at every posture, mm/s.
    pub v: Vec<f64>,
    /// Highest sampled path speed inside each block, mm/s.
    pub block_peak: Vec<f64>,
    /// Total time, s.
    pub total: f64,
    /// Number of cycles simulated (Level 2).
    pub cycles: usize,
    /// Cycles where no candidate was acceptable and the least-violating jerk was used.
    pub fallbacks: usize,
    /// Cycles whose jerk lies between two candidates: found by the boundary search.
    pub searches: usize,
    /// Times the interpolator found no feasible successor and ran the previous state's
    /// stop manoeuvre in closed form instead (an unplanned stop; see `Sim::run`).
    pub stop_recoveries: usize,
    /// Largest ratio of sampled |g_i ṡ|, |g_i s̈|, |g_i s⃛| to the axis limits (≤ 1 + 1e-6).
    pub max_axis_ratio: f64,
    /// Largest ratio of the speed at a posture to its ceiling.
    pub max_ceiling_ratio: f64,
}

/// Level 1 (§6.1): acceleration-limited look-ahead, forward and backward pass, then a
/// trapezoid per block. Exact and O(N); no jerk.
pub fn plan_acc_only(b: &Blocks) -> Timing {
    let n = b.n();
    let np = n + 1;
    let mut vin = vec![0.0; np];
    let mut vout = vec![0.0; n];
    for k in 0..n {
        let reach = (vin[k] * vin[k] + 2.0 * b.abar[k] * b.len[k]).sqrt();
        vout[k] = b.ceil[k + 1].min(b.vbar[k]).min(reach);
        vin[k + 1] = vout[k];
    }
    vin[n] = 0.0;
    for k in (0..n).rev() {
        vout[k] = vout[k].min(vin[k + 1]);
        let reach = (vout[k] * vout[k] + 2.0 * b.abar[k] * b.len[k]).sqrt();
        vin[k] = vin[k].min(reach);
    }
    let mut t = vec![0.0; np];
    let mut peak = vec![0.0; n];
    for k in 0..n {
        let (a, l) = (b.abar[k], b.len[k]);
        let (v0, v1) = (vin[k], vout[k]);
        let vp = b.vbar[k]
            .min(((v0 * v0 + v1 * v1 + 2.0 * a * l) / 2.0).sqrt())
            .max(v0.max(v1));
        let d_up = (vp * vp - v0 * v0) / (2.0 * a);
        let d_dn = (vp * vp - v1 * v1) / (2.0 * a);
        let cruise = (l - d_up - d_dn).max(0.0);
        let dt = (vp - v0) / a + (vp - v1) / a + if vp > 0.0 { cruise / vp } else { 0.0 };
        t[k + 1] = t[k] + dt;
        peak[k] = vp;
    }
    Timing {
        total: t[n],
        t,
        v: vin,
        block_peak: peak,
        max_axis_ratio: 0.0,
        max_ceiling_ratio: 0.0,
        cycles: 0,
        fallbacks: 0,
        searches: 0,
        stop_recoveries: 0,
    }
}

/// The three-phase braking profile from (v, a) with limits A, J: jerk −J until the
/// acceleration is −a_p, hold, then +J back to zero acceleration (§6.3 "full stop").
/// With a speed offset it is also the brake-to-c profile of `brake_dist`.
#[derive(Debug, Clone, Copy)]
struct Stop {
    v0: f64,
    a0: f64,
    /// The limits the profile was built with: A and J.
    amax: f64,
    j: f64,
    ap: f64,
    t1: f64,
    t2: f64,
    t3: f64,
}

impl Stop {
    /// The profile, or `None` when the speed would reach zero before the deceleration is
    /// released (the state cannot stop without reversing).
    fn new(v: f64, a: f64, amax: f64, jmax: f64) -> Option<Stop> {
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

    fn duration(&self) -> f64 {
        self.t1 + self.t2 + self.t3
    }

    /// (position, speed, acceleration) at time t from the start (clamped at the end).
    fn at(&self, t: f64) -> (f64, f64, f64) {
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

    fn distance(&self) -> f64 {
        self.at(self.duration()).0
    }

    /// Peak speed (reached when a positive initial acceleration has been ramped down).
    fn peak(&self) -> f64 {
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
    fn under_kind(&self, x: f64, c: f64) -> (Option<bool>, f64) {
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
    fn time_at(&self, x: f64) -> f64 {
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

/// Root of `pos(t) = x` on `[lo, hi]` for a non-decreasing position with derivative `vel`
/// (`f(t)` returns both), from a first guess: safeguarded Newton, falling back to bisection
/// when a step leaves the bracket. Converges to the last few ULP; the same answer as a
/// 60-step bisection in a few evaluations.
#[inline]
fn solve_monotone(
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

/// Shortest distance to bring the speed from (v, a) down to c with zero final
/// acceleration (§6.3 "brake_dist").
fn brake_dist(v: f64, a: f64, c: f64, amax: f64, jmax: f64) -> f64 {
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

/// The interior maximum of the speed during a cycle of jerk j from (v, a) when the
/// acceleration turns from positive to negative inside it: (time, speed).
fn interior_peak(v: f64, a: f64, j: f64, t: f64) -> Option<(f64, f64)> {
    (a > 0.0 && a + j * t < 0.0).then(|| (-a / j, v - a * a / (2.0 * j)))
}

/// One cycle of constant jerk from (v, a): (Δs, v', a') after time τ.
fn step(v: f64, a: f64, j: f64, tau: f64) -> (f64, f64, f64) {
    (
        v * tau + a * tau * tau / 2.0 + j * tau.powi(3) / 6.0,
        v + a * tau + j * tau * tau / 2.0,
        a + j * tau,
    )
}

/// Blocks (and postures) per chunk of the look-ahead skip tables.
const CHUNK: usize = 16;

/// Minima of ā (blocks) and the ceilings (postures) over chunks of [`CHUNK`] entries, so
/// that the look-ahead scans skip whole chunks that cannot bind. The minima are exact, so
/// the scans give the same answers as visiting every entry.
///
/// Also, per block, the next block with a strictly lower ā (and j̄): the minimum over a run
/// of blocks from k is the last block of that chain inside the run, so `limits_over` hops
/// over the records instead of visiting every block.
struct Chunks {
    abar: Vec<f64>,
    ceil: Vec<f64>,
    next_lower_a: Vec<u32>,
    next_lower_j: Vec<u32>,
}

/// For every index, the next index with a strictly lower value (`x.len()` if none).
fn next_lower(x: &[f64]) -> Vec<u32> {
    let mut out = vec![x.len() as u32; x.len()];
    let mut stack: Vec<usize> = Vec::new();
    for (i, &xi) in x.iter().enumerate() {
        while let Some(&top) = stack.last() {
            if xi < x[top] {
                out[top] = i as u32;
                stack.pop();
            } else {
                break;
            }
        }
        stack.push(i);
    }
    out
}

impl Chunks {
    fn new(b: &Blocks) -> Chunks {
        let mins = |x: &[f64]| -> Vec<f64> {
            x.chunks(CHUNK)
                .map(|c| c.iter().copied().fold(f64::INFINITY, f64::min))
                .collect()
        };
        Chunks {
            abar: mins(&b.abar),
            ceil: mins(&b.ceil),
            next_lower_a: next_lower(&b.abar),
            next_lower_j: next_lower(&b.jbar),
        }
    }
}

struct Sim<'b> {
    b: &'b Blocks,
    ch: &'b Chunks,
    cycle: f64,
    lookahead: usize,
    /// Last block of the segment being planned (exclusive).
    end: usize,
    /// Find the boundary jerk by the plain bisection (the reference of the tests).
    bisect_only: bool,
}

/// How acceptable a next state is.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Debug)]
enum Tier {
    Rejected = 0,
    Feasible = 1,
    Releasable = 2,
}

/// The interpolator's state at the start of a cycle: block k, path position s, speed v,
/// acceleration a.
#[derive(Clone, Copy, Debug)]
struct State {
    k: usize,
    s: f64,
    v: f64,
    a: f64,
}

/// What a caller of [`Sim::evaluate`] needs to know.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Need {
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
struct Bind {
    /// A constraint without a slack function was violated (the search bisects).
    other: bool,
    /// The speed inside the step against the lowest v̄ of the step's blocks.
    step_speed: bool,
    /// The speed at the crossing of posture p during the step against its ceiling.
    crossing: Option<usize>,
    /// The stop's end against the end of the look-ahead window or of the segment.
    window: bool,
    /// The peak speed ahead against v̄ of the blocks m0..=m1 that it reaches.
    peak: Option<(usize, usize)>,
    /// The full stop passing postures p0..=p1 under their ceilings.
    under: Option<(usize, usize)>,
    /// Braking to the ceilings of postures p0..=p1 with zero acceleration before them
    /// (releasable).
    release: Option<(usize, usize)>,
}

/// Widen an index range to include `i`.
fn widen(r: Option<(usize, usize)>, i: usize) -> Option<(usize, usize)> {
    Some(r.map_or((i, i), |(a, b)| (a.min(i), b.max(i))))
}

/// The constraints (and stop limits) that bounded the last cycle's jerk from above, for
/// the next cycle's [`Sim::follow_hint`].
type Hint = Option<(Bind, (f64, f64))>;

/// The jerk [`Sim::choose`] takes for a cycle.
struct Choice {
    j: f64,
    /// No candidate was acceptable: `j` is the least-violating jerk.
    fell: bool,
    /// `j` was found by the boundary search between two candidates.
    searched: bool,
    /// The constraints that bound `j`, for the next cycle.
    hint: Hint,
    /// Length of the stop profile from the next state, when `j` was evaluated in full
    /// (`NAN` otherwise): it tells [`Sim::run`] whether the final stop is due.
    dist: f64,
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

/// The verdict of [`Sim::evaluate`]: the tier, the constraints that keep the state below
/// the tier asked for, and the limits (A, J) of the state's stop profile.
#[derive(Clone, Copy, Debug)]
struct Eval {
    tier: Tier,
    bind: Bind,
    lim: (f64, f64),
    /// Length of the stop profile from the state (`NAN` when the evaluation stopped
    /// before building it).
    dist: f64,
}

impl Eval {
    fn rejected(bind: Bind, lim: (f64, f64)) -> Eval {
        Eval {
            tier: Tier::Rejected,
            bind,
            lim,
            dist: f64::NAN,
        }
    }
}

impl Sim<'_> {
    /// Block containing s, searching forward from `k` (never past `end − 1`).
    fn block_at(&self, mut k: usize, s: f64) -> usize {
        while k + 1 < self.end && self.b.start[k + 1] <= s {
            k += 1;
        }
        k
    }

    /// Minimum ā and j̄ over blocks covering [s, s + d], from block k: the last records of
    /// the next-lower chains from k that start before s + d.
    fn limits_over(&self, k: usize, s: f64, d: f64) -> (f64, f64) {
        let b = self.b;
        let lim = s + d;
        let last = |next: &[u32]| {
            let mut m = k;
            loop {
                let nx = next[m] as usize;
                if nx >= self.end || b.start[nx] >= lim {
                    return m;
                }
                m = nx;
            }
        };
        (
            b.abar[last(&self.ch.next_lower_a)],
            b.jbar[last(&self.ch.next_lower_j)],
        )
    }

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

    fn min_vbar(&self, k0: usize, k1: usize) -> f64 {
        self.b.vbar[k0..=k1]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }

    /// End of the look-ahead window seen from block k.
    fn window_end(&self, k: usize) -> f64 {
        if self.lookahead == 0 {
            self.b.start[self.end]
        } else {
            self.b.start[(k + self.lookahead + 1).min(self.end)]
        }
    }

    /// The full-stop profile from (v, a) at s in block k, with A and J over the blocks it
    /// covers (iterated twice), both scaled by `margin`.
    fn stop_from(&self, k: usize, s: f64, v: f64, a: f64, margin: f64) -> Option<Stop> {
        let (mut am, mut jm) = (self.b.abar[k], self.b.jbar[k]);
        let mut prof = Stop::new(v, a, am * margin, jm * margin)?;
        for _ in 0..2 {
            let (a2, j2) = self.limits_over(k, s, COVER * prof.distance() + v * self.cycle);
            if a2 >= am && j2 >= jm {
                break;
            }
            am = a2;
            jm = j2;
            prof = Stop::new(v, a, am * margin, jm * margin)?;
        }
        Some(prof)
    }

    /// Classify the state after one cycle of jerk j from (s, v, a) in block k, and name the
    /// constraints that keep it below the tier asked for (see [`Eval`]). `need` says what
    /// the caller asks: [`Need::Classify`] and [`Need::Releasable`] compute the full tier,
    /// [`Need::Feasible`] skips the releasability tests.
    fn evaluate(&self, st: State, j: f64, need: Need) -> Eval {
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
        let Some(prof) = self.stop_from(k1, s1, v1, a1, MARGIN) else {
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
            if p % CHUNK == 0 {
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
    fn slack(&self, st: State, j: f64, bind: Bind, lim: Option<(f64, f64)>) -> f64 {
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
            None => self.stop_from(k1, s1, v1, a1, MARGIN),
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
    fn choose(&self, st: State, hint: Hint) -> Choice {
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
        if let Some(h) = hint.filter(|_| !self.bisect_only) {
            if let Some(c) = self.follow_hint(st, &cands, h) {
                return c;
            }
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

/// Brent's method (zeroin: inverse quadratic interpolation, secant and bisection steps)
/// for a root of f on a bracket with f(g) ≥ 0 > f(b). Returns the end of the final
/// bracket where f ≥ 0; the bracket is then at most `tol` wide.
fn brent(g: f64, fg: f64, b: f64, fb: f64, tol: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
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

/// Highest speed reached from (v, a > 0) when the acceleration is ramped down at −J in
/// whole cycles of length T, the last one with the jerk −a/T that ends at a = 0. It is the
/// discrete counterpart of v + a²/(2J), never lower, so that a greedy interpolator can
/// settle exactly on a speed cap instead of oscillating around it.
fn peak_discrete(v: f64, a: f64, jm: f64, t: f64) -> f64 {
    if a <= 0.0 {
        return v;
    }
    let n = (a / (jm * t)).floor();
    let r = a - n * jm * t;
    v + n * n * jm * t * t / 2.0 + n * r * t + r * t / 2.0
}

/// Largest jerk j in [j_lo, j_hi] such that, after one cycle, the discrete peak speed is
/// ≤ vcap (`NEG_INFINITY` if none).
fn jerk_cap(v: f64, a: f64, t: f64, jm: f64, vcap: f64, j_lo: f64, j_hi: f64) -> f64 {
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

/// Duration of a jerk-limited rest-to-rest move over distance d (speed ≤ vmax): the
/// speed-up mirrors the stop profile from the peak speed.
fn rest_to_rest(d: f64, vmax: f64, amax: f64, jmax: f64) -> f64 {
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

/// Time τ in [0, T] at which a constant-jerk step from (v, a) has advanced by x.
fn crossing_time(v: f64, a: f64, j: f64, t: f64, x: f64) -> f64 {
    // First guess: at the start speed (exact for a constant speed).
    solve_monotone(0.0, t, if v > 0.0 { x / v } else { 0.5 * t }, x, |tau| {
        let (ds, vs, _) = step(v, a, j, tau);
        (ds, vs)
    })
}

/// Level 2 (§6.3): jerk-limited look-ahead interpolator at the cycle time. Exact stops
/// (zero ceilings) split the path into rest-to-rest segments.
pub fn plan_jerk(b: &Blocks, cycle_time: f64, lookahead_blocks: usize) -> Timing {
    plan_jerk_with(b, cycle_time, lookahead_blocks, false)
}

/// [`plan_jerk`], optionally with the plain bisection for the boundary jerk.
fn plan_jerk_with(
    b: &Blocks,
    cycle_time: f64,
    lookahead_blocks: usize,
    bisect_only: bool,
) -> Timing {
    let n = b.n();
    let np = n + 1;
    let mut out = Timing {
        t: vec![0.0; np],
        v: vec![0.0; np],
        block_peak: vec![0.0; n],
        ..Default::default()
    };
    if n == 0 {
        return out;
    }
    // Segment ends: the path ends, exact stops, and ceilings below the speed change of one
    // cycle at the incoming block's jerk (j̄ T²). Braking to such a ceiling needs a phase
    // switch inside a cycle, which a constant jerk per cycle cannot follow; a stop there
    // costs less than a cycle and is planned in closed form like the path end.
    let mut cuts = vec![0];
    for p in 1..n {
        let c = b.ceil[p];
        if c <= b.jbar[p - 1] * cycle_time * cycle_time {
            cuts.push(p);
        }
    }
    cuts.push(n);
    // The segments start and end at rest, so they are planned apart (in parallel), each
    // from time 0, and then put end to end.
    let ch = Chunks::new(b);
    let mut segs = Vec::with_capacity(cuts.len() - 1);
    {
        let (mut t, mut v, mut peak) = (&mut out.t[1..], &mut out.v[1..], &mut out.block_peak[..]);
        for w in cuts.windows(2) {
            let len = w[1] - w[0];
            let (ts, tr) = std::mem::take(&mut t).split_at_mut(len);
            let (vs, vr) = std::mem::take(&mut v).split_at_mut(len);
            let (ps, pr) = std::mem::take(&mut peak).split_at_mut(len);
            (t, v, peak) = (tr, vr, pr);
            segs.push((
                w[1],
                SegOut {
                    k0: w[0],
                    t: ts,
                    v: vs,
                    peak: ps,
                    cycles: 0,
                    fallbacks: 0,
                    searches: 0,
                    stop_recoveries: 0,
                    max_axis_ratio: 0.0,
                },
            ));
        }
    }
    let durations: Vec<f64> = segs
        .par_iter_mut()
        .map(|(end, seg)| {
            let sim = Sim {
                b,
                ch: &ch,
                cycle: cycle_time,
                lookahead: lookahead_blocks,
                end: *end,
                bisect_only,
            };
            sim.run(seg)
        })
        .collect();
    let mut t0 = 0.0;
    for ((_, seg), d) in segs.iter_mut().zip(&durations) {
        if t0 != 0.0 {
            seg.t.iter_mut().for_each(|t| *t += t0);
        }
        t0 += d;
        out.cycles += seg.cycles;
        out.fallbacks += seg.fallbacks;
        out.searches += seg.searches;
        out.stop_recoveries += seg.stop_recoveries;
        out.max_axis_ratio = out.max_axis_ratio.max(seg.max_axis_ratio);
    }
    drop(segs);
    out.total = out.t[n];
    // Self-check at the postures.
    for p in 0..np {
        let c = b.ceil[p];
        let r = if c > 0.0 {
            out.v[p] / c
        } else if out.v[p] > 0.0 {
            f64::INFINITY
        } else {
            0.0
        };
        out.max_ceiling_ratio = out.max_ceiling_ratio.max(r);
    }
    out
}

/// What one segment of [`plan_jerk`] writes: postures k0+1..=end (time from the
/// segment's start, speed), blocks k0..end (peak speed), and its counters.
struct SegOut<'a> {
    k0: usize,
    t: &'a mut [f64],
    v: &'a mut [f64],
    peak: &'a mut [f64],
    cycles: usize,
    fallbacks: usize,
    searches: usize,
    stop_recoveries: usize,
    max_axis_ratio: f64,
}

impl SegOut<'_> {
    /// Record posture p (k0 < p ≤ end).
    fn put(&mut self, p: usize, t: f64, v: f64) {
        self.t[p - self.k0 - 1] = t;
        self.v[p - self.k0 - 1] = v;
    }

    /// Time recorded at posture p (0 at k0, the segment's start).
    fn t(&self, p: usize) -> f64 {
        if p == self.k0 {
            0.0
        } else {
            self.t[p - self.k0 - 1]
        }
    }
}

impl Sim<'_> {
    /// Simulate the segment of blocks [k0, end), starting at rest at time 0. Returns the
    /// end time.
    fn run(&self, out: &mut SegOut) -> f64 {
        let k0 = out.k0;
        let t0 = 0.0;
        let b = self.b;
        let cyc = self.cycle;
        let s_end = b.start[self.end];
        let seg_len = s_end - b.start[k0];
        let eps = 1e-9 * seg_len;
        let (mut s, mut v, mut a, mut t) = (b.start[k0], 0.0f64, 0.0f64, t0);
        let mut k = k0;
        let mut next = k0 + 1; // next posture to record
        // Guard against a creeping simulation: far more cycles than any sane plan needs.
        let l1 = {
            let mut tmin = 0.0;
            for m in k0..self.end {
                tmin += b.len[m] / b.vbar[m];
            }
            tmin
        };
        let max_cycles = (50.0 * l1 / cyc) as usize + 100_000;
        let mut cycles = 0usize;
        let mut prev: Option<(f64, f64, f64, f64, usize, usize)> = None;
        let mut hint: Hint = None;
        let mut stop_dist = f64::NAN;
        loop {
            k = self.block_at(k, s);
            // Final stop in closed form when the path end lies in the window and is due
            // (not while the stop from here, known from the last cycle's evaluation, ends
            // short of it).
            let rem = s_end - s;
            let due_maybe = stop_dist.is_nan() || stop_dist >= rem - eps || cycles >= max_cycles;
            if self.window_end(k) >= s_end && due_maybe {
                let prof = self.stop_from(k, s, v, a, 1.0);
                let due = if MARGIN == 1.0 {
                    prof
                } else {
                    self.stop_from(k, s, v, a, MARGIN)
                };
                if let (Some(check), Some(prof)) = (due, prof) {
                    let d = prof.distance();
                    if check.distance() >= rem - eps || cycles >= max_cycles {
                        if cycles >= max_cycles {
                            out.fallbacks += 1;
                        }
                        let gap = (rem - d).max(0.0);
                        let tg = if gap > 0.0 && v > 0.0 { gap / v } else { 0.0 };
                        while next < self.end {
                            let x = b.start[next] - s;
                            let (tt, vv) = if x <= gap {
                                (if gap > 0.0 { tg * x / gap } else { 0.0 }, v)
                            } else {
                                let tp = prof.time_at(x - gap);
                                (tg + tp, prof.at(tp).1)
                            };
                            out.put(next, t + tt, vv.max(0.0));
                            next += 1;
                        }
                        let tend = t + tg + prof.duration();
                        let tend = tend.max(out.t(self.end - 1));
                        out.put(self.end, tend, 0.0);
                        self.sample(k, v, a, 0.0, out);
                        out.cycles += cycles;
                        return tend;
                    }
                }
            }
            let Choice {
                j,
                fell,
                searched,
                hint: next_hint,
                dist,
            } = self.choose(State { k, s, v, a }, hint);
            hint = next_hint;
            stop_dist = if fell { f64::NAN } else { dist };
            out.searches += usize::from(searched);
            if fell {
                if let Some((ps, 0.0, 0.0, pt, pnext, pk)) = prev {
                    // Stuck at rest: a rest-to-rest move to the end of the block, in closed
                    // form, then on from rest.
                    let end_s = b.start[pk + 1];
                    let dt = rest_to_rest(end_s - ps, b.vbar[pk], b.abar[pk], b.jbar[pk]);
                    next = pnext;
                    while next <= pk + 1 && next < self.end {
                        out.put(next, pt + dt, 0.0);
                        next += 1;
                    }
                    s = end_s;
                    t = pt + dt;
                    v = 0.0;
                    a = 0.0;
                    out.stop_recoveries += 1;
                    cycles += 1;
                    prev = None;
                    continue;
                }
                if let Some((ps, pv, pa, pt, pnext, pk)) = prev.take() {
                    // The last state was feasible but has no feasible successor: it rode
                    // the full-stop boundary into a phase switch inside a cycle. Its stop
                    // manoeuvre is admissible by construction, so run it in closed form
                    // from the last state and restart from rest.
                    if let Some(prof) = self.stop_from(pk, ps, pv, pa, MARGIN) {
                        next = pnext;
                        while next < self.end && b.start[next] <= ps + prof.distance() {
                            let tp = prof.time_at(b.start[next] - ps);
                            out.put(next, pt + tp, prof.at(tp).1.max(0.0));
                            next += 1;
                        }
                        s = ps + prof.distance();
                        t = pt + prof.duration();
                        v = 0.0;
                        a = 0.0;
                        out.stop_recoveries += 1;
                        cycles += 1;
                        continue;
                    }
                }
                out.fallbacks += 1;
            }
            prev = Some((s, v, a, t, next, k));
            let (ds, v1, a1) = step(v, a, j, cyc);
            let s1 = (s + ds).min(s_end);
            // Record postures crossed during the cycle.
            while next < self.end && b.start[next] <= s1 {
                let tau = crossing_time(v, a, j, cyc, b.start[next] - s);
                let (_, vc, ac) = step(v, a, j, tau);
                out.put(next, t + tau, vc.max(0.0));
                self.sample(next, vc, ac, j, out);
                next += 1;
            }
            // Self-check samples inside the cycle.
            for q in 1..=4 {
                let tau = cyc * q as f64 / 4.0;
                let (dq, vq, aq) = step(v, a, j, tau);
                let kq = self.block_at(k, (s + dq).min(s_end));
                self.sample(kq, vq, aq, j, out);
            }
            s = s1;
            v = v1.max(0.0);
            a = a1;
            t += cyc;
            cycles += 1;
        }
    }

    /// Record a state sample in block k for the self-check and the block's peak speed.
    fn sample(&self, k: usize, v: f64, a: f64, j: f64, out: &mut SegOut) {
        let k = k.min(self.end - 1);
        let b = self.b;
        let rv = v / b.vaxis[k];
        let ra = a.abs() / b.abar[k];
        let rj = j.abs() / b.jbar[k];
        out.max_axis_ratio = out.max_axis_ratio.max(rv).max(ra).max(rj);
        let peak = &mut out.peak[k - out.k0];
        if v > *peak {
            *peak = v;
        }
    }
}

/// The limiting constraint of the block starting at each posture (the last posture: stop).
pub fn limits_per_posture(b: &Blocks, timing: &Timing, lookahead_blocks: usize) -> Vec<Limit> {
    let n = b.n();
    let mut out = Vec::with_capacity(n + 1);
    for p in 0..=n {
        if p == n {
            out.push(Limit::Stop);
            continue;
        }
        let v = timing.v[p];
        let c = b.ceil[p];
        let lim = if p > 0 && b.ceil_junction[p] && v >= 0.999 * c && c > 0.0 {
            Limit::Junction
        } else if timing.block_peak[p] >= 0.999 * b.vbar[p] {
            b.vbar_by[p]
        } else if lookahead_blocks > 0 {
            Limit::Lookahead
        } else {
            Limit::Ramp(b.jbar_by[p])
        };
        out.push(lim);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

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
        let settings = super::super::Settings {
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

    #[test]
    fn next_lower_chains_give_range_minima() {
        let x = [5.0, 3.0, 4.0, 3.0, 1.0, 2.0, 2.0, 0.5, 7.0];
        let next = next_lower(&x);
        assert_eq!(next, vec![1, 4, 3, 4, 7, 7, 7, 9, 9]);
        for k in 0..x.len() {
            for end in k..x.len() {
                let mut m = k;
                while (next[m] as usize) <= end {
                    m = next[m] as usize;
                }
                let want = x[k..=end].iter().copied().fold(f64::INFINITY, f64::min);
                assert_eq!(x[m], want, "{k}..={end}");
            }
        }
    }

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
    fn jerk_cap_hits_the_cap() {
        let (t, jm, vcap) = (0.003, 40000.0, 83.0);
        for &(v, a) in &[(82.8, 0.0), (82.0, 200.0), (82.95, -30.0)] {
            let j = jerk_cap(v, a, t, jm, vcap, -jm, jm);
            let (_, v1, a1) = step(v, a, j, t);
            assert_relative_eq!(peak_discrete(v1, a1, jm, t), vcap, max_relative = 1e-9);
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
