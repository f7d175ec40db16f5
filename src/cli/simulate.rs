//! `crest simulate`: predict the machined surface of a tool path as a height map.
//!
//! ```text
//! crest simulate FILE --tool tool.toml [--process process.toml] [--rpm N] [--feed-mm-min V]
//!     [--fz-mm F] --model dome|ice [--dtheta-deg D] --grid-um G
//!     (--window X0,Y0,X1,Y1 | --patch-at S_MM --patch-mm L,W) -o OUT.(csv|gsf|sdf|x3p) [--json]
//! crest simulate FILE --part PART.stl --map-mm D [--region …] -o MAP.ply
//! crest simulate FILE --part PART.stl --map-mm D --shard K/N -o DIR   (then crest merge)
//! ```
//!
//! The spindle speed and feed come from the options, else from `process.toml`, else from
//! the file's SPINDL/FEDRAT. The feed per tooth is `--fz-mm` (or `fz_mm`), else
//! feed / (Z · rpm). Progress goes to stderr (`cli::progress::Phases`: a bar on a terminal,
//! plain lines elsewhere once the run is long).

use super::Outcome;
use crest::pipeline::fields::for_cli;
use crest::pipeline::simulate::{GridRequest, Output, SimulateRequest, SimulateRun};
use crest::surface::ModelKind;
use miette::{IntoDiagnostic, WrapErr, miette};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `crest simulate`.
///
/// The part (`--part`) must be in the frame of the path as crest reads it: the MCS of a CLSF
/// (MSYS not applied), or the absolute frame with `--absolute` (which applies MSYS to the
/// path). Without `--part` and without contact data in the file, the reference surface is
/// derived from the path itself (the cutter's offset surface fitted over neighbouring passes).
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("grid").required(true).multiple(true).args(["window", "patch_at", "patch_near", "map_mm", "like"])))]
pub struct Args {
    /// Tool-path file (NX CLSF or APT, contact12, or G-code with `--machine`).
    pub file: PathBuf,
    /// Cutter description (tool.toml); default: the file's TLDATA with --teeth.
    #[arg(long, value_name = "TOOL.TOML")]
    pub tool: Option<PathBuf>,
    /// Number of teeth of a tool taken from TLDATA (which has no tooth count).
    #[arg(long, value_name = "N")]
    pub teeth: Option<usize>,
    /// Helix angle of a tool taken from TLDATA, degrees (default 30).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub helix_deg: Option<f64>,
    /// The part's design surface (binary or ASCII STL, OBJ, PLY; mm), in the frame of the
    /// path as read (the MCS of a CLSF, or the absolute frame with --absolute): heights are
    /// measured along its normal, from it.
    #[arg(long, value_name = "PART.STL")]
    pub part: Option<PathBuf>,
    /// Apply MSYS: read the path in the absolute frame (the part must be in it too).
    #[arg(long)]
    pub absolute: bool,
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
    /// (the feed the machine of `--machine` really reaches, as `crest feed` plans it;
    /// the spindle speed stays fixed, so the feed per tooth follows the feed).
    /// Default: `programmed`, or `predicted` when `--machine` is given.
    #[arg(long, value_enum, value_name = "SOURCE")]
    pub feed: Option<crest::pipeline::simulate::FeedSource>,
    /// Machine description (`machine.toml`) for `--feed predicted` (given alone, it implies
    /// `--feed predicted`). With `--feed-mm-min V`, the machine is planned at V.
    #[arg(long, value_name = "MACHINE.TOML")]
    pub machine: Option<PathBuf>,
    /// Tool-centre-point control of G-code input (read through the kinematics of
    /// `--machine`; the feed is then predicted only with `--feed predicted`): `auto` (as
    /// the program says), `on` or `off`.
    #[arg(long, value_enum, default_value = "auto")]
    pub rtcp: crest::nc::Rtcp,
    /// Surface model (default: ice, the teeth's edges swept).
    #[arg(long, value_enum, default_value = "ice")]
    pub model: ModelKind,
    /// Spindle step of the ICE model, degrees.
    #[arg(long, value_name = "D", default_value_t = 1.0)]
    pub dtheta_deg: f64,
    /// Grid spacing, µm (default: a tenth of the feed per tooth, 0.5 … 20 µm, printed).
    #[arg(long, value_name = "G")]
    pub grid_um: Option<f64>,
    /// Chord tolerance of the cutter's meridian polyline and of the dome model's angular
    /// mesh, µm (default 0.01, 0.001 … 10). A coarser mesh is faster; heights then err by up
    /// to about this much.
    #[arg(long, value_name = "T")]
    pub chord_tol_um: Option<f64>,
    /// Height of the first band above the reference that is rasterised, µm (default 5; the
    /// surface is then finished in a band four times as high). Speed only: set it above the
    /// expected scallop so that tiles are not computed twice; heights do not change.
    #[arg(long, value_name = "B")]
    pub band_um: Option<f64>,
    /// A window of the WCS xy plane, mm: X0,Y0,X1,Y1 (heights along +z above the reference
    /// surface).
    #[arg(
        long,
        value_name = "X0,Y0,X1,Y1",
        allow_hyphen_values = true,
        conflicts_with_all = ["patch_at", "patch_near", "map_mm"]
    )]
    pub window: Option<String>,
    /// A patch on the tangent plane at the contact point at this arc length of the path, mm
    /// (heights along the surface normal).
    #[arg(
        long,
        value_name = "S_MM",
        requires = "patch_mm",
        allow_negative_numbers = true,
        conflicts_with_all = ["patch_near", "map_mm", "like"]
    )]
    pub patch_at: Option<f64>,
    /// A patch centred at the part point nearest X,Y,Z (on the design surface of --part;
    /// without it, the nearest contact point of the cut moves), along the local feed and
    /// across it. The output line says where the patch is centred.
    #[arg(
        long,
        value_name = "X,Y,Z",
        allow_hyphen_values = true,
        conflicts_with = "map_mm"
    )]
    pub patch_near: Option<String>,
    /// Patch size, mm: L (along the feed), W (across).
    #[arg(long, value_name = "L,W")]
    pub patch_mm: Option<String>,
    /// Simulate on the grid of a measured height map (any format crest reads: .x3p, .sur,
    /// .sdf, .gsf, …): its node spacing and its extent. With --patch-near, a patch of the
    /// map's size centred there (its columns along the feed); alone, the window of the WCS
    /// xy plane the map covers (from its origin). The map's spacing must be the same along
    /// x and y.
    #[arg(
        long,
        value_name = "MEASURED",
        conflicts_with_all = ["window", "map_mm", "grid_um", "patch_mm"]
    )]
    pub like: Option<PathBuf>,
    /// Map the whole part (needs --part) at this node spacing, mm; the output is a PLY point
    /// cloud with normals and a height_um property.
    #[arg(long, value_name = "SPACING")]
    pub map_mm: Option<f64>,
    /// The region of the part to map, mm: X0,Y0,Z0,X1,Y1,Z1.
    #[arg(
        long,
        value_name = "X0,Y0,Z0,X1,Y1,Z1",
        allow_hyphen_values = true,
        requires = "map_mm"
    )]
    pub region: Option<String>,
    /// Depth of cut ap, mm (overrides process.toml; default 0.5): nodes that would be cut
    /// higher than this above the nominal surface are reported as not reached.
    #[arg(long, value_name = "AP")]
    pub ap_mm: Option<f64>,
    /// Simulate only this tool path (1-based, in file order); default: all.
    #[arg(long, value_name = "N")]
    pub path: Option<usize>,
    /// Which moves cut: `cut` (default: only the cutting passes define the surface and are
    /// simulated; a patch in the air is refused) or `all` (every feed move, engage and
    /// retract too, as before crest told them apart).
    #[arg(long, value_enum, default_value = "cut")]
    pub moves: crest::toolpath::Moves,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Output: a height map .csv (µm), .gsf, .sdf or .x3p (ISO 25178-72, opens in MountainsMap and the x3p viewers); a part map (--map-mm) .ply.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub output: PathBuf,
    /// Also write the result as a self-contained 3-D viewer page (HTML, as `crest view OUT
    /// -o VIEW.html` would).
    #[arg(long, value_name = "VIEW.html")]
    pub view: Option<PathBuf>,
    /// Print one JSON object with the grid, counts, time and height statistics.
    #[arg(long)]
    pub json: bool,
    /// With --map-mm: simulate only shard K of N of the map's cells (1 ≤ K ≤ N: cells K,
    /// K+N, …) and write them as JSON lines to OUT/shard-K-of-N.jsonl (OUT is then a
    /// folder); `crest merge OUT/shard-*.jsonl -o MAP.ply` writes the single-process PLY.
    #[arg(long, value_name = "K/N", requires = "map_mm", value_parser = crest::pipeline::tasks::parse_shard)]
    pub shard: Option<(usize, usize)>,
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

