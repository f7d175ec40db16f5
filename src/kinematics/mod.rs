//! Machine kinematics: two-rotary-axis chains, inverse and forward kinematics, and
//! jerk-limited feed planning that predicts the feed the machine really reaches
//! (kinematics.md, seed 000 §2.1).
//!
//! The programmed feed is seldom the real one: axis velocity, acceleration and jerk
//! limits, the interpolation cycle and the path tolerance slow the machine down, most of
//! all on dense 5-axis output where the rotary axes move fast. The stage works in four
//! steps, each a module:
//!
//! - [`machine`]: the machine file (`machine.toml`) with its units checked;
//! - [`chain`]: inverse kinematics posture by posture (branch-continuous, unwound,
//!   singularities kept at the previous value) and forward kinematics;
//! - [`blocks`]: per-block limits in the path parameter s and junction ceilings (§4–§5);
//! - [`plan`]: Level 1 (acceleration-limited, exact) and Level 2 (jerk-limited look-ahead
//!   interpolator at the cycle time, "Eq 4").
//!
//! The feed at the CL point (Eq 6) is rebuilt from the joint velocities by a central
//! difference of the forward kinematics. The stage does not know tools: feed per tooth is
//! left to the caller.

pub mod blocks;
pub mod chain;
pub mod machine;
pub mod plan;

pub use blocks::{Blocks, Limit, Settings};
pub use chain::{IkFailure, IkTracker, Joints, Pose};
pub use machine::Machine;
pub use plan::Timing;
use rayon::prelude::*;

use crate::math::{Point3, Vec3};
use crate::toolpath::{MotionKind, Toolpath};

/// Why a path could not be planned. Errors name the posture (0-based) and its source line.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum KinematicsError {
    /// The tool axis cannot be reached by the machine's rotary pair.
    #[error(
        "line {line}: posture {index}: tool axis ({i:.6}, {j:.6}, {k:.6}) is out of reach of the rotary axes"
    )]
    Unreachable {
        /// Posture index.
        index: usize,
        /// Source line.
        line: u32,
        /// Tool axis components.
        i: f64,
        /// Tool axis components.
        j: f64,
        /// Tool axis components.
        k: f64,
    },
    /// Every joint solution violates a rotary travel limit.
    #[error(
        "line {line}: posture {index}: every joint solution is outside the rotary travel limits"
    )]
    Travel {
        /// Posture index.
        index: usize,
        /// Source line.
        line: u32,
    },
    /// A posture has a non-finite position or a zero tool axis.
    #[error("line {line}: posture {index}: position or tool axis is not finite / not a direction")]
    BadPosture {
        /// Posture index.
        index: usize,
        /// Source line.
        line: u32,
    },
}

impl KinematicsError {
    /// The 1-based source line of the posture at fault.
    pub fn line(&self) -> u32 {
        match self {
            KinematicsError::Unreachable { line, .. }
            | KinematicsError::Travel { line, .. }
            | KinematicsError::BadPosture { line, .. } => *line,
        }
    }
}

/// Which planner to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Level {
    /// §6.1: acceleration-limited, no jerk (exact, O(N)).
    Acceleration,
    /// §6.3: jerk-limited look-ahead interpolator at the cycle time (default).
    #[default]
    Jerk,
}

/// One planned posture.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedPosture {
    /// Time stamp, s.
    pub t_s: f64,
    /// Path speed ṡ (chord parameter), mm/s.
    pub path_speed_mm_s: f64,
    /// Feed of the tool tip relative to the part (Eq 6), mm/s.
    pub feed_mm_s: f64,
    /// The constraint limiting the block that starts here.
    pub limit: Limit,
    /// Joint values, mm and rad.
    pub joints: Joints,
    /// IKT branch (0 or 1).
    pub branch: usize,
    /// The branch changed at this posture.
    pub branch_switch: bool,
    /// A rotary axis was undefined here and kept its previous value.
    pub singular: bool,
}

