//! The Level 2 segment runner: the path cut at exact stops into rest-to-rest segments,
//! each simulated cycle by cycle (final stop and recoveries in closed form) in parallel,
//! then put end to end.

use super::Timing;
use super::cycle::{crossing_time, step};
use super::search::{Choice, Hint};
use super::sim::{Sim, State};
use super::skip::Chunks;
use super::stop::rest_to_rest;
use crate::kinematics::blocks::Blocks;
use rayon::prelude::*;

/// Level 2 (§6.3): jerk-limited look-ahead interpolator at the cycle time. Exact stops
/// (zero ceilings) split the path into rest-to-rest segments.
pub fn plan_jerk(b: &Blocks, cycle_time: f64, lookahead_blocks: usize) -> Timing {
    plan_jerk_with(b, cycle_time, lookahead_blocks, false)
}

/// [`plan_jerk`], optionally with the plain bisection for the boundary jerk.
pub(super) fn plan_jerk_with(
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
            if self.window_end(k) >= s_end
                && due_maybe
                && let Some(prof) = self.stop_from(k, s, v, a)
            {
                let d = prof.distance();
                if d >= rem - eps || cycles >= max_cycles {
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
                    if let Some(prof) = self.stop_from(pk, ps, pv, pa) {
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
