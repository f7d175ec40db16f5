//! `crest simulate`: predict the machined surface of a tool path as a height map.
//!
//! ```text
//! crest simulate FILE --tool tool.toml [--process process.toml] [--rpm N] [--feed-mm-min V]
//!     [--fz-mm F] --model dome|ice [--dtheta-deg D] --grid-um G
//!     (--window X0,Y0,X1,Y1 | --patch-at S_MM --patch-mm L,W) -o OUT.(csv|gsf|sdf) [--json]
//! ```
//!
//! The spindle speed and feed come from the options, else from `process.toml`, else from
//! the file's SPINDL/FEDRAT. The feed per tooth is `--fz-mm` (or `fz_mm`), else
//! feed / (Z · rpm). A progress bar is drawn on stderr when it is a terminal.

use super::Outcome;
use crate::resample::{self, Mode, Sample};
use crate::surface::{self, GridSpec, Model, Simulation};
use crate::toolpath::{MotionKind, Program};
use clap::ValueEnum;
use miette::{IntoDiagnostic, WrapErr, miette};
use serde::Deserialize;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The surface model, as named on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModelName {
    /// Instantaneous positions: the revolved body of each tooth at every fz.
    Dome,
    /// Pondered movement: the teeth's cutting edges swept at every Δθ.
    Ice,
}

/// Options of `crest simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Tool-path file (NX CLSF or contact12).
    pub file: PathBuf,
    /// Cutter description (tool.toml).
    #[arg(long, value_name = "TOOL.TOML")]
    pub tool: PathBuf,
    /// Process parameters (process.toml: rpm, fz_mm, feed_mm_min, ap_mm, …).
    #[arg(long, value_name = "PROCESS.TOML")]
    pub process: Option<PathBuf>,
    /// Spindle speed, rpm (overrides process.toml and the file's SPINDL).
    #[arg(long, value_name = "N")]
    pub rpm: Option<f64>,
    /// Feed, mm/min (overrides process.toml and the file's FEDRAT).
    #[arg(long, value_name = "V")]
    pub feed_mm_min: Option<f64>,
    /// Feed per tooth, mm (default: feed / (teeth × rpm)).
    #[arg(long, value_name = "F")]
    pub fz_mm: Option<f64>,
    /// Which feed moves the tool: `programmed` (FEDRAT, or `--feed-mm-min`) or `predicted`
    /// (the feed the machine of `--machine` really reaches, `crest feed`, kinematics.md;
    /// the spindle speed stays fixed, so the feed per tooth follows the feed).
    /// Default: `programmed`, or `predicted` when `--machine` is given.
    #[arg(long, value_enum, value_name = "SOURCE")]
    pub feed: Option<super::feed::FeedSource>,
    /// Machine description (`machine.toml`) for `--feed predicted` (given alone, it implies
    /// `--feed predicted`). With `--feed-mm-min V`, the machine is planned at V.
    #[arg(long, value_name = "MACHINE.TOML")]
    pub machine: Option<PathBuf>,
    /// Surface model.
    #[arg(long, value_enum)]
    pub model: ModelName,
    /// Spindle step of the ICE model, degrees.
    #[arg(long, value_name = "D", default_value_t = 1.0)]
    pub dtheta_deg: f64,
    /// Grid spacing, µm.
    #[arg(long, value_name = "G")]
    pub grid_um: f64,
    /// A window of the WCS xy plane, mm: X0,Y0,X1,Y1 (heights along +z).
    #[arg(long, value_name = "X0,Y0,X1,Y1", allow_hyphen_values = true, conflicts_with_all = ["patch_at", "patch_mm"], required_unless_present = "patch_at")]
    pub window: Option<String>,
    /// A patch on the tangent plane at the contact point at this arc length of the path, mm
    /// (heights along the surface normal).
    #[arg(
        long,
        value_name = "S_MM",
        requires = "patch_mm",
        allow_negative_numbers = true
    )]
    pub patch_at: Option<f64>,
    /// Patch size, mm: L (along the feed), W (across).
    #[arg(long, value_name = "L,W", requires = "patch_at")]
    pub patch_mm: Option<String>,
    /// Depth of cut ap, mm (overrides process.toml; default 0.5): nodes that would be cut
    /// higher than this above the nominal surface are reported as not reached.
    #[arg(long, value_name = "AP")]
    pub ap_mm: Option<f64>,
    /// Simulate only this tool path (1-based, in file order); default: all.
    #[arg(long, value_name = "N")]
    pub path: Option<usize>,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Output height map: .csv (µm), .gsf or .sdf.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub output: PathBuf,
    /// Print one JSON object with the grid, counts, time and height statistics.
    #[arg(long)]
    pub json: bool,
}

