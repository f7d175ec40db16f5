//! `crest atlas`: the roughness atlas of a part, a patch every D mm over every finishing
//! region, written as a table and a point cloud (and a map picture).
//!
//! ```text
//! crest atlas FILE [--tool T | --teeth N] --rpm R --every-mm D [--patch-mm L[,W]] [--grid-um G]
//!     -o atlas.csv|atlas.ply [-o …] [--plot atlas.svg|png [--plot-column Sa_um]] [--json]
//! crest atlas FILE … --shard K/N -o DIR        (then crest merge DIR/shard-*.jsonl -o atlas.csv)
//! ```
//!
//! The pipeline is `crest::pipeline::atlas`; this file parses the options and prints.

use super::Outcome;
use crest::pipeline::atlas::{Atlas, AtlasRequest};
use crest::pipeline::simulate::{GridRequest, SimulateRequest};
use crest::surface::ModelKind;
use miette::{IntoDiagnostic, WrapErr, miette};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `crest atlas`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Patches: in each finishing region (crest inspect --regions) every \
k-th pass, k = max(1, round(D / median stepover)), and along each chosen pass of length L \
floor(L / D) patches D apart, centred on the pass. Each patch is simulated as `crest simulate \
--patch-near` would, and measured. A patch that is refused (in the air, no cut near it) or \
fails a sanity check keeps its row with the reason in `warnings`; a run in which no patch \
produced numbers fails (exit 2). Columns: patch, path, region, pass, s_mm, x, y, z, nx, ny, nz, \
Sa_um, Sq_um, Sz_um, scallop_um (across the feed), feed_mark_um (along the feed), \
scallop_closed_um, feed_mark_closed_um, stepover_mm, curvature_along_per_mm, \
curvature_across_per_mm, lead_deg, tilt_deg, nodes, nodes_cut, warnings."
)]
pub struct Args {
    /// Tool-path file (NX CLSF or APT, contact12).
    pub file: PathBuf,
    /// Cutter description (tool.toml); default: the file's TLDATA with --teeth.
    #[arg(long, value_name = "TOOL.TOML")]
    pub tool: Option<PathBuf>,
    /// Number of teeth of a tool taken from TLDATA.
    #[arg(long, value_name = "N")]
    pub teeth: Option<usize>,
    /// Helix angle of a tool taken from TLDATA, degrees (default 30).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub helix_deg: Option<f64>,
    /// The part's design surface (STL, OBJ, PLY) in the path's frame: heights from it, and a
    /// patch whose cut lies off it is refused (in the air).
    #[arg(long, value_name = "PART.STL")]
    pub part: Option<PathBuf>,
    /// Apply MSYS: read the path in the absolute frame.
    #[arg(long)]
    pub absolute: bool,
    /// Process parameters (process.toml).
    #[arg(long, value_name = "PROCESS.TOML")]
    pub process: Option<PathBuf>,
    /// Spindle speed, rpm (overrides process.toml and SPINDL).
    #[arg(long, value_name = "R")]
    pub rpm: Option<f64>,
    /// Feed, mm/min (overrides process.toml and FEDRAT).
    #[arg(long, value_name = "V")]
    pub feed_mm_min: Option<f64>,
    /// Feed per tooth, mm.
    #[arg(long, value_name = "F")]
    pub fz_mm: Option<f64>,
    /// Spacing of the patches along and across the passes, mm.
    #[arg(long, value_name = "D")]
    pub every_mm: f64,
    /// Patch size, mm: L (square) or L,W (along the feed, across); default twice the
    /// region's median stepover, at least 0.5 mm.
    #[arg(long, value_name = "L[,W]")]
    pub patch_mm: Option<String>,
    /// Grid spacing, µm (default: a tenth of the feed per tooth, but at most 200 × 200
    /// nodes a patch).
    #[arg(long, value_name = "G")]
    pub grid_um: Option<f64>,
    /// Surface model (default dome: the teeth's bodies at every feed per tooth).
    #[arg(long, value_enum, default_value = "dome")]
    pub model: ModelKind,
    /// Spindle step of the ICE model, degrees.
    #[arg(long, value_name = "D", default_value_t = 1.0)]
    pub dtheta_deg: f64,
    /// Chord tolerance of the meshes, µm (as `crest simulate`; default a hundredth of each
    /// patch's closed-form scallop, between 0.01 and 1 µm).
    #[arg(long, value_name = "T")]
    pub chord_tol_um: Option<f64>,
    /// First rasterised band above the reference, µm (speed only, as `crest simulate`;
    /// default 1.5 × each patch's closed-form scallop, at least 5 µm).
    #[arg(long, value_name = "B")]
    pub band_um: Option<f64>,
    /// Depth of cut ap, mm (default process.toml, else 0.5).
    #[arg(long, value_name = "AP")]
    pub ap_mm: Option<f64>,
    /// Only this tool path (1-based).
    #[arg(long, value_name = "N")]
    pub path: Option<usize>,
    /// Which moves cut: `cut` (default) or `all`.
    #[arg(long, value_enum, default_value = "cut")]
    pub moves: crest::toolpath::Moves,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Output: the table (.csv) or the point cloud (.ply, coloured by any column in `crest
    /// view --colour-by`); give -o twice for both. With --shard, the folder of the shard file.
    #[arg(
        short = 'o',
        long = "output",
        value_name = "atlas.csv|atlas.ply",
        required = true
    )]
    pub output: Vec<PathBuf>,
    /// Also draw the atlas as a map over the part's x, y (SVG or PNG).
    #[arg(long, value_name = "MAP.svg|png")]
    pub plot: Option<PathBuf>,
    /// The column the map is coloured by.
    #[arg(
        long,
        value_name = "COLUMN",
        default_value = "Sa_um",
        requires = "plot"
    )]
    pub plot_column: String,
    /// Print one JSON object (counts, time, output paths, the rows) on stdout.
    #[arg(long)]
    pub json: bool,
    /// Simulate only shard K of N of the patches (patches K, K+N, …) and write their rows
    /// as JSON lines to OUT/shard-K-of-N.jsonl; `crest merge OUT/shard-*.jsonl -o
    /// atlas.csv` writes the single-process outputs.
    #[arg(long, value_name = "K/N", value_parser = crest::pipeline::tasks::parse_shard)]
    pub shard: Option<(usize, usize)>,
}

