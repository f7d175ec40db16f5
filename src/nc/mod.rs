//! The machine's own program: 5-axis ISO G-code read through the forward kinematics of a
//! `machine.toml` into postures, and postures written as G-code through its inverse
//! kinematics (`grammars/gcode.ebnf`).
//!
//! Reading ([`NcReader`]) keeps the modal state of the NC (motion G0/G1/G2/G3, plane
//! G17/G18/G19, G90/G91, G20/G21, G93/G94/G95, F, S with M3/M4/M5, tool changes) and turns
//! every block that moves into a CL record for [`crate::toolpath::Lowerer`], so G-code
//! gives the same [`crate::toolpath::Program`] as a CLSF would: tip and axis in the part
//! frame, arcs, feeds in mm/min at the tool tip.
//!
//! - Tool-centre-point control on (`G43.4`, `TRAORI`, `M128`, or [`Rtcp::On`]): X Y Z are the
//!   tool tip in the part frame; the rotary words (the machine's axis names, degrees)
//!   give the tool axis through the rotary chain. `G49`, `TRAFOOF`, `M129` switch it off.
//! - Off: X Y Z and the rotary words are joint positions; the full forward kinematics
//!   (with the tool length in `tip_home`) gives tip and axis.
//!
//! The feed of a move at the tool tip: with TCP on, F itself (per minute, G94) or the tip
//! length times F (inverse time, G93); with TCP off under G94, the NC spends
//! `√(Σ Δlinear² + Σ Δrotary_deg²) / F` on the block, and the tip feed is the tip length
//! over that time. Between blocks crest moves the tip as it moves CL points (straight, or
//! on the arc, the axis turning evenly), not along the joint interpolation of a TCP-off
//! move with rotary motion.
//!
//! Writing ([`GcodeWriter`]) solves every posture with [`crate::kinematics::IkTracker`]
//! (branch kept, rotaries unwound) and prints joints with up to nine decimals, so the
//! program reads back to the same postures within 1e-9 mm.

pub mod read;
pub mod write;

pub use read::NcReader;
pub use write::GcodeWriter;

use crate::kinematics::Machine;

/// Tool-centre-point control (RTCP, TCPM, TRAORI); also the command line's values (the
/// variants' lines are their help).
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
pub enum Rtcp {
    /// As the program says (`G43.4`, `TRAORI`, `M128` on; `G49`, `TRAFOOF`, `M129` off).
    #[default]
    Auto,
    /// On throughout: X Y Z are the tool tip in the part frame.
    On,
    /// Off throughout: X Y Z are joint positions.
    Off,
}

/// Why a machine's joints cannot be G-code addresses.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LetterError {
    /// A joint name that is not one address letter.
    #[error("machine axis `{0}` is not a G-code address letter (X, Y, Z, A, B, C, U, V, W, …)")]
    NotALetter(String),
    /// The linear joints are not X, Y and Z.
    #[error("the machine's linear axes are {}, {}, {}: G-code needs X, Y and Z", .0[0] as char, .0[1] as char, .0[2] as char)]
    Linear([u8; 3]),
    /// The two rotary joints share a letter or use a linear one.
    #[error("the machine's rotary axes {} and {} need two letters of their own", *.0 as char, *.1 as char)]
    Rotary(u8, u8),
}

/// The address letters of the machine's five joints (linear X Y Z in the machine file's
/// order, then the rotary axes), or what is wrong with their names.
pub fn joint_letters(machine: &Machine) -> Result<[u8; 5], LetterError> {
    let mut out = [0u8; 5];
    for (k, name) in machine.joint_names().iter().enumerate() {
        let b = name.as_bytes();
        let ok = b.len() == 1
            && b[0].is_ascii_alphabetic()
            && !b"DEFGHIJKLMNOPQRST".contains(&b[0].to_ascii_uppercase());
        if !ok {
            return Err(LetterError::NotALetter(name.to_string()));
        }
        out[k] = b[0].to_ascii_uppercase();
    }
    let mut lin = [out[0], out[1], out[2]];
    lin.sort_unstable();
    if lin != *b"XYZ" {
        return Err(LetterError::Linear([out[0], out[1], out[2]]));
    }
    if out[3] == out[4] || b"XYZ".contains(&out[3]) || b"XYZ".contains(&out[4]) {
        return Err(LetterError::Rotary(out[3], out[4]));
    }
    Ok(out)
}
