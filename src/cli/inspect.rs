//! `crest inspect`: summarise the tool paths of a CLSF (or APT), contact12 or G-code file.
//!
//! Per tool path: name, tool (from TLDATA), record counts (GOTO, RAPID, CIRCLE, NURBS),
//! path and cutting lengths, feeds and spindle speeds seen, postures with contact data,
//! postures and groups of each move kind; with `--regions` the finishing regions
//! ([`crest::toolpath::regions`]); then the warnings. Reading streams, so huge files
//! summarise in constant memory (`--regions` keeps the postures).

use super::Outcome;
use super::reading::read_options;
use crest::io::toolpath::{detect, stream_program};
use crest::nc::Rtcp;
use crest::toolpath::{LowerOptions, MotionKind, MoveCounts, Posture, Toolpath};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

/// Options of `crest inspect`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// CLSF (or APT), contact12 or G-code file (detected by content).
    pub file: PathBuf,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    /// Machine description (`machine.toml`): G-code is read through its kinematics.
    #[arg(long, value_name = "MACHINE.toml")]
    pub machine: Option<PathBuf>,
    /// Tool-centre-point control of G-code: `auto` (as the program says), `on` (X Y Z
    /// are the tool tip) or `off` (X Y Z are joint positions).
    #[arg(long, value_enum, default_value = "auto")]
    pub rtcp: Rtcp,
    /// Also list the finishing regions (groups of neighbouring cut passes): extents,
    /// passes, stepover, tool-axis range, feeds, cutting length and a centre point for
    /// `simulate --patch-near`.
    #[arg(long)]
    pub regions: bool,
}

/// Postures per move kind: rapid, approach, engage, cut, retract, departure (in path
/// order; JSON object keys in that order are not guaranteed, the names are).
pub type KindCounts = BTreeMap<&'static str, usize>;

fn kind_counts(m: &MoveCounts, groups: bool) -> KindCounts {
    MotionKind::MOVES
        .iter()
        .map(|k| (k.name(), if groups { m.groups(*k) } else { m.postures(*k) }))
        .collect()
}

/// One finishing region at the interface (mm, degrees, mm/min).
#[derive(Debug, Serialize)]
pub struct RegionSummary {
    /// 1-based, over the whole file.
    pub id: usize,
    /// 1-based tool path.
    pub path: usize,
    /// Lower corner of the extents, mm (the file's coordinates).
    pub min_mm: [f64; 3],
    /// Upper corner, mm.
    pub max_mm: [f64; 3],
    /// Cut passes.
    pub passes: usize,
    /// Median stepover across the feed, mm (null without a neighbouring pass).
    pub stepover_mm: Option<f64>,
    /// Smallest and largest angle of the tool axis to the path's mean axis, degrees.
    pub axis_deg: [f64; 2],
    /// Programmed feeds of the cut moves, mm/min.
    pub feeds_mm_min: Vec<f64>,
    /// Length of the cut moves, mm.
    pub cut_length_mm: f64,
    /// A point on the cut (middle pass, half its length), mm: for `--patch-near`.
    pub centre_mm: [f64; 3],
}

/// TLDATA of a path, at the interface (mm, degrees).
#[derive(Debug, Serialize)]
pub struct ToolSummary {
    /// Tool name from `TOOL PATH/…,TOOL,<name>`.
    pub name: String,
    /// Kind word (`MILL`, `DRILL`, …).
    pub kind: String,
    /// Diameter, mm.
    pub diameter_mm: f64,
    /// Corner (lower) radius, mm.
    pub corner_radius_mm: f64,
    /// Length, mm.
    pub length_mm: f64,
    /// Taper angle, degrees.
    pub taper_deg: f64,
    /// Tip angle, degrees.
    pub tip_deg: f64,
    /// The seven APT parameters of `CUTTER/d,r,e,f,a,b,h` (mm; a and b in degrees), when
    /// the file gives them.
    pub apt: Option<[f64; 7]>,
}

