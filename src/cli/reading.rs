//! The options of the commands that read tool paths: `--machine` and `--rtcp` for G-code
//! (read through the machine's kinematics), and how they combine with `--feed predicted`.

use crest::io::toolpath::{InputKind, ReadOptions};
use crest::toolpath::LowerOptions;
use std::path::Path;

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

/// The reading options of a file of `kind`: the machine (loaded from `machine`) for
/// G-code, none for CLSF and contact12.
pub fn read_options(
    kind: InputKind,
    lower: LowerOptions,
    machine: Option<&Path>,
    rtcp: crest::nc::Rtcp,
) -> miette::Result<ReadOptions> {
    let machine = match (kind, machine) {
        (InputKind::Gcode, Some(m)) => Some(crest::pipeline::load_machine(m)?),
        _ => None,
    };
    Ok(ReadOptions {
        lower,
        machine,
        rtcp,
    })
}
