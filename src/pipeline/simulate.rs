//! `crest simulate`: a tool-path file read from disk, the cutter, spindle speed and feed
//! resolved (options, then `process.toml`, then the file's SPINDL/FEDRAT), the feed the
//! machine reaches planned when asked, the path resampled for the surface model and the
//! surface simulated on the requested grid.

use crate::config::ProcessConfig;
use crate::kinematics::Machine;
use crate::resample::{self, Sample};
use crate::surface::{self, GridSpec, ModelKind, Simulation};
use crate::tool::Cutter;
use crate::toolpath::{MotionKind, Posture, Program, Toolpath};
use miette::miette;
use std::path::{Path, PathBuf};

/// Which feed moves the tool.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FeedSource {
    /// The programmed feed (FEDRAT, or the feed given).
    #[default]
    Programmed,
    /// The feed the machine really reaches (`crest feed`, kinematics.md §7).
    Predicted,
}

/// Resolve the feed source and the machine: the machine to plan on, or `None` for the
/// programmed feed. `Predicted` needs a machine; a machine alone means `Predicted`;
/// `Programmed` with a machine is refused (the machine would be ignored).
pub fn resolve_feed_source(
    feed: Option<FeedSource>,
    machine: Option<&Path>,
) -> miette::Result<Option<Machine>> {
    match (feed, machine) {
        (Some(FeedSource::Predicted), None) => Err(miette!(
            "--feed predicted needs the machine: add --machine MACHINE.toml"
        )),
        (Some(FeedSource::Programmed), Some(m)) => Err(miette!(
            "--machine {} is only used with --feed predicted (drop --feed programmed or --machine)",
            m.display()
        )),
        (Some(FeedSource::Predicted) | None, Some(m)) => Ok(Some(super::load_machine(m)?)),
        (Some(FeedSource::Programmed) | None, None) => Ok(None),
    }
}

/// Where to simulate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GridRequest {
    /// A window of the WCS xy plane, mm.
    Window {
        /// Lower x.
        x0_mm: f64,
        /// Lower y.
        y0_mm: f64,
        /// Upper x.
        x1_mm: f64,
        /// Upper y.
        y1_mm: f64,
    },
    /// A patch on the tangent plane at the contact point at arc length `s_mm` of the path.
    PatchAt {
        /// Arc length, mm.
        s_mm: f64,
        /// Along the feed, mm.
        length_mm: f64,
        /// Across, mm.
        width_mm: f64,
    },
}

/// Everything `crest simulate` is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulateRequest {
    /// Tool-path file (CLSF or contact12).
    pub file: PathBuf,
    /// Cutter description (`tool.toml`).
    pub tool: PathBuf,
    /// Process parameters (`process.toml`).
    pub process: Option<PathBuf>,
    /// Spindle speed, rpm.
    pub rpm: Option<f64>,
    /// Feed, mm/min.
    pub feed_mm_min: Option<f64>,
    /// Feed per tooth, mm.
    pub fz_mm: Option<f64>,
    /// Programmed or predicted feed.
    pub feed: Option<FeedSource>,
    /// Machine description for the predicted feed.
    pub machine: Option<PathBuf>,
    /// Surface model.
    pub model: ModelKind,
    /// Spindle step of the ICE model, degrees.
    pub dtheta_deg: f64,
    /// Grid spacing, µm.
    pub grid_um: f64,
    /// Grid placement.
    pub grid: GridRequest,
    /// Depth of cut, mm (default: process.toml, else 0.5).
    pub ap_mm: Option<f64>,
    /// Only this tool path (1-based).
    pub path: Option<usize>,
}

/// Spindle speed, feed and feed per tooth after resolving options, process.toml and file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cutting {
    /// Spindle speed, rpm.
    pub rpm: f64,
    /// Feed given by the user (None = the file's FEDRAT, per posture).
    pub feed_mm_min: Option<f64>,
    /// Representative feed, mm/min.
    pub feed_nominal: f64,
    /// Feed per tooth, mm.
    pub fz_mm: f64,
}

