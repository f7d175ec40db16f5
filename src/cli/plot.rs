//! `crest plot`: the cutter's profile, trochoids of the ICE elements, lateral run-out, height
//! maps, profiles and the feed (or crest height) along a path, as SVG or PNG by the extension
//! of `-o`.

use super::Outcome;
use crest::plot::chart::{Chart, Series};
use crest::plot::{Format, feed, heightmap, profile, trochoid};
use miette::miette;
use std::path::{Path, PathBuf};

/// Options of `crest plot`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// What to plot.
    #[command(subcommand)]
    pub what: What,
}

/// The plots.
#[derive(Debug, clap::Subcommand)]
pub enum What {
    /// The cutter's profile (its meridian and mirror image) at equal scales.
    Cutter(CutterArgs),
    /// Trochoidal paths of the cutting-edge elements along a pass and the crest heights
    /// between consecutive marks (as Marin et al. 2023, Fig 14a/b).
    Trochoid(TrochoidArgs),
    /// Lateral run-out along the surface normal against tool height, one curve per lead
    /// (as Marin et al. 2023, Fig 14c).
    Runout(RunoutArgs),
    /// A height map as a colour map (µm scale bar, axes in mm, missing points blank).
    Heightmap(HeightmapArgs),
    /// A profile of a height map, optionally against a measured profile.
    Profile(ProfileArgs),
    /// The programmed (and actual) feed, or the feed-mark crest height, along a path.
    Feed(FeedArgs),
}

/// Options common to every plot.
#[derive(Debug, clap::Args)]
pub struct Common {
    /// Output picture: `.svg` or `.png`.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: PathBuf,
    /// Title (a default names what is shown).
    #[arg(long)]
    pub title: Option<String>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Options of `crest plot cutter`.
#[derive(Debug, clap::Args)]
pub struct CutterArgs {
    /// Cutter description (tool.toml).
    #[arg(long, value_name = "TOOL.toml")]
    pub tool: PathBuf,
    /// How much of the side to draw above the end, mm (default: half the radius).
    #[arg(long, value_name = "MM")]
    pub side_mm: Option<f64>,
    #[command(flatten)]
    pub common: Common,
}

/// Options of `crest plot trochoid`.
#[derive(Debug, clap::Args)]
pub struct TrochoidArgs {
    /// Cutter description (tool.toml), run-out included.
    #[arg(long, value_name = "TOOL.toml")]
    pub tool: PathBuf,
    /// Tool heights above the tip, mm.
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.25,0.5,1,2,3")]
    pub heights_mm: Vec<f64>,
    /// Lead angles, degrees (one to four; one isometric panel each).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "5,15,25",
        allow_negative_numbers = true
    )]
    pub lead_deg: Vec<f64>,
    /// Parallel passes in the isometric views.
    #[arg(long, default_value_t = 3)]
    pub passes: usize,
    /// Distance between passes, mm.
    #[arg(long, default_value_t = 0.5)]
    pub stepover_mm: f64,
    /// Feed per tooth of the drawn trochoids, mm.
    #[arg(long, default_value_t = 0.2)]
    pub fz_mm: f64,
    /// Feeds per tooth of the crest-height panel, mm.
    #[arg(long, value_delimiter = ',', default_value = "0.05,0.2")]
    pub crest_fz_mm: Vec<f64>,
    /// Spindle revolutions traced.
    #[arg(long, default_value_t = 3.0)]
    pub revolutions: f64,
    #[command(flatten)]
    pub common: Common,
}

/// Options of `crest plot runout`.
#[derive(Debug, clap::Args)]
pub struct RunoutArgs {
    /// Cutter description (tool.toml) with its run-out.
    #[arg(long, value_name = "TOOL.toml")]
    pub tool: PathBuf,
    /// Lead angles, degrees (one curve each).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "5,15,25",
        allow_negative_numbers = true
    )]
    pub lead_deg: Vec<f64>,
    /// Tool heights above the tip to mark, mm (default: six heights spread over the end).
    #[arg(long, value_delimiter = ',')]
    pub heights_mm: Vec<f64>,
    #[command(flatten)]
    pub common: Common,
}

