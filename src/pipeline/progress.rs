//! What a long pipeline run reports while it works: each phase as it begins (reading,
//! deriving contact points, resampling, simulating), then the steps done out of a total
//! known when the counting starts. Nothing here draws; the command line draws a bar.

/// Receives a pipeline's progress. Every method has a silent default.
pub trait Progress: Sync {
    /// A phase begins; its steps are counted in `unit` (nothing is counted when the phase
    /// cannot be, e.g. reading a file).
    fn phase(&self, _name: &str, _unit: &str) {}
    /// `done` of `total` steps of the current phase are done (`total` 0: unknown).
    fn advance(&self, _done: u64, _total: u64) {}
}

/// No progress reported.
pub struct Silent;

impl Progress for Silent {}