fn patch_size(s: &str) -> miette::Result<(f64, f64)> {
    let v: Result<Vec<f64>, _> = s.split(',').map(|p| p.trim().parse::<f64>()).collect();
    match v.as_deref() {
        Ok([l]) => Ok((*l, *l)),
        Ok([l, w]) => Ok((*l, *w)),
        _ => Err(miette!("--patch-mm wants L or L,W in mm, got '{s}'")),
    }
}

use crest::io::tables::json_number as num;

/// What an output name is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Csv,
    Ply,
}

fn kind_of(p: &Path) -> Option<Kind> {
    match p.extension()?.to_str()?.to_ascii_lowercase().as_str() {
        "csv" => Some(Kind::Csv),
        "ply" => Some(Kind::Ply),
        _ => None,
    }
}

/// Check atlas output names (.csv or .ply) and the plot's.
pub fn check_names(outputs: &[PathBuf], plot: Option<&Path>) -> miette::Result<()> {
    for o in outputs {
        if kind_of(o).is_none() {
            return Err(miette!(
                "{}: unknown output extension (an atlas is written as .csv or .ply)",
                o.display()
            ));
        }
    }
    if let Some(p) = plot
        && crest::plot::Format::from_path(p).is_none()
    {
        return Err(miette!("{}: the map is drawn as .svg or .png", p.display()));
    }
    let all: Vec<&Path> = outputs.iter().map(PathBuf::as_path).chain(plot).collect();
    super::check_outputs(all)
}