/// Options of height-map input.
#[derive(Debug, clap::Args)]
pub struct MapInput {
    /// Height map: `.csv` (grid, µm; needs --dx-um), `.xyz`/`.txt`, `.gsf`, `.sdf`, `.x3p`,
    /// or an instrument's `.sur`, `.al3d`, `.gwy`, `.plu`, `.plux`, `.opd`, `.vk4`.
    pub map: PathBuf,
    /// Grid spacing along x, µm (grid CSV).
    #[arg(long)]
    pub dx_um: Option<f64>,
    /// Grid spacing along y, µm (default: --dx-um).
    #[arg(long)]
    pub dy_um: Option<f64>,
    /// The channel of a Gwyddion `.gwy` to read, by its title (default: the first channel
    /// with heights in a length unit).
    #[arg(long, value_name = "NAME")]
    pub channel: Option<String>,
}

/// Options of `crest plot heightmap`.
#[derive(Debug, clap::Args)]
pub struct HeightmapArgs {
    #[command(flatten)]
    pub input: MapInput,
    #[command(flatten)]
    pub common: Common,
}

/// Options of `crest plot profile`.
#[derive(Debug, clap::Args)]
pub struct ProfileArgs {
    #[command(flatten)]
    pub input: MapInput,
    /// Profile along x at this y, mm (the nearest row; default: the middle row).
    #[arg(long, allow_negative_numbers = true, conflicts_with = "x_mm")]
    pub y_mm: Option<f64>,
    /// Profile along y at this x, mm (the nearest column).
    #[arg(long, allow_negative_numbers = true)]
    pub x_mm: Option<f64>,
    /// Measured profile to overlay: two columns, position (mm) and height (µm), separated
    /// by commas, semicolons or blanks; an optional header line.
    #[arg(long, value_name = "CSV")]
    pub measured: Option<PathBuf>,
    /// Align the measured profile to the simulated one: the lateral shift of best
    /// correlation (within half the profile, to a fraction of a node), then the offset of the
    /// means; printed (and in --json).
    #[arg(long, requires = "measured")]
    pub align: bool,
    #[command(flatten)]
    pub common: Common,
}

/// Options of `crest plot feed`.
#[derive(Debug, clap::Args)]
pub struct FeedArgs {
    /// Tool path: CLSF or contact12.
    pub path: PathBuf,
    /// Actual feed to overlay: the poses CSV of `crest feed -o` (matched by source line), or
    /// two columns, path length (mm) and feed (mm/min).
    #[arg(long, value_name = "CSV")]
    pub actual: Option<PathBuf>,
    /// Plot the feed-mark crest height (R − √(R² − fz²/4) with fz = F/(Z n)) instead of the feed;
    /// needs --tool.
    #[arg(long, requires = "tool")]
    pub crest: bool,
    /// Cutter (tool.toml), for --crest.
    #[arg(long, value_name = "TOOL.toml")]
    pub tool: Option<PathBuf>,
    /// Spindle speed, rpm (default: the path's SPINDL).
    #[arg(long)]
    pub rpm: Option<f64>,
    /// Feed, mm/min, where the path states none (contact12 has no feed).
    #[arg(long)]
    pub feed_mm_min: Option<f64>,
    /// Plot only from this path length on, mm (the cutting length the x axis shows).
    #[arg(long, value_name = "MM")]
    pub from_mm: Option<f64>,
    /// Plot only up to this path length, mm.
    #[arg(long, value_name = "MM")]
    pub to_mm: Option<f64>,
    #[command(flatten)]
    pub common: Common,
}

/// A point of the feed plot over a range of path length: posture `i` itself, or a point at
/// path length `s` on the move ending at posture `i` (where the range cuts that move).
#[derive(Clone, Copy)]
enum RangePoint {
    Posture(usize),
    Cut(f64, usize),
}

