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
use clap::ValueEnum;
use crest::pipeline::simulate::{GridRequest, SimulateRequest, SimulateRun};
use crest::surface::ModelKind;
use miette::{IntoDiagnostic, WrapErr, miette};
use std::path::PathBuf;
use std::time::Instant;

/// The surface model, as named on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModelName {
    /// Instantaneous positions: the revolved body of each tooth at every fz.
    Dome,
    /// Pondered movement: the teeth's cutting edges swept at every Δθ.
    Ice,
}

impl From<ModelName> for ModelKind {
    fn from(m: ModelName) -> ModelKind {
        match m {
            ModelName::Dome => ModelKind::Dome,
            ModelName::Ice => ModelKind::Ice,
        }
    }
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

/// Run `crest simulate`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let started = Instant::now();
    let grid = match (&args.window, args.patch_at, &args.patch_mm) {
        (Some(w), _, _) => {
            let v = numbers(w, 4, "window")?;
            GridRequest::Window {
                x0_mm: v[0],
                y0_mm: v[1],
                x1_mm: v[2],
                y1_mm: v[3],
            }
        }
        (None, Some(s), Some(lw)) => {
            let v = numbers(lw, 2, "patch-mm")?;
            GridRequest::PatchAt {
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
    if crest::io::HeightMapFormat::from_path(&args.output).is_none() {
        return Err(miette!(
            "{}: unknown output extension (expected .csv, .gsf or .sdf)",
            args.output.display()
        ));
    }
    let req = SimulateRequest {
        file: args.file.clone(),
        tool: args.tool.clone(),
        process: args.process.clone(),
        rpm: args.rpm,
        feed_mm_min: args.feed_mm_min,
        fz_mm: args.fz_mm,
        feed: args.feed.map(Into::into),
        machine: args.machine.clone(),
        model: args.model.into(),
        dtheta_deg: args.dtheta_deg,
        grid_um: args.grid_um,
        grid,
        ap_mm: args.ap_mm,
        path: args.path,
    };
    let bar = super::progress::bar(0, "simulate", "tiles");
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
    let run = pool.install(|| crest::pipeline::simulate::simulate(&req, &progress))?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let sim = &run.sim;
    crest::io::write_heightmap(&args.output, &sim.map)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write {}", args.output.display()))?;
    let elapsed = started.elapsed().as_secs_f64();
    let st = crest::metrics::height_stats(&sim.map.z_um);
    if args.json {
        let j = summary(&args, &run, st.as_ref(), elapsed);
        outln!("{j}");
    } else {
        let nan = f64::NAN;
        outln!(
            "{}: {} × {} nodes at {} µm, {} cut; heights {:.4}..{:.4} µm (Sq {:.4} µm); {:.2} s",
            args.output.display(),
            sim.map.nx,
            sim.map.ny,
            args.grid_um,
            sim.nodes_cut,
            st.map_or(nan, |s| s.min),
            st.map_or(nan, |s| s.max),
            st.map_or(nan, |s| s.sq),
            elapsed
        );
    }
    Ok(Outcome::Ok)
}

fn num(v: f64) -> serde_json::Value {
    serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

fn summary(
    args: &Args,
    run: &SimulateRun,
    st: Option<&crest::metrics::HeightStats>,
    elapsed: f64,
) -> serde_json::Value {
    let sim = &run.sim;
    let cutting = &run.cutting;
    let m = &sim.map;
    let f = &sim.frame;
    let origin = f.origin + f.u * m.x0_mm + f.v * m.y0_mm;
    let v3 = |v: &crest::math::Vec3| serde_json::json!([num(v.x), num(v.y), num(v.z)]);
    let stat = |pick: fn(&crest::metrics::HeightStats) -> f64| num(st.map_or(f64::NAN, pick));
    let (fmin, fmax, fmean) = run.sample_feed_mm_min;
    serde_json::json!({
        "output": args.output.display().to_string(),
        "model": ModelKind::from(args.model).name(),
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
        "samples": run.samples,
        "strips": sim.strips,
        "tiles_widened": sim.tiles_widened,
        "rpm": num(cutting.rpm),
        "feed_mm_min": num(cutting.feed_nominal),
        "feed_from_file": cutting.feed_mm_min.is_none(),
        "fz_mm": num(cutting.fz_mm),
        "ap_mm": num(run.ap_mm),
        "time_s": num(elapsed),
        "heights_um": {
            "min": stat(|s| s.min),
            "max": stat(|s| s.max),
            "mean": stat(|s| s.mean),
            "sz": stat(|s| s.sz()),
            "sq": stat(|s| s.sq),
            "sa": stat(|s| s.sa),
        },
        "feed": {
            "source": if run.predicted { "predicted" } else { "programmed" },
            "machine": args.machine.as_ref().map(|m| m.display().to_string()),
            "cut_time_s": num(run.cut_time_s),
            "sample_feed_mm_min": {
                "min": num(fmin),
                "max": num(fmax),
                "mean": num(fmean),
            },
        },
    })
}
