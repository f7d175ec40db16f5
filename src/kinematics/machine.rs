//! The machine (kinematics.md §3.2): axis chain, axis limits, interpolation cycle and
//! look-ahead, in internal units (mm, rad, s). The `machine.toml` file that describes it is
//! read by `crate::config::machine` ([`Machine::from_toml_str`]).

use crate::math::{Point3, Vec3};

/// Which side of the chain a rotary axis sits on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The axis rotates the part (table).
    Table,
    /// The axis rotates the tool (head).
    Head,
}

/// Velocity, acceleration, jerk limits and following tolerance of one axis, in internal
/// units (mm or rad, per s, s², s³).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Maximum velocity.
    pub vmax: f64,
    /// Maximum acceleration.
    pub amax: f64,
    /// Maximum jerk.
    pub jmax: f64,
    /// Position tolerance e of Eq 3 (mm or rad).
    pub tol: f64,
}

/// A linear axis: displacement of the tool relative to the table along `direction`
/// (times `sign`, −1 when the axis moves the table).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearAxis {
    /// Axis name (`X`, `Y`, `Z`).
    pub name: String,
    /// Unit direction in the machine frame.
    pub direction: Vec3,
    /// +1 or −1.
    pub sign: f64,
    /// Limits in mm/s, mm/s², mm/s³, mm.
    pub limits: Limits,
}

/// A rotary axis (kinematics.md §2.1).
#[derive(Debug, Clone, PartialEq)]
pub struct RotaryAxis {
    /// Axis name (`A`, `B`, `C`).
    pub name: String,
    /// Table or head.
    pub side: Side,
    /// Unit direction at the home configuration, machine frame.
    pub axis: Vec3,
    /// A point on the axis at home, machine frame, mm.
    pub point: Point3,
    /// +1 or −1: the rotation is `sign · angle` about `axis` (right hand).
    pub sign: f64,
    /// Travel limits in rad, `None` for an endless axis.
    pub travel: Option<(f64, f64)>,
    /// Limits in rad/s, rad/s², rad/s³, rad.
    pub limits: Limits,
}

/// Which IKT branch to take at the first posture.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BranchPreference {
    /// The first rotary axis at a non-negative angle (default).
    #[default]
    FirstPositive,
    /// The first rotary axis at a non-positive angle.
    FirstNegative,
}

/// A five-axis machine: three linear axes, two rotary axes, interpolator settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Machine {
    /// Free-text name.
    pub name: String,
    /// Interpolation cycle, s.
    pub cycle_time: f64,
    /// A block lasts at least this many cycles (0 disables the rule).
    pub min_block_cycles: f64,
    /// Look-ahead in blocks (0 = unlimited).
    pub lookahead_blocks: usize,
    /// Apply the junction spacing rule of §5.3.
    pub junction_spacing_rule: bool,
    /// Branch preference at the first posture.
    pub branch: BranchPreference,
    /// Tool axis (tip → holder) at home, machine frame.
    pub dir_home: Vec3,
    /// Tool tip at home (linear axes and head rotaries at 0), machine frame, mm.
    pub tip_home: Point3,
    /// Part-frame origin in the table frame, mm.
    pub part_origin: Vec3,
    /// X, Y, Z in file order.
    pub linear: [LinearAxis; 3],
    /// The two rotary axes: table axes base → part, then head axes base → spindle.
    pub rotary: [RotaryAxis; 2],
}

impl Machine {
    /// The five joint names: linear axes, then rotary axes.
    pub fn joint_names(&self) -> [&str; 5] {
        [
            &self.linear[0].name,
            &self.linear[1].name,
            &self.linear[2].name,
            &self.rotary[0].name,
            &self.rotary[1].name,
        ]
    }

    /// The five joint limits in internal units (mm or rad).
    pub fn joint_limits(&self) -> [Limits; 5] {
        [
            self.linear[0].limits,
            self.linear[1].limits,
            self.linear[2].limits,
            self.rotary[0].limits,
            self.rotary[1].limits,
        ]
    }
}

/// The Table I machine of seed 000 as an AC table–table (kinematics.md §3.2), as TOML.
pub const TABLE_I_AC_TOML: &str = include_str!("../../samples/machines/table1_ac.toml");