/// The points of `s` (path length, NaN between runs) within `[from, to]`, with a point where
/// the range cuts a move (so a long move across a bound is drawn up to it); runs still apart
/// (one NaN point between them). Errors when the range is empty or holds no cutting move.
fn length_range(
    s: &[f64],
    from: Option<f64>,
    to: Option<f64>,
    total: f64,
) -> miette::Result<Vec<RangePoint>> {
    let (lo, hi) = (from.unwrap_or(0.0), to.unwrap_or(f64::INFINITY));
    if !(lo.is_finite() && lo >= 0.0) || hi.is_nan() || lo >= hi {
        return Err(miette!(
            "--from-mm {} and --to-mm {} do not give a range of path length (0 … {total:.3} mm)",
            crest::math::limits::shown(lo),
            crest::math::limits::shown(hi)
        ));
    }
    let mut keep: Vec<RangePoint> = Vec::new();
    let gap = |k: &RangePoint| matches!(*k, RangePoint::Posture(i) if s[i].is_nan());
    for (i, &v) in s.iter().enumerate() {
        if v.is_nan() {
            if keep.last().is_some_and(|k| !gap(k)) {
                keep.push(RangePoint::Posture(i));
            }
            continue;
        }
        let prev = (i > 0 && s[i - 1].is_finite()).then(|| s[i - 1]);
        if let Some(p) = prev
            && p < lo
            && v > lo
        {
            keep.push(RangePoint::Cut(lo, i));
        }
        if (lo..=hi).contains(&v) {
            keep.push(RangePoint::Posture(i));
        }
        if let Some(p) = prev
            && p < hi
            && v > hi
        {
            keep.push(RangePoint::Cut(hi, i));
        }
    }
    while keep.last().is_some_and(gap) {
        keep.pop();
    }
    if keep.is_empty() {
        return Err(miette!(
            "no cutting move between {} and {} mm of path length (the cutting length is {total:.3} mm)",
            crest::math::limits::shown(lo),
            crest::math::limits::shown(hi)
        ));
    }
    Ok(keep)
}

fn check_format(path: &Path) -> miette::Result<()> {
    Format::from_path(path)
        .map(|_| ())
        .ok_or_else(|| miette!("{}: unknown plot format (use .svg or .png)", path.display()))?;
    super::check_outputs([path])
}

fn done(common: &Common, kind: &str, extra: serde_json::Value) -> miette::Result<Outcome> {
    if common.json {
        let mut obj = serde_json::json!({
            "plot": kind,
            "output": common.output.display().to_string(),
        });
        if let (Some(o), serde_json::Value::Object(e)) = (obj.as_object_mut(), extra) {
            o.extend(e);
        }
        outln!("{obj}");
    } else {
        outln!("wrote {}", common.output.display());
    }
    Ok(Outcome::Ok)
}

/// Run `crest plot`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    match args.what {
        What::Cutter(a) => run_cutter(a),
        What::Trochoid(a) => run_trochoid(a),
        What::Runout(a) => run_runout(a),
        What::Heightmap(a) => run_heightmap(a),
        What::Profile(a) => run_profile(a),
        What::Feed(a) => run_feed(a),
    }
}

fn run_cutter(a: CutterArgs) -> miette::Result<Outcome> {
    check_format(&a.common.output)?;
    let cutter = crest::pipeline::load_tool(&a.tool)?;
    let side = a.side_mm.unwrap_or(0.5 * cutter.radius_mm);
    crest::plot::cutter::plot_cutter(&cutter, a.common.title.as_deref(), side, &a.common.output)
        .map_err(|e| miette!("{e}"))?;
    done(
        &a.common,
        "cutter",
        serde_json::json!({
            "shape": cutter.shape.name(),
            "description": cutter.describe(),
            "radius_mm": cutter.radius_mm,
            "end_height_mm": cutter.end_height_mm(),
        }),
    )
}