/// Write the atlas' outputs (all or none) and print its summary; exit 1 when a patch has
/// warnings, an error when none has numbers.
pub fn write_outputs(
    atlas: &Atlas,
    outputs: &[PathBuf],
    plot: Option<(&Path, &str)>,
    json: bool,
    started: Instant,
) -> miette::Result<Outcome> {
    // The rows' warnings name request fields (`‹grid_um›`): the files show options.
    let mut shown = atlas.clone();
    for w in shown
        .rows
        .iter_mut()
        .flat_map(|r| r.warnings.iter_mut())
        .chain(shown.warnings.iter_mut())
    {
        *w = crest::pipeline::fields::for_cli(w).into_owned();
    }
    let atlas = &shown;
    let (file, every_mm) = (atlas.file.as_str(), atlas.every_mm);
    crest::pipeline::atlas::check_numbers(file, &atlas.rows)?;
    let mut set = crest::io::output::Outputs::new();
    for o in outputs {
        let rows = &atlas.rows;
        match kind_of(o) {
            Some(Kind::Ply) => set.file(o, |w| crest::io::atlas::write_atlas_ply(rows, w)),
            _ => set.file(o, |w| crest::io::atlas::write_atlas_csv(rows, w)),
        }
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write {}", o.display()))?;
    }
    if let Some((p, column)) = plot {
        let png = crest::plot::Format::from_path(p) == Some(crest::plot::Format::Png);
        let title = format!(
            "{column} of {} patches, {every_mm} mm apart",
            atlas.rows.len()
        );
        let bytes = crest::plot::atlas::atlas_map(&atlas.rows, column, &title, every_mm, png)
            .map_err(|e| miette!("{}: {e}", p.display()))?;
        set.file(p, |w| w.write_all(&bytes))
            .into_diagnostic()
            .wrap_err_with(|| format!("cannot write {}", p.display()))?;
    }
    let written = set
        .land()
        .into_diagnostic()
        .wrap_err("cannot write the outputs")?;
    let with_numbers = atlas.rows.iter().filter(|r| r.has_numbers()).count();
    let warned = atlas.rows.iter().filter(|r| !r.warnings.is_empty()).count();
    let elapsed = started.elapsed().as_secs_f64();
    let col = |f: fn(&crest::study::atlas::AtlasRow) -> Option<f64>| {
        let v: Vec<f64> = atlas.rows.iter().filter_map(f).collect();
        if v.is_empty() {
            (f64::NAN, f64::NAN)
        } else {
            (
                v.iter().copied().fold(f64::INFINITY, f64::min),
                v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            )
        }
    };
    let sa = col(|r| r.sa_um);
    let scallop = col(|r| r.scallop_um);
    if json {
        let j = serde_json::json!({
            "file": file,
            "every_mm": every_mm,
            "regions": atlas.regions,
            "patches": atlas.rows.len(),
            "patches_with_numbers": with_numbers,
            "patches_with_warnings": warned,
            "sa_um": {"min": num(sa.0), "max": num(sa.1)},
            "scallop_um": {"min": num(scallop.0), "max": num(scallop.1)},
            "warnings": atlas.warnings,
            "outputs": written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "rows": atlas.rows,
            "time_s": num(elapsed),
        });
        outln!("{j}");
    } else {
        for w in &atlas.warnings {
            super::warn(w);
        }
        outln!(
            "{file}: {} patches in {} finishing region(s), {} mm apart: {with_numbers} with numbers, {warned} with warnings; Sa {:.3}..{:.3} µm, scallop {:.3}..{:.3} µm; {elapsed:.1} s; wrote {}",
            atlas.rows.len(),
            atlas.regions,
            every_mm,
            sa.0,
            sa.1,
            scallop.0,
            scallop.1,
            written
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(if warned > 0 {
        Outcome::CheckFailed
    } else {
        Outcome::Ok
    })
}

fn shard_name(k: usize, n: usize) -> String {
    format!("shard-{k}-of-{n}.jsonl")
}

/// Run `crest atlas`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let started = Instant::now();
    let patch_mm = args.patch_mm.as_deref().map(patch_size).transpose()?;
    match args.shard {
        Some((k, n)) => {
            if args.output.len() != 1 || args.plot.is_some() {
                return Err(miette!(
                    "with --shard, -o names one folder for the shard file (and --plot goes to `crest merge`'s outputs)"
                ));
            }
            super::check_output_folder(&args.output[0], &[shard_name(k, n)])?;
        }
        None => check_names(&args.output, args.plot.as_deref())?,
    }
    let req = AtlasRequest {
        simulate: SimulateRequest {
            file: args.file.clone(),
            tool: args.tool.clone().map(crest::pipeline::ToolSource::File),
            teeth: args.teeth,
            helix_deg: args.helix_deg,
            part: args.part.clone(),
            absolute: args.absolute,
            process: args.process.clone(),
            rpm: args.rpm,
            feed_mm_min: args.feed_mm_min,
            fz_mm: args.fz_mm,
            feed: None,
            machine: None,
            rtcp: crest::nc::Rtcp::default(),
            model: args.model,
            dtheta_deg: args.dtheta_deg,
            grid_um: args.grid_um,
            chord_tol_um: args.chord_tol_um,
            band_um: args.band_um,
            grid: GridRequest::PatchNear {
                point: [0.0; 3],
                length_mm: 1.0,
                width_mm: 1.0,
            },
            ap_mm: args.ap_mm,
            path: args.path,
            moves: args.moves,
        },
        every_mm: args.every_mm,
        patch_mm,
    };
    let progress = super::progress::Phases::new();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .into_diagnostic()?;
    let file = args.file.display().to_string();
    if let Some((k, n)) = args.shard {
        let task = crest::pipeline::tasks::atlas::AtlasTask {
            kind: crest::pipeline::tasks::atlas::ATLAS_PATCHES.to_string(),
            request: req,
            shard: k,
            shards: n,
        };
        let out =
            pool.install(|| crest::pipeline::tasks::atlas::run_atlas_task_with(&task, &progress));
        progress.finish();
        let result = out?;
        let mut text = serde_json::to_vec(&result).into_diagnostic()?;
        text.push(b'\n');
        let name = shard_name(k, n);
        crest::io::write_files(&args.output[0], &[(name.clone(), text)])
            .into_diagnostic()
            .wrap_err_with(|| format!("cannot write into {}", args.output[0].display()))?;
        let path = args.output[0].join(&name);
        let elapsed = started.elapsed().as_secs_f64();
        if args.json {
            let j = serde_json::json!({
                "file": file,
                "shard": [k, n],
                "patches": result.rows.len(),
                "patches_total": result.patches_total,
                "output": path.display().to_string(),
                "time_s": num(elapsed),
            });
            outln!("{j}");
        } else {
            outln!(
                "{file}: shard {k}/{n}, {} of {} patches in {elapsed:.1} s; wrote {}",
                result.rows.len(),
                result.patches_total,
                path.display()
            );
        }
        return Ok(Outcome::Ok);
    }
    // The request's fields named as flags.
    crest::pipeline::prepare::check_request(&req.simulate).map_err(|e| miette::miette!("{e}"))?;
    let atlas = pool.install(|| crest::pipeline::atlas::run(&req, None, &progress));
    progress.finish();
    let atlas = atlas?;
    write_outputs(
        &atlas,
        &args.output,
        args.plot.as_deref().map(|p| (p, args.plot_column.as_str())),
        args.json,
        started,
    )
}