/// A planned path: per-posture results and totals (kinematics.md §7).
#[derive(Debug, Clone)]
pub struct FeedPlan {
    /// Per posture, same order and length as the input.
    pub postures: Vec<PlannedPosture>,
    /// Predicted time to run the path, s.
    pub total_time_s: f64,
    /// Time at the programmed feed Σ L/F, s (blocks without F at their axis speed limit).
    pub programmed_time_s: f64,
    /// The Level 1 time (a lower bound of the Level 2 time), s.
    pub level1_time_s: f64,
    /// Cycles where the interpolator had to take its least-violating fallback.
    pub fallbacks: usize,
    /// Cycles simulated.
    pub cycles: usize,
    /// Unplanned stops: states with no feasible successor, resolved by running the previous
    /// state's stop manoeuvre in closed form (admissible, but slower than the reference).
    pub stop_recoveries: usize,
    /// IKT branch switches along the path.
    pub branch_switches: usize,
    /// Self-check: largest sampled |g_i ṡ|, |g_i s̈|, |g_i s⃛| over the axis limits.
    pub max_axis_ratio: f64,
    /// Self-check: largest speed at a posture over its ceiling.
    pub max_ceiling_ratio: f64,
    /// The blocks (limits in the path parameter), for diagnostics.
    pub blocks: Blocks,
}

impl FeedPlan {
    /// True when the §7 self-check passes (ratios ≤ 1 + 1e-6, no fallback).
    pub fn self_check_ok(&self) -> bool {
        self.max_axis_ratio <= 1.0 + 1e-6
            && self.max_ceiling_ratio <= 1.0 + 1e-6
            && self.fallbacks == 0
    }
}

/// A posture to plan: pose in the part frame plus the programmed feed of the move that
/// reaches it and whether the NC stops exactly there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanInput {
    /// Tool tip and axis, part frame.
    pub pose: Pose,
    /// Programmed feed of the move into this posture, mm/s (`INFINITY` = none, rapid).
    pub feed_mm_s: f64,
    /// Exact stop at this posture (speed 0).
    pub exact_stop: bool,
    /// Source line (for errors).
    pub line: u32,
}

/// Postures per chunk of the IKT's rotary pass.
const IKT_CHUNK: usize = 1 << 14;

fn settings_of(machine: &Machine) -> Settings {
    Settings {
        cycle_time: machine.cycle_time,
        min_block_cycles: machine.min_block_cycles,
        lookahead_blocks: machine.lookahead_blocks,
        junction_spacing_rule: machine.junction_spacing_rule,
    }
}

