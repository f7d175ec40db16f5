//! `crest resample`: the arguments of resampling the cutting moves of a CLSF, contact12 or
//! G-code file to even feed per tooth (`--mode fz`) or a constant spindle step (`--mode
//! dtheta`), and the printed counts; the work is [`crest::pipeline::resample`], the CSV
//! (`s_mm,t_s,theta_deg,x,y,z,i,j,k,cx,cy,cz,nx,ny,nz,fx,fy,fz,feed_mm_min`; the CC point
//! and normal empty where the path has no contact data) [`crest::io::samples`].

use super::Outcome;
use crest::pipeline::resample::{PathReport, ResampleRequest, resample_to_csv};
use crest::resample::{AxisInterpolation, Mode, Options};
use std::path::PathBuf;

/// Spacing mode on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ModeArg {
    /// A sample every fz of arc length (instantaneous tool positions).
    Fz,
    /// A sample every Δθ of spindle angle (cutting-edge trochoids).
    Dtheta,
}

/// Tool-axis interpolation on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AxisArg {
    /// Spherical linear interpolation.
    Slerp,
    /// Normalised linear interpolation of the axis.
    Nlerp,
}

/// Options of `crest resample`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// CLSF, contact12 or G-code file (detected by content).
    pub file: PathBuf,
    /// Spacing: `fz` (every fz of arc length) or `dtheta` (every Δθ of spindle angle).
    #[arg(long, value_enum)]
    pub mode: ModeArg,
    /// Nominal feed per tooth, mm. Required by `--mode fz`; with `--mode dtheta` it only
    /// derives the spindle speed from the feed (without it: `--rpm` or the file's SPINDL).
    #[arg(long)]
    pub fz_mm: Option<f64>,
    /// Number of teeth Z (required with --fz-mm).
    #[arg(long)]
    pub teeth: Option<usize>,
    /// Spindle step Δθ for `--mode dtheta`, degrees (0.5° or less resolves the edges' sweep).
    #[arg(long, default_value_t = 0.5)]
    pub dtheta_deg: f64,
    /// Spindle speed, rpm. Default: derived from fz and the programmed feed
    /// (n = V/(Z·fz)), or the file's SPINDL when it has no feed.
    #[arg(long)]
    pub rpm: Option<f64>,
    /// Constant feed, mm/min, overriding the file's FEDRAT.
    #[arg(long)]
    pub feed_mm_min: Option<f64>,
    /// Which feed drives the clock and the spacing: `programmed` (FEDRAT or
    /// `--feed-mm-min`) or `predicted` (the feed the machine of `--machine` really reaches,
    /// `crest feed`; linear in time between postures).
    /// Default: `programmed`, or `predicted` when `--machine` is given.
    #[arg(long, value_enum, value_name = "SOURCE")]
    pub feed: Option<crest::pipeline::simulate::FeedSource>,
    /// Machine description (`machine.toml`) for `--feed predicted` (given alone with a
    /// CLSF or contact12 file, it implies `--feed predicted`); G-code is read through its
    /// kinematics (the feed is then predicted only with `--feed predicted`).
    #[arg(long, value_name = "MACHINE.toml")]
    pub machine: Option<PathBuf>,
    /// Tool-centre-point control of G-code input: `auto` (as the program says), `on` or
    /// `off`.
    #[arg(long, value_enum, default_value = "auto")]
    pub rtcp: crest::nc::Rtcp,
    /// Tool-axis interpolation.
    #[arg(long, value_enum, default_value = "slerp")]
    pub axis: AxisArg,
    /// Interpolate positions on a cubic spline through the postures (smooth trochoids).
    #[arg(long)]
    pub spline: bool,
    /// Resample only this tool path (1-based, in file order).
    #[arg(long)]
    pub path: Option<usize>,
    /// Which moves are resampled: `cut` (default: the cutting passes) or `all` (every feed
    /// move, engage and retract too).
    #[arg(long, value_enum, default_value = "cut")]
    pub moves: crest::toolpath::Moves,
    /// Output CSV.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Refuse to start when the output is estimated beyond this many GB (see --force).
    #[arg(long, value_name = "GB", default_value_t = 1.0)]
    pub max_output_gb: f64,
    /// Write however large the estimated output is.
    #[arg(long)]
    pub force: bool,
    /// Print one JSON object with the counts on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Run `crest resample`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    super::check_outputs([args.output.as_path()])?;
    let req = ResampleRequest {
        file: args.file.clone(),
        mode: match args.mode {
            ModeArg::Fz => Mode::FeedPerTooth,
            ModeArg::Dtheta => Mode::SpindleStep {
                dtheta_rad: args.dtheta_deg.to_radians(),
            },
        },
        fz_mm: args.fz_mm,
        teeth: args.teeth,
        rpm: args.rpm,
        feed_mm_min: args.feed_mm_min,
        feed: args.feed,
        machine: args.machine.clone(),
        rtcp: args.rtcp,
        axis: match args.axis {
            AxisArg::Slerp => AxisInterpolation::Slerp,
            AxisArg::Nlerp => AxisInterpolation::Nlerp,
        },
        spline: args.spline,
        path: args.path,
        moves: args.moves,
    };
    let run = resample_to_csv(&req, &args.output, args.max_output_gb, args.force)?;
    report(&args, &run.options, &run.paths, run.predicted)?;
    Ok(Outcome::Ok)
}

fn report(
    args: &Args,
    opts: &Options,
    per_path: &[PathReport],
    predicted: bool,
) -> miette::Result<()> {
    let samples: u64 = per_path.iter().map(|p| p.stats.samples).sum();
    let runs: usize = per_path.iter().map(|p| p.stats.runs).sum();
    if args.json {
        let paths: Vec<_> = per_path
            .iter()
            .map(|p| {
                let mut stats = serde_json::to_value(&p.stats).unwrap_or_default();
                if args.teeth.is_none() {
                    // Without the tooth count there is no feed per tooth to report.
                    stats["fz_min_mm"] = serde_json::Value::Null;
                    stats["fz_max_mm"] = serde_json::Value::Null;
                }
                serde_json::json!({
                    "index": p.index + 1,
                    "name": p.name,
                    "tool": p.tool,
                    "postures": p.postures,
                    "moves": super::reading::counts_json(&p.moves),
                    "stats": stats,
                })
            })
            .collect();
        let out = serde_json::json!({
            "file": args.file.display().to_string(),
            "output": args.output.display().to_string(),
            "mode": match args.mode { ModeArg::Fz => "fz", ModeArg::Dtheta => "dtheta" },
            "fz_mm": args.fz_mm,
            "teeth": args.teeth,
            "dtheta_deg": matches!(args.mode, ModeArg::Dtheta).then_some(args.dtheta_deg),
            "step_mm": opts.nominal_step_mm(),
            "moves_resampled": args.moves.name(),
            "machine": args.machine.as_ref().map(|m| m.display().to_string()),
            "feed": if predicted { "predicted" } else { "programmed" },
            "samples": samples,
            "runs": runs,
            "paths": paths,
        });
        outln!("{out}");
    } else {
        outln!(
            "{}: {samples} samples in {runs} cutting run(s) of {} tool path(s)",
            args.output.display(),
            per_path.len()
        );
        if samples == 0 {
            eprintln!(
                "warning: {} has no cutting moves; only the header was written",
                args.file.display()
            );
        }
    }
    Ok(())
}
