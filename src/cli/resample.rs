//! `crest resample`: resample the cutting moves of a CLSF, contact12 or G-code file to even feed per
//! tooth (`--mode fz`) or a constant spindle step (`--mode dtheta`), written as CSV.
//!
//! The CSV is written while the path is resampled (one sample at a time, through
//! [`crest::io::write_atomic`]), so memory does not grow with the output. Columns:
//! `s_mm,t_s,theta_deg,x,y,z,i,j,k,cx,cy,cz,nx,ny,nz,fx,fy,fz,feed_mm_min`; the CC point
//! and normal are empty where the path has no contact data. Every tool path of the file
//! is resampled in turn (or only the one chosen with `--path`); s accumulates over the
//! cutting runs of a tool path, t and θ restart at every run.

use super::Outcome;
use super::reading::{feed_machine, read_options};
use crest::io::toolpath::{InputKind, ReadOptions, detect, stream_from};
use crest::resample::{
    AxisInterpolation, Mode, Options, ResampleError, Resampler, Sample, SpindleScan, SpindleSource,
    Stats, resample_with,
};
use crest::toolpath::write::push_decimals;
use crest::toolpath::{LowerOptions, Posture, Program, Toolpath};
use std::io::Write;
use std::path::{Path, PathBuf};

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
    pub feed: Option<super::feed::FeedSource>,
    /// Machine description (`machine.toml`) for `--feed predicted` (given alone with a
    /// CLSF or contact12 file, it implies `--feed predicted`); G-code is read through its
    /// kinematics (the feed is then predicted only with `--feed predicted`).
    #[arg(long, value_name = "MACHINE.toml")]
    pub machine: Option<PathBuf>,
    /// Tool-centre-point control of G-code input: `auto` (as the program says), `on` or
    /// `off`.
    #[arg(long, value_enum, default_value = "auto")]
    pub rtcp: super::reading::RtcpArg,
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
    pub moves: super::reading::MovesArg,
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
    let mode = match args.mode {
        ModeArg::Fz => Mode::FeedPerTooth,
        ModeArg::Dtheta => Mode::SpindleStep {
            dtheta_rad: args.dtheta_deg.to_radians(),
        },
    };
    // Feed per tooth and teeth: needed for the fz spacing; for Δθ only to derive the
    // spindle speed from the feed, which otherwise comes from --rpm or the file's SPINDL.
    let (fz_mm, teeth, spindle_from_path) = match (args.mode, args.fz_mm, args.teeth) {
        (_, Some(f), Some(z)) => (f, z, false),
        (ModeArg::Dtheta, None, None) => (1.0, 1, args.rpm.is_none()),
        (ModeArg::Fz, _, _) => {
            return Err(miette::miette!(
                "--mode fz spaces the samples every feed per tooth: give --fz-mm and --teeth"
            ));
        }
        (ModeArg::Dtheta, _, _) => {
            return Err(miette::miette!(
                "--fz-mm and --teeth go together (they derive the spindle speed from the feed); give both, or neither to take --rpm or the file's SPINDL"
            ));
        }
    };
    let mut opts = Options::new(mode, fz_mm, teeth)
        .with_axis_interpolation(match args.axis {
            AxisArg::Slerp => AxisInterpolation::Slerp,
            AxisArg::Nlerp => AxisInterpolation::Nlerp,
        })
        .with_spline(args.spline);
    opts.rpm = args.rpm;
    opts.feed_mm_min = args.feed_mm_min;
    opts.spindle_from_path = spindle_from_path;

    let kind = detect(&args.file)?;
    let gcode = kind == InputKind::Gcode;
    if !gcode && args.machine.is_some() && args.feed_mm_min.is_some() {
        return Err(miette::miette!(
            "--machine (the predicted feed) cannot be used with --feed-mm-min"
        ));
    }
    let read = read_options(
        kind,
        LowerOptions::default(),
        args.machine.as_deref(),
        args.rtcp,
    )?;
    // The predicted feed needs the whole path (`--feed predicted`, or `--machine` with a
    // CLSF or contact12 file, and the invalid combinations, reported there as before): in
    // memory. Otherwise the file is read, resampled and written posture by posture.
    // Invalid options first, then the budget: estimate the samples (one pass over the file)
    // before any work.
    Resampler::new(&opts).map_err(|e| miette::miette!("{}: {e}", args.file.display()))?;
    if !(args.max_output_gb.is_finite() && args.max_output_gb > 0.0) {
        return Err(miette::miette!(
            "--max-output-gb must be positive, got {}",
            args.max_output_gb
        ));
    }
    let extent = crest::pipeline::inputs::path_extent(
        &args.file,
        read.clone(),
        args.path.map(|n| n.saturating_sub(1)),
        args.moves.into(),
    )?;
    let rpm = args.rpm.or(if spindle_from_path {
        extent.spindle_rpm
    } else {
        None
    });
    let samples = crest::resample::estimate_samples(&extent, mode, fz_mm, teeth, rpm);
    crest::pipeline::inputs::check_output_budget(
        &format!(
            "{}: resampling {:.1} mm of cutting moves into about {samples:.3e} samples",
            args.file.display(),
            extent.cutting_mm
        ),
        samples * crest::pipeline::inputs::RESAMPLE_ROW_BYTES,
        args.max_output_gb,
        args.force,
    )?;
    let predicted = matches!(args.feed, Some(super::feed::FeedSource::Predicted));
    let in_memory = predicted || (!gcode && args.machine.is_some());
    let (per_path, predicted) = if in_memory {
        resample_in_memory(&args, &opts, kind, &read)?
    } else {
        (resample_streaming(&args, &opts, &read)?, false)
    };
    report(&args, &opts, &per_path, predicted)?;
    Ok(Outcome::Ok)
}