/// The grid and spacing (µm) of `--like MEASURED`: a patch of the map's size at
/// `patch_near`, else the window the map covers.
fn like_grid(measured: &Path, patch_near: Option<&str>) -> miette::Result<(GridRequest, f64)> {
    let opts = crest::io::ReadOptions::default();
    let map = crest::io::read_heightmap(measured, &opts).map_err(|e| miette!("{e}"))?;
    let (dx, dy) = (map.dx_um, map.dy_um);
    if (dx - dy).abs() > 1e-9 * dx.abs().max(dy.abs()) {
        return Err(miette!(
            "--like {}: the map's spacing is {dx} µm along x and {dy} µm along y; crest simulates on square grids (resample the map to one spacing first)",
            measured.display()
        ));
    }
    let (l, w) = (
        (map.nx - 1) as f64 * dx * 1e-3,
        (map.ny - 1) as f64 * dy * 1e-3,
    );
    let grid = match patch_near {
        Some(p) => {
            let q = numbers(p, 3, "patch-near")?;
            GridRequest::PatchNear {
                point: [q[0], q[1], q[2]],
                length_mm: l,
                width_mm: w,
            }
        }
        None => GridRequest::Window {
            x0_mm: map.x0_mm,
            y0_mm: map.y0_mm,
            x1_mm: map.x0_mm + l,
            y1_mm: map.y0_mm + w,
        },
    };
    Ok((grid, dx))
}

