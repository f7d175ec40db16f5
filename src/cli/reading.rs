//! The options of the commands that read tool paths: `--machine` and `--rtcp` for G-code
//! (read through the machine's kinematics), and how they combine with `--feed predicted`.

use crest::io::toolpath::{InputKind, ReadOptions};
use crest::toolpath::LowerOptions;
use std::path::Path;

/// The `--rtcp` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum RtcpArg {
    /// As the program says (`G43.4`, `TRAORI`, `M128` on; `G49`, `TRAFOOF`, `M129` off).
    #[default]
    Auto,
    /// On throughout: X Y Z are the tool tip in the part frame.
    On,
    /// Off throughout: X Y Z are joint positions.
    Off,
}

/// The `--moves` values: which moves cut.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum MovesArg {
    /// Only the cut moves (NX colours 31 and 36, or every feed move nothing marks
    /// otherwise).
    #[default]
    Cut,
    /// Every feed move: engage and retract moves too.
    All,
}

impl From<MovesArg> for crest::toolpath::Moves {
    fn from(m: MovesArg) -> Self {
        match m {
            MovesArg::Cut => crest::toolpath::Moves::Cut,
            MovesArg::All => crest::toolpath::Moves::All,
        }
    }
}

/// Postures per move kind as JSON: `{"rapid": n, "approach": n, "engage": n, "cut": n,
/// "retract": n, "departure": n}`.
pub fn moves_json<'a>(
    postures: impl IntoIterator<Item = &'a crest::toolpath::Posture>,
) -> serde_json::Value {
    let mut counts = crest::toolpath::MoveCounts::default();
    for p in postures {
        counts.add(p.motion);
    }
    counts_json(&counts)
}

/// [`moves_json`] of counts already made (a path's `stats.moves`).
pub fn counts_json(counts: &crest::toolpath::MoveCounts) -> serde_json::Value {
    let mut m = serde_json::Map::new();
    for k in crest::toolpath::MotionKind::MOVES {
        m.insert(k.name().to_string(), counts.postures(k).into());
    }
    serde_json::Value::Object(m)
}

impl From<RtcpArg> for crest::nc::Rtcp {
    fn from(r: RtcpArg) -> Self {
        match r {
            RtcpArg::Auto => crest::nc::Rtcp::Auto,
            RtcpArg::On => crest::nc::Rtcp::On,
            RtcpArg::Off => crest::nc::Rtcp::Off,
        }
    }
}

/// The reading options of a file of `kind`: the machine (loaded from `machine`) for
/// G-code, none for CLSF and contact12.
pub fn read_options(
    kind: InputKind,
    lower: LowerOptions,
    machine: Option<&Path>,
    rtcp: RtcpArg,
) -> miette::Result<ReadOptions> {
    let machine = match (kind, machine) {
        (InputKind::Gcode, Some(m)) => Some(crest::pipeline::load_machine(m)?),
        _ => None,
    };
    Ok(ReadOptions {
        lower,
        machine,
        rtcp: rtcp.into(),
    })
}

/// The `--feed` values of `crest resample` and `crest simulate`: which feed drives the
/// clock and the feed per tooth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FeedSource {
    /// The programmed feed (FEDRAT, or `--feed-mm-min`).
    Programmed,
    /// The feed the machine of `--machine` really reaches (`crest feed`: the jerk-limited
    /// interpolator's tool-tip feed).
    Predicted,
}

impl From<FeedSource> for crest::pipeline::simulate::FeedSource {
    fn from(f: FeedSource) -> Self {
        match f {
            FeedSource::Programmed => crest::pipeline::simulate::FeedSource::Programmed,
            FeedSource::Predicted => crest::pipeline::simulate::FeedSource::Predicted,
        }
    }
}