/// What was done to one tool path: 0-based index in the file, name, tool, postures, counts.
struct PathReport {
    index: usize,
    name: String,
    tool: String,
    postures: usize,
    /// Postures per move kind, as the file gives them.
    moves: crest::toolpath::MoveCounts,
    stats: Stats,
}

/// Resample with the whole file in memory (needed for the predicted feed).
/// Returns the reports and whether the feed was predicted.
fn resample_in_memory(
    args: &Args,
    opts: &Options,
    kind: InputKind,
    read: &ReadOptions,
) -> miette::Result<(Vec<PathReport>, bool)> {
    let mut program = crest::io::toolpath::read_program_with(&args.file, read.clone())?;
    crest::toolpath::Moves::from(args.moves).apply(&mut program);
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

    let machine = feed_machine(kind, read, args.feed, args.machine.as_deref())?;
    let mut path_opts = Vec::with_capacity(selected.len());
    for &idx in &selected {
        let mut o = opts.clone();
        if let Some(machine) = &machine {
            let path = &program.paths[idx];
            let feeds = crest::kinematics::predict_posture_feed(path, machine).map_err(|e| {
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
    let written = crest::io::write_atomic(&args.output, |w| {
        let mut out = CsvOut::new(w);
        out.header()?;
        for (&idx, opts) in selected.iter().zip(&path_opts) {
            let path = &program.paths[idx];
            let result = resample_with(path, opts, |s| out.sample(s));
            out.check()?;
            match result {
                Ok(stats) => per_path.push(PathReport {
                    index: idx,
                    name: path.name.clone(),
                    tool: path.tool_name.clone(),
                    postures: path.postures.len(),
                    moves: path.stats.moves,
                    stats,
                }),
                Err(e) => {
                    failure = Some((path.name.clone(), e));
                    return Err(std::io::Error::other("resampling failed"));
                }
            }
        }
        out.flush()
    });
    if let Some((name, e)) = failure {
        return Err(path_error(&args.file, &name, e));
    }
    written.map_err(|e| miette::miette!("{}: {e}", args.output.display()))?;
    Ok((per_path, machine.is_some()))
}

/// The spindle speed of every streamed tool path (in order), when known beforehand.
type Spindles = Vec<Result<Option<(f64, SpindleSource)>, ResampleError>>;

/// One streaming pass: which tool path to resample (`target`, among the tool paths that
/// have postures, in file order; `None` = all) and the spindle speeds found by an earlier
/// pass (`None` = resolve each at its first cutting move).
struct Pass<'a> {
    target: Option<Option<usize>>,
    spindles: Option<&'a Spindles>,
}

/// What a pass found out.
enum PassResult {
    Done(Vec<PathReport>),
    /// Resample again: the tool path to resample (same meaning as [`Pass::target`]) and
    /// the spindle speeds of the whole paths.
    Again(Option<Option<usize>>, Option<Spindles>),
}

/// The tool path being streamed.
struct Current {
    ordinal: usize,
    resampler: Option<Resampler>,
    /// A scan of the whole path, when its spindle speed is resolved lazily.
    scan: Option<SpindleScan>,
    /// An error met while the spindle speed was provisional.
    lazy_error: Option<ResampleError>,
}

/// Resample while reading: the file is lowered posture by posture and every posture goes
/// straight to a [`Resampler`]; memory does not depend on the path length.
///
/// The spindle speed derived from the feed uses the highest feed of the whole path; it is
/// taken at the first cutting move and checked against a scan of the whole path at the
/// end. In the rare case they differ (a later cutting move faster than the first), or when
/// `--path` has to skip tool paths without postures, the file is resampled again with what
/// the first pass found; the output is replaced only when everything succeeded.
fn resample_streaming(
    args: &Args,
    opts: &Options,
    read: &ReadOptions,
) -> miette::Result<Vec<PathReport>> {
    // Invalid options are reported before anything is read.
    Resampler::new(opts).map_err(|e| miette::miette!("{}: {e}", args.file.display()))?;
    let first = Pass {
        target: args.path.map(|n| Some(n.saturating_sub(1))),
        spindles: None,
    };
    match stream_pass(args, opts, read, &first)? {
        PassResult::Done(reports) => Ok(reports),
        PassResult::Again(target, spindles) => {
            let again = Pass {
                target,
                spindles: spindles.as_ref(),
            };
            match stream_pass(args, opts, read, &again)? {
                PassResult::Done(reports) => Ok(reports),
                PassResult::Again(..) => Err(miette::miette!(
                    "{}: resampling did not settle (internal error)",
                    args.file.display()
                )),
            }
        }
    }
}

fn stream_pass(
    args: &Args,
    opts: &Options,
    read: &ReadOptions,
    pass: &Pass<'_>,
) -> miette::Result<PassResult> {
    let file = &args.file;
    let moves = crest::toolpath::Moves::from(args.moves);
    let (kind, reader) = crest::io::toolpath::open_detected(file)?;
    let lower = ReadOptions {
        lower: LowerOptions {
            keep_postures: false,
            ..read.lower.clone()
        },
        ..read.clone()
    };
    let lazy = pass.spindles.is_none() && opts.rpm.is_none();
    let selected = |ordinal: usize| match pass.target {
        None => true,
        Some(t) => t == Some(ordinal),
    };

    let mut failure: Option<miette::Report> = None;
    let mut outcome: Option<PassResult> = None;
    let written = crest::io::write_atomic(&args.output, |w| {
        let mut out = CsvOut::new(w);
        out.header()?;
        let mut current: Option<Current> = None;
        let mut finished: Vec<(usize, Option<Stats>, Option<SpindleScan>, bool)> = Vec::new();
        let mut count = 0usize;
        // Finish the current tool path: its last samples, its counts.
        let finish = |cur: Current,
                      out: &mut CsvOut<'_>,
                      finished: &mut Vec<(usize, Option<Stats>, Option<SpindleScan>, bool)>|
         -> Result<(), ResampleError> {
            let mut stats = None;
            let mut redo = cur.lazy_error.is_some();
            if let (Some(r), None) = (cur.resampler, &cur.lazy_error) {
                match r.finish(|s| out.sample(s)) {
                    Ok(s) => stats = Some(s),
                    Err(e) if lazy => {
                        let _ = e;
                        redo = true;
                    }
                    Err(e) => return Err(e),
                }
            }
            finished.push((cur.ordinal, stats, cur.scan, redo));
            Ok(())
        };
        let mut error: Option<(String, ResampleError)> = None;
        let mut sink = |path: &Toolpath, p: &Posture| -> std::io::Result<()> {
            if path.stats.postures == 1 {
                if let Some(cur) = current.take()
                    && let Err(e) = finish(cur, &mut out, &mut finished)
                {
                    error = Some((path.name.clone(), e));
                    return Err(std::io::Error::other("resampling failed"));
                }
                let ordinal = count;
                count += 1;
                let mut resampler = None;
                if selected(ordinal) {
                    let mut r = Resampler::new(opts).map_err(std::io::Error::other)?;
                    if let Some(spindles) = pass.spindles {
                        match spindles.get(ordinal) {
                            Some(Ok(Some((rpm, source)))) => r = r.with_spindle(*rpm, *source),
                            Some(Err(e)) => {
                                error = Some((path.name.clone(), e.clone()));
                                return Err(std::io::Error::other("resampling failed"));
                            }
                            _ => {}
                        }
                    }
                    resampler = Some(r);
                }
                current = Some(Current {
                    ordinal,
                    resampler,
                    scan: lazy.then(SpindleScan::new),
                    lazy_error: None,
                });
            }
            let Some(cur) = current.as_mut() else {
                return Ok(());
            };
            // `--moves all`: every feed move is resampled as a cut move.
            let relabelled;
            let p = if moves.cuts(p.motion) && p.motion != crest::toolpath::MotionKind::Cut {
                let mut q = p.clone();
                moves.relabel(&mut q);
                relabelled = q;
                &relabelled
            } else {
                p
            };
            if let Some(scan) = cur.scan.as_mut() {
                scan.push(p);
            }
            if cur.lazy_error.is_none()
                && let Some(r) = cur.resampler.as_mut()
                && let Err(e) = r.push(p, |s| out.sample(s))
            {
                if lazy {
                    cur.lazy_error = Some(e);
                } else {
                    error = Some((path.name.clone(), e));
                    return Err(std::io::Error::other("resampling failed"));
                }
            }
            out.check()
        };
        let streamed = stream_from(file, kind, reader, lower, &mut sink);
        let program: Program = match streamed {
            Ok(p) => p,
            Err(e) => {
                failure = Some(match error.take() {
                    Some((name, e)) => path_error(file, &name, e),
                    None => e,
                });
                return Err(std::io::Error::other("resampling failed"));
            }
        };
        if let Some(cur) = current.take()
            && let Err(e) = finish(cur, &mut out, &mut finished)
        {
            let name = program
                .paths
                .iter()
                .filter(|p| p.stats.postures > 0)
                .nth(count.saturating_sub(1))
                .map(|p| p.name.clone())
                .unwrap_or_default();
            failure = Some(path_error(file, &name, e));
            return Err(std::io::Error::other("resampling failed"));
        }
        out.flush()?;

        // Which tool paths were streamed (those with postures), by ordinal.
        let streamed_paths: Vec<usize> = (0..program.paths.len())
            .filter(|&i| program.paths[i].stats.postures > 0)
            .collect();
        let wanted: Vec<usize> = match args.path {
            Some(n) if n >= 1 && n <= program.paths.len() => vec![n - 1],
            Some(n) => {
                failure = Some(miette::miette!(
                    "{}: --path {n} is out of range: the file has {} tool path(s)",
                    file.display(),
                    program.paths.len()
                ));
                return Err(std::io::Error::other("bad --path"));
            }
            None => (0..program.paths.len()).collect(),
        };
        let target = args
            .path
            .map(|n| streamed_paths.iter().position(|&i| i == n - 1));
        let spindles = || -> Option<Spindles> {
            let scans: Spindles = finished
                .iter()
                .map(|(_, _, scan, _)| match scan {
                    Some(scan) => scan.resolve(opts),
                    None => Ok(None),
                })
                .collect();
            lazy.then_some(scans)
        };
        if target != pass.target {
            outcome = Some(PassResult::Again(target, spindles()));
            return Err(std::io::Error::other("again"));
        }
        if lazy {
            let settled = finished.iter().all(|(_, stats, scan, redo)| {
                let Some(stats) = stats else {
                    return !redo;
                };
                let used = stats.spindle_rpm.zip(stats.spindle_source);
                match scan.as_ref().map(|s| s.resolve(opts)) {
                    Some(Ok(resolved)) => resolved == used,
                    Some(Err(_)) => false,
                    None => true,
                }
            });
            if !settled {
                outcome = Some(PassResult::Again(target, spindles()));
                return Err(std::io::Error::other("again"));
            }
        }
        let mut reports = Vec::new();
        for idx in wanted {
            let p = &program.paths[idx];
            let stats = streamed_paths
                .iter()
                .position(|&i| i == idx)
                .and_then(|ordinal| finished.iter().find(|f| f.0 == ordinal))
                .and_then(|f| f.1.clone());
            let stats = match stats {
                Some(s) => s,
                // A tool path without postures: nothing resampled.
                None => Resampler::new(opts)
                    .and_then(|r| r.finish(|_| {}))
                    .map_err(std::io::Error::other)?,
            };
            reports.push(PathReport {
                index: idx,
                name: p.name.clone(),
                tool: p.tool_name.clone(),
                postures: p.stats.postures,
                moves: p.stats.moves,
                stats,
            });
        }
        outcome = Some(PassResult::Done(reports));
        Ok(())
    });
    if let Some(e) = failure {
        return Err(crest::io::toolpath::name_output(e, &args.output));
    }
    match (written, outcome) {
        (Ok(()), Some(done @ PassResult::Done(_))) => Ok(done),
        (Err(_), Some(again @ PassResult::Again(..))) => Ok(again),
        (Err(e), _) => Err(miette::miette!("{}: {e}", args.output.display())),
        (Ok(()), _) => Err(miette::miette!(
            "{}: resampling did not finish (internal error)",
            file.display()
        )),
    }
}

fn path_error(file: &Path, name: &str, e: ResampleError) -> miette::Report {
    miette::miette!(
        "{}: tool path {}: {e}",
        file.display(),
        if name.is_empty() { "(unnamed)" } else { name }
    )
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
            "moves_resampled": crest::toolpath::Moves::from(args.moves).name(),
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

/// The CSV sink: rows are formatted into a buffer that goes to the output in 64 KiB
/// blocks; the first write error is kept and reported by [`CsvOut::check`].
struct CsvOut<'w> {
    w: &'w mut dyn Write,
    buf: Vec<u8>,
    error: Option<std::io::Error>,
}

impl<'w> CsvOut<'w> {
    const BLOCK: usize = 1 << 16;

    fn new(w: &'w mut dyn Write) -> CsvOut<'w> {
        CsvOut {
            w,
            buf: Vec::with_capacity(Self::BLOCK + 512),
            error: None,
        }
    }

    fn header(&mut self) -> std::io::Result<()> {
        self.buf.extend_from_slice(HEADER.as_bytes());
        self.buf.push(b'\n');
        Ok(())
    }

    fn sample(&mut self, s: &Sample) {
        if self.error.is_some() {
            return;
        }
        format_sample(&mut self.buf, s);
        if self.buf.len() >= Self::BLOCK {
            if let Err(e) = self.w.write_all(&self.buf) {
                self.error = Some(e);
            }
            self.buf.clear();
        }
    }

    /// The first write error, if any.
    fn check(&mut self) -> std::io::Result<()> {
        match self.error.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.check()?;
        self.w.write_all(&self.buf)?;
        self.buf.clear();
        Ok(())
    }
}

/// Decimals of the columns: lengths and angles 6, time and unit vectors 9, feed 3.
const LEN: u32 = 6;
const UNIT: u32 = 9;

/// Append one CSV row (with the newline) for `s`: the digits of `{:.6}` (lengths, θ),
/// `{:.9}` (t, unit vectors) and `{:.3}` (feed).
fn format_sample(out: &mut Vec<u8>, s: &Sample) {
    let p = &s.position;
    let a = &s.axis;
    let f = &s.feed_dir;
    fn num(out: &mut Vec<u8>, v: f64, dec: u32) {
        push_decimals(out, v, dec);
        out.push(b',');
    }
    num(out, s.s_mm, LEN);
    // No feed known (feed-per-tooth spacing of a path without feed or spindle speed): the
    // time and the feed are left empty.
    if s.t_s.is_nan() {
        out.push(b',');
    } else {
        num(out, s.t_s, UNIT);
    }
    num(out, s.theta_rad.to_degrees(), LEN);
    num(out, p.x, LEN);
    num(out, p.y, LEN);
    num(out, p.z, LEN);
    num(out, a.x, UNIT);
    num(out, a.y, UNIT);
    num(out, a.z, UNIT);
    match &s.contact {
        Some(c) => {
            num(out, c.x, LEN);
            num(out, c.y, LEN);
            num(out, c.z, LEN);
        }
        None => out.extend_from_slice(b",,,"),
    }
    match &s.normal {
        Some(n) => {
            num(out, n.x, UNIT);
            num(out, n.y, UNIT);
            num(out, n.z, UNIT);
        }
        None => out.extend_from_slice(b",,,"),
    }
    num(out, f.x, UNIT);
    num(out, f.y, UNIT);
    num(out, f.z, UNIT);
    if !s.feed_mm_min.is_nan() {
        push_decimals(out, s.feed_mm_min, 3);
    }
    out.push(b'\n');
}

#[cfg(test)]
mod tests {
    use super::*;
    use crest::math::{Point3, Vec3};

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
        let mut row = Vec::new();
        format_sample(&mut row, &s);
        let row = String::from_utf8(row).unwrap();
        assert_eq!(
            row,
            "1.500000,0.250000000,180.000000,1.000000,2.000000,3.000000,\
             0.000000000,0.000000000,1.000000000,,,,,,,1.000000000,0.000000000,0.000000000,1000.000\n"
        );
        assert_eq!(row.split(',').count(), HEADER.split(',').count());
    }
}