/// One tool path's summary.
#[derive(Debug, Serialize)]
pub struct PathSummary {
    /// Operation name.
    pub name: String,
    /// Tool name from the `TOOL PATH` record.
    pub tool_name: String,
    /// Tool data from TLDATA (null without TLDATA).
    pub tool: Option<ToolSummary>,
    /// GOTO records (contact12: data lines).
    pub gotos: usize,
    /// RAPID records.
    pub rapids: usize,
    /// CIRCLE records.
    pub circles: usize,
    /// NURBS blocks.
    pub nurbs: usize,
    /// Postures after lowering (NURBS blocks are sampled).
    pub postures: usize,
    /// Postures with contact data.
    pub contact_postures: usize,
    /// Postures whose normal was derived from the cutter.
    pub derived_normals: usize,
    /// Cutting postures (cut moves).
    pub cutting_postures: usize,
    /// Postures per move kind.
    pub moves: KindCounts,
    /// Groups of consecutive postures per move kind.
    pub move_groups: KindCounts,
    /// Length of all moves, mm.
    pub length_mm: f64,
    /// Length of cutting moves, mm.
    pub cutting_length_mm: f64,
    /// Distinct feeds seen, mm/min.
    pub feeds_mm_min: Vec<f64>,
    /// Distinct spindle speeds seen, rpm.
    pub spindles_rpm: Vec<f64>,
    /// MSYS as written (origin mm, X axis, Y axis), if any.
    pub msys: Option<[f64; 9]>,
    /// Unknown records kept raw.
    pub raw_records: usize,
    /// `PPRINT`/`TPRINT` comments kept.
    pub prints: usize,
}

/// A warning at the interface.
#[derive(Debug, Serialize)]
pub struct WarningSummary {
    /// 1-based line (0 = not tied to a line).
    pub line: u32,
    /// 1-based column (0 = not tied to a column).
    pub column: u32,
    /// Message.
    pub message: String,
}

/// The whole `inspect --json` object.
#[derive(Debug, Serialize)]
pub struct InspectReport {
    /// File as given.
    pub file: String,
    /// `clsf`, `contact12` or `gcode`.
    pub format: &'static str,
    /// Tool paths in file order.
    pub paths: Vec<PathSummary>,
    /// Postures per move kind over all tool paths.
    pub moves: KindCounts,
    /// Finishing regions (with `--regions`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub regions: Option<Vec<RegionSummary>>,
    /// Warnings in file order.
    pub warnings: Vec<WarningSummary>,
}

#[derive(Default, Clone, Copy)]
struct Counts {
    contact: usize,
    derived: usize,
    cutting: usize,
}