/// Run `crest simulate`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let started = Instant::now();
    let like = match &args.like {
        Some(m) => Some(like_grid(m, args.patch_near.as_deref())?),
        None => None,
    };
    let grid_um = args.grid_um.or(like.map(|l| l.1));
    let grid = if let Some((g, _)) = like {
        g
    } else {
        let fixed =
            |v: Option<&String>, n: usize, flag: &str| -> miette::Result<Option<Vec<f64>>> {
                v.map(|t| numbers(t, n, flag)).transpose()
            };
        let choice = crest::pipeline::simulate::GridChoice {
            window: fixed(args.window.as_ref(), 4, "window")?.map(|v| [v[0], v[1], v[2], v[3]]),
            patch_at: args.patch_at,
            patch_near: fixed(args.patch_near.as_ref(), 3, "patch-near")?
                .map(|v| [v[0], v[1], v[2]]),
            patch_mm: fixed(args.patch_mm.as_ref(), 2, "patch-mm")?.map(|v| [v[0], v[1]]),
            map_mm: args.map_mm,
            region: fixed(args.region.as_ref(), 6, "region")?
                .map(|v| [v[0], v[1], v[2], v[3], v[4], v[5]]),
        };
        choice.resolve().map_err(|e| miette!("{e}"))?
    };
    let map = matches!(grid, GridRequest::Map { .. });
    let ext_ok = if args.shard.is_some() {
        if args.view.is_some() {
            return Err(miette!(
                "--view draws the whole map: give it to `crest merge`'s output (crest view MAP.ply), not to a shard"
            ));
        }
        true
    } else if map {
        args.output
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("ply"))
    } else {
        crest::io::HeightMapFormat::from_path(&args.output).is_some()
    };
    if !ext_ok {
        return Err(miette!(
            "{}: unknown output extension (expected {})",
            args.output.display(),
            if map {
                ".ply for a part map"
            } else {
                ".csv, .gsf, .sdf or .x3p"
            }
        ));
    }
    // A blocked output is refused before the simulation, not after it.
    match args.shard {
        Some((k, n)) => super::check_output_folder(&args.output, &[shard_name(k, n)])?,
        None => super::check_outputs(
            std::iter::once(args.output.as_path()).chain(args.view.as_deref()),
        )?,
    }
    let req = SimulateRequest {
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
        feed: args.feed,
        machine: args.machine.clone(),
        rtcp: args.rtcp,
        model: args.model,
        dtheta_deg: args.dtheta_deg,
        grid_um,
        chord_tol_um: args.chord_tol_um,
        band_um: args.band_um,
        grid,
        ap_mm: args.ap_mm,
        path: args.path,
        moves: args.moves,
    };
    let progress = super::progress::Phases::new();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .into_diagnostic()?;
    if let Some((k, n)) = args.shard {
        let task = crest::pipeline::tasks::map::MapTask {
            kind: crest::pipeline::tasks::map::MAP_TILES.to_string(),
            request: req,
            shard: k,
            shards: n,
        };
        let out = pool.install(|| crest::pipeline::tasks::map::run_map_task_with(&task, &progress));
        progress.finish();
        return write_shard(&args, out?, started);
    }
    // The request's fields named as flags.
    crest::pipeline::prepare::check_request(&req).map_err(|e| miette!("{e}"))?;
    let run = pool.install(|| crest::pipeline::simulate::simulate(&req, &progress));
    progress.finish();
    let run = run?;
    for w in &run.warnings {
        super::warn(w);
    }
    // The page is rendered before the first output is written.
    let page = match &args.view {
        Some(_) => {
            let name = args.output.display().to_string();
            let info = crest::report::view::ViewInfo {
                title: args
                    .output
                    .file_name()
                    .map_or_else(|| name.clone(), |n| n.to_string_lossy().into_owned()),
                source: name.clone(),
                file: Some(name.clone()),
            };
            let html = match &run.output {
                // The heights as the output file stores them (GSF: float32), so that a
                // clicked profile's Rz is the one `crest metrics OUT --profile …` prints.
                Output::Grid(sim) => crest::io::HeightMapFormat::from_path(&args.output)
                    .ok_or_else(|| format!("{name}: unknown height-map extension"))
                    .and_then(|f| crest::io::as_stored(&sim.map, f).map_err(|e| e.to_string()))
                    .and_then(|m| {
                        crest::report::view::heightmap_page(&m, &info).map_err(|e| e.to_string())
                    }),
                Output::Map(m) => {
                    crest::report::view::part_map_page(&m.points, &info).map_err(|e| e.to_string())
                }
            };
            Some(html.map_err(|e| miette!("{name}: cannot make the 3-D view: {e}"))?)
        }
        None => None,
    };
    // The heights' statistics are taken while the file is staged (the same values); the
    // height map and the page land together or not at all.
    let mut outputs = crest::io::output::Outputs::new();
    let (staged, st) = match &run.output {
        Output::Grid(sim) => pool.install(|| {
            rayon::join(
                || crest::io::stage_heightmap(&mut outputs, &args.output, &sim.map),
                || crest::metrics::height_stats(&sim.map.z_um),
            )
        }),
        Output::Map(m) => {
            let heights: Vec<f64> = m.points.iter().map(|p| p.height_um).collect();
            (
                outputs.file(&args.output, |w| {
                    crest::io::mesh::write_map_ply(&m.points, w)
                }),
                crest::metrics::height_stats(&heights),
            )
        }
    };
    staged
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write {}", args.output.display()))?;
    if let (Some(path), Some(html)) = (&args.view, &page) {
        outputs
            .file(path, |w| w.write_all(html.as_bytes()))
            .into_diagnostic()
            .wrap_err_with(|| format!("cannot write {}", path.display()))?;
    }
    outputs
        .land()
        .into_diagnostic()
        .wrap_err("cannot write the outputs (none was changed)")?;
    let elapsed = started.elapsed().as_secs_f64();
    let fraction = run.nodes_cut as f64 / run.nodes.max(1) as f64;
    let thin = fraction < 0.1;
    let warning = thin.then(|| {
        format!(
            "only {} of {} nodes ({:.1} %) were cut: the grid is mostly outside the tool's reach",
            run.nodes_cut,
            run.nodes,
            100.0 * fraction
        )
    });
    if args.json {
        let j = summary(&args, &run, st.as_ref(), elapsed, warning.as_deref());
        outln!("{j}");
    } else {
        let nan = f64::NAN;
        let shape = match &run.output {
            Output::Grid(sim) => {
                // Where a patch landed (--patch-at, --patch-near): its centre in the file's frame.
                let (m, centre) = (&sim.map, grid_centre(sim));
                format!(
                    "{} × {} nodes at {} µm{}{}",
                    m.nx,
                    m.ny,
                    run.grid_um,
                    if grid_um.is_none() {
                        " (a tenth of fz; --grid-um to change)"
                    } else {
                        ""
                    },
                    if args.window.is_none() {
                        format!(
                            ", centred at {:.4},{:.4},{:.4}",
                            centre.x, centre.y, centre.z
                        )
                    } else {
                        String::new()
                    }
                )
            }
            Output::Map(m) => format!("{} part points in {} cells", m.points.len(), m.tiles),
        };
        outln!(
            "{}: {shape}, {} cut; heights {:.4}..{:.4} µm (Sq {:.4} µm) from the {}; tool {}; {:.2} s",
            args.output.display(),
            run.nodes_cut,
            st.map_or(nan, |s| s.min),
            st.map_or(nan, |s| s.max),
            st.map_or(nan, |s| s.sq),
            run.reference.name(),
            run.tool_source,
            elapsed
        );
    }
    for w in &run.failed_checks {
        eprintln!("crest simulate: {}", for_cli(w));
    }
    if let Some(w) = warning {
        eprintln!("crest simulate: {}", for_cli(&w));
        return Ok(Outcome::CheckFailed);
    }
    if !run.failed_checks.is_empty() {
        return Ok(Outcome::CheckFailed);
    }
    Ok(Outcome::Ok)
}

