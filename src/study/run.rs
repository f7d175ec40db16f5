//! One run of a designed experiment: the synthetic path over a plane (tool posture,
//! pass interval from the scallop), resampled, simulated on a periodic unit cell (or the
//! design's window) and measured with the areal parameters of the design's responses.

use super::design::{DEFAULT_DTHETA_DEG, Design, RunOutput, RunPoint, StepRule, StepSpec};
use crate::synth::SynthError;

/// Why a run of a design cannot be planned, is refused or fails. The messages name the
/// design's keys (`grid_um`, `window_mm`, `dtheta_deg`), not command-line options.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// The synthetic path (its cross-section, pass interval or passes) cannot be made.
    #[error(transparent)]
    Synth(#[from] SynthError),
    /// A value of the run beyond a plausibility limit (the feed per tooth).
    #[error(transparent)]
    Limit(#[from] crate::math::limits::LimitError),
    /// The run is estimated past a simulation's limits or [`MAX_RUN_BYTES`].
    #[error("{run} is refused before it starts: {why}")]
    Refused {
        /// "run 3 (yaw_deg = 0, …)".
        run: String,
        /// Which budget and the keys that bring the run within it.
        why: String,
    },
    /// Runs of a design past the budget ([`check_runs`]).
    #[error(
        "{count} of {total} runs are past the budget, nothing was run:\n  {}{}",
        join_refused(.refused),
        more_refused(*.count, .refused.len())
    )]
    PastBudget {
        /// Runs past the budget.
        count: usize,
        /// Runs of the design.
        total: usize,
        /// The first three refusals.
        refused: Vec<RunError>,
    },
    /// The synthetic program came out without a tool path.
    #[error("the synthetic program has no tool path")]
    NoPath,
    /// Resampling the synthetic path failed.
    #[error(transparent)]
    Resample(#[from] crate::resample::ResampleError),
    /// A response that is not an areal parameter.
    #[error("'{0}' is not an areal parameter")]
    NotAreal(String),
    /// The surface simulation failed.
    #[error(transparent)]
    Surface(#[from] crate::surface::SurfaceError),
    /// The areal parameters failed.
    #[error(transparent)]
    Metrics(#[from] crate::metrics::MetricsError),
    /// Nodes of the window that no pass reached.
    #[error("{missing} of {nodes} nodes of the window were not reached")]
    NotReached {
        /// Nodes not reached.
        missing: usize,
        /// Nodes of the window.
        nodes: usize,
    },
    /// The window reaches higher than the path covers.
    #[error(
        "the window reaches {top_um:.1} µm above the plane, beyond the {} µm the path covers",
        1e3 * REACH_HEIGHT_MM
    )]
    TooHigh {
        /// Highest node, µm.
        top_um: f64,
    },
}

fn join_refused(refused: &[RunError]) -> String {
    refused
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("\n  ")
}

fn more_refused(count: usize, shown: usize) -> String {
    if count > shown {
        format!("\n  … and {} more", count - shown)
    } else {
        String::new()
    }
}

/// The evaluated grid of a run: the unit cell or the design's window, in the WCS (passes
/// along +x, stepped along +y), and the extent of the path that covers it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunWindow {
    /// Grid placement.
    pub grid: crate::surface::GridSpec,
    /// Field of the synthetic path: length along the passes, width across, mm.
    pub field_mm: (f64, f64),
}

/// Highest surface height (above the plane) a run may reach, mm: passes and tooth passes
/// that stay higher than this over the window are left out of the path, and a run whose
/// window comes out higher fails rather than report a wrong value.
pub const REACH_HEIGHT_MM: f64 = 0.1;

/// How far from its lowest point the swept body of `cutter` (unit axis `axis_fgn` in
/// (f, g, n)) stays within `h_mm` of the plane: (along f, across along g), mm. A pass (or a
/// tooth pass) farther than this from a node cannot cut it lower than `h_mm`.
pub fn reach_mm(
    cutter: &crate::tool::Cutter,
    axis_fgn: &crate::math::Vec3,
    h_mm: f64,
) -> Result<(f64, f64), SynthError> {
    let one = |axis: &crate::math::Vec3| -> Result<f64, SynthError> {
        let cs = crate::synth::CrossSection::new(cutter, axis)?;
        let [yb, zb] = cs.bottom();
        let step = 0.005;
        let mut reach: f64 = 0.0;
        for sign in [-1.0, 1.0] {
            let mut k = 1usize;
            loop {
                let y = yb + sign * step * k as f64;
                match cs.lower(y) {
                    Some(z) if z - zb <= h_mm && k < 100_000 => k += 1,
                    _ => break,
                }
            }
            reach = reach.max(step * k as f64);
        }
        Ok(reach)
    };
    let a = axis_fgn;
    // Seen along g instead of f: (f, g, n) → (g, −f, n).
    let along = one(&crate::math::Vec3::new(a.y, -a.x, a.z))?;
    let across = one(a)?;
    Ok((along, across))
}