/// Build the summary of a file (streams; keeps no postures).
pub fn summarise(
    file: &std::path::Path,
    machine: Option<&std::path::Path>,
    rtcp: Rtcp,
    regions: bool,
) -> miette::Result<InspectReport> {
    let kind = detect(file)?;
    let mut counts: Vec<Counts> = Vec::new();
    let mut sink = |path: &Toolpath, p: &Posture| {
        if path.stats.postures == 1 {
            counts.push(Counts::default());
        }
        if let Some(c) = counts.last_mut() {
            if let Some(ct) = &p.contact {
                c.contact += 1;
                c.derived += usize::from(ct.normal_derived);
            }
            c.cutting += usize::from(p.motion == MotionKind::Cut);
        }
        Ok(())
    };
    let lower = LowerOptions {
        keep_postures: regions,
        ..Default::default()
    };
    let opts = read_options(kind, lower, machine, rtcp)?;
    let program = stream_program(file, opts, &mut sink)?;
    let mut k = 0;
    let paths = program
        .paths
        .iter()
        .map(|t| {
            let c = if t.stats.postures > 0 {
                k += 1;
                counts.get(k - 1).copied().unwrap_or_default()
            } else {
                Counts::default()
            };
            PathSummary {
                name: t.name.clone(),
                tool_name: t.tool_name.clone(),
                tool: t.tool.as_ref().map(|d| ToolSummary {
                    name: t.tool_name.clone(),
                    kind: d.kind.clone(),
                    diameter_mm: d.diameter_mm,
                    corner_radius_mm: d.corner_radius_mm,
                    length_mm: d.length_mm,
                    taper_deg: d.taper_rad.to_degrees(),
                    tip_deg: d.tip_rad.to_degrees(),
                    apt: d.apt.map(|a| {
                        let mut v = a;
                        v[4] = a[4].to_degrees();
                        v[5] = a[5].to_degrees();
                        v
                    }),
                }),
                gotos: t.stats.gotos,
                rapids: t.stats.rapids,
                circles: t.stats.circles,
                nurbs: t.stats.nurbs,
                postures: t.stats.postures,
                contact_postures: c.contact,
                derived_normals: c.derived,
                cutting_postures: c.cutting,
                moves: kind_counts(&t.stats.moves, false),
                move_groups: kind_counts(&t.stats.moves, true),
                length_mm: round(t.stats.length_mm, 4),
                cutting_length_mm: round(t.stats.cutting_length_mm, 4),
                feeds_mm_min: t.stats.feeds_mm_min.iter().map(|v| round(*v, 4)).collect(),
                spindles_rpm: t.stats.spindles_rpm.iter().map(|v| round(*v, 4)).collect(),
                msys: t.msys,
                raw_records: t.raw_records.len(),
                prints: t.prints.len(),
            }
        })
        .collect();
    let mut moves = KindCounts::new();
    for t in &program.paths {
        for (k, n) in kind_counts(&t.stats.moves, false) {
            *moves.entry(k).or_insert(0) += n;
        }
    }
    let regions = regions.then(|| {
        let mut out = Vec::new();
        for (pi, t) in program.paths.iter().enumerate() {
            for r in crest::toolpath::regions::regions(t) {
                let p3 = |p: &crest::math::Point3| [round(p.x, 4), round(p.y, 4), round(p.z, 4)];
                out.push(RegionSummary {
                    id: out.len() + 1,
                    path: pi + 1,
                    min_mm: p3(&r.min),
                    max_mm: p3(&r.max),
                    passes: r.passes,
                    stepover_mm: r.stepover_mm.map(|v| round(v, 4)),
                    axis_deg: [
                        round(r.axis_rad.0.to_degrees(), 3),
                        round(r.axis_rad.1.to_degrees(), 3),
                    ],
                    feeds_mm_min: r.feeds_mm_min.iter().map(|v| round(*v, 4)).collect(),
                    cut_length_mm: round(r.cut_length_mm, 4),
                    centre_mm: p3(&r.centre),
                });
            }
        }
        out
    });
    Ok(InspectReport {
        file: file.display().to_string(),
        format: kind.name(),
        paths,
        moves,
        regions,
        warnings: program
            .warnings
            .into_iter()
            .map(|w| WarningSummary {
                line: w.at.line,
                column: w.at.column,
                message: w.message,
            })
            .collect(),
    })
}

fn round(v: f64, decimals: i32) -> f64 {
    let p = 10f64.powi(decimals);
    (v * p).round() / p
}

fn list(v: &[f64], unit: &str) -> String {
    if v.is_empty() {
        return "none".into();
    }
    let items: Vec<String> = v.iter().map(|x| format!("{x}")).collect();
    format!("{} {unit}", items.join(", "))
}

