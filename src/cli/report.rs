//! `crest report`: hold a study's simulated roughness against a measured table and write
//! `DIR/report.md`, `DIR/report.html` and the SVG plots.
//!
//! Every input is read and checked, and every output rendered in memory, before the first
//! file is written; the files go through `crest::io::write_atomic`. Bad input leaves no
//! output behind (the directory is not even created).

use super::Outcome;
use crest::study::compare::DEFAULT_TOLERANCE_PCT;
use miette::{IntoDiagnostic, WrapErr, miette};
use std::path::PathBuf;

/// Options of `crest report`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Measured table (CSV): lead_deg,side,sample,Ra_um,Rz_um (one row per case and sample);
    /// optional Sa_um, Sz_um, Sq_um, Sdq, Ra_stepover_um, Rz_stepover_um, and measured_file (a
    /// height map relative to the table, measured with the predictions' filters: Rz, Ra along
    /// x, Sz, Sa, Sq, Sdq) (docs/config.md).
    #[arg(long, value_name = "TABLE.csv")]
    pub measured: PathBuf,
    /// Study (TOML): tool file, run-out, fz, cases (lead, side) and model.
    #[arg(long, value_name = "STUDY.toml")]
    pub study: PathBuf,
    /// Output directory (created if needed): report.md, report.html, rz.svg, ra.svg (and a plot
    /// per other roughness column of the table).
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub output: PathBuf,
    /// A case passes when every simulated parameter is within this percentage of the measured mean.
    #[arg(long, value_name = "P", default_value_t = DEFAULT_TOLERANCE_PCT)]
    pub tolerance_pct: f64,
    /// Print one JSON object with every case on stdout.
    #[arg(long)]
    pub json: bool,
    /// Also write a 3-D viewer page of each case's simulated window, `DIR/view-N.html`
    /// (N = the case's number; needs `model = "simulate"`, the crest model simulates no
    /// surface).
    #[arg(long)]
    pub view: bool,
    /// Calibrate these process parameters (comma-separated, as `crest calibrate --free`);
    /// a case then passes only on its leave-one-out prediction.
    #[arg(long, value_name = "NAME[,NAME…]")]
    pub free: Option<String>,
    /// Monte Carlo samples for P5/P50/P95 bands (inputs from the study's [uncertainty]).
    #[arg(long, value_name = "N")]
    pub monte_carlo: Option<usize>,
    /// Seed of the Monte Carlo samples.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
}

/// Run `crest report`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let mut command = format!(
        "crest report --measured {} --study {} -o {} --tolerance-pct {}",
        args.measured.display(),
        args.study.display(),
        args.output.display(),
        args.tolerance_pct
    );
    if let Some(f) = &args.free {
        command.push_str(&format!(" --free {f}"));
    }
    if let Some(n) = args.monte_carlo {
        command.push_str(&format!(" --monte-carlo {n} --seed {}", args.seed));
    }
    let opts = crest::pipeline::report::ReportOptions {
        free: args.free.clone(),
        monte_carlo: args.monte_carlo.map(|n| (n, args.seed)),
    };
    super::check_output_folder(&args.output, &["report.md".into(), "report.html".into()])?;
    let reg = crest::pipeline::report::regression(
        &args.measured,
        &args.study,
        args.tolerance_pct,
        command,
        &opts,
    )?;
    // Render everything before writing anything.
    let mut files = crest::report::regression::outputs(&reg).map_err(|e| miette!("{e}"))?;
    if args.view {
        let pages = crest::report::view::regression_pages(&reg).map_err(|e| miette!("{e}"))?;
        if pages.is_empty() {
            return Err(miette!(
                "{}: --view needs model = \"simulate\" (the crest model simulates no surface)",
                args.study.display()
            ));
        }
        files.extend(pages);
    }
    let json = if args.json {
        Some(serde_json::to_string(&reg).into_diagnostic()?)
    } else {
        None
    };
    let written = crest::io::write_files(&args.output, &files)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write the report into {}", args.output.display()))?;

    match json {
        Some(j) => outln!("{j}"),
        None => {
            for c in &reg.cases {
                for k in &c.comparisons {
                    let unit = if k.parameter == "Sdq" { "" } else { " µm" };
                    outln!(
                        "lead {:>5}° {:<8} {}: measured {}{unit}, simulated {:.4}{unit}, ratio {:.3}, {}",
                        c.lead_deg,
                        c.side.name(),
                        k.parameter,
                        crest::report::regression::fmt_stat(&k.measured, 3),
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