/// `process.toml`: cutting parameters, units in the key names; every key is optional.
///
/// ```toml
/// rpm = 15000.0
/// fz_mm = 0.05
/// feed_mm_min = 3000.0
/// ap_mm = 0.2
/// ae_mm = 0.2
/// lead_deg = 15.0
/// tilt_deg = 0.0
/// ```
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProcessConfig {
    /// Spindle speed, rpm.
    pub rpm: Option<f64>,
    /// Feed per tooth, mm.
    pub fz_mm: Option<f64>,
    /// Feed, mm/min.
    pub feed_mm_min: Option<f64>,
    /// Depth of cut, mm (the stock above the nominal surface).
    pub ap_mm: Option<f64>,
    /// Stepover (radial engagement), mm. Informative: the path sets it.
    pub ae_mm: Option<f64>,
    /// Lead angle, degrees. Informative: the path's tool axis sets it.
    pub lead_deg: Option<f64>,
    /// Side tilt angle, degrees. Informative: the path's tool axis sets it.
    pub tilt_deg: Option<f64>,
}

impl ProcessConfig {
    /// Parse `process.toml` text; errors name the line and column.
    pub fn parse(text: &str, file: &Path) -> miette::Result<ProcessConfig> {
        let cfg: ProcessConfig = toml::from_str(text).map_err(|e| {
            let (line, col) = e
                .span()
                .map(|s| line_column(text, s.start))
                .unwrap_or((0, 0));
            miette!("{}:{line}:{col}: {}", file.display(), e.message())
        })?;
        let checks = [
            ("rpm", cfg.rpm),
            ("fz_mm", cfg.fz_mm),
            ("feed_mm_min", cfg.feed_mm_min),
            ("ap_mm", cfg.ap_mm),
            ("ae_mm", cfg.ae_mm),
        ];
        for (key, v) in checks {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    let at = text.find(key).unwrap_or(0);
                    let (line, col) = line_column(text, at);
                    return Err(miette!(
                        "{}:{line}:{col}: {key} must be positive, got {v}",
                        file.display()
                    ));
                }
            }
        }
        for (key, v) in [("lead_deg", cfg.lead_deg), ("tilt_deg", cfg.tilt_deg)] {
            if let Some(v) = v {
                if !(v.is_finite() && v.abs() <= 90.0) {
                    let at = text.find(key).unwrap_or(0);
                    let (line, col) = line_column(text, at);
                    return Err(miette!(
                        "{}:{line}:{col}: {key} must be within ±90°, got {v}",
                        file.display()
                    ));
                }
            }
        }
        Ok(cfg)
    }
}

/// 1-based line and column of byte offset `at`.
fn line_column(text: &str, at: usize) -> (usize, usize) {
    let before = &text.as_bytes()[..at.min(text.len())];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |p| p + 1);
    let col = String::from_utf8_lossy(&before[start..]).chars().count() + 1;
    (line, col)
}

/// Parse `n` comma-separated numbers of option `name`.
fn numbers(s: &str, n: usize, name: &str) -> miette::Result<Vec<f64>> {
    let v: Result<Vec<f64>, _> = s.split(',').map(|p| p.trim().parse::<f64>()).collect();
    match v {
        Ok(v) if v.len() == n && v.iter().all(|x| x.is_finite()) => Ok(v),
        _ => Err(miette!(
            "--{name} wants {n} comma-separated numbers, got '{s}'"
        )),
    }
}

/// Spindle speed, feed and feed per tooth after resolving options, process.toml and file.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Cutting {
    rpm: f64,
    /// Feed given by the user (None = the file's FEDRAT, per posture).
    feed_mm_min: Option<f64>,
    /// Representative feed, mm/min.
    feed_nominal: f64,
    fz_mm: f64,
}

