//! `crest simulate`: a tool-path file read from disk, the cutter, spindle speed and feed
//! resolved (options, then `process.toml`, then the file's SPINDL/FEDRAT), the feed the
//! machine reaches planned when asked, the path resampled for the surface model and the
//! surface simulated on the requested grid.

use crate::config::ProcessConfig;
use crate::kinematics::Machine;
use crate::math::{Frame, Point3, Vec3};
use crate::resample::{self, Sample};
use crate::surface::cull::{Reach, Subset};
use crate::surface::{self, GridFrame, GridSpec, ModelKind, PartMap, Reference, Simulation};
use crate::tool::Cutter;
use crate::toolpath::{LowerOptions, MotionKind, Moves, Posture, Program, Toolpath};
use miette::miette;
use std::path::{Path, PathBuf};

/// Which feed moves the tool.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
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
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
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
    /// A patch centred at the part point nearest `point` (the design surface of `--part`, or
    /// the surface derived from the path), `length_mm` along the local feed, `width_mm`
    /// across.
    PatchNear {
        /// The point, mm (the path's frame).
        point: [f64; 3],
        /// Along the feed, mm.
        length_mm: f64,
        /// Across, mm.
        width_mm: f64,
    },
    /// The whole part (or a region of it) at `spacing_mm`, as a point cloud (needs a part).
    Map {
        /// Node spacing, mm.
        spacing_mm: f64,
        /// X0, Y0, Z0, X1, Y1, Z1 of the region, mm (the part's bounds when `None`).
        region: Option<[f64; 6]>,
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

/// Accepted chord tolerances, µm: finer meshes take unbounded time, coarser ones are not a
/// model of the cutter any more.
pub const CHORD_TOL_UM: (f64, f64) = (0.001, 10.0);

/// Everything `crest simulate` is asked (serde data: a part-map task carries it).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulateRequest {
    /// Tool-path file (CLSF or contact12).
    pub file: PathBuf,
    /// Cutter description (`tool.toml` file or text); the file's TLDATA when `None`.
    pub tool: Option<super::inputs::ToolSource>,
    /// Teeth of a tool taken from TLDATA.
    pub teeth: Option<usize>,
    /// Helix angle of a tool taken from TLDATA, degrees.
    pub helix_deg: Option<f64>,
    /// The design surface (STL, OBJ, PLY) in the path's frame.
    pub part: Option<PathBuf>,
    /// Apply MSYS: read the path in the absolute frame (the part must be in it too).
    pub absolute: bool,
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
    /// Machine description for the predicted feed (and to read G-code through).
    pub machine: Option<PathBuf>,
    /// Tool-centre-point control of G-code input.
    pub rtcp: crate::nc::Rtcp,
    /// Surface model.
    pub model: ModelKind,
    /// Spindle step of the ICE model, degrees.
    pub dtheta_deg: f64,
    /// Grid spacing, µm; by default a tenth of the feed per tooth (see [`default_grid_um`]).
    pub grid_um: Option<f64>,
    /// Chord tolerance of the meshes, µm (default [`surface::Options`]'s 0.01 µm; see
    /// [`CHORD_TOL_UM`]).
    #[serde(default)]
    pub chord_tol_um: Option<f64>,
    /// First rasterised band above the reference, µm (speed only; default 5 µm).
    #[serde(default)]
    pub band_um: Option<f64>,
    /// Grid placement.
    pub grid: GridRequest,
    /// Depth of cut, mm (default: process.toml, else 0.5).
    pub ap_mm: Option<f64>,
    /// Only this tool path (1-based).
    pub path: Option<usize>,
    /// Which moves cut (define the reference surface, are simulated, give the feed).
    #[serde(default)]
    pub moves: Moves,
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

/// Where the heights are measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReferenceSource {
    /// The contact data of the file.
    File,
    /// Contact data derived from the centre-line path (offset-surface fit).
    Derived,
    /// The design surface of the part.
    Part,
    /// None: a window measures WCS z.
    None,
}