/// The window of a run with feed per tooth `fz_mm` and pass interval `step_mm`: without
/// `window_mm`, one unit cell `fz × s` (`fz × 2s` for zigzag passes) with its last column
/// and row left out, so that the periodic surface is counted once; with it, a window of that
/// size centred on the origin. The path field (centred on the origin) reaches `reach_mm`
/// (along, across; see [`reach_mm`]) plus 0.2 mm beyond the window on every side.
pub fn run_window(design: &Design, reach_mm: (f64, f64), fz_mm: f64, step_mm: f64) -> RunWindow {
    let d = design.grid_um * 1e-3;
    let across = if design.pattern == crate::synth::Pattern::Zigzag {
        2.0 * step_mm
    } else {
        step_mm
    };
    let (grid, a, b) = match design.window_mm {
        None => (
            crate::surface::GridSpec::Window {
                x0_mm: 0.0,
                y0_mm: 0.0,
                x1_mm: fz_mm - d,
                y1_mm: across - d,
            },
            fz_mm,
            across,
        ),
        Some([a, b]) => (
            crate::surface::GridSpec::Window {
                x0_mm: -0.5 * a,
                y0_mm: -0.5 * b,
                x1_mm: 0.5 * a,
                y1_mm: 0.5 * b,
            },
            a,
            b,
        ),
    };
    RunWindow {
        grid,
        field_mm: (2.0 * (a + reach_mm.0 + 0.2), 2.0 * (b + reach_mm.1 + 0.2)),
    }
}

/// The tool axis in (f, g, n) by convention B of model.md §7: lead λ about g, then a side
/// tilt ψ about f, `a = R_f(ψ)(sin λ f + cos λ n)`.
pub fn convention_b_axis(tilt_rad: f64, yaw_rad: f64) -> crate::math::Vec3 {
    crate::math::Vec3::new(
        tilt_rad.sin(),
        -yaw_rad.sin() * tilt_rad.cos(),
        yaw_rad.cos() * tilt_rad.cos(),
    )
}

/// Simulate one run of a design: the synthetic path (plane, passes along +x, tool posture
/// by convention A, pass interval from the scallop by the exact swept envelope), resampled
/// at a constant spindle step, the surface model of the design on [`run_window`], and the
/// areal parameters of the raw window (no levelling: a unit cell of a plane is periodic).
/// Every pass starts at the same spindle phase (model.md §8). The responses come back in
/// [`Design::responses`] order.
pub fn simulate_run(
    design: &Design,
    cutter: &crate::tool::Cutter,
    p: &RunPoint,
) -> Result<RunOutput, RunError> {
    let prepared = prepare_run(design, cutter, p)?;
    evaluate_run(design, &prepared, cutter, &[])
}

/// The part of a run that does not depend on the tool's run-out or the spindle phase: the
/// synthetic path planned with the nominal cutter (the pass interval from the scallop, the
/// window, the resampled samples), simulated once per Monte Carlo sample by
/// [`evaluate_run`].
#[derive(Debug, Clone)]
pub struct PreparedRun {
    /// The resampled path; `Sample::run` is the pass.
    pub samples: Vec<crate::resample::Sample>,
    /// Number of passes (cutting runs) of the path.
    pub passes: usize,
    /// The evaluated window.
    pub window: RunWindow,
    /// Surface model with its resampling.
    pub model: crate::surface::Model,
    /// Feed per tooth, mm.
    pub fz_mm: f64,
    /// Pass interval (drive-plane spacing), mm.
    pub stepover_mm: f64,
    /// The responses as areal parameters, in [`Design::responses`] order.
    pub params: Vec<crate::metrics::Param>,
}

/// What one run of a design plans before it builds anything: its tool posture, pass
/// interval, feed per tooth and window (shared by [`prepare_run`] and [`estimate_run`]).
struct RunPlan {
    orientation: crate::synth::Orientation,
    step_mm: f64,
    fz_mm: f64,
    window: RunWindow,
}