/// A finished simulation and what it was run with.
#[derive(Debug, Clone)]
pub struct SimulateRun {
    /// The simulated surface.
    pub sim: Simulation,
    /// The cutter.
    pub cutter: Cutter,
    /// Spindle speed and feeds used.
    pub cutting: Cutting,
    /// Depth of cut, mm.
    pub ap_mm: f64,
    /// Whether the feed was predicted on a machine.
    pub predicted: bool,
    /// Samples simulated.
    pub samples: usize,
    /// Cutting time of the resampled runs, s.
    pub cut_time_s: f64,
    /// Feed of the samples, mm/min: min, max, mean.
    pub sample_feed_mm_min: (f64, f64, f64),
}

fn first_in_cut<T>(program: &Program, pick: impl Fn(&Posture) -> Option<T>) -> Option<T> {
    program
        .paths
        .iter()
        .flat_map(|p| p.postures.iter())
        .filter(|p| p.motion == MotionKind::Cut)
        .find_map(pick)
}

/// Resolve spindle speed, feed and feed per tooth: the options first, then `process.toml`,
/// then the file (first cutting SPINDL and FEDRAT); fz defaults to feed / (Z · rpm).
pub fn resolve_cutting(
    req: &SimulateRequest,
    process: &ProcessConfig,
    program: &Program,
    teeth: usize,
) -> miette::Result<Cutting> {
    for (name, v) in [
        ("rpm", req.rpm),
        ("feed-mm-min", req.feed_mm_min),
        ("fz-mm", req.fz_mm),
    ] {
        if let Some(v) = v {
            if !(v.is_finite() && v > 0.0) {
                return Err(miette!("--{name} must be positive, got {v}"));
            }
        }
    }
    let rpm = req
        .rpm
        .or(process.rpm)
        .or_else(|| first_in_cut(program, |p| p.spindle_rpm.filter(|r| *r > 0.0)));
    let feed_user = req.feed_mm_min.or(process.feed_mm_min);
    let fz_user = req.fz_mm.or(process.fz_mm);
    let feed_file = first_in_cut(program, |p| p.feed_mm_min.filter(|f| *f > 0.0));
    let Some(rpm) = rpm else {
        return Err(miette!(
            "no spindle speed: {} has no SPINDL; add --rpm N (or rpm in --process process.toml)",
            req.file.display()
        ));
    };
    let z = teeth as f64;
    let (feed_mm_min, feed_nominal, fz_mm) = match (feed_user, fz_user, feed_file) {
        (Some(f), Some(fz), _) => (Some(f), f, fz),
        (Some(f), None, _) => (Some(f), f, f / (z * rpm)),
        (None, Some(fz), Some(ff)) => (None, ff, fz),
        (None, Some(fz), None) => (Some(fz * z * rpm), fz * z * rpm, fz),
        (None, None, Some(ff)) => (None, ff, ff / (z * rpm)),
        (None, None, None) => {
            return Err(miette!(
                "no feed: {} has no FEDRAT; add --feed-mm-min V or --fz-mm F (or feed_mm_min / fz_mm in --process process.toml)",
                req.file.display()
            ));
        }
    };
    Ok(Cutting {
        rpm,
        feed_mm_min,
        feed_nominal,
        fz_mm,
    })
}

/// The predicted feed per posture (mm/min) of `path` on `machine`; with a feed override
/// the machine is planned at that programmed feed.
pub fn predicted_feed(
    path: &Toolpath,
    machine: &Machine,
    feed_override: Option<f64>,
) -> Result<Vec<f64>, crate::kinematics::KinematicsError> {
    match feed_override {
        Some(f) => {
            let mut p = path.clone();
            for q in &mut p.postures {
                q.feed_mm_min = Some(f);
            }
            crate::kinematics::predict_posture_feed(&p, machine)
        }
        None => crate::kinematics::predict_posture_feed(path, machine),
    }
}

/// Cutting time and the (min, max, mean) sample feed of resampled runs.
fn feed_figures(samples: &[Sample]) -> (f64, (f64, f64, f64)) {
    // t restarts at every run: the cutting time is the sum of the runs' last stamps.
    let mut cut_time = 0.0;
    let mut run_end = 0.0f64;
    let mut run = None;
    let (mut fmin, mut fmax, mut fsum) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
    for s in samples {
        if run != Some(s.run) {
            cut_time += run_end;
            run_end = 0.0;
            run = Some(s.run);
        }
        run_end = run_end.max(s.t_s);
        fmin = fmin.min(s.feed_mm_min);
        fmax = fmax.max(s.feed_mm_min);
        fsum += s.feed_mm_min;
    }
    cut_time += run_end;
    (cut_time, (fmin, fmax, fsum / samples.len().max(1) as f64))
}