impl ReferenceSource {
    /// The name used in output.
    pub fn name(self) -> &'static str {
        match self {
            ReferenceSource::File => "contact data of the file",
            ReferenceSource::Derived => "surface derived from the path",
            ReferenceSource::Part => "design surface of the part",
            ReferenceSource::None => "z = 0 (no contact data)",
        }
    }
}

/// What was simulated.
#[derive(Debug, Clone)]
pub enum Output {
    /// A height map on a window or patch.
    Grid(Box<Simulation>),
    /// A point cloud over the part.
    Map(PartMap),
}

/// A finished simulation and what it was run with.
#[derive(Debug, Clone)]
pub struct SimulateRun {
    /// The simulated surface.
    pub output: Output,
    /// Nodes in the grid or map.
    pub nodes: usize,
    /// Nodes with a height.
    pub nodes_cut: usize,
    /// Where the tool came from (a file or TLDATA).
    pub tool_source: String,
    /// What the heights are measured from.
    pub reference: ReferenceSource,
    /// Non-fatal findings (tool/TLDATA mismatch, degenerate mesh triangles, …).
    pub warnings: Vec<String>,
    /// Checks that failed (also in `warnings`): the command exits 1.
    pub failed_checks: Vec<String>,
    /// Which moves were simulated.
    pub moves: Moves,
    /// Distance from the `--patch-near` point to the cut surface and its tolerance, mm.
    pub patch_distance_mm: Option<(f64, f64)>,
    /// Samples the path gave before culling.
    pub samples_total: usize,
    /// Grid spacing used, µm (the option, or the default from the feed per tooth).
    pub grid_um: f64,
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
        if let Some(v) = v
            && !(v.is_finite() && v > 0.0)
        {
            return Err(miette!(
                "--{name} must be positive, got {}",
                crate::math::limits::shown(v)
            ));
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
            // A FEDRAT of 0 is not "no FEDRAT": name its line.
            let zero = first_in_cut(program, |p| {
                p.feed_mm_min.filter(|f| *f == 0.0).map(|_| p.line)
            });
            return Err(match zero {
                Some(line) => miette!(
                    "{}:{line}: the cutting moves run at FEDRAT 0 mm/min; add --feed-mm-min V or --fz-mm F",
                    req.file.display()
                ),
                None => miette!(
                    "no feed: {} has no FEDRAT; add --feed-mm-min V or --fz-mm F (or feed_mm_min / fz_mm in --process process.toml)",
                    req.file.display()
                ),
            });
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

/// Cutting time and the (min, max, mean) sample feed of resampled runs, accumulated.
#[derive(Debug, Default)]
struct FeedFigures {
    n: usize,
    cut_time: f64,
    run_end: f64,
    run: Option<usize>,
    min: f64,
    max: f64,
    sum: f64,
}

impl FeedFigures {
    fn push(&mut self, s: &Sample) {
        if self.n == 0 {
            self.min = f64::INFINITY;
            self.max = f64::NEG_INFINITY;
        }
        // t restarts at every run: the cutting time is the sum of the runs' last stamps.
        if self.run != Some(s.run) {
            self.cut_time += self.run_end;
            self.run_end = 0.0;
            self.run = Some(s.run);
        }
        self.run_end = self.run_end.max(s.t_s);
        self.min = self.min.min(s.feed_mm_min);
        self.max = self.max.max(s.feed_mm_min);
        self.sum += s.feed_mm_min;
        self.n += 1;
    }

    fn finish(&self) -> (f64, (f64, f64, f64)) {
        (
            self.cut_time + self.run_end,
            (self.min, self.max, self.sum / self.n.max(1) as f64),
        )
    }
}

/// The default grid spacing: a tenth of the feed per tooth (so that each feed mark spans ten
/// nodes), rounded down to 1, 2 or 5 × 10ⁿ µm, within 0.5 … 20 µm.
pub fn default_grid_um(fz_mm: f64) -> f64 {
    let target = (fz_mm * 1e3 / 10.0).clamp(0.5, 20.0);
    let decade = 10f64.powf(target.log10().floor());
    let m = target / decade;
    let nice = if m >= 5.0 {
        5.0
    } else if m >= 2.0 {
        2.0
    } else {
        1.0
    };
    nice * decade
}

fn has_contacts(program: &Program) -> bool {
    program
        .paths
        .iter()
        .flat_map(|p| p.postures.iter())
        .any(|p| p.motion == MotionKind::Cut && p.contact.is_some())
}

/// Run a simulation, reporting each phase to `progress` (the simulation itself counts
/// tiles of the grid, or cells of a map, out of a total fixed when it starts). Runs on the
/// current rayon pool.
pub fn simulate(
    req: &SimulateRequest,
    progress: &dyn super::Progress,
) -> miette::Result<SimulateRun> {
    simulate_shard(req, None, progress)
}

/// [`simulate`], for a part map only the cells of shard `k` of `n` (`shard = Some((k, n))`:
/// cells k, k+n, … as [`surface::map_part`] splits them; see [`super::tasks::map`]).
/// Other grids are not split: a shard of one is refused.
pub fn simulate_shard(
    req: &SimulateRequest,
    shard: Option<(usize, usize)>,
    progress: &dyn super::Progress,
) -> miette::Result<SimulateRun> {
    if shard.is_some() && !matches!(req.grid, GridRequest::Map { .. }) {
        return Err(miette!(
            "--shard splits a part map (--map-mm) into its cells; a window or patch is one task"
        ));
    }
    let tiles = |done: usize, total: usize| progress.advance(done as u64, total as u64);
    let tiles: &(dyn Fn(usize, usize) + Sync) = &tiles;
    if let Some(g) = req.grid_um
        && !(g.is_finite() && g > 0.0)
    {
        return Err(miette!("--grid-um must be positive, got {g}"));
    }
    if let Some(t) = req.chord_tol_um
        && !(CHORD_TOL_UM.0..=CHORD_TOL_UM.1).contains(&t)
    {
        return Err(miette!(
            "--chord-tol-um must be between {} and {} µm, got {t}",
            CHORD_TOL_UM.0,
            CHORD_TOL_UM.1
        ));
    }
    if let Some(b) = req.band_um
        && !(b.is_finite() && b >= 0.1)
    {
        return Err(miette!("--band-um must be at least 0.1 µm, got {b}"));
    }
    let dmin = crate::math::limits::MIN_DTHETA_DEG;
    if !(req.dtheta_deg.is_finite() && req.dtheta_deg >= dmin && req.dtheta_deg <= 90.0) {
        return Err(miette!(
            "--dtheta-deg must be in [{dmin}, 90], got {}",
            req.dtheta_deg
        ));
    }
    if let GridRequest::Window {
        x0_mm,
        y0_mm,
        x1_mm,
        y1_mm,
    } = req.grid
        && (x1_mm < x0_mm || y1_mm < y0_mm)
    {
        return Err(miette!(
            "--window X0,Y0,X1,Y1 needs X0 ≤ X1 and Y0 ≤ Y1, got {x0_mm},{y0_mm},{x1_mm},{y1_mm}"
        ));
    }
    let mut warnings = Vec::new();
    let mut failed_checks = Vec::new();
    let mut patch_distance = None;
    let part = match &req.part {
        Some(p) => {
            progress.phase(&format!("reading {}", p.display()), "");
            let f = crate::io::mesh::read_part(p)?;
            warnings.extend(f.warnings);
            Some(f.part)
        }
        None => None,
    };
    if matches!(req.grid, GridRequest::Map { .. }) && part.is_none() {
        return Err(miette!(
            "--map-mm maps the design surface of a part: give --part PART.stl"
        ));
    }
    let process = match &req.process {
        Some(p) => super::load_process(p)?,
        None => ProcessConfig::default(),
    };
    let lower = LowerOptions {
        apply_msys: req.absolute,
        ..Default::default()
    };
    // G-code is read through the machine, which then predicts the feed only when asked.
    let gcode = crate::io::toolpath::detect(&req.file)? == crate::io::toolpath::InputKind::Gcode;
    let read = crate::io::toolpath::ReadOptions {
        lower,
        machine: match (&req.machine, gcode) {
            (Some(m), true) => Some(super::load_machine(m)?),
            _ => None,
        },
        rtcp: req.rtcp,
    };
    let read_machine = read.machine.clone();
    progress.phase(&format!("reading {}", req.file.display()), "");
    let mut program = crate::io::toolpath::read_program_with(&req.file, read)?;
    // The cut moves as the file gives them, before `--moves all` makes every feed move one.
    let cut_kinds: Vec<Vec<bool>> = program
        .paths
        .iter()
        .map(|p| {
            p.postures
                .iter()
                .map(|q| q.motion == MotionKind::Cut)
                .collect()
        })
        .collect();
    req.moves.apply(&mut program);
    let (cutter, tool_source, tool_warnings) = super::inputs::resolve_cutter(
        req.tool.as_ref(),
        &program,
        &req.file,
        req.teeth,
        req.helix_deg,
    )?;
    warnings.extend(tool_warnings);
    let cutting = resolve_cutting(req, &process, &program, cutter.teeth())?;
    let machine = match (gcode, req.feed) {
        (true, Some(FeedSource::Predicted)) => read_machine,
        (true, _) => None,
        (false, _) => resolve_feed_source(req.feed, req.machine.as_deref())?,
    };
    let grid_um = req
        .grid_um
        .unwrap_or_else(|| default_grid_um(cutting.fz_mm));
    let ap_mm = req.ap_mm.or(process.ap_mm).unwrap_or(0.5);
    if !(ap_mm.is_finite() && ap_mm > 0.0) {
        return Err(miette!("--ap-mm must be positive, got {ap_mm}"));
    }
    let file = req.file.display().to_string();
    // Contact data: the file's, else derived from the path when the heights need it.
    let from_file = has_contacts(&program);
    let mut derived: Option<super::contact::DerivedContacts> = None;
    let needs_contacts = part.is_none() && !matches!(req.grid, GridRequest::Map { .. });
    let reference = if part.is_some() && !matches!(req.grid, GridRequest::PatchAt { .. }) {
        ReferenceSource::Part
    } else if from_file {
        ReferenceSource::File
    } else if needs_contacts || matches!(req.grid, GridRequest::PatchAt { .. }) {
        progress.phase("deriving contact points from the path", "");
        let found = super::contact::derive_contacts(&mut program, &cutter);
        if let Some(w) = found.summary() {
            warnings.push(w);
        }
        derived = Some(found.clone());
        if found.with_contact == 0 {
            match req.grid {
                GridRequest::Window { .. } => ReferenceSource::None,
                _ => {
                    return Err(miette!(
                        "{file}: the path has no contact data and none can be derived from it (a single pass has no neighbour to fit the surface to); give --part PART.stl"
                    ));
                }
            }
        } else {
            ReferenceSource::Derived
        }
    } else {
        ReferenceSource::None
    };
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
    // The region the tool must reach, for culling.
    let margin = cutter.radius_mm + ap_mm + 1.0;
    let (grid, reach): (Option<GridSpec>, Option<Reach>) = match req.grid {
        GridRequest::Window {
            x0_mm,
            y0_mm,
            x1_mm,
            y1_mm,
        } => (
            Some(GridSpec::Window {
                x0_mm,
                y0_mm,
                x1_mm,
                y1_mm,
            }),
            Some(Reach {
                lo: Point3::new(x0_mm, y0_mm, f64::NEG_INFINITY),
                hi: Point3::new(x1_mm, y1_mm, f64::INFINITY),
            }),
        ),
        GridRequest::PatchAt {
            s_mm,
            length_mm,
            width_mm,
        } => (
            Some(GridSpec::Patch {
                s_mm,
                length_mm,
                width_mm,
            }),
            None,
        ),
        GridRequest::PatchNear {
            point,
            length_mm,
            width_mm,
        } => {
            let q = Point3::new(point[0], point[1], point[2]);
            if !point.iter().all(|v| v.is_finite()) {
                return Err(miette!("--patch-near wants three finite numbers"));
            }
            let half = 0.5 * (length_mm * length_mm + width_mm * width_mm).sqrt();
            (None, Some(Reach::around(&q, half + 2.0)))
        }
        GridRequest::Map { region, .. } => (
            None,
            match region {
                Some(r) => Some(Reach {
                    lo: Point3::new(r[0], r[1], r[2]),
                    hi: Point3::new(r[3], r[4], r[5]),
                }),
                None => part.as_ref().map(|p| {
                    let (lo, hi) = p.bounds();
                    Reach { lo, hi }
                }),
            },
        ),
    };
    let (model, mode) =
        req.model
            .with_resampling(req.dtheta_deg.to_radians(), cutting.fz_mm, cutter.teeth());
    let mut ropts =
        resample::Options::new(mode, cutting.fz_mm, cutter.teeth()).with_rpm(cutting.rpm);
    if let Some(f) = cutting.feed_mm_min {
        ropts = ropts.with_feed_mm_min(f);
    }
    // The budget: the samples the resampling streams (before culling) follow the path.
    let estimated_samples = {
        let mut extent = crate::resample::PathExtent::default();
        for &i in &paths {
            let p = &program.paths[i];
            extent.cutting_mm += p.stats.cutting_length_mm;
            extent.runs += p.cutting_runs().len();
        }
        let est = crate::resample::estimate_samples(
            &extent,
            mode,
            cutting.fz_mm,
            cutter.teeth(),
            Some(cutting.rpm),
        );
        let cap = crate::math::limits::MAX_SAMPLES as f64;
        if est > cap {
            return Err(miette!(
                "{file}: {:.1} mm of cutting moves would be resampled into about {est:.3e} poses (more than {cap:.0e}): check the feed per tooth ({} mm) and Δθ",
                extent.cutting_mm,
                cutting.fz_mm
            ));
        }
        est
    };
    progress.phase("resampling", "poses");
    let mut streamed = 0u64;
    let mut subset = Subset::default();
    let mut all_samples = (0usize, 0.0f64, (f64::INFINITY, f64::NEG_INFINITY, 0.0f64));
    let mut run_base = 0;
    let mut last_run = 0;
    for &i in &paths {
        let path = &program.paths[i];
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
        let mut figures = FeedFigures::default();
        resample::resample_with(path, &popts, |s| {
            let mut s = s.clone();
            s.run += run_base;
            last_run = last_run.max(s.run);
            figures.push(&s);
            let keep = reach.as_ref().is_none_or(|r| r.near(&s.position, margin));
            subset.push(&s, keep);
            streamed += 1;
            if streamed.is_multiple_of(8192) {
                progress.advance(streamed, (estimated_samples as u64).max(streamed));
            }
        })
        .map_err(|e| miette!("{file}: tool path {} ({}): {e}", i + 1, path.name))?;
        run_base = last_run + 1;
        let (cut, (lo, hi, mean)) = figures.finish();
        let n = all_samples.0 + figures.n;
        all_samples.2 = (
            all_samples.2.0.min(lo),
            all_samples.2.1.max(hi),
            if n > 0 {
                (all_samples.2.2 * all_samples.0 as f64 + mean * figures.n as f64) / n as f64
            } else {
                0.0
            },
        );
        all_samples.0 = n;
        all_samples.1 += cut;
    }
    let samples_total = subset.seen;
    let samples = subset.samples;
    if samples_total == 0 {
        return Err(miette!("{file}: no cutting moves to simulate"));
    }
    if samples.is_empty() {
        if let GridRequest::PatchNear { point, .. } = req.grid {
            let q = Point3::new(point[0], point[1], point[2]);
            let is_cut =
                |pi: usize, i: usize| program.paths[pi].postures[i].motion == MotionKind::Cut;
            let far = 2.0 * cutter.radius_mm;
            if let Some(n) = super::air::nearest(&program, &paths, &q, far, true, is_cut) {
                return Err(miette!(
                    "{file}: --patch-near {},{},{} is {:.3} mm from the surface the {} moves define (nearest point {:.4},{:.4},{:.4}): no cutting move comes within reach of the patch; pick a point on a finishing region (`crest inspect --regions` lists them)",
                    point[0],
                    point[1],
                    point[2],
                    n.distance_mm,
                    if req.moves == Moves::All {
                        "feed"
                    } else {
                        "cut"
                    },
                    n.point.x,
                    n.point.y,
                    n.point.z
                ));
            }
        }
        return Err(miette!(
            "{file}: no cutting move comes within reach of the grid (tool radius + depth of cut {margin:.3} mm); check the coordinates and the frame (--absolute applies MSYS)"
        ));
    }
    let mut sopts = surface::Options::new(
        model,
        grid.unwrap_or(GridSpec::Window {
            x0_mm: 0.0,
            y0_mm: 0.0,
            x1_mm: 0.0,
            y1_mm: 0.0,
        }),
        grid_um * 1e-3,
    );
    sopts.depth_mm = ap_mm;
    if let Some(t) = req.chord_tol_um {
        sopts.chord_tol_mm = t * 1e-3;
    }
    if let Some(b) = req.band_um {
        sopts.band_mm = (b * 1e-3).min(ap_mm);
    }
    sopts.process = process.effects(match &req.tool {
        Some(t) => t.min_chip()?,
        None => None,
    });
    let reference_arg = match (&part, reference) {
        (Some(p), ReferenceSource::Part) => Reference::Part(p),
        _ => Reference::Contacts,
    };
    let output = match req.grid {
        GridRequest::Map { spacing_mm, .. } => {
            let Some(p) = &part else {
                unreachable!("checked above")
            };
            if let GridRequest::Map {
                region: Some(r), ..
            } = req.grid
                && !(r.iter().all(|v| v.is_finite())
                    && r[3] >= r[0]
                    && r[4] >= r[1]
                    && r[5] >= r[2])
            {
                return Err(miette!(
                    "--region X0,Y0,Z0,X1,Y1,Z1 needs finite numbers with X0 ≤ X1, Y0 ≤ Y1, Z0 ≤ Z1"
                ));
            }
            let tile = (128.0 * spacing_mm).clamp(0.5, 10.0).max(spacing_mm);
            sopts.spacing_mm = spacing_mm;
            let region = reach.map(|r| (r.lo, r.hi));
            progress.phase("simulating the part map", "cells");
            let m = surface::map_part(
                &samples, &cutter, &sopts, p, spacing_mm, tile, region, shard, tiles,
            )
            .map_err(|e| miette!("{file}: {e}"))?;
            Output::Map(m)
        }
        GridRequest::PatchNear {
            point,
            length_mm,
            width_mm,
        } => {
            let q = Point3::new(point[0], point[1], point[2]);
            let far = 2.0 * cutter.radius_mm;
            let is_cut =
                |pi: usize, i: usize| program.paths[pi].postures[i].motion == MotionKind::Cut;
            // The cut surface near q: the contacts of the cut moves, else (a part) their CL points.
            let near_cut = super::air::nearest(&program, &paths, &q, far, part.is_some(), is_cut);
            // A point in the air (on a lead-in arc, a rapid) is refused with its distance.
            if let Some(n) = &near_cut {
                let tol = super::air::tolerance_mm(n, cutter.radius_mm);
                let (d, at) = match &part {
                    Some(p) => {
                        let c = p.closest(&q).point;
                        ((c - q).norm(), c)
                    }
                    None => (n.off_surface_mm(cutter.radius_mm), n.point),
                };
                patch_distance = Some((d, tol));
                // `--moves all` simulates as crest did before (a patch reached by engage or
                // retract moves only is then a warning, below).
                if d > tol && req.moves == Moves::Cut {
                    return Err(miette!(
                        "{file}: --patch-near {},{},{} is {d:.3} mm from the surface the cut moves define (off it along its normal; nearest point {:.4},{:.4},{:.4}), more than the tolerance {tol:.3} mm (the larger of {} mm and {} × the local stepover{}): the point is in the air, on an approach, engage or retract move or a rapid; pick a point on a finishing region (`crest inspect --regions` lists them), or simulate every feed move with --moves all",
                        point[0],
                        point[1],
                        point[2],
                        at.x,
                        at.y,
                        at.z,
                        super::air::MIN_TOLERANCE_MM,
                        super::air::STEPOVERS,
                        n.stepover_mm.map_or_else(
                            || format!(
                                ", unknown: the tool radius {} mm stands for it",
                                cutter.radius_mm
                            ),
                            |s| format!(" {s:.3} mm")
                        ),
                    ));
                }
            }
            let (centre, normal) = match &part {
                Some(p) => {
                    let c = p.closest(&q);
                    (c.point, c.normal)
                }
                None => {
                    let best = samples
                        .iter()
                        .filter_map(|s| Some((s.contact?, s.normal?)))
                        .min_by(|a, b| (a.0 - q).norm().total_cmp(&(b.0 - q).norm()));
                    let Some(b) = best else {
                        return Err(miette!(
                            "{file}: no contact point near {},{},{}",
                            point[0],
                            point[1],
                            point[2]
                        ));
                    };
                    b
                }
            };
            // With every feed move simulated: is the patch reached by cut moves at all?
            if req.moves == Moves::All
                && let Some((_, tol)) = patch_distance
            {
                let was_cut = |pi: usize, i: usize| cut_kinds[pi][i];
                let cut_only =
                    super::air::nearest(&program, &paths, &centre, far, part.is_some(), was_cut);
                let away = cut_only.map_or(f64::INFINITY, |c| c.distance_mm);
                if away > tol {
                    let w = format!(
                        "the patch at {:.4},{:.4},{:.4} is reached by engage and retract moves only ({}): its heights are those of lead-in or lead-out arcs, not of the finishing passes",
                        centre.x,
                        centre.y,
                        centre.z,
                        if away.is_finite() {
                            format!("the nearest cut move's surface is {away:.3} mm away")
                        } else {
                            "the path has no cut move".to_string()
                        }
                    );
                    warnings.push(w.clone());
                    failed_checks.push(w);
                }
            }
            // The patch centre must lie within the tool radius of the cutter somewhere.
            let rc = cutter.corner_radius_mm();
            let near = samples
                .iter()
                .map(|s| ((s.position + s.axis * rc) - centre).norm() - rc)
                .fold(f64::INFINITY, f64::min);
            if near > cutter.radius_mm {
                return Err(miette!(
                    "{file}: the patch centre {:.4},{:.4},{:.4} is {near:.3} mm from the nearest cutter position, farther than the tool radius {} mm: the path does not cut there",
                    centre.x,
                    centre.y,
                    centre.z,
                    cutter.radius_mm
                ));
            }
            let feed = samples
                .iter()
                .min_by(|a, b| {
                    (a.position - centre)
                        .norm()
                        .total_cmp(&(b.position - centre).norm())
                })
                .map_or_else(Vec3::x, |s| s.feed_dir);
            let f = Frame::tool(&normal, &feed);
            sopts.grid = GridSpec::Oriented {
                frame: GridFrame {
                    origin: centre,
                    u: f.x,
                    v: f.y,
                    w: f.z,
                },
                length_mm,
                width_mm,
            };
            Output::Grid(Box::new(
                {
                    progress.phase("simulating", "tiles");
                    surface::simulate_with(&samples, &cutter, &sopts, reference_arg, tiles)
                }
                .map_err(|e| miette!("{file}: {e}"))?,
            ))
        }
        GridRequest::PatchAt { s_mm, .. } => {
            let last = samples.last().map_or(0.0, |s| s.s_mm);
            if !(0.0..=last + 1e-9).contains(&s_mm) {
                return Err(miette!(
                    "--patch-at {s_mm}: the path has {last:.3} mm of cutting moves (0 to {last:.3})"
                ));
            }
            Output::Grid(Box::new(
                {
                    progress.phase("simulating", "tiles");
                    surface::simulate_with(&samples, &cutter, &sopts, reference_arg, tiles)
                }
                .map_err(|e| miette!("{file}: {e}"))?,
            ))
        }
        GridRequest::Window { .. } => Output::Grid(Box::new(
            {
                progress.phase("simulating", "tiles");
                surface::simulate_with(&samples, &cutter, &sopts, reference_arg, tiles)
            }
            .map_err(|e| miette!("{file}: {e}"))?,
        )),
    };
    // Derived contacts left out as inconsistent fail the run where their cutter touches the
    // grid: the reference surface there is not the one the cutter touched. A posture
    // touches it when its lowest point along the grid's normal (its contact, were the
    // surface level there) lies over the grid and within `TOUCH_MM` of its plane.
    if let (Output::Grid(sim), Some(d)) = (&output, &derived) {
        const TOUCH_MM: f64 = 0.5;
        let (centre, w) = sim.node_point(sim.map.nx / 2, sim.map.ny / 2);
        let half =
            0.5e-3 * (sim.map.nx as f64 * sim.map.dx_um).hypot(sim.map.ny as f64 * sim.map.dy_um);
        let rc = cutter.corner_radius_mm();
        let rd = cutter.radius_mm - rc;
        let reaching: Vec<_> = d
            .inconsistent
            .iter()
            .filter(|(pi, _, _)| paths.contains(pi))
            .filter(|(pi, i, _)| {
                let p = &program.paths[*pi].postures[*i];
                let a = p.axis.normalize();
                let lowest =
                    p.position + a * rc + crate::part::derive::radial(&w, &a) * rd - w * rc;
                let d = lowest - centre;
                let up = d.dot(&w);
                up.abs() <= TOUCH_MM && (d - w * up).norm() <= half + TOUCH_MM
            })
            .collect();
        if let Some((pi, i, why)) = reaching.first() {
            let p = &program.paths[*pi].postures[*i];
            let w = format!(
                "{} postures whose derived contact is inconsistent reach the grid (the first at {:.4},{:.4},{:.4}: {}): the reference surface there is not the one the cutter touched; give the part (--part PART.stl)",
                reaching.len(),
                p.position.x,
                p.position.y,
                p.position.z,
                why.describe()
            );
            warnings.push(w.clone());
            failed_checks.push(w);
        }
    }
    // The sanity checks (README "Sanity checks"): each finding fails the run.
    let mut sane = super::sanity::unit_findings(&program);
    let no_heights: [f64; 0] = [];
    let mut facts = super::sanity::Facts {
        cutter: &cutter,
        model: req.model,
        fz_mm: cutting.fz_mm,
        chord_tol_um: sopts.chord_tol_mm * 1e3,
        stepover_mm: None,
        ap_mm,
        heights_um: &no_heights,
        patch_mm: None,
        axis_normal_cos: None,
    };
    if let Output::Grid(sim) = &output {
        let (centre, normal) = sim.node_point(sim.map.nx / 2, sim.map.ny / 2);
        let is_cut = |pi: usize, i: usize| program.paths[pi].postures[i].motion == MotionKind::Cut;
        let far = 2.0 * cutter.radius_mm;
        facts.stepover_mm = super::air::nearest(&program, &paths, &centre, far, true, is_cut)
            .and_then(|n| n.stepover_mm);
        facts.heights_um = &sim.map.z_um;
        facts.patch_mm = match req.grid {
            GridRequest::PatchNear {
                length_mm,
                width_mm,
                ..
            }
            | GridRequest::PatchAt {
                length_mm,
                width_mm,
                ..
            } => Some((length_mm, width_mm)),
            _ => None,
        };
        facts.axis_normal_cos = samples
            .iter()
            .min_by(|a, b| {
                (a.position - centre)
                    .norm()
                    .total_cmp(&(b.position - centre).norm())
            })
            .map(|s| s.axis.dot(&normal).abs());
    }
    sane.extend(super::sanity::check(&facts));
    warnings.extend(sane.iter().cloned());
    failed_checks.extend(sane);
    let (nodes, nodes_cut) = match &output {
        Output::Grid(sim) => (sim.map.nx * sim.map.ny, sim.nodes_cut),
        Output::Map(m) => (m.points.len(), m.nodes_cut),
    };
    Ok(SimulateRun {
        output,
        nodes,
        nodes_cut,
        tool_source,
        reference,
        warnings,
        failed_checks,
        moves: req.moves,
        patch_distance_mm: patch_distance,
        samples_total,
        grid_um,
        cutter,
        cutting,
        ap_mm,
        predicted: machine.is_some(),
        samples: samples.len(),
        cut_time_s: all_samples.1,
        sample_feed_mm_min: all_samples.2,
    })
}