/// Pass intervals and reaches already worked out, by the bits of their inputs: the runs of a
/// design share a few orientations and steps (they are the slow part of a plan).
#[derive(Default)]
struct PlanCache {
    steps: std::collections::HashMap<[u64; 4], Result<f64, SynthError>>,
    sections: std::collections::HashMap<[u64; 3], Result<crate::synth::CrossSection, SynthError>>,
    /// Relative tolerance of the pass interval (0 for a run, a lower bound for a budget).
    step_rel: f64,
    reaches: std::collections::HashMap<[u64; 3], Result<(f64, f64), SynthError>>,
}

fn plan_run(
    design: &Design,
    cutter: &crate::tool::Cutter,
    p: &RunPoint,
) -> Result<RunPlan, RunError> {
    plan_run_with(design, cutter, p, &mut PlanCache::default())
}

fn plan_run_with(
    design: &Design,
    cutter: &crate::tool::Cutter,
    p: &RunPoint,
    cache: &mut PlanCache,
) -> Result<RunPlan, RunError> {
    use crate::synth::Orientation;
    let lead = design.factors.lead_deg.is_some();
    let orientation = if lead {
        Orientation::Lead {
            lead_rad: p.tilt_deg.to_radians(),
        }
    } else {
        Orientation::TiltYaw {
            tilt_rad: p.tilt_deg.to_radians(),
            yaw_rad: p.yaw_deg.to_radians(),
        }
    };
    let step_mm = match p.step {
        StepSpec::StepoverMm(s) => s,
        StepSpec::ScallopUm(h) => {
            let axis = if design.step_rule == StepRule::ConventionB {
                convention_b_axis(p.tilt_deg.to_radians(), p.yaw_deg.to_radians())
            } else {
                orientation.axis_fgn()
            };
            let key = [
                axis.x.to_bits(),
                axis.y.to_bits(),
                axis.z.to_bits(),
                h.to_bits(),
            ];
            match cache.steps.get(&key) {
                Some(step) => step.clone()?,
                None => {
                    // The same as `synth::exact_step_mm`, the section kept for the next scallop.
                    let section = cache
                        .sections
                        .entry([key[0], key[1], key[2]])
                        .or_insert_with(|| crate::synth::CrossSection::new(cutter, &axis))
                        .as_ref()
                        .map_err(Clone::clone)?;
                    let step = section.step_for_scallop_within(h * 1e-3, cache.step_rel);
                    cache.steps.insert(key, step.clone());
                    step?
                }
            }
        }
    };
    let z = cutter.teeth().max(1) as f64;
    let fz_mm = p.feed_mm_min / (z * design.rpm);
    crate::math::limits::within(
        "the feed per tooth",
        "mm",
        fz_mm,
        crate::math::limits::FZ_MM,
    )?;
    let a = orientation.axis_fgn();
    let reach = cache
        .reaches
        .entry([a.x.to_bits(), a.y.to_bits(), a.z.to_bits()])
        .or_insert_with(|| reach_mm(cutter, &a, REACH_HEIGHT_MM))
        .clone()?;
    let window = run_window(design, reach, fz_mm, step_mm);
    Ok(RunPlan {
        orientation,
        step_mm,
        fz_mm,
        window,
    })
}

/// Most memory one run of a design may take by its estimate ([`estimate_run`]), bytes: the
/// synthetic path and its resampled poses are held whole, unlike `crest simulate`'s stream.
pub const MAX_RUN_BYTES: f64 = 1.0e9;

/// Bytes per node of a run's grid (the height map, the z-buffer and the areal parameters'
/// work arrays), for [`estimate_run`].
const BYTES_PER_NODE: f64 = 32.0;

/// Bytes the surface model takes per resampled pose beyond the pose itself (its edges and
/// tiles), for [`estimate_run`]: peak memory of single-thread runs of a unit cell at a
/// 0.0001 µm scallop (285 MB for 442 000 poses) and of a 2 mm window (115 MB for 197 000
/// poses and 1 million nodes) lies under the estimate.
const SURFACE_BYTES_PER_SAMPLE: f64 = 512.0;

/// The size of one run of a design, estimated from its plan alone (nothing is built).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunEstimate {
    /// Passes of the synthetic path.
    pub passes: f64,
    /// Postures of the synthetic path.
    pub postures: f64,
    /// Resampled poses ([`crate::resample::estimate_samples`]).
    pub samples: f64,
    /// Nodes of the evaluated grid.
    pub nodes: f64,
    /// Memory, bytes: the path, its poses and the grid.
    pub bytes: f64,
}

