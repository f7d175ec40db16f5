//! `crest resample`: resample the cutting moves of a CLSF or contact12 file to even feed per
//! tooth (`--mode fz`) or a constant spindle step (`--mode dtheta`), written as CSV.
//!
//! The CSV is written while the path is resampled (one sample at a time, through
//! [`crate::io::write_atomic`]), so memory does not grow with the output. Columns:
//! `s_mm,t_s,theta_deg,x,y,z,i,j,k,cx,cy,cz,nx,ny,nz,fx,fy,fz,feed_mm_min`; the CC point
//! and normal are empty where the path has no contact data. Every tool path of the file
//! is resampled in turn (or only the one chosen with `--path`); s accumulates over the
//! cutting runs of a tool path, t and θ restart at every run.

use super::Outcome;
use crate::resample::{AxisInterpolation, Mode, Options, ResampleError, Sample, resample_with};
use std::path::PathBuf;

/// The CSV header, in column order.
pub const HEADER: &str = "s_mm,t_s,theta_deg,x,y,z,i,j,k,cx,cy,cz,nx,ny,nz,fx,fy,fz,feed_mm_min";

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
    /// Normalised linear interpolation (the model.md reference).
    Nlerp,
}

/// Options of `crest resample`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// CLSF or contact12 file.
    pub file: PathBuf,
    /// Spacing: `fz` (every fz of arc length) or `dtheta` (every Δθ of spindle angle).
    #[arg(long, value_enum)]
    pub mode: ModeArg,
    /// Nominal feed per tooth, mm.
    #[arg(long)]
    pub fz_mm: f64,
    /// Number of teeth Z.
    #[arg(long)]
    pub teeth: usize,
    /// Spindle step Δθ for `--mode dtheta`, degrees (model.md §5.3 suggests ≤ 0.5°).
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
    /// `crest feed`, kinematics.md; linear in time between postures, model.md §5.3).
    /// Default: `programmed`, or `predicted` when `--machine` is given.
    #[arg(long, value_enum, value_name = "SOURCE")]
    pub feed: Option<super::feed::FeedSource>,
    /// Machine description (`machine.toml`) for `--feed predicted` (given alone, it implies
    /// `--feed predicted`).
    #[arg(long, value_name = "MACHINE.toml", conflicts_with = "feed_mm_min")]
    pub machine: Option<PathBuf>,
    /// Tool-axis interpolation.
    #[arg(long, value_enum, default_value = "slerp")]
    pub axis: AxisArg,
    /// Interpolate positions on a cubic spline through the postures (smooth trochoids).
    #[arg(long)]
    pub spline: bool,
    /// Resample only this tool path (1-based, in file order).
    #[arg(long)]
    pub path: Option<usize>,
    /// Output CSV.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Print one JSON object with the counts on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Run `crest resample`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let program = super::input::read_program(&args.file)?;
    let mode = match args.mode {
        ModeArg::Fz => Mode::FeedPerTooth,
        ModeArg::Dtheta => Mode::SpindleStep {
            dtheta_rad: args.dtheta_deg.to_radians(),
        },
    };
    let mut opts = Options::new(mode, args.fz_mm, args.teeth)
        .with_axis_interpolation(match args.axis {
            AxisArg::Slerp => AxisInterpolation::Slerp,
            AxisArg::Nlerp => AxisInterpolation::Nlerp,
        })
        .with_spline(args.spline);
    opts.rpm = args.rpm;
    opts.feed_mm_min = args.feed_mm_min;

    let selected: Vec<usize> = match args.path {
        Some(n) if n >= 1 && n <= program.paths.len() => vec![n - 1],
        Some(n) => {
            return Err(miette::miette!(
                "{}: --path {n} is out of range: the file has {} tool path(s)",
                args.file.display(),
                program.paths.len()
            ));
        }
        None => (0..program.paths.len()).collect(),
    };

    let machine = super::feed::resolve_feed_source(args.feed, args.machine.as_deref())?;
    let mut path_opts = Vec::with_capacity(selected.len());
    for &idx in &selected {
        let mut o = opts.clone();
        if let Some(machine) = &machine {
            let path = &program.paths[idx];
            let feeds = crate::kinematics::predict_posture_feed(path, machine).map_err(|e| {
                miette::miette!(
                    "{}: tool path {}: feed prediction: {e}",
                    args.file.display(),
                    path.name
                )
            })?;
            o.posture_feed_mm_min = Some(feeds);
        }
        path_opts.push(o);
    }

    let mut failure: Option<(String, ResampleError)> = None;
    let mut per_path = Vec::new();
    let written = crate::io::write_atomic(&args.output, |w| {
        writeln!(w, "{HEADER}")?;
        let mut line = String::with_capacity(256);
        for (&idx, opts) in selected.iter().zip(&path_opts) {
            let path = &program.paths[idx];
            let mut io_error: Option<std::io::Error> = None;
            let result = resample_with(path, opts, |s| {
                if io_error.is_some() {
                    return;
                }
                line.clear();
                format_sample(&mut line, s);
                if let Err(e) = w.write_all(line.as_bytes()) {
                    io_error = Some(e);
                }
            });
            if let Some(e) = io_error {
                return Err(e);
            }
            match result {
                Ok(stats) => per_path.push((idx, stats)),
                Err(e) => {
                    failure = Some((path.name.clone(), e));
                    return Err(std::io::Error::other("resampling failed"));
                }
            }
        }
        Ok(())
    });
    if let Some((name, e)) = failure {
        return Err(miette::miette!(
            "{}: tool path {}: {e}",
            args.file.display(),
            if name.is_empty() { "(unnamed)" } else { &name }
        ));
    }
    written.map_err(|e| miette::miette!("{}: {e}", args.output.display()))?;

    let samples: u64 = per_path.iter().map(|(_, s)| s.samples).sum();
    let runs: usize = per_path.iter().map(|(_, s)| s.runs).sum();
    if args.json {
        let paths: Vec<_> = per_path
            .iter()
            .map(|(idx, stats)| {
                let p = &program.paths[*idx];
                serde_json::json!({
                    "index": idx + 1,
                    "name": p.name,
                    "tool": p.tool_name,
                    "postures": p.postures.len(),
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
            "machine": args.machine.as_ref().map(|m| m.display().to_string()),
            "feed": if machine.is_some() { "predicted" } else { "programmed" },
            "samples": samples,
            "runs": runs,
            "paths": paths,
        });
        println!("{out}");
    } else {
        println!(
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
    Ok(Outcome::Ok)
}

/// Append one CSV row (with the newline) for `s`.
fn format_sample(out: &mut String, s: &Sample) {
    use std::fmt::Write as _;
    let p = &s.position;
    let a = &s.axis;
    let f = &s.feed_dir;
    let _ = write!(
        out,
        "{:.6},{:.9},{:.6},{:.6},{:.6},{:.6},{:.9},{:.9},{:.9},",
        s.s_mm,
        s.t_s,
        s.theta_rad.to_degrees(),
        p.x,
        p.y,
        p.z,
        a.x,
        a.y,
        a.z
    );
    match &s.contact {
        Some(c) => {
            let _ = write!(out, "{:.6},{:.6},{:.6},", c.x, c.y, c.z);
        }
        None => out.push_str(",,,"),
    }
    match &s.normal {
        Some(n) => {
            let _ = write!(out, "{:.9},{:.9},{:.9},", n.x, n.y, n.z);
        }
        None => out.push_str(",,,"),
    }
    let _ = writeln!(out, "{:.9},{:.9},{:.9},{:.3}", f.x, f.y, f.z, s.feed_mm_min);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Point3, Vec3};

    #[test]
    fn row_has_every_column_and_empty_contact() {
        let s = Sample {
            run: 0,
            s_mm: 1.5,
            t_s: 0.25,
            theta_rad: std::f64::consts::PI,
            position: Point3::new(1.0, 2.0, 3.0),
            axis: Vec3::z(),
            contact: None,
            normal: None,
            feed_dir: Vec3::x(),
            feed_mm_min: 1000.0,
        };
        let mut row = String::new();
        format_sample(&mut row, &s);
        assert_eq!(
            row,
            "1.500000,0.250000000,180.000000,1.000000,2.000000,3.000000,\
             0.000000000,0.000000000,1.000000000,,,,,,,1.000000000,0.000000000,0.000000000,1000.000\n"
        );
        assert_eq!(row.split(',').count(), HEADER.split(',').count());
    }
}