/// Run a simulation. `progress(done, total)` is called from the calling thread after each
/// batch of tiles. Runs on the current rayon pool.
pub fn simulate(
    req: &SimulateRequest,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> miette::Result<SimulateRun> {
    if !(req.grid_um.is_finite() && req.grid_um > 0.0) {
        return Err(miette!("--grid-um must be positive, got {}", req.grid_um));
    }
    if !(req.dtheta_deg.is_finite() && req.dtheta_deg > 0.0 && req.dtheta_deg <= 90.0) {
        return Err(miette!(
            "--dtheta-deg must be in (0, 90], got {}",
            req.dtheta_deg
        ));
    }
    let grid = match req.grid {
        GridRequest::Window {
            x0_mm,
            y0_mm,
            x1_mm,
            y1_mm,
        } => {
            if x1_mm < x0_mm || y1_mm < y0_mm {
                return Err(miette!(
                    "--window X0,Y0,X1,Y1 needs X0 ≤ X1 and Y0 ≤ Y1, got {x0_mm},{y0_mm},{x1_mm},{y1_mm}"
                ));
            }
            GridSpec::Window {
                x0_mm,
                y0_mm,
                x1_mm,
                y1_mm,
            }
        }
        GridRequest::PatchAt {
            s_mm,
            length_mm,
            width_mm,
        } => GridSpec::Patch {
            s_mm,
            length_mm,
            width_mm,
        },
    };
    let cutter = super::load_tool(&req.tool)?;
    let process = match &req.process {
        Some(p) => super::load_process(p)?,
        None => ProcessConfig::default(),
    };
    let program = crate::io::toolpath::read_program(&req.file)?;
    let cutting = resolve_cutting(req, &process, &program, cutter.teeth())?;
    let machine = resolve_feed_source(req.feed, req.machine.as_deref())?;
    let ap_mm = req.ap_mm.or(process.ap_mm).unwrap_or(0.5);
    if !(ap_mm.is_finite() && ap_mm > 0.0) {
        return Err(miette!("--ap-mm must be positive, got {ap_mm}"));
    }
    let (model, mode) = req.model.with_resampling(req.dtheta_deg.to_radians());
    let mut ropts =
        resample::Options::new(mode, cutting.fz_mm, cutter.teeth()).with_rpm(cutting.rpm);
    if let Some(f) = cutting.feed_mm_min {
        ropts = ropts.with_feed_mm_min(f);
    }
    let file = req.file.display();
    let paths: Vec<usize> = match req.path {
        Some(n) if n >= 1 && n <= program.paths.len() => vec![n - 1],
        Some(n) => {
            return Err(miette!(
                "--path {n}: {file} has {} tool path(s)",
                program.paths.len()
            ));
        }
        None => (0..program.paths.len()).collect(),
    };
    let mut samples: Vec<Sample> = Vec::new();
    for &i in &paths {
        let path = &program.paths[i];
        let first_run = samples.last().map_or(0, |s| s.run + 1);
        let mut popts = ropts.clone();
        if let Some(m) = &machine {
            popts.posture_feed_mm_min =
                Some(predicted_feed(path, m, cutting.feed_mm_min).map_err(|e| {
                    miette!(
                        "{file}: tool path {} ({}): feed prediction: {e}",
                        i + 1,
                        path.name
                    )
                })?);
        }
        let mut got = resample::resample(path, &popts)
            .map_err(|e| miette!("{file}: tool path {} ({}): {e}", i + 1, path.name))?;
        for s in &mut got {
            s.run += first_run;
        }
        samples.extend(got);
    }
    if samples.is_empty() {
        return Err(miette!("{file}: no cutting moves to simulate"));
    }
    let mut sopts = surface::Options::new(model, grid, req.grid_um * 1e-3);
    sopts.depth_mm = ap_mm;
    let sim = surface::simulate(&samples, &cutter, &sopts, progress)
        .map_err(|e| miette!("{file}: {e}"))?;
    let (cut_time_s, sample_feed_mm_min) = feed_figures(&samples);
    Ok(SimulateRun {
        sim,
        cutter,
        cutting,
        ap_mm,
        predicted: machine.is_some(),
        samples: samples.len(),
        cut_time_s,
        sample_feed_mm_min,
    })
}