fn print_text(r: &InspectReport, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(
        out,
        "{} ({}), {} tool path(s)",
        r.file,
        r.format,
        r.paths.len()
    )?;
    for (k, p) in r.paths.iter().enumerate() {
        writeln!(
            out,
            "path {}: {}",
            k + 1,
            if p.name.is_empty() {
                "(unnamed)"
            } else {
                &p.name
            }
        )?;
        match &p.tool {
            Some(t) => writeln!(
                out,
                "  tool: {} ({}, D {} mm, R {} mm, L {} mm)",
                t.name, t.kind, t.diameter_mm, t.corner_radius_mm, t.length_mm
            )?,
            None => writeln!(
                out,
                "  tool: {} (no TLDATA)",
                if p.tool_name.is_empty() {
                    "-"
                } else {
                    &p.tool_name
                }
            )?,
        }
        writeln!(
            out,
            "  records: {} GOTO, {} RAPID, {} CIRCLE, {} NURBS; {} postures ({} cutting, {} with contact data, {} derived normals)",
            p.gotos,
            p.rapids,
            p.circles,
            p.nurbs,
            p.postures,
            p.cutting_postures,
            p.contact_postures,
            p.derived_normals
        )?;
        writeln!(
            out,
            "  length: {:.4} mm, cutting {:.4} mm",
            p.length_mm, p.cutting_length_mm
        )?;
        let kinds: Vec<String> = MotionKind::MOVES
            .iter()
            .map(|k| {
                let n = p.moves.get(k.name()).copied().unwrap_or(0);
                let g = p.move_groups.get(k.name()).copied().unwrap_or(0);
                format!("{n} {} ({g} groups)", k.name())
            })
            .collect();
        writeln!(out, "  moves: {}", kinds.join(", "))?;
        writeln!(out, "  feeds: {}", list(&p.feeds_mm_min, "mm/min"))?;
        writeln!(out, "  spindle: {}", list(&p.spindles_rpm, "rpm"))?;
    }
    if let Some(regions) = &r.regions {
        writeln!(out, "{} finishing region(s):", regions.len())?;
        for g in regions {
            writeln!(
                out,
                "region {} (path {}): {} passes, stepover {}, cut {:.1} mm at {}",
                g.id,
                g.path,
                g.passes,
                g.stepover_mm
                    .map_or_else(|| "-".to_string(), |v| format!("{v:.4} mm")),
                g.cut_length_mm,
                list(&g.feeds_mm_min, "mm/min")
            )?;
            writeln!(
                out,
                "  x {:.4} … {:.4}, y {:.4} … {:.4}, z {:.4} … {:.4} mm; tool axis {:.2}° … {:.2}° from the mean",
                g.min_mm[0],
                g.max_mm[0],
                g.min_mm[1],
                g.max_mm[1],
                g.min_mm[2],
                g.max_mm[2],
                g.axis_deg[0],
                g.axis_deg[1]
            )?;
            writeln!(
                out,
                "  centre {},{},{} (for --patch-near)",
                g.centre_mm[0], g.centre_mm[1], g.centre_mm[2]
            )?;
        }
    }
    if r.warnings.is_empty() {
        writeln!(out, "no warnings")?;
    } else {
        writeln!(out, "warnings:")?;
        for w in &r.warnings {
            if w.line > 0 {
                writeln!(out, "  line {}, column {}: {}", w.line, w.column, w.message)?;
            } else {
                writeln!(out, "  {}", w.message)?;
            }
        }
    }
    Ok(())
}

/// Run `crest inspect`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let report = summarise(&args.file, args.machine.as_deref(), args.rtcp, args.regions)?;
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let written = if args.json {
        serde_json::to_writer(&mut out, &report)
            .map_err(std::io::Error::from)
            .and_then(|()| writeln!(out))
    } else {
        print_text(&report, &mut out)
    };
    match written {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => return Ok(Outcome::Ok),
        Err(e) => return Err(miette::miette!("writing to stdout failed: {e}")),
    }
    // Nothing to summarise is not a success: say why.
    if report.paths.iter().all(|p| p.postures == 0) {
        eprintln!(
            "crest inspect: {} has no motion (no GOTO, CIRCLE or contact12 row): it does not look like a tool path (CLSF, APT, contact12 or G-code)",
            args.file.display()
        );
        return Ok(Outcome::CheckFailed);
    }
    // Contradictory units fail the check (README "Sanity checks").
    let units: Vec<_> = report
        .warnings
        .iter()
        .filter(|w| w.message.starts_with(crest::toolpath::CONTRADICTORY_UNITS))
        .collect();
    for w in &units {
        eprintln!(
            "crest inspect: {}:{}:{}: {}",
            args.file.display(),
            w.line,
            w.column,
            w.message
        );
    }
    if !units.is_empty() {
        return Ok(Outcome::CheckFailed);
    }
    Ok(Outcome::Ok)
}
