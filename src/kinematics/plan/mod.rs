//! Velocity planning along the blocks (kinematics.md §6): Level 1, the exact
//! acceleration-limited look-ahead (`plan_acc_only`), and Level 2, the jerk-limited
//! look-ahead interpolator simulated at the NC cycle time (`plan_jerk`, "Eq 4").
//!
//! Level 2 is a greedy choice of a constant jerk per cycle: the largest jerk whose next
//! state is *feasible* (the full-stop manoeuvre from it stays under every ceiling ahead and
//! ends before the path end and the look-ahead window) and, if possible, *releasable*
//! (every ceiling ahead can still be met with zero acceleration). The final stop is appended
//! in closed form. The stop profiles are evaluated in closed form, not by integration.
//!
//! The stage's files, one concept each:
//!
//! - `level1`: Level 1;
//! - `stop`: the closed-form stop and brake profiles, the rest-to-rest move;
//! - `cycle`: one cycle of constant jerk (crossing times, the discrete peak, the jerk
//!   that keeps it under a cap);
//! - `root`: the root finders (safeguarded Newton, Brent);
//! - `skip`: the look-ahead skip tables (chunk minima, next-lower chains);
//! - `sim`: the Level 2 simulator of one segment, its state and its look-ahead queries;
//! - `feasible`: the verdict on a next state (its tier) and the slack of its constraints;
//! - `search`: the jerk of a cycle (candidates, boundary search, hints, replay);
//! - `segment`: cutting the path into rest-to-rest segments, running each cycle by
//!   cycle in parallel, and putting them end to end.

mod cycle;
mod feasible;
mod level1;
mod root;
mod search;
mod segment;
mod sim;
mod skip;
mod stop;

use super::blocks::{Blocks, Limit};
pub use level1::plan_acc_only;
pub use segment::plan_jerk;

/// Relative slack on speed checks.
const REL: f64 = 1e-9;

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
