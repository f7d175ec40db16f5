//! `crest report`: hold a study's simulated roughness against a measured table and write
//! `DIR/report.md`, `DIR/report.html` and the SVG plots.
//!
//! Every input is read and checked, and every output rendered in memory, before the first
//! file is written; the files go through [`crate::io::write_atomic`]. Bad input leaves no
//! output behind (the directory is not even created).

use super::Outcome;
use crate::report::regression::{self, DEFAULT_TOLERANCE_PCT, Provenance, RunoutSpec};
use crate::tool::Cutter;
use miette::{IntoDiagnostic, WrapErr, miette};
use std::path::{Path, PathBuf};

/// Options of `crest report`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Measured table (CSV): lead_deg,side,sample,Ra_um,Rz_um (one row per case and sample).
    #[arg(long, value_name = "TABLE.csv")]
    pub measured: PathBuf,
    /// Study (TOML): tool file, run-out, fz, cases (lead, side) and model.
    #[arg(long, value_name = "STUDY.toml")]
    pub study: PathBuf,
    /// Output directory (created if needed): report.md, report.html, rz.svg, ra.svg.
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub output: PathBuf,
    /// A case passes when every simulated parameter is within this percentage of the measured mean.
    #[arg(long, value_name = "P", default_value_t = DEFAULT_TOLERANCE_PCT)]
    pub tolerance_pct: f64,
    /// Print one JSON object with every case on stdout.
    #[arg(long)]
    pub json: bool,
}

fn load_tool(path: &Path) -> miette::Result<Cutter> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot read the tool file {name}"))?;
    crate::tool::load_tool_toml(&text)
        .map_err(|e| miette!("{name}:{}:{}: {}", e.line(), e.column(), e.message()))
}

fn check_runout(r: &RunoutSpec, teeth: usize) -> Result<(), String> {
    let n = r.tooth_radius_deviation_um.len();
    if n != 0 && n != teeth {
        return Err(format!(
            "tooth_radius_deviation_um has {n} values for {teeth} teeth"
        ));
    }
    let all = [
        r.offset_um,
        r.offset_phase_deg,
        r.axis_tilt_deg,
        r.axis_tilt_phase_deg,
    ];
    if all
        .iter()
        .chain(r.tooth_radius_deviation_um.iter())
        .any(|v| !v.is_finite())
    {
        return Err("values must be finite".to_string());
    }
    Ok(())
}

fn read(path: &Path, what: &str) -> miette::Result<String> {
    std::fs::read_to_string(path)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot read the {what} {}", path.display()))
}

/// Run `crest report`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    if !(args.tolerance_pct.is_finite() && args.tolerance_pct >= 0.0) {
        return Err(miette!(
            "--tolerance-pct must be a non-negative number, found {}",
            args.tolerance_pct
        ));
    }
    let measured_name = args.measured.display().to_string();
    let study_name = args.study.display().to_string();
    let table =
        regression::parse_measured(&read(&args.measured, "measured table")?, &measured_name)?;
    let study = regression::parse_study(&read(&args.study, "study")?, &study_name)?;
    let tool_path = args
        .study
        .parent()
        .unwrap_or(Path::new("."))
        .join(&study.tool);
    let mut cutter = load_tool(&tool_path)
        .wrap_err_with(|| format!("{study_name}: tool = \"{}\"", study.tool))?;
    if let Some(r) = &study.runout {
        check_runout(r, cutter.teeth()).map_err(|e| miette!("{study_name}: [runout] {e}"))?;
        cutter.runout = r.to_runout();
    }
    let command = format!(
        "crest report --measured {} --study {} -o {} --tolerance-pct {}",
        measured_name,
        study_name,
        args.output.display(),
        args.tolerance_pct
    );
    let reg = regression::regress(
        &table,
        &study,
        &cutter,
        args.tolerance_pct,
        Provenance {
            measured_file: measured_name,
            study_file: study_name,
            command,
        },
    )?;

    // Render everything before writing anything.
    let mut plots: Vec<(String, String, String)> = Vec::new(); // (file, caption, svg)
    for (param, file) in [("Rz", "rz.svg"), ("Ra", "ra.svg")] {
        if reg
            .cases
            .iter()
            .any(|c| c.comparisons.iter().any(|k| k.parameter == param))
        {
            let svg = regression::render_plot(&reg, param)
                .map_err(|e| miette!("cannot draw the {param} plot: {e}"))?;
            let caption = format!(
                "{param}: measured mean ± σ and samples against simulated, per lead angle and side"
            );
            plots.push((file.to_string(), caption, svg));
        }
    }
    let md_plots: Vec<(String, String)> = plots
        .iter()
        .map(|(f, c, _)| (f.clone(), c.clone()))
        .collect();
    let html_plots: Vec<(String, String)> = plots
        .iter()
        .map(|(_, c, s)| (c.clone(), s.clone()))
        .collect();
    let markdown = regression::render_markdown(&reg, &md_plots);
    let html = regression::render_html(&reg, &html_plots);
    let json = if args.json {
        Some(serde_json::to_string(&reg).into_diagnostic()?)
    } else {
        None
    };

    std::fs::create_dir_all(&args.output)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot create {}", args.output.display()))?;
    let write = |name: &str, bytes: &[u8]| -> miette::Result<PathBuf> {
        let path = args.output.join(name);
        crate::io::write_atomic(&path, |w| w.write_all(bytes))
            .into_diagnostic()
            .wrap_err_with(|| format!("cannot write {}", path.display()))?;
        Ok(path)
    };
    let mut written = Vec::new();
    for (file, _, svg) in &plots {
        written.push(write(file, svg.as_bytes())?);
    }
    written.push(write("report.html", html.as_bytes())?);
    written.push(write("report.md", markdown.as_bytes())?);

    match json {
        Some(j) => outln!("{j}"),
        None => {
            for c in &reg.cases {
                for k in &c.comparisons {
                    outln!(
                        "lead {:>5}° {:<8} {}: measured {:.3} ± {:.3} µm, simulated {:.4} µm, ratio {:.3}, {}",
                        c.lead_deg,
                        c.side.name(),
                        k.parameter,
                        k.measured.mean,
                        k.measured.sd.unwrap_or(f64::NAN),
                        k.simulated_um,
                        k.ratio,
                        if k.pass { "pass" } else { "FAIL" }
                    );
                }
            }
            for p in &written {
                outln!("wrote {}", p.display());
            }
        }
    }
    Ok(if reg.pass {
        Outcome::Ok
    } else {
        Outcome::CheckFailed
    })
}
