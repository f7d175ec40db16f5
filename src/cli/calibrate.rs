//! `crest calibrate --measured TABLE.csv --study STUDY.toml --free NAME[,NAME…] [-o DIR]
//! [--json]`: fit process parameters to a measured table by weighted least squares, with
//! uncertainties and leave-one-out predictions (`crest::study::calibrate`).

use super::Outcome;
use miette::{IntoDiagnostic, WrapErr};
use std::path::PathBuf;

/// Options of `crest calibrate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Measured table (CSV): lead_deg,side,sample,Ra_um,Rz_um, or measured_file (a height map
    /// relative to the table whose Rz and Ra along x are measured as `crest report` does).
    #[arg(long, value_name = "TABLE.csv")]
    pub measured: PathBuf,
    /// Study (TOML) whose [process] and run-out are the starting point.
    #[arg(long, value_name = "STUDY.toml")]
    pub study: PathBuf,
    /// Parameters to fit: min_chip_um, recovery, texture_sq_um, texture_corr_um,
    /// runout_offset_um, runout_phase_deg, tooth_deviation_um.
    #[arg(long, value_name = "NAME[,NAME…]")]
    pub free: String,
    /// Write calibration.json and calibration.csv into this folder.
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub output: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Run `crest calibrate`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    if let Some(dir) = &args.output {
        super::check_output_folder(dir, &["calibration.json".into(), "calibration.csv".into()])?;
    }
    let inputs = crest::pipeline::report::load(&args.measured, &args.study)?;
    let cal = crest::pipeline::report::calibrate(&inputs, &args.free)?;
    let json = crest::report::regression::calibration_json(&cal);
    if let Some(dir) = &args.output {
        let files = vec![
            (
                "calibration.json".to_string(),
                format!("{json:#}\n").into_bytes(),
            ),
            (
                "calibration.csv".to_string(),
                crest::report::regression::calibration_csv(&cal).into_bytes(),
            ),
        ];
        crest::io::write_files(dir, &files)
            .into_diagnostic()
            .wrap_err_with(|| format!("cannot write into {}", dir.display()))?;
    }
    if args.json {
        outln!("{json}");
    } else {
        for (name, v, s) in &cal.parameters {
            outln!("{name} = {v:.4} ± {s:.4}");
        }
        for c in &cal.cases {
            outln!(
                "lead {:>5}° {:<8} {}: measured {:.3} µm, geometric {:.3}, calibrated {:.3}, leave-one-out {:.3} ({:+.1} %)",
                c.lead_deg,
                c.side.name(),
                c.parameter,
                c.measured_um,
                c.geometric_um,
                c.calibrated_um,
                c.loo_um,
                100.0 * (c.loo_um - c.measured_um) / c.measured_um
            );
        }
        outln!(
            "leave-one-out RMS {:.1} % (a constant offset on the geometric model: {:.1} %)",
            cal.loo_rms_pct,
            cal.constant_loo_rms_pct
        );
        let factors: Vec<String> = cal
            .factors
            .iter()
            .map(|(n, v)| format!("{n} × {v:.4}"))
            .collect();
        outln!(
            "constant factor on the geometric model (all cases): {}; its leave-one-out RMS {:.1} %",
            factors.join(", "),
            cal.factor_loo_rms_pct
        );
    }
    Ok(Outcome::Ok)
}
