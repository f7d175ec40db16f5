//! `crest compare`: hold a predicted height map against a measured one and write
//! `DIR/compare.md`, `DIR/compare.html` and the figures; the work is in
//! `crest::pipeline::compare`.

use std::path::PathBuf;

use miette::{IntoDiagnostic, WrapErr, miette};

use super::Outcome;
use crest::metrics::Level;
use crest::pipeline::compare::{CompareOptions, DEFAULT_TOLERANCE_PCT};

/// Options of `crest compare`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Both maps go through the same chain (F-operator, S-filter, L-filter) on the \
measured map's grid, over the nodes valid in both; the prediction is resampled bilinearly onto \
it. Registration: the feed direction of each map from its 2-D spectrum (perpendicular to the \
strongest peak), the prediction rotated onto the measurement's, then shifted by FFT \
cross-correlation to a fraction of a node.\n\
Exit status: 0 every judged value within --tolerance-pct, 1 the verdict fails, 2 bad input."
)]
pub struct Args {
    /// The predicted height map (any format `crest metrics` reads, except grid CSV).
    pub predicted: PathBuf,
    /// The measured height map (its grid is the comparison's).
    pub measured: PathBuf,
    /// Output directory (created if needed).
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub output: PathBuf,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    /// Form removal (F-operator): `none`, `plane` or `poly:N`.
    #[arg(long, default_value = "plane", value_parser = Level::parse, value_name = "none|plane|poly:N")]
    pub level: Level,
    /// S-filter nesting index λs, µm (Gaussian low-pass).
    #[arg(long, value_name = "L")]
    pub lambda_s_um: Option<f64>,
    /// L-filter nesting index λc, µm (Gaussian high-pass).
    #[arg(long, value_name = "L")]
    pub lambda_c_um: Option<f64>,
    /// Lay the maps centre on centre, without rotation or shift.
    #[arg(long)]
    pub no_register: bool,
    /// A judged value passes within this percentage of the measured one.
    #[arg(long, value_name = "P", default_value_t = DEFAULT_TOLERANCE_PCT)]
    pub tolerance_pct: f64,
}

/// Run `crest compare`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    if !(args.tolerance_pct.is_finite() && args.tolerance_pct >= 0.0) {
        return Err(miette!(
            "--tolerance-pct must be a non-negative number, got {}",
            args.tolerance_pct
        ));
    }
    let opts = CompareOptions {
        level: args.level,
        lambda_s_um: args.lambda_s_um,
        lambda_c_um: args.lambda_c_um,
        register: !args.no_register,
        tolerance_pct: args.tolerance_pct,
    };
    let mut command = format!(
        "crest compare {} {} -o {} --level {} --tolerance-pct {}",
        args.predicted.display(),
        args.measured.display(),
        args.output.display(),
        args.level.label(),
        args.tolerance_pct
    );
    for (flag, v) in [
        ("--lambda-s-um", args.lambda_s_um),
        ("--lambda-c-um", args.lambda_c_um),
    ] {
        if let Some(v) = v {
            command.push_str(&format!(" {flag} {v}"));
        }
    }
    if args.no_register {
        command.push_str(" --no-register");
    }
    super::check_output_folder(&args.output, &["compare.md".into(), "compare.html".into()])?;
    let c = crest::pipeline::compare::compare(&args.predicted, &args.measured, &opts)?;
    let files = crest::report::compare::outputs(&c, &command)
        .map_err(|e| miette!("cannot draw the comparison: {e}"))?;
    let written = crest::io::write_files(&args.output, &files)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write the comparison into {}", args.output.display()))?;
    if args.json {
        outln!("{}", crest::pipeline::compare::to_json(&c));
    } else {
        for (s, p) in &c.params {
            outln!(
                "{s:<4} predicted {:>12.5}  measured {:>12.5}  difference {:>+8.1} %",
                p.predicted,
                p.measured,
                p.diff_pct
            );
        }
        outln!(
            "feed direction: predicted {:.2}°, measured {:.2}°; shift ({:.3}, {:.3}) µm; correlation {:.4}; residual Sq {:.4} µm",
            c.feed_direction_deg[0],
            c.feed_direction_deg[1],
            c.shift_um[0],
            c.shift_um[1],
            c.correlation,
            c.residual_sq_um
        );
        for p in &written {
            outln!("wrote {}", p.display());
        }
    }
    if c.pass() {
        Ok(Outcome::Ok)
    } else {
        eprintln!(
            "crest compare: the verdict fails (tolerance ±{} %): {}",
            args.tolerance_pct,
            c.failing.join(", ")
        );
        Ok(Outcome::CheckFailed)
    }
}