fn run_trochoid(a: TrochoidArgs) -> miette::Result<Outcome> {
    use crest::math::limits::{FZ_MM, within};
    check_format(&a.common.output)?;
    let cutter = crest::pipeline::load_tool(&a.tool)?;
    // Plausible values only: a pass 1e305 mm long would never finish drawing.
    within("--fz-mm", "mm", a.fz_mm, FZ_MM).map_err(|e| miette!("{e}"))?;
    for &f in &a.crest_fz_mm {
        within("--crest-fz-mm", "mm", f, FZ_MM).map_err(|e| miette!("{e}"))?;
    }
    within(
        "--stepover-mm",
        "mm",
        a.stepover_mm,
        (0.0, 10.0 * cutter.radius_mm),
    )
    .map_err(|e| miette!("{e}"))?;
    for &z in &a.heights_mm {
        within("--heights-mm", "mm", z, (0.0, 2.0 * cutter.radius_mm))
            .map_err(|e| miette!("{e}"))?;
    }
    within("--revolutions", "", a.revolutions, (0.0, 1000.0)).map_err(|e| miette!("{e}"))?;
    if a.passes > 1000 {
        return Err(miette!("--passes must be at most 1000, got {}", a.passes));
    }
    for &l in &a.lead_deg {
        within("--lead-deg", "°", l, (-89.0, 89.0)).map_err(|e| miette!("{e}"))?;
    }
    let o = trochoid::TrochoidOptions {
        heights_mm: a.heights_mm.clone(),
        leads_rad: a.lead_deg.iter().map(|d| d.to_radians()).collect(),
        passes: a.passes,
        stepover_mm: a.stepover_mm,
        fz_mm: a.fz_mm,
        crest_fz_mm: a.crest_fz_mm.clone(),
        revolutions: a.revolutions,
        points_per_rev: 180,
        title: a
            .common
            .title
            .clone()
            .unwrap_or_else(|| "Trochoidal paths of ICE elements".to_string()),
    };
    trochoid::plot_trochoids(&cutter, &o, &a.common.output).map_err(|e| miette!("{e}"))?;
    let mut crests = Vec::new();
    for &fz in &a.crest_fz_mm {
        for &lead in &a.lead_deg {
            for &z in &a.heights_mm {
                let c = crest::tool::trochoid::crest_between_marks_mm(
                    &cutter,
                    z,
                    fz,
                    lead.to_radians(),
                );
                crests.push(serde_json::json!({
                    "fz_mm": fz,
                    "lead_deg": lead,
                    "height_mm": z,
                    "crest_um": c * 1e3,
                }));
            }
        }
    }
    done(
        &a.common,
        "trochoid",
        serde_json::json!({ "crests": crests }),
    )
}

