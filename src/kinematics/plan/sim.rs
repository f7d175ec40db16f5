//! The Level 2 simulator of one segment ([`Sim`]), its state, and its look-ahead queries:
//! the block at a position, the end of the window, the limits over a distance and the
//! full-stop profile from a state.

use super::skip::Chunks;
use super::stop::Stop;
use crate::kinematics::blocks::Blocks;

/// The limits of a stop profile are the minimum over the blocks within this multiple of
/// its distance (plus one cycle of travel). With exactly its distance (factor 1), a
/// profile that ends just before a block with a lower jerk limit is feasible, the next
/// one that reaches into it by a hair is not, and the interpolator is caught braking too
/// late; looking half a stop further makes the switch happen while there is room.
const COVER: f64 = 1.5;

/// The Level 2 interpolator over one segment of the blocks.
pub(super) struct Sim<'b> {
    pub(super) b: &'b Blocks,
    pub(super) ch: &'b Chunks,
    /// The interpolation cycle T, s.
    pub(super) cycle: f64,
    /// Look-ahead window in blocks (0: the whole segment).
    pub(super) lookahead: usize,
    /// Last block of the segment being planned (exclusive).
    pub(super) end: usize,
    /// Find the boundary jerk by the plain bisection (the reference of the tests).
    pub(super) bisect_only: bool,
}

/// The interpolator's state at the start of a cycle: block k, path position s, speed v,
/// acceleration a.
#[derive(Clone, Copy, Debug)]
pub(super) struct State {
    pub(super) k: usize,
    pub(super) s: f64,
    pub(super) v: f64,
    pub(super) a: f64,
}

impl Sim<'_> {
    /// Block containing s, searching forward from `k` (never past `end − 1`).
    pub(super) fn block_at(&self, mut k: usize, s: f64) -> usize {
        while k + 1 < self.end && self.b.start[k + 1] <= s {
            k += 1;
        }
        k
    }

    /// Minimum ā and j̄ over blocks covering [s, s + d], from block k: the last records of
    /// the next-lower chains from k that start before s + d.
    pub(super) fn limits_over(&self, k: usize, s: f64, d: f64) -> (f64, f64) {
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

    pub(super) fn min_vbar(&self, k0: usize, k1: usize) -> f64 {
        self.b.vbar[k0..=k1]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }

    /// End of the look-ahead window seen from block k.
    pub(super) fn window_end(&self, k: usize) -> f64 {
        if self.lookahead == 0 {
            self.b.start[self.end]
        } else {
            self.b.start[(k + self.lookahead + 1).min(self.end)]
        }
    }

    /// The full-stop profile from (v, a) at s in block k, with A and J over the blocks it
    /// covers (iterated twice). The profile uses the full limits, as the moves themselves:
    /// rather than a margin, the tests of [`Sim::evaluate`] are ones that a state's
    /// successors can keep passing by following its stop profile, and the few states left
    /// without a feasible successor run that profile in closed form (see [`Sim::run`]).
    pub(super) fn stop_from(&self, k: usize, s: f64, v: f64, a: f64) -> Option<Stop> {
        let (mut am, mut jm) = (self.b.abar[k], self.b.jbar[k]);
        let mut prof = Stop::new(v, a, am, jm)?;
        for _ in 0..2 {
            let (a2, j2) = self.limits_over(k, s, COVER * prof.distance() + v * self.cycle);
            if a2 >= am && j2 >= jm {
                break;
            }
            am = a2;
            jm = j2;
            prof = Stop::new(v, a, am, jm)?;
        }
        Some(prof)
    }
}
