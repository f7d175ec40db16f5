//! The `crest feed` pipeline: read a tool-path file and plan every path on the machine
//! (kinematics.md §7), each on its own, rapids included, starting and ending at rest.

use crate::kinematics::{FeedPlan, Level, Machine, PlanInput, plan_input, plan_poses};
use crate::nc::Rtcp;
use crate::pipeline::{Error, Result};
use std::path::Path;

/// One tool path of the file, planned.
#[derive(Debug, Clone)]
pub struct PlannedPath {
    /// The path's name (`TOOL PATH/…` of a CLSF).
    pub name: String,
    /// The planner's input postures (source line, programmed feed, …).
    pub input: Vec<PlanInput>,
    /// The plan: per-posture time, feed and limit, totals and the self-check.
    pub plan: FeedPlan,
}

/// Every path of `file` planned on `machine` at `level`. `absolute` applies MSYS (plan in the
/// absolute frame instead of the MCS); `rtcp` is how G-code input is read. An error names the
/// file, the line and the path; when a path in a tilted or flipped MCS meets the machine's
/// travel limits, it says to plan it with `--absolute`.
pub fn plan_file(
    file: &Path,
    machine: &Machine,
    level: Level,
    absolute: bool,
    rtcp: Rtcp,
) -> Result<Vec<PlannedPath>> {
    let read = crate::io::toolpath::ReadOptions {
        lower: crate::toolpath::LowerOptions {
            apply_msys: absolute,
            ..Default::default()
        },
        machine: Some(machine.clone()),
        rtcp,
    };
    let program = crate::io::toolpath::read_program_with(file, read)?;
    let name = file.display().to_string();
    let mut plans = Vec::with_capacity(program.paths.len());
    for path in &program.paths {
        let input = plan_input(path);
        let plan = plan_poses(&input, machine, level).map_err(|e| {
            let msg = e.to_string();
            let line = e.line();
            let msg = msg
                .strip_prefix(&format!("line {line}: "))
                .unwrap_or(&msg)
                .to_string();
            let hint = match (&path.msys, path.msys_applied) {
                (Some(m), false) if msg.contains("travel limits") => {
                    let x = crate::math::Vec3::new(m[3], m[4], m[5]);
                    let y = crate::math::Vec3::new(m[6], m[7], m[8]);
                    let z = x.cross(&y);
                    if (z - crate::math::Vec3::z()).norm() > 1e-6 {
                        format!(
                            "; the path is in the MCS of its MSYS, whose Z axis is ({:.3}, {:.3}, {:.3}) in the absolute frame: plan it in the absolute frame with ‹absolute›",
                            z.x, z.y, z.z
                        )
                    } else {
                        String::new()
                    }
                }
                _ => String::new(),
            };
            Error::Input(format!(
                "{name}:{line}:1: {msg} (tool path \"{}\"){hint}",
                path.name
            ))
        })?;
        plans.push(PlannedPath {
            name: path.name.clone(),
            input,
            plan,
        });
    }
    Ok(plans)
}
