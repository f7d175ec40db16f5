//! `crest inspect`: summarise the tool paths of a CLSF (or APT), contact12 or G-code file.
//!
//! Per tool path: name, tool (from TLDATA), record counts (GOTO, RAPID, CIRCLE, NURBS),
//! path and cutting lengths, feeds and spindle speeds seen, postures with contact data;
//! then the warnings. Reading streams, so huge files summarise in constant memory.

use super::Outcome;
use super::reading::{RtcpArg, read_options};
use crest::io::toolpath::{detect, stream_program};
use crest::toolpath::{LowerOptions, MotionKind, Posture, Toolpath};
use serde::Serialize;
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
    pub rtcp: RtcpArg,
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
    /// Cutting postures.
    pub cutting_postures: usize,
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
    rtcp: RtcpArg,
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
        keep_postures: false,
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
    Ok(InspectReport {
        file: file.display().to_string(),
        format: kind.name(),
        paths,
        warnings: program
            .warnings
            .into_iter()
            .map(|w| WarningSummary {
                line: w.line,
                column: w.column,
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
        writeln!(out, "  feeds: {}", list(&p.feeds_mm_min, "mm/min"))?;
        writeln!(out, "  spindle: {}", list(&p.spindles_rpm, "rpm"))?;
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
    let report = summarise(&args.file, args.machine.as_deref(), args.rtcp)?;
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
    Ok(Outcome::Ok)
}