/// Estimate run `p` of `design` with `cutter` (pass interval, window and path field as
/// [`prepare_run`] plans them; the passes and points as `synth::generate` lays them out;
/// the poses by [`crate::resample::estimate_samples`]).
pub fn estimate_run(
    design: &Design,
    cutter: &crate::tool::Cutter,
    p: &RunPoint,
) -> Result<RunEstimate, RunError> {
    Ok(estimate_plan(
        design,
        cutter,
        p,
        &plan_run(design, cutter, p)?,
    ))
}

fn estimate_plan(
    design: &Design,
    cutter: &crate::tool::Cutter,
    p: &RunPoint,
    plan: &RunPlan,
) -> RunEstimate {
    let (length, width) = plan.window.field_mm;
    let passes = (width / plan.step_mm - 1e-9).ceil().max(0.0) + 1.0;
    let points = (length / POINT_STEP_MM).ceil().max(1.0) + 1.0;
    let postures = passes * (points + 2.0);
    let dtheta = design.dtheta_deg.unwrap_or(DEFAULT_DTHETA_DEG).to_radians();
    let (_, mode) = design
        .model
        .with_resampling(dtheta, plan.fz_mm, cutter.teeth());
    let extent = crate::resample::PathExtent {
        cutting_mm: passes * length,
        runs: passes.min(usize::MAX as f64) as usize,
        feed_range_mm_min: Some((p.feed_mm_min, p.feed_mm_min)),
        spindle_rpm: Some(design.rpm),
    };
    let samples = crate::resample::estimate_samples(
        &extent,
        mode,
        plan.fz_mm,
        cutter.teeth(),
        Some(design.rpm),
    );
    let d = design.grid_um * 1e-3;
    let nodes = match plan.window.grid {
        crate::surface::GridSpec::Window {
            x0_mm,
            y0_mm,
            x1_mm,
            y1_mm,
        } => (((x1_mm - x0_mm) / d).floor() + 1.0) * (((y1_mm - y0_mm) / d).floor() + 1.0),
        _ => f64::INFINITY,
    };
    let bytes = postures * std::mem::size_of::<crate::toolpath::Posture>() as f64
        + samples
            * (std::mem::size_of::<crate::resample::Sample>() as f64 + SURFACE_BYTES_PER_SAMPLE)
        + nodes * BYTES_PER_NODE;
    RunEstimate {
        passes,
        postures,
        samples,
        nodes,
        bytes,
    }
}

/// [`estimate_run`], refused past the limits of a simulation (README "Limits": the nodes of
/// a grid, the resampled poses) and [`MAX_RUN_BYTES`]: the error gives the estimate, the
/// limit and the keys that bring the run within it.
pub fn check_run(
    design: &Design,
    cutter: &crate::tool::Cutter,
    p: &RunPoint,
) -> Result<RunEstimate, RunError> {
    let plan = plan_run(design, cutter, p)?;
    check_estimate(design, p, estimate_plan(design, cutter, p, &plan))
}

fn check_estimate(design: &Design, p: &RunPoint, e: RunEstimate) -> Result<RunEstimate, RunError> {
    use crate::math::limits::{MAX_NODES, MAX_SAMPLES};
    // NaN (an impossible plan) counts as beyond.
    let beyond = |v: f64, cap: f64| v.is_nan() || v > cap;
    let over = if beyond(e.nodes, MAX_NODES as f64) {
        Some(format!(
            "its grid would have about {:.3e} nodes, more than the {:.0e} of a simulation (raise grid_um = {}{})",
            e.nodes,
            MAX_NODES as f64,
            design.grid_um,
            match design.window_mm {
                Some([a, b]) => format!(" or shrink window_mm = [{a}, {b}]"),
                None => String::new(),
            }
        ))
    } else if beyond(e.samples, MAX_SAMPLES as f64) {
        Some(format!(
            "its {:.3e} passes would be resampled into about {:.3e} poses, more than the {:.0e} of a simulation (raise the pass interval, dtheta_deg or the feed)",
            e.passes, e.samples, MAX_SAMPLES as f64
        ))
    } else if beyond(e.bytes, MAX_RUN_BYTES) {
        Some(format!(
            "it would hold about {:.1} GB ({:.3e} passes, {:.3e} path postures, {:.3e} poses, {:.3e} nodes), more than the {:.0} GB a run may take (raise the pass interval, dtheta_deg or grid_um{})",
            e.bytes / 1e9,
            e.passes,
            e.postures,
            e.samples,
            e.nodes,
            MAX_RUN_BYTES / 1e9,
            match design.window_mm {
                Some(_) => ", or shrink window_mm",
                None => "",
            }
        ))
    } else {
        None
    };
    match over {
        Some(why) => Err(RunError::Refused {
            run: describe(design, p),
            why,
        }),
        None => Ok(e),
    }
}

