//! Which moves cut: the `--moves cut|all` selection, and the counts of postures and groups
//! of each move kind.

use super::{MotionKind, Posture, Program};

/// Which moves count as cutting: they define the reference surface, are simulated, and
/// give the feed of a patch. Also the command line's values (the variants' lines are their
/// help): engage and retract moves (lead-in and lead-out arcs) are in the air or only
/// entering the material, so only cut moves count by default.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Moves {
    /// Only the cut moves (NX colours 31 and 36, or every feed move nothing marks
    /// otherwise).
    #[default]
    Cut,
    /// Every feed move: engage and retract moves too.
    All,
}

impl Moves {
    /// The name at the interface (`cut`, `all`).
    pub fn name(self) -> &'static str {
        match self {
            Moves::Cut => "cut",
            Moves::All => "all",
        }
    }

    /// Whether a move of `kind` cuts under this selection.
    pub fn cuts(self, kind: MotionKind) -> bool {
        match self {
            Moves::Cut => kind == MotionKind::Cut,
            Moves::All => kind.is_feed(),
        }
    }

    /// Relabel one posture for the later stages, which simulate `MotionKind::Cut`: under
    /// [`Moves::All`] every feed move becomes a cut move. Returns whether it changed.
    pub fn relabel(self, p: &mut Posture) -> bool {
        if self == Moves::All && p.motion.is_feed() && p.motion != MotionKind::Cut {
            p.motion = MotionKind::Cut;
            return true;
        }
        false
    }

    /// [`Self::relabel`] every posture of `program`; under [`Moves::All`] the cutting length
    /// of each path becomes the length of its feed moves.
    pub fn apply(self, program: &mut Program) {
        if self == Moves::Cut {
            return;
        }
        for path in &mut program.paths {
            for p in &mut path.postures {
                self.relabel(p);
            }
            path.stats.cutting_length_mm = path.stats.feed_length_mm;
        }
    }
}

/// Postures and groups (maximal runs of consecutive postures of one kind) per move kind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MoveCounts {
    postures: [usize; 9],
    groups: [usize; 9],
    last: Option<MotionKind>,
}

fn index(kind: MotionKind) -> usize {
    match kind {
        MotionKind::From => 0,
        MotionKind::Rapid => 1,
        MotionKind::Approach => 2,
        MotionKind::Engage => 3,
        MotionKind::Cut => 4,
        MotionKind::Retract => 5,
        MotionKind::Departure => 6,
        MotionKind::Cycle => 7,
        MotionKind::GoHome => 8,
    }
}

impl MoveCounts {
    /// Count one posture (in path order).
    pub fn add(&mut self, kind: MotionKind) {
        let k = index(kind);
        self.postures[k] += 1;
        if self.last != Some(kind) {
            self.groups[k] += 1;
        }
        self.last = Some(kind);
    }

    /// Postures of `kind`.
    pub fn postures(&self, kind: MotionKind) -> usize {
        self.postures[index(kind)]
    }

    /// Groups of consecutive postures of `kind`.
    pub fn groups(&self, kind: MotionKind) -> usize {
        self.groups[index(kind)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_are_runs_of_one_kind() {
        use MotionKind::*;
        let mut c = MoveCounts::default();
        for k in [
            Rapid, Approach, Engage, Cut, Cut, Retract, Approach, Engage, Cut,
        ] {
            c.add(k);
        }
        assert_eq!((c.postures(Cut), c.groups(Cut)), (3, 2));
        assert_eq!((c.postures(Approach), c.groups(Approach)), (2, 2));
        assert_eq!(c.postures(Departure), 0);
        assert!(Moves::All.cuts(Engage) && !Moves::Cut.cuts(Engage) && !Moves::All.cuts(Rapid));
    }
}