fn shard_name(k: usize, n: usize) -> String {
    format!("shard-{k}-of-{n}.jsonl")
}

/// `crest simulate --map-mm … --shard K/N`: write the shard's cells as one JSON line.
fn write_shard(
    args: &Args,
    (result, run): (crest::pipeline::tasks::map::MapResult, SimulateRun),
    started: Instant,
) -> miette::Result<Outcome> {
    for w in &run.warnings {
        super::warn(w);
    }
    let (k, n) = (result.shard, result.shards);
    let mut text = serde_json::to_vec(&result).into_diagnostic()?;
    text.push(b'\n');
    let name = shard_name(k, n);
    crest::io::write_files(&args.output, &[(name.clone(), text)])
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write into {}", args.output.display()))?;
    let path = args.output.join(&name);
    let elapsed = started.elapsed().as_secs_f64();
    let points: usize = result.cells.iter().map(|c| c.points.len()).sum();
    if args.json {
        let j = serde_json::json!({
            "file": args.file.display().to_string(),
            "shard": [k, n],
            "cells": result.cells.len(),
            "cells_total": result.cells_total,
            "nodes": points,
            "nodes_cut": run.nodes_cut,
            "warnings": run.warnings,
            "output": path.display().to_string(),
            "time_s": num(elapsed),
        });
        outln!("{j}");
    } else {
        outln!(
            "{}: shard {k}/{n}, {} of {} cells ({points} part points, {} cut) in {elapsed:.1} s; wrote {}",
            args.file.display(),
            result.cells.len(),
            result.cells_total,
            run.nodes_cut,
            path.display()
        );
    }
    Ok(Outcome::Ok)
}