/// Check every run of `design` against the budget of [`check_run`] before the first one
/// starts (nothing is built: a few milliseconds a run). A run whose plan itself fails (a
/// feed per tooth out of range, …) is left to fail as it runs. The error names the refused
/// runs (the first three) and how many there are.
pub fn check_runs(design: &Design, cutter: &crate::tool::Cutter) -> Result<(), RunError> {
    let runs = design.runs();
    let mut refused = Vec::new();
    let mut count = 0usize;
    // A pass interval at most 0.1 % under the exact one: the passes are never fewer.
    let mut cache = PlanCache {
        step_rel: 1e-3,
        ..PlanCache::default()
    };
    for p in &runs {
        let Ok(plan) = plan_run_with(design, cutter, p, &mut cache) else {
            continue;
        };
        if let Err(e) = check_estimate(design, p, estimate_plan(design, cutter, p, &plan)) {
            count += 1;
            if refused.len() < 3 {
                refused.push(e);
            }
        }
    }
    if count == 0 {
        return Ok(());
    }
    Err(RunError::PastBudget {
        count,
        total: runs.len(),
        refused,
    })
}

/// "run 3 (yaw_deg = 0, scallop_um = 5, …)".
fn describe(design: &Design, p: &RunPoint) -> String {
    let levels: Vec<String> = design
        .factors()
        .iter()
        .zip(&p.values)
        .map(|(f, v)| format!("{} = {v}", f.name))
        .collect();
    format!("run {} ({})", p.run, levels.join(", "))
}

/// Points along a pass of a run's synthetic path, mm.
const POINT_STEP_MM: f64 = 1.0;

/// Plan and resample run `p` of `design` with the nominal `cutter` (see [`simulate_run`]);
/// a run past the budget ([`check_run`]) is refused before its path is built.
pub fn prepare_run(
    design: &Design,
    cutter: &crate::tool::Cutter,
    p: &RunPoint,
) -> Result<PreparedRun, RunError> {
    use crate::synth::{PathSpec, Step, Surface};
    let plan = plan_run(design, cutter, p)?;
    check_estimate(design, p, estimate_plan(design, cutter, p, &plan))?;
    let RunPlan {
        orientation,
        step_mm,
        fz_mm,
        window: win,
    } = plan;
    let mut spec = PathSpec::new(
        Surface::Plane,
        cutter.clone(),
        orientation,
        Step::Stepover {
            spacing_mm: step_mm,
        },
        win.field_mm,
    );
    spec.pattern = design.pattern;
    spec.point_step_mm = POINT_STEP_MM;
    spec.clearance_mm = 1.0;
    spec.feed_mm_min = p.feed_mm_min;
    spec.spindle_rpm = design.rpm;
    let synth = crate::synth::generate(&spec)?;
    let path = synth.program.paths.first().ok_or(RunError::NoPath)?;

    let dtheta = design.dtheta_deg.unwrap_or(DEFAULT_DTHETA_DEG).to_radians();
    let (model, mode) = design.model.with_resampling(dtheta, fz_mm, cutter.teeth());
    let ropts = crate::resample::Options::new(mode, fz_mm, cutter.teeth())
        .with_rpm(design.rpm)
        .with_feed_mm_min(p.feed_mm_min);
    let samples = crate::resample::resample(path, &ropts)?;
    let params: Vec<crate::metrics::Param> = design
        .responses
        .iter()
        .map(|r| {
            crate::metrics::Param::from_symbol(r)
                .filter(|p| !p.is_profile())
                .ok_or_else(|| RunError::NotAreal(r.clone()))
        })
        .collect::<Result<_, _>>()?;
    Ok(PreparedRun {
        passes: samples.iter().map(|s| s.run + 1).max().unwrap_or(0),
        samples,
        window: win,
        model,
        fz_mm,
        stepover_mm: synth.stepover_mm,
        params,
    })
}