fn run_runout(a: RunoutArgs) -> miette::Result<Outcome> {
    use crest::plot::runout::lateral_chart;
    use crest::study::runout::{default_marked_heights_mm, lateral_curves_for};
    let format = Format::from_path(&a.common.output).ok_or_else(|| {
        miette!(
            "{}: unknown plot format (use .svg or .png)",
            a.common.output.display()
        )
    })?;
    if a.lead_deg.is_empty() || a.lead_deg.iter().any(|l| !l.is_finite() || l.abs() >= 90.0) {
        return Err(miette!(
            "--lead-deg: give leads strictly between -90 and 90 degrees"
        ));
    }
    let cutter = crest::pipeline::load_tool(&a.tool)?;
    let top = cutter.end_height_mm();
    if let Some(z) = a
        .heights_mm
        .iter()
        .find(|z| !z.is_finite() || **z < 0.0 || **z > top)
    {
        return Err(miette!(
            "--heights-mm: {z} mm is outside the cutter's end (0 to {top} mm)"
        ));
    }
    let marks: Vec<f64> = if a.heights_mm.is_empty() {
        default_marked_heights_mm(&cutter)
    } else {
        a.heights_mm.clone()
    };
    let curves = lateral_curves_for(&cutter, &a.lead_deg, &marks);
    let name = a
        .tool
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut chart = lateral_chart(&curves, &name);
    if let Some(t) = &a.common.title {
        chart.title = t.clone();
    }
    let bytes = match format {
        Format::Svg => crest::plot::runout::render_svg(&chart).map(String::into_bytes),
        Format::Png => crest::plot::runout::render_png(&chart),
    }
    .map_err(|e| miette!("{}: cannot render: {e}", a.common.output.display()))?;
    crest::io::write_atomic(&a.common.output, |w| w.write_all(&bytes))
        .map_err(|e| miette!("{}: cannot write: {e}", a.common.output.display()))?;
    let json_curves: Vec<_> = curves
        .iter()
        .map(|c| {
            serde_json::json!({
                "lead_deg": c.lead_deg,
                "max_um": c.curve.iter().map(|p| p.1).fold(0.0, f64::max),
                "marks": c.marks.iter().map(|(z, d)| serde_json::json!({"height_mm": z, "runout_um": d})).collect::<Vec<_>>(),
            })
        })
        .collect();
    done(
        &a.common,
        "runout",
        serde_json::json!({ "curves": json_curves }),
    )
}

fn read_map(input: &MapInput) -> miette::Result<crest::surface::HeightMap> {
    let opts = crest::io::ReadOptions {
        dx_um: input.dx_um,
        dy_um: input.dy_um,
        channel: input.channel.clone(),
    };
    crest::io::read_heightmap(&input.map, &opts).map_err(|e| miette!("{e}"))
}