/// Plan a sequence of postures on a machine: IKT, constraints, Level 1 or 2, Eq 6 feed.
pub fn plan_poses(
    input: &[PlanInput],
    machine: &Machine,
    level: Level,
) -> Result<FeedPlan, KinematicsError> {
    let mut ik = IkTracker::new(machine);
    // The first posture that is not a posture at all; errors before it come first.
    let bad = input.iter().position(|p| {
        !(p.pose.tip.coords.iter().all(|x| x.is_finite())
            && p.pose.axis.iter().all(|x| x.is_finite())
            && p.pose.axis.norm() > 1e-9)
    });
    let good = &input[..bad.unwrap_or(input.len())];
    // IKT in three passes: the rotary solutions of each axis (parallel), the branch choice
    // and unwinding along the path (sequential, cheap), the linear joints (parallel). The
    // first two go chunk by chunk, the rotary solutions of the next chunk while the branch
    // choice runs through this one, so the solutions stay in cache.
    let mut joints: Vec<Joints> = Vec::with_capacity(input.len());
    let mut meta: Vec<(usize, bool, bool)> = Vec::with_capacity(input.len());
    let chunks: Vec<&[PlanInput]> = good.chunks(IKT_CHUNK).collect();
    let rotaries = |chunk: &[PlanInput], out: &mut Vec<_>| {
        chunk
            .par_iter()
            .map(|p| machine.rotary_solutions_fixed(&p.pose.axis.normalize()))
            .collect_into_vec(out)
    };
    let (mut cur, mut next) = (Vec::new(), Vec::new());
    if let Some(first) = chunks.first() {
        rotaries(first, &mut cur);
    }
    for (c, chunk) in chunks.iter().enumerate() {
        let branch_choice = || -> Result<(), KinematicsError> {
            for (i, (p, fixed)) in chunk.iter().zip(cur.drain(..)).enumerate() {
                let index = c * IKT_CHUNK + i;
                let s = ik.solve_rotaries(fixed).map_err(|e| match e {
                    chain::IkFailure::Unreachable => {
                        let u = p.pose.axis.normalize();
                        KinematicsError::Unreachable {
                            index,
                            line: p.line,
                            i: u.x,
                            j: u.y,
                            k: u.z,
                        }
                    }
                    chain::IkFailure::Travel => KinematicsError::Travel {
                        index,
                        line: p.line,
                    },
                })?;
                joints.push(s.joints);
                meta.push((s.branch, s.switched, s.singular));
            }
            Ok(())
        };
        let ((), done) = rayon::join(
            || {
                if let Some(n) = chunks.get(c + 1) {
                    rotaries(n, &mut next);
                }
            },
            branch_choice,
        );
        done?;
        std::mem::swap(&mut cur, &mut next);
    }
    if let Some(index) = bad {
        return Err(KinematicsError::BadPosture {
            index,
            line: input[index].line,
        });
    }
    let frame = machine.linear_frame();
    joints
        .par_iter_mut()
        .zip(input.par_iter())
        .for_each(|(q, p)| machine.linear_joints_with(&frame, q, &p.pose.tip));
    let positions: Vec<[f64; 3]> = input
        .par_iter()
        .map(|p| [p.pose.tip.x, p.pose.tip.y, p.pose.tip.z])
        .collect();
    let feed: Vec<f64> = input.par_iter().skip(1).map(|p| p.feed_mm_s).collect();
    let stops: Vec<bool> = input.par_iter().map(|p| p.exact_stop).collect();
    let settings = settings_of(machine);
    let blocks = Blocks::build(
        &joints,
        &positions,
        &feed,
        &stops,
        &machine.joint_limits(),
        &settings,
    );
    let l1 = plan::plan_acc_only(&blocks);
    let timing = match level {
        Level::Acceleration => l1.clone(),
        Level::Jerk => plan::plan_jerk(&blocks, machine.cycle_time, machine.lookahead_blocks),
    };
    let limits = plan::limits_per_posture(&blocks, &timing, machine.lookahead_blocks);
    let n = blocks.n();
    // Eq 6 and the per-posture records are independent: in parallel.
    let postures = joints
        .par_iter()
        .zip(&meta)
        .enumerate()
        .map(|(p, (q, &(branch, branch_switch, singular)))| {
            let k = if p < n { p } else { n.saturating_sub(1) };
            let v = timing.v.get(p).copied().unwrap_or(0.0);
            let feed_mm_s = if n == 0 {
                0.0
            } else {
                cl_speed(machine, q, &blocks.g[k], v)
            };
            PlannedPosture {
                t_s: timing.t.get(p).copied().unwrap_or(0.0),
                path_speed_mm_s: v,
                feed_mm_s,
                limit: limits.get(p).copied().unwrap_or(Limit::Stop),
                joints: *q,
                branch,
                branch_switch,
                singular,
            }
        })
        .collect();
    Ok(FeedPlan {
        postures,
        total_time_s: timing.total,
        programmed_time_s: blocks.programmed_time(&feed),
        level1_time_s: l1.total,
        fallbacks: timing.fallbacks,
        cycles: timing.cycles,
        stop_recoveries: timing.stop_recoveries,
        branch_switches: ik.switches,
        max_axis_ratio: timing.max_axis_ratio,
        max_ceiling_ratio: timing.max_ceiling_ratio,
        blocks,
    })
}

/// Eq 6: speed of the tool tip relative to the part when the joints move as q̇ = g·ṡ,
/// from the derivative of the forward kinematics to the part frame
/// ([`Machine::tip_velocity`]).
pub fn cl_speed(machine: &Machine, q: &Joints, g: &Joints, path_speed: f64) -> f64 {
    if path_speed == 0.0 {
        return 0.0;
    }
    machine.tip_velocity(q, g).norm() * path_speed
}