fn first_in_cut<T>(
    program: &Program,
    pick: impl Fn(&crate::toolpath::Posture) -> Option<T>,
) -> Option<T> {
    program
        .paths
        .iter()
        .flat_map(|p| p.postures.iter())
        .filter(|p| p.motion == MotionKind::Cut)
        .find_map(pick)
}

fn resolve_cutting(
    args: &Args,
    process: &ProcessConfig,
    program: &Program,
    teeth: usize,
) -> miette::Result<Cutting> {
    for (name, v) in [
        ("rpm", args.rpm),
        ("feed-mm-min", args.feed_mm_min),
        ("fz-mm", args.fz_mm),
    ] {
        if let Some(v) = v {
            if !(v.is_finite() && v > 0.0) {
                return Err(miette!("--{name} must be positive, got {v}"));
            }
        }
    }
    let rpm = args
        .rpm
        .or(process.rpm)
        .or_else(|| first_in_cut(program, |p| p.spindle_rpm.filter(|r| *r > 0.0)));
    let feed_user = args.feed_mm_min.or(process.feed_mm_min);
    let fz_user = args.fz_mm.or(process.fz_mm);
    let feed_file = first_in_cut(program, |p| p.feed_mm_min.filter(|f| *f > 0.0));
    let Some(rpm) = rpm else {
        return Err(miette!(
            "no spindle speed: {} has no SPINDL; add --rpm N (or rpm in --process process.toml)",
            args.file.display()
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
                args.file.display()
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

fn read_text(path: &Path, what: &str) -> miette::Result<String> {
    std::fs::read_to_string(path)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot read {what} {}", path.display()))
}

/// Run `crest simulate`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let started = Instant::now();
    if !(args.grid_um.is_finite() && args.grid_um > 0.0) {
        return Err(miette!("--grid-um must be positive, got {}", args.grid_um));
    }
    if !(args.dtheta_deg.is_finite() && args.dtheta_deg > 0.0 && args.dtheta_deg <= 90.0) {
        return Err(miette!(
            "--dtheta-deg must be in (0, 90], got {}",
            args.dtheta_deg
        ));
    }
    let grid = match (&args.window, args.patch_at, &args.patch_mm) {
        (Some(w), _, _) => {
            let v = numbers(w, 4, "window")?;
            if v[2] < v[0] || v[3] < v[1] {
                return Err(miette!(
                    "--window X0,Y0,X1,Y1 needs X0 ≤ X1 and Y0 ≤ Y1, got '{w}'"
                ));
            }
            GridSpec::Window {
                x0_mm: v[0],
                y0_mm: v[1],
                x1_mm: v[2],
                y1_mm: v[3],
            }
        }
        (None, Some(s), Some(lw)) => {
            let v = numbers(lw, 2, "patch-mm")?;
            GridSpec::Patch {
                s_mm: s,
                length_mm: v[0],
                width_mm: v[1],
            }
        }
        _ => {
            return Err(miette!(
                "give --window X0,Y0,X1,Y1 or --patch-at S_MM --patch-mm L,W"
            ));
        }
    };
    if crate::io::HeightMapFormat::from_path(&args.output).is_none() {
        return Err(miette!(
            "{}: unknown output extension (expected .csv, .gsf or .sdf)",
            args.output.display()
        ));
    }

    let tool_text = read_text(&args.tool, "tool file")?;
    let cutter = crate::tool::load_tool_toml(&tool_text).map_err(|e| {
        miette!(
            "{}:{}:{}: {}",
            args.tool.display(),
            e.line(),
            e.column(),
            e.message()
        )
    })?;
    let process = match &args.process {
        Some(p) => ProcessConfig::parse(&read_text(p, "process file")?, p)?,
        None => ProcessConfig::default(),
    };
    let program = super::input::read_program(&args.file)?;
    let cutting = resolve_cutting(&args, &process, &program, cutter.teeth())?;
    let machine = super::feed::resolve_feed_source(args.feed, args.machine.as_deref())?;
    let ap_mm = args.ap_mm.or(process.ap_mm).unwrap_or(0.5);
    if !(ap_mm.is_finite() && ap_mm > 0.0) {
        return Err(miette!("--ap-mm must be positive, got {ap_mm}"));
    }

    let (model, mode) = match args.model {
        ModelName::Dome => (Model::Dome, Mode::FeedPerTooth),
        ModelName::Ice => {
            let d = args.dtheta_deg.to_radians();
            // Resample every ≥ 8° of spindle and let the engine subdivide to Δθ: the
            // samples are then a few µm apart, where straight interpolation is exact to
            // far below a nanometre, and memory stays small on long paths.
            let coarse = d * (8f64.to_radians() / d).floor().max(1.0);
            (
                Model::Ice { dtheta_rad: d },
                Mode::SpindleStep { dtheta_rad: coarse },
            )
        }
    };
    let mut ropts =
        resample::Options::new(mode, cutting.fz_mm, cutter.teeth()).with_rpm(cutting.rpm);
    if let Some(f) = cutting.feed_mm_min {
        ropts = ropts.with_feed_mm_min(f);
    }
    let paths: Vec<usize> = match args.path {
        Some(n) if n >= 1 && n <= program.paths.len() => vec![n - 1],
        Some(n) => {
            return Err(miette!(
                "--path {n}: {} has {} tool path(s)",
                args.file.display(),
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
                        "{}: tool path {} ({}): feed prediction: {e}",
                        args.file.display(),
                        i + 1,
                        path.name
                    )
                })?);
        }
        let mut got = resample::resample(path, &popts).map_err(|e| {
            miette!(
                "{}: tool path {} ({}): {e}",
                args.file.display(),
                i + 1,
                path.name
            )
        })?;
        for s in &mut got {
            s.run += first_run;
        }
        samples.extend(got);
    }
    if samples.is_empty() {
        return Err(miette!(
            "{}: no cutting moves to simulate",
            args.file.display()
        ));
    }

    let mut sopts = surface::Options::new(model, grid, args.grid_um * 1e-3);
    sopts.depth_mm = ap_mm;
    let bar = std::io::stderr().is_terminal().then(|| {
        let b = indicatif::ProgressBar::new(1);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} simulate [{bar:40}] {pos}/{len} tiles {elapsed_precise} eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let progress = |done: usize, total: usize| {
        if let Some(b) = &bar {
            b.set_length(total as u64);
            b.set_position(done as u64);
        }
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .into_diagnostic()?;
    let sim = pool
        .install(|| surface::simulate(&samples, &cutter, &sopts, &progress))
        .map_err(|e| miette!("{}: {e}", args.file.display()))?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    crate::io::write_heightmap(&args.output, &sim.map)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write {}", args.output.display()))?;
    let elapsed = started.elapsed().as_secs_f64();
    if args.json {
        let mut j = summary(&args, &sim, &cutting, ap_mm, samples.len(), elapsed);
        j["feed"] = feed_summary(&args, machine.is_some(), &samples);
        outln!("{j}");
    } else {
        let st = HeightStats::of(&sim.map.z_um);
        outln!(
            "{}: {} × {} nodes at {} µm, {} cut; heights {:.4}..{:.4} µm (Sq {:.4} µm); {:.2} s",
            args.output.display(),
            sim.map.nx,
            sim.map.ny,
            args.grid_um,
            sim.nodes_cut,
            st.min,
            st.max,
            st.sq,
            elapsed
        );
    }
    Ok(Outcome::Ok)
}

/// The predicted feed per posture (mm/min) of `path` on `machine`; with a feed override
/// the machine is planned at that programmed feed.
fn predicted_feed(
    path: &crate::toolpath::Toolpath,
    machine: &crate::kinematics::Machine,
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

/// The `feed` object of the JSON summary: which feed was used, the machine, the cutting
/// time of the resampled runs and the feed range of the samples.
fn feed_summary(args: &Args, predicted: bool, samples: &[Sample]) -> serde_json::Value {
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
    serde_json::json!({
        "source": if predicted { "predicted" } else { "programmed" },
        "machine": args.machine.as_ref().map(|m| m.display().to_string()),
        "cut_time_s": num(cut_time),
        "sample_feed_mm_min": {
            "min": num(fmin),
            "max": num(fmax),
            "mean": num(fsum / samples.len().max(1) as f64),
        },
    })
}

/// Basic statistics of the finite heights, µm.
#[derive(Debug, Clone, Copy, PartialEq)]
struct HeightStats {
    min: f64,
    max: f64,
    mean: f64,
    sq: f64,
    sa: f64,
}

impl HeightStats {
    fn of(z: &[f64]) -> HeightStats {
        let (mut n, mut sum, mut min, mut max) = (0usize, 0.0, f64::INFINITY, f64::NEG_INFINITY);
        for &v in z.iter().filter(|v| v.is_finite()) {
            n += 1;
            sum += v;
            min = min.min(v);
            max = max.max(v);
        }
        if n == 0 {
            return HeightStats {
                min: f64::NAN,
                max: f64::NAN,
                mean: f64::NAN,
                sq: f64::NAN,
                sa: f64::NAN,
            };
        }
        let mean = sum / n as f64;
        let (mut s2, mut s1) = (0.0, 0.0);
        for &v in z.iter().filter(|v| v.is_finite()) {
            s2 += (v - mean) * (v - mean);
            s1 += (v - mean).abs();
        }
        HeightStats {
            min,
            max,
            mean,
            sq: (s2 / n as f64).sqrt(),
            sa: s1 / n as f64,
        }
    }
}

fn num(v: f64) -> serde_json::Value {
    serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

fn summary(
    args: &Args,
    sim: &Simulation,
    cutting: &Cutting,
    ap_mm: f64,
    samples: usize,
    elapsed: f64,
) -> serde_json::Value {
    let m = &sim.map;
    let st = HeightStats::of(&m.z_um);
    let f = &sim.frame;
    let origin = f.origin + f.u * m.x0_mm + f.v * m.y0_mm;
    let v3 = |v: &crate::math::Vec3| serde_json::json!([num(v.x), num(v.y), num(v.z)]);
    serde_json::json!({
        "output": args.output.display().to_string(),
        "model": match args.model { ModelName::Dome => "dome", ModelName::Ice => "ice" },
        "dtheta_deg": matches!(args.model, ModelName::Ice).then_some(args.dtheta_deg),
        "grid": if args.window.is_some() { "window" } else { "patch" },
        "nx": m.nx,
        "ny": m.ny,
        "dx_um": num(m.dx_um),
        "dy_um": num(m.dy_um),
        "x0_mm": num(m.x0_mm),
        "y0_mm": num(m.y0_mm),
        "origin": {
            "wcs_mm": [num(origin.x), num(origin.y), num(origin.z)],
            "u": v3(&f.u),
            "v": v3(&f.v),
            "w": v3(&f.w),
        },
        "nodes": m.nx * m.ny,
        "nodes_cut": sim.nodes_cut,
        "nodes_not_reached": m.nx * m.ny - sim.nodes_cut,
        "nominal_from_contacts": sim.nominal_from_contacts,
        "samples": samples,
        "strips": sim.strips,
        "tiles_widened": sim.tiles_widened,
        "rpm": num(cutting.rpm),
        "feed_mm_min": num(cutting.feed_nominal),
        "feed_from_file": cutting.feed_mm_min.is_none(),
        "fz_mm": num(cutting.fz_mm),
        "ap_mm": num(ap_mm),
        "time_s": num(elapsed),
        "heights_um": {
            "min": num(st.min),
            "max": num(st.max),
            "mean": num(st.mean),
            "sz": num(st.max - st.min),
            "sq": num(st.sq),
            "sa": num(st.sa),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn process_toml_rejects_unknown_keys_with_position() {
        let err = ProcessConfig::parse("rpm = 15000\nspeed = 3\n", Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("p.toml:2:"), "{err}");
        assert!(err.contains("speed"), "{err}");
        let err = ProcessConfig::parse("fz_mm = -0.05\n", Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("p.toml:1:1") && err.contains("fz_mm"), "{err}");
        let ok = ProcessConfig::parse(
            "rpm = 15000\nfz_mm = 0.05\nfeed_mm_min = 3000\nap_mm = 0.2\nae_mm = 0.2\nlead_deg = 15\ntilt_deg = 0\n",
            Path::new("p.toml"),
        )
        .unwrap();
        assert_eq!(ok.rpm, Some(15000.0));
        assert_eq!(ok.lead_deg, Some(15.0));
    }

    #[test]
    fn height_stats_ignore_nan() {
        let s = HeightStats::of(&[f64::NAN, 1.0, 3.0]);
        assert_eq!(
            (s.min, s.max, s.mean, s.sq, s.sa),
            (1.0, 3.0, 2.0, 1.0, 1.0)
        );
    }
}