fn file_stem(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn run_heightmap(a: HeightmapArgs) -> miette::Result<Outcome> {
    check_format(&a.common.output)?;
    let map = read_map(&a.input)?;
    let title = a
        .common
        .title
        .clone()
        .unwrap_or_else(|| format!("Height map {}", file_stem(&a.input.map)));
    heightmap::plot_heightmap(&map, &title, &a.common.output).map_err(|e| miette!("{e}"))?;
    done(
        &a.common,
        "heightmap",
        serde_json::json!({ "nx": map.nx, "ny": map.ny, "dx_um": map.dx_um, "dy_um": map.dy_um }),
    )
}

/// Read a two-column numeric table (optional header; commas, semicolons, tabs or blanks).
fn read_two_columns(path: &Path) -> miette::Result<(Vec<f64>, Vec<f64>)> {
    crest::io::series::read_two_columns(path).map_err(|e| miette!("{e}"))
}

fn run_profile(a: ProfileArgs) -> miette::Result<Outcome> {
    check_format(&a.common.output)?;
    let map = read_map(&a.input)?;
    if map.nx == 0 || map.ny == 0 {
        return Err(miette!("{}: empty height map", a.input.map.display()));
    }
    let nearest = |v: f64, v0: f64, d_um: f64, n: usize| -> usize {
        let i = ((v - v0) / (d_um * 1e-3)).round();
        if i.is_finite() {
            i.clamp(0.0, (n - 1) as f64) as usize
        } else {
            0
        }
    };
    let (pos, z, what) = if let Some(x) = a.x_mm {
        let col = nearest(x, map.x0_mm, map.dx_um, map.nx);
        let pos: Vec<f64> = (0..map.ny)
            .map(|r| map.y0_mm + r as f64 * map.dy_um * 1e-3)
            .collect();
        let z: Vec<f64> = (0..map.ny).map(|r| map.get(col, r)).collect();
        let x = map.x0_mm + col as f64 * map.dx_um * 1e-3;
        (pos, z, format!("along y at x = {x:.3} mm"))
    } else {
        let row = match a.y_mm {
            Some(y) => nearest(y, map.y0_mm, map.dy_um, map.ny),
            None => map.ny / 2,
        };
        let pos: Vec<f64> = (0..map.nx)
            .map(|c| map.x0_mm + c as f64 * map.dx_um * 1e-3)
            .collect();
        let y = map.y0_mm + row as f64 * map.dy_um * 1e-3;
        (
            pos,
            map.row(row).to_vec(),
            format!("along x at y = {y:.3} mm"),
        )
    };
    let mut measured = match &a.measured {
        Some(p) => Some(read_two_columns(p)?),
        None => None,
    };
    let mut alignment = serde_json::Value::Null;
    if a.align
        && let (Some(path), Some((mx, mz))) = (&a.measured, measured.as_mut())
    {
        let Some(al) = crest::metrics::align_profile((&pos, &z), (mx, mz)) else {
            return Err(miette!(
                "{}: --align: the measured profile cannot be aligned to the simulated one (its positions must rise, no shift within half the profile leaves half of it overlapped, or a profile is flat)",
                path.display()
            ));
        };
        for x in mx.iter_mut() {
            *x += al.shift_mm;
        }
        for v in mz.iter_mut() {
            *v += al.offset_um;
        }
        if !a.common.json {
            outln!(
                "measured profile aligned: moved {:+.4} mm and {:+.4} µm (correlation {:.4})",
                al.shift_mm,
                al.offset_um,
                al.correlation
            );
        }
        alignment = serde_json::json!({
            "shift_mm": al.shift_mm,
            "offset_um": al.offset_um,
            "correlation": crest::io::tables::json_number(al.correlation),
        });
    }
    let title = a
        .common
        .title
        .clone()
        .unwrap_or_else(|| format!("Profile of {} {what}", file_stem(&a.input.map)));
    profile::plot_profiles(
        &title,
        (&pos, &z),
        measured.as_ref().map(|(x, y)| (x.as_slice(), y.as_slice())),
        &a.common.output,
    )
    .map_err(|e| miette!("{e}"))?;
    done(
        &a.common,
        "profile",
        serde_json::json!({ "points": pos.len(), "profile": what, "align": alignment }),
    )
}

fn run_feed(a: FeedArgs) -> miette::Result<Outcome> {
    check_format(&a.common.output)?;
    // The feed along every feed move (engage and retract too).
    let mut program = crest::io::toolpath::read_program(&a.path)?;
    crest::toolpath::Moves::All.apply(&mut program);
    let Some(tp) = program.paths.iter().find(|p| !p.cutting_runs().is_empty()) else {
        return Err(miette!("{}: no cutting moves", a.path.display()));
    };
    // Path length of the CL point over cutting moves; runs are separated by a gap (NaN).
    let (mut s, mut feed, mut rpm) = (Vec::new(), Vec::new(), Vec::new());
    let mut lines: Vec<Option<u32>> = Vec::new();
    let mut len = 0.0;
    for run in tp.cutting_runs() {
        if !s.is_empty() {
            s.push(f64::NAN);
            feed.push(f64::NAN);
            rpm.push(f64::NAN);
            lines.push(None);
        }
        for i in run.clone() {
            if i > run.start {
                len += (tp.postures[i].position - tp.postures[i - 1].position).norm();
            }
            let p = &tp.postures[i];
            s.push(len);
            lines.push(Some(p.line));
            feed.push(p.feed_mm_min.or(a.feed_mm_min).unwrap_or(f64::NAN));
            rpm.push(a.rpm.or(p.spindle_rpm).unwrap_or(f64::NAN));
        }
    }
    if a.from_mm.is_some() || a.to_mm.is_some() {
        let keep = length_range(&s, a.from_mm, a.to_mm, len)?;
        let pick = |v: &[f64], at_cut: bool| {
            keep.iter()
                .map(|k| match *k {
                    RangePoint::Posture(i) => v[i],
                    RangePoint::Cut(x, _) if at_cut => x,
                    RangePoint::Cut(_, i) => v[i],
                })
                .collect::<Vec<f64>>()
        };
        (s, feed, rpm) = (pick(&s, true), pick(&feed, false), pick(&rpm, false));
        lines = keep
            .iter()
            .map(|k| match *k {
                RangePoint::Posture(i) => lines[i],
                RangePoint::Cut(..) => None,
            })
            .collect();
    }
    let name = file_stem(&a.path);
    if a.crest {
        let tool = a
            .tool
            .as_ref()
            .ok_or_else(|| miette!("--crest needs --tool"))?;
        let cutter = crest::pipeline::load_tool(tool)?;
        if let Some(n) = a.rpm {
            crest::math::limits::within("--rpm", "rpm", n, crest::math::limits::RPM)
                .map_err(|e| miette!("{e}"))?;
        }
        if let Some(f) = a.feed_mm_min {
            crest::math::limits::within(
                "--feed-mm-min",
                "mm/min",
                f,
                crest::math::limits::FEED_MM_MIN,
            )
            .map_err(|e| miette!("{e}"))?;
        }
        let teeth = cutter.teeth() as f64;
        let r = cutter.corner_radius_mm();
        let crest: Vec<f64> = feed
            .iter()
            .zip(&rpm)
            .map(|(f, n)| crest::tool::crest_height_mm(r, f / (teeth * n)) * 1e3)
            .collect();
        if crest.iter().all(|c| !c.is_finite()) {
            return Err(miette!(
                "{}: no feed and spindle speed to compute fz (give --feed-mm-min and --rpm)",
                a.path.display()
            ));
        }
        let title = a
            .common
            .title
            .clone()
            .unwrap_or_else(|| format!("Feed-mark crest height along {name}"));
        feed::plot_crest_along_path(&title, &s, &[("programmed feed", &crest)], &a.common.output)
            .map_err(|e| miette!("{e}"))?;
        let finite = crest.iter().cloned().filter(|c| c.is_finite());
        let lo = finite.clone().fold(f64::INFINITY, f64::min);
        let hi = finite.fold(f64::NEG_INFINITY, f64::max);
        return done(
            &a.common,
            "crest",
            serde_json::json!({ "points": len_points(&s), "crest_um_min": lo, "crest_um_max": hi }),
        );
    }
    let mut series = vec![Series::line("programmed", &s, &feed, 0)];
    let mut actual_points = 0;
    if let Some(p) = &a.actual {
        match crest::io::series::read_planned_feed(p).map_err(|e| miette!("{e}"))? {
            // The poses of `crest feed -o`: the planned feed at each posture's source line.
            Some(planned) => {
                let y: Vec<f64> = lines
                    .iter()
                    .map(|l| match l {
                        Some(l) => planned
                            .get(&(tp.name.clone(), *l))
                            .copied()
                            .unwrap_or(f64::NAN),
                        None => f64::NAN,
                    })
                    .collect();
                if y.iter().all(|v| !v.is_finite()) {
                    return Err(miette!(
                        "{}: no planned feed for tool path '{}' of {} (was it written by `crest feed` for this file?)",
                        p.display(),
                        tp.name,
                        a.path.display()
                    ));
                }
                actual_points = len_points(&y);
                series.push(Series::line("actual (planned)", &s, &y, 1));
            }
            None => {
                let (x, y) = read_two_columns(p)?;
                actual_points = len_points(&y);
                series.push(Series::line("actual", &x, &y, 1));
            }
        }
    }
    let title = a
        .common
        .title
        .clone()
        .unwrap_or_else(|| format!("Feed along {name}"));
    crest::plot::chart::write(
        &Chart::lines(title, "path length [mm]", "feed [mm/min]", series),
        &a.common.output,
    )
    .map_err(|e| miette!("{e}"))?;
    done(
        &a.common,
        "feed",
        serde_json::json!({ "points": len_points(&s), "length_mm": len, "actual_points": actual_points }),
    )
}

fn len_points(s: &[f64]) -> usize {
    s.iter().filter(|v| v.is_finite()).count()
}