/// Turn a tool path into planner input: the programmed feed of each move (rapids and
/// moves without a feed are limited by the axes only), exact stops where rapid and feed
/// motion meet and at hole positions.
pub fn plan_input(path: &Toolpath) -> Vec<PlanInput> {
    let is_feed = |m: MotionKind| m.is_feed() || m == MotionKind::Cycle;
    let ps = &path.postures;
    ps.iter()
        .enumerate()
        .map(|(i, p)| {
            let feed_mm_s = if is_feed(p.motion) {
                p.feed_mm_min
                    .filter(|f| f.is_finite() && *f > 0.0)
                    .map_or(f64::INFINITY, |f| f / 60.0)
            } else {
                f64::INFINITY
            };
            let exact_stop = p.motion == MotionKind::Cycle
                || (i > 0 && i + 1 < ps.len() && is_feed(p.motion) != is_feed(ps[i + 1].motion));
            PlanInput {
                pose: Pose {
                    tip: p.position,
                    axis: p.axis,
                },
                feed_mm_s,
                exact_stop,
                line: p.line,
            }
        })
        .collect()
}

/// Plan a tool path on a machine with the given planner level.
pub fn plan_path(
    path: &Toolpath,
    machine: &Machine,
    level: Level,
) -> Result<FeedPlan, KinematicsError> {
    plan_poses(&plan_input(path), machine, level)
}

/// Predicted CL feed per posture, mm/min (Level 2, Eq 6), same length as `path.postures`.
/// This is what `resample` and `simulate` take as `posture_feed_mm_min`.
///
/// Moves whose speed peaks far above both ends break a clock rebuilt from posture feeds
/// (001 Eq 1, Δt = 2L/(V_i + V_{i+1})): a move that starts and ends at (or very near) rest,
/// between exact stops or at the segment cuts of the planner, would take for ever. Where
/// Eq 1 would take more than twice the planned time (V_i + V_{i+1} < L/Δt), the feed
/// move's end posture (its start when the end is an exact stop) gets the feed that makes
/// Eq 1 give the planned time, 2L/Δt − V_i; exact stops keep their zero feed (the next
/// move then starts a little faster than planned).
pub fn predict_posture_feed(
    path: &Toolpath,
    machine: &Machine,
) -> Result<Vec<f64>, KinematicsError> {
    let plan = plan_path(path, machine, Level::Jerk)?;
    let mut feed: Vec<f64> = plan.postures.iter().map(|p| p.feed_mm_s * 60.0).collect();
    let ps = &path.postures;
    let n = feed.len();
    let is_feed = |m: MotionKind| m.is_feed() || m == MotionKind::Cycle;
    for k in 0..n.saturating_sub(1) {
        if !is_feed(ps[k + 1].motion) {
            continue; // rapids are not resampled
        }
        let l = (ps[k + 1].position - ps[k].position).norm();
        let dt = plan.postures[k + 1].t_s - plan.postures[k].t_s;
        if l > 0.0 && dt > 0.0 {
            let v = l / dt * 60.0;
            if feed[k] + feed[k + 1] < v {
                // Exact stops (path ends, feed/rapid changes) keep their zero feed.
                let end_stops = k + 2 >= n || !is_feed(ps[k + 2].motion);
                if !end_stops {
                    feed[k + 1] = 2.0 * v - feed[k];
                } else if k > 0 && is_feed(ps[k].motion) {
                    feed[k] = 2.0 * v - feed[k + 1];
                }
            }
        }
    }
    Ok(feed)
}

/// Helper for tests and examples: a pose from tip coordinates and tool-axis tilt and
/// azimuth in degrees (axis = (sin t cos a, sin t sin a, cos t)).
pub fn pose_tilt_azimuth(tip: [f64; 3], tilt_deg: f64, azimuth_deg: f64) -> Pose {
    let (t, a) = (tilt_deg.to_radians(), azimuth_deg.to_radians());
    Pose {
        tip: Point3::new(tip[0], tip[1], tip[2]),
        axis: Vec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos()),
    }
}