/// The centre of a simulated grid in the file's frame: where a patch landed.
fn grid_centre(sim: &crest::surface::Simulation) -> crest::math::Point3 {
    let (m, f) = (&sim.map, &sim.frame);
    f.origin
        + f.u * (m.x0_mm + 0.5e-3 * m.dx_um * (m.nx.max(1) - 1) as f64)
        + f.v * (m.y0_mm + 0.5e-3 * m.dy_um * (m.ny.max(1) - 1) as f64)
}

use crest::io::tables::json_number as num;

fn summary(
    args: &Args,
    run: &SimulateRun,
    st: Option<&crest::metrics::HeightStats>,
    elapsed: f64,
    warning: Option<&str>,
) -> serde_json::Value {
    let cutting = &run.cutting;
    let v3 = |v: &crest::math::Vec3| serde_json::json!([num(v.x), num(v.y), num(v.z)]);
    let stat = |pick: fn(&crest::metrics::HeightStats) -> f64| num(st.map_or(f64::NAN, pick));
    let (fmin, fmax, fmean) = run.sample_feed_mm_min;
    let mut j = serde_json::json!({
        "output": args.output.display().to_string(),
        "view": args.view.as_ref().map(|p| p.display().to_string()),
        "model": args.model.name(),
        "dtheta_deg": matches!(args.model, ModelKind::Ice).then_some(args.dtheta_deg),
        "nodes": run.nodes,
        "nodes_cut": run.nodes_cut,
        "nodes_not_reached": run.nodes - run.nodes_cut,
        "cut_fraction": num(run.nodes_cut as f64 / run.nodes.max(1) as f64),
        "grid_um": num(run.grid_um),
        "grid_um_default": args.grid_um.is_none() && args.like.is_none(),
        "warning": warning,
        "warnings": run.warnings,
        "moves": run.moves.name(),
        "patch_distance_mm": run.patch_distance_mm.map(|d| num(d.0)),
        "patch_tolerance_mm": run.patch_distance_mm.map(|d| num(d.1)),
        "tool": run.tool_source,
        "reference": run.reference.name(),
        "samples": run.samples,
        "samples_total": run.samples_total,
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
    });
    match &run.output {
        Output::Grid(sim) => {
            let m = &sim.map;
            let f = &sim.frame;
            let origin = f.origin + f.u * m.x0_mm + f.v * m.y0_mm;
            j["grid"] = serde_json::json!(if args.window.is_some() {
                "window"
            } else {
                "patch"
            });
            j["nx"] = m.nx.into();
            j["ny"] = m.ny.into();
            j["dx_um"] = num(m.dx_um);
            j["dy_um"] = num(m.dy_um);
            j["x0_mm"] = num(m.x0_mm);
            j["y0_mm"] = num(m.y0_mm);
            let centre = grid_centre(sim);
            j["centre_mm"] = serde_json::json!([num(centre.x), num(centre.y), num(centre.z)]);
            j["origin"] = serde_json::json!({
                "wcs_mm": [num(origin.x), num(origin.y), num(origin.z)],
                "u": v3(&f.u),
                "v": v3(&f.v),
                "w": v3(&f.w),
            });
            j["nominal_from_contacts"] = sim.nominal_from_contacts.into();
            j["strips"] = sim.strips.into();
            j["tiles_widened"] = sim.tiles_widened.into();
        }
        Output::Map(m) => {
            j["grid"] = serde_json::json!("map");
            j["map_mm"] = num(args.map_mm.unwrap_or(f64::NAN));
            j["cells"] = m.tiles.into();
        }
    }
    j
}