/// Simulate a prepared run with `cutter` (the nominal one, or one with its run-out
/// perturbed) and the spindle at `phases_rad[k]` at the start of pass k (a pass beyond the
/// list, and every pass when it is empty, starts at phase 0, as [`simulate_run`]).
pub fn evaluate_run(
    design: &Design,
    run: &PreparedRun,
    cutter: &crate::tool::Cutter,
    phases_rad: &[f64],
) -> Result<RunOutput, RunError> {
    let shifted: Vec<crate::resample::Sample>;
    let samples = if phases_rad.iter().any(|&p| p != 0.0) {
        shifted = run
            .samples
            .iter()
            .map(|s| {
                let mut s = s.clone();
                let phase = phases_rad.get(s.run).copied().unwrap_or(0.0);
                if phase != 0.0 {
                    s.theta_rad += phase;
                }
                s
            })
            .collect();
        &shifted
    } else {
        &run.samples
    };
    let sopts = crate::surface::Options::new(run.model, run.window.grid, design.grid_um * 1e-3);
    let sim = crate::surface::simulate(samples, cutter, &sopts, &|_, _| {})?;
    let nodes = sim.map.nx * sim.map.ny;
    if sim.nodes_cut != nodes {
        return Err(RunError::NotReached {
            missing: nodes - sim.nodes_cut,
            nodes,
        });
    }
    let top = sim
        .map
        .z_um
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    if top > 1e3 * REACH_HEIGHT_MM {
        return Err(RunError::TooHigh { top_um: top });
    }
    let params = &run.params;
    let mut set_list: Vec<&str> = params.iter().map(|p| p.symbol()).collect();
    set_list.dedup();
    let set = crate::metrics::ParamSet::parse(&set_list.join(","), false)?;
    let values = crate::metrics::areal_parameters(&sim.map, &set)?;
    let responses = params
        .iter()
        .map(|p| {
            values
                .iter()
                .find(|(q, _)| q == p)
                .map_or(f64::NAN, |(_, v)| *v)
        })
        .collect();
    Ok(RunOutput {
        responses,
        fz_mm: run.fz_mm,
        stepover_mm: run.stepover_mm,
        bands: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reach_follows_the_effective_radii() {
        // R 5, rc 1.5, tilt 10°, yaw 0: across, z ≈ y²/(2 R_eff) with R_eff = 21.656 mm
        // (model.md R6); along, the corner circle rc in front: y = √(2 rc h).
        let cutter = crate::tool::Cutter::new(
            crate::tool::Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            1,
            0.0,
        );
        let a = crate::synth::axis_convention_a(10f64.to_radians(), 0.0);
        let h = 0.001;
        let (along, across) = reach_mm(&cutter, &a, h).unwrap();
        assert!(
            (across - (2.0 * 21.656 * h).sqrt()).abs() < 0.006,
            "{across}"
        );
        assert!((along - (2.0 * 1.5 * h).sqrt()).abs() < 0.006, "{along}");
        // At tilt 1° the end face trails at slope tan 1°: 0.1 mm is reached 5.73 mm behind.
        let a1 = crate::synth::axis_convention_a(1f64.to_radians(), 0.0);
        let (along, _) = reach_mm(&cutter, &a1, REACH_HEIGHT_MM).unwrap();
        let want = REACH_HEIGHT_MM / 1f64.to_radians().tan();
        assert!((along - want).abs() < 0.05, "{along} vs {want}");
    }

    #[test]
    fn convention_b_gives_the_r6_step_of_test_4() {
        // model.md R6, test 4 (B): yaw 20°, tilt 10°, h = 10 µm → s = 0.5259 mm; A: 1.2385.
        let cutter = crate::tool::Cutter::new(
            crate::tool::Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            1,
            0.0,
        );
        let (l, p) = (10f64.to_radians(), 20f64.to_radians());
        let b = crate::synth::exact_step_mm(&cutter, &convention_b_axis(l, p), 0.01).unwrap();
        assert!((b - 0.5259).abs() < 1e-3, "{b}");
        let a = crate::synth::exact_step_mm(&cutter, &crate::synth::axis_convention_a(l, p), 0.01)
            .unwrap();
        assert!((a - 1.2385).abs() < 1e-3, "{a}");
        // Without yaw the conventions agree.
        let a0 = crate::synth::axis_convention_a(l, 0.0);
        assert!((convention_b_axis(l, 0.0) - a0).norm() < 1e-15);
    }
}
