//! `crest resample` (and Python's `crest.resample`): the cutting moves of a CLSF, contact12
//! or G-code file resampled to even feed per tooth or a constant spindle step, either into
//! a sink in memory ([`resample_each`]: needed for the predicted feed, which plans whole
//! paths) or streamed from the file to a CSV ([`resample_to_csv`]: memory does not depend
//! on the path length). s accumulates over the cutting runs of a tool path, t and θ restart
//! at every run.

use super::inputs::select_paths;
use super::simulate::{FeedSource, resolve_feed_source};
use crate::io::samples::SampleCsv;
use crate::io::toolpath::{InputKind, ReadOptions, detect, stream_from};
use crate::kinematics::Machine;
use crate::pipeline::{Error, Result};
use crate::resample::{
    AxisInterpolation, Mode, Options, ResampleError, Resampler, Sample, SpindleScan, SpindleSource,
    Stats, resample_with,
};
use crate::toolpath::{LowerOptions, MoveCounts, Moves, Posture, Program, Toolpath};
use std::path::{Path, PathBuf};

/// Everything `crest resample` is asked but where the output goes.
#[derive(Debug, Clone, PartialEq)]
pub struct ResampleRequest {
    /// Tool-path file (detected by content).
    pub file: PathBuf,
    /// Spacing: every fz of arc length, or every Δθ of spindle angle.
    pub mode: Mode,
    /// Nominal feed per tooth, mm (needed by the fz spacing; with Δθ it only derives the
    /// spindle speed from the feed).
    pub fz_mm: Option<f64>,
    /// Number of teeth (with `fz_mm`).
    pub teeth: Option<usize>,
    /// Spindle speed, rpm.
    pub rpm: Option<f64>,
    /// Constant feed, mm/min, overriding the file's.
    pub feed_mm_min: Option<f64>,
    /// Programmed or predicted feed.
    pub feed: Option<FeedSource>,
    /// Machine for the predicted feed (and to read G-code through).
    pub machine: Option<PathBuf>,
    /// Tool-centre-point control of G-code input.
    pub rtcp: crate::nc::Rtcp,
    /// Tool-axis interpolation.
    pub axis: AxisInterpolation,
    /// Positions on a cubic spline through the postures.
    pub spline: bool,
    /// Only this tool path (1-based).
    pub path: Option<usize>,
    /// Which moves are resampled.
    pub moves: Moves,
}

/// What was done to one tool path: 0-based index in the file, name, tool, postures, counts.
#[derive(Debug, Clone)]
pub struct PathReport {
    /// Index in the file, 0-based.
    pub index: usize,
    /// Name.
    pub name: String,
    /// Tool name.
    pub tool: String,
    /// Postures.
    pub postures: usize,
    /// Postures per move kind, as the file gives them.
    pub moves: MoveCounts,
    /// The resampling's counts.
    pub stats: Stats,
}

/// A finished resampling.
#[derive(Debug, Clone)]
pub struct ResampleRun {
    /// One report per tool path resampled.
    pub paths: Vec<PathReport>,
    /// Whether the feed was predicted on a machine.
    pub predicted: bool,
    /// The options used.
    pub options: Options,
}

/// The resampling options of `req` (checked): the feed per tooth and teeth are needed for
/// the fz spacing; for Δθ only to derive the spindle speed from the feed, which otherwise
/// comes from `rpm` or the file's SPINDL.
pub fn options(req: &ResampleRequest) -> Result<Options> {
    let dtheta = matches!(req.mode, Mode::SpindleStep { .. });
    let (fz_mm, teeth, spindle_from_path) = match (dtheta, req.fz_mm, req.teeth) {
        (_, Some(f), Some(z)) => (f, z, false),
        (true, None, None) => (1.0, 1, req.rpm.is_none()),
        (false, _, _) => {
            return Err(Error::Request(
                "‹mode› fz spaces the samples every feed per tooth: give ‹fz_mm› and ‹teeth›"
                    .into(),
            ));
        }
        (true, _, _) => {
            return Err(Error::Request("‹fz_mm› and ‹teeth› go together (they derive the spindle speed from the feed); give both, or neither to take ‹rpm› or the file's SPINDL".into()));
        }
    };
    let mut opts = Options::new(req.mode, fz_mm, teeth)
        .with_axis_interpolation(req.axis)
        .with_spline(req.spline);
    opts.rpm = req.rpm;
    opts.feed_mm_min = req.feed_mm_min;
    opts.spindle_from_path = spindle_from_path;
    // Invalid options are reported before anything is read.
    Resampler::new(&opts).map_err(|e| Error::within(req.file.display(), e))?;
    Ok(opts)
}

/// How the file is read: the machine (for G-code) and whether the feed is planned on it,
/// which needs the whole path in memory.
fn reading(req: &ResampleRequest) -> Result<(InputKind, ReadOptions, bool)> {
    let kind = detect(&req.file)?;
    let gcode = kind == InputKind::Gcode;
    if !gcode && req.machine.is_some() && req.feed_mm_min.is_some() {
        return Err(Error::Request(
            "‹machine› (the predicted feed) cannot be used with ‹feed_mm_min›".into(),
        ));
    }
    let machine = match (gcode, &req.machine) {
        (true, Some(m)) => Some(super::load_machine(m)?),
        _ => None,
    };
    let read = ReadOptions {
        lower: LowerOptions::default(),
        machine,
        rtcp: req.rtcp,
    };
    let in_memory = req.feed == Some(FeedSource::Predicted) || (!gcode && req.machine.is_some());
    Ok((kind, read, in_memory))
}

/// The machine to predict the feed on: for G-code the machine reads the file, and plans
/// the feed only when asked; for CLSF and contact12 a machine means the predicted feed
/// ([`resolve_feed_source`]).
fn feed_machine(
    req: &ResampleRequest,
    kind: InputKind,
    read: &ReadOptions,
) -> Result<Option<Machine>> {
    if kind == InputKind::Gcode {
        return Ok(match req.feed {
            Some(FeedSource::Predicted) => read.machine.clone(),
            _ => None,
        });
    }
    resolve_feed_source(req.feed, req.machine.as_deref())
}

/// Resample the selected tool paths of `req` with the whole file in memory, handing each
/// sample to `sink` with its tool path's index (0-based).
pub fn resample_each(
    req: &ResampleRequest,
    sink: impl FnMut(usize, &Sample),
) -> Result<ResampleRun> {
    let opts = options(req)?;
    let (kind, read, _) = reading(req)?;
    resample_read(req, opts, kind, &read, sink)
}

/// [`resample_each`] with the options checked and the reading resolved.
fn resample_read(
    req: &ResampleRequest,
    opts: Options,
    kind: InputKind,
    read: &ReadOptions,
    mut sink: impl FnMut(usize, &Sample),
) -> Result<ResampleRun> {
    let mut program = crate::io::toolpath::read_program_with(&req.file, read.clone())?;
    req.moves.apply(&mut program);
    let selected = select_paths(&req.file, req.path, program.paths.len())?;
    let machine = feed_machine(req, kind, read)?;
    let mut paths = Vec::with_capacity(selected.len());
    for &idx in &selected {
        let path = &program.paths[idx];
        let mut o = opts.clone();
        if let Some(machine) = &machine {
            let feeds = crate::kinematics::predict_posture_feed(path, machine).map_err(|e| {
                Error::within(
                    format_args!(
                        "{}: tool path {}: feed prediction",
                        req.file.display(),
                        path.name
                    ),
                    e,
                )
            })?;
            o.posture_feed_mm_min = Some(feeds);
        }
        let stats = resample_with(path, &o, |s| sink(idx, s))
            .map_err(|e| path_error(&req.file, &path.name, e))?;
        paths.push(PathReport {
            index: idx,
            name: path.name.clone(),
            tool: path.tool_name.clone(),
            postures: path.postures.len(),
            moves: path.stats.moves,
            stats,
        });
    }
    Ok(ResampleRun {
        paths,
        predicted: machine.is_some(),
        options: opts,
    })
}

/// `crest resample`: resample `req` into the CSV `output` ([`crate::io::samples`]), refused
/// beyond `max_output_gb` of estimated output unless `force`. The output is replaced only
/// when everything succeeded.
pub fn resample_to_csv(
    req: &ResampleRequest,
    output: &Path,
    max_output_gb: f64,
    force: bool,
) -> Result<ResampleRun> {
    let opts = options(req)?;
    let (kind, read, in_memory) = reading(req)?;
    if !(max_output_gb.is_finite() && max_output_gb > 0.0) {
        return Err(Error::field(
            "max_output_gb",
            format!("must be positive, got {max_output_gb}"),
        ));
    }
    // The budget: estimate the samples (one pass over the file) before any work.
    let extent = super::inputs::path_extent(
        &req.file,
        read.clone(),
        req.path.map(|n| n.saturating_sub(1)),
        req.moves,
    )?;
    let rpm = req.rpm.or(if opts.spindle_from_path {
        extent.spindle_rpm
    } else {
        None
    });
    let samples = crate::resample::estimate_samples(&extent, req.mode, opts.fz_mm, opts.teeth, rpm);
    super::inputs::check_output_budget(
        &format!(
            "{}: resampling {:.1} mm of cutting moves into about {samples:.3e} samples",
            req.file.display(),
            extent.cutting_mm
        ),
        samples * super::inputs::RESAMPLE_ROW_BYTES,
        max_output_gb,
        force,
    )?;
    if !in_memory {
        let paths = resample_streaming(req, output, &opts, &read)?;
        return Ok(ResampleRun {
            paths,
            predicted: false,
            options: opts,
        });
    }
    // The predicted feed needs the whole path: in memory.
    let mut run = None;
    let mut failure = None;
    let written = crate::io::write_atomic(output, |w| {
        let mut out = SampleCsv::new(w)?;
        match resample_read(req, opts.clone(), kind, &read, |_, s| out.sample(s)) {
            Ok(r) => run = Some(r),
            Err(e) => {
                failure = Some(e);
                return Err(std::io::Error::other("resampling failed"));
            }
        }
        out.flush()
    });
    if let Some(e) = failure {
        return Err(e);
    }
    written.map_err(|e| Error::within(output.display(), e))?;
    run.ok_or_else(|| {
        Error::Internal(format!(
            "{}: resampling did not finish (internal error)",
            req.file.display()
        ))
    })
}

/// A streamed tool path: its ordinal, counts, spindle scan, and whether it must be redone.
type Finished = (usize, Option<Stats>, Option<SpindleScan>, bool);

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
    req: &ResampleRequest,
    output: &Path,
    opts: &Options,
    read: &ReadOptions,
) -> Result<Vec<PathReport>> {
    // Invalid options are reported before anything is read.
    Resampler::new(opts).map_err(|e| Error::within(req.file.display(), e))?;
    let first = Pass {
        target: req.path.map(|n| Some(n.saturating_sub(1))),
        spindles: None,
    };
    match stream_pass(req, output, opts, read, &first)? {
        PassResult::Done(reports) => Ok(reports),
        PassResult::Again(target, spindles) => {
            let again = Pass {
                target,
                spindles: spindles.as_ref(),
            };
            match stream_pass(req, output, opts, read, &again)? {
                PassResult::Done(reports) => Ok(reports),
                PassResult::Again(..) => Err(Error::Internal(format!(
                    "{}: resampling did not settle (internal error)",
                    req.file.display()
                ))),
            }
        }
    }
}

fn stream_pass(
    req: &ResampleRequest,
    output: &Path,
    opts: &Options,
    read: &ReadOptions,
    pass: &Pass<'_>,
) -> Result<PassResult> {
    let file = &req.file;
    let moves = req.moves;
    let (kind, reader) = crate::io::toolpath::open_detected(file)?;
    let lower = ReadOptions {
        lower: LowerOptions {
            keep_postures: false,
            ..read.lower.clone()
        },
        ..read.clone()
    };
    let lazy = pass.spindles.is_none() && opts.rpm.is_none();

    let mut failure: Option<Error> = None;
    let mut outcome: Option<PassResult> = None;
    let written = crate::io::write_atomic(output, |w| {
        let mut out = SampleCsv::new(w)?;
        let mut current: Option<Current> = None;
        let mut finished: Vec<Finished> = Vec::new();
        let mut count = 0usize;
        let finish = |cur: Current, out: &mut SampleCsv<'_>, finished: &mut Vec<Finished>| {
            finish_path(cur, lazy, out, finished)
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
                let resampler = match start_path(opts, pass, ordinal) {
                    Ok(r) => r,
                    Err(e) => {
                        error = Some((path.name.clone(), e));
                        return Err(std::io::Error::other("resampling failed"));
                    }
                };
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
            let p = if moves.cuts(p.motion) && p.motion != crate::toolpath::MotionKind::Cut {
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
                    None => e.into(),
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

        match conclude(req, opts, pass, lazy, &program, &finished) {
            Ok(done @ PassResult::Done(_)) => {
                outcome = Some(done);
                Ok(())
            }
            Ok(again) => {
                outcome = Some(again);
                Err(std::io::Error::other("again"))
            }
            Err(e) => {
                failure = Some(e);
                Err(std::io::Error::other("resampling failed"))
            }
        }
    });
    if let Some(e) = failure {
        return Err(e.name_output(output));
    }
    match (written, outcome) {
        (Ok(()), Some(done @ PassResult::Done(_))) => Ok(done),
        (Err(_), Some(again @ PassResult::Again(..))) => Ok(again),
        (Err(e), _) => Err(Error::within(output.display(), e)),
        (Ok(()), _) => Err(Error::Internal(format!(
            "{}: resampling did not finish (internal error)",
            file.display()
        ))),
    }
}

/// The resampler of the tool path `ordinal` (`None` when the pass does not resample it),
/// with the spindle speed an earlier pass found.
fn start_path(
    opts: &Options,
    pass: &Pass<'_>,
    ordinal: usize,
) -> Result<Option<Resampler>, ResampleError> {
    if pass.target.is_some_and(|t| t != Some(ordinal)) {
        return Ok(None);
    }
    let mut r = Resampler::new(opts)?;
    match pass.spindles.and_then(|s| s.get(ordinal)) {
        Some(Ok(Some((rpm, source)))) => r = r.with_spindle(*rpm, *source),
        Some(Err(e)) => return Err(e.clone()),
        _ => {}
    }
    Ok(Some(r))
}

/// Finish the current tool path: its last samples, its counts (with a provisional spindle
/// speed, `lazy`, an error only asks for another pass).
fn finish_path(
    cur: Current,
    lazy: bool,
    out: &mut SampleCsv<'_>,
    finished: &mut Vec<Finished>,
) -> Result<(), ResampleError> {
    let mut stats = None;
    let mut redo = cur.lazy_error.is_some();
    if let (Some(r), None) = (cur.resampler, &cur.lazy_error) {
        match r.finish(|s| out.sample(s)) {
            Ok(s) => stats = Some(s),
            Err(_) if lazy => redo = true,
            Err(e) => return Err(e),
        }
    }
    finished.push((cur.ordinal, stats, cur.scan, redo));
    Ok(())
}

/// What a streaming pass found once the file is read: the reports of the tool paths asked
/// for, or another pass (another target, or the spindle speeds of the whole paths).
fn conclude(
    req: &ResampleRequest,
    opts: &Options,
    pass: &Pass<'_>,
    lazy: bool,
    program: &Program,
    finished: &[Finished],
) -> Result<PassResult> {
    // Which tool paths were streamed (those with postures), by ordinal.
    let streamed_paths: Vec<usize> = (0..program.paths.len())
        .filter(|&i| program.paths[i].stats.postures > 0)
        .collect();
    let wanted = select_paths(&req.file, req.path, program.paths.len())?;
    let target = req
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
        return Ok(PassResult::Again(target, spindles()));
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
            return Ok(PassResult::Again(target, spindles()));
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
                .map_err(|e| path_error(&req.file, &p.name, e))?,
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
    Ok(PassResult::Done(reports))
}

fn path_error(file: &Path, name: &str, e: ResampleError) -> Error {
    Error::within(
        format_args!(
            "{}: tool path {}",
            file.display(),
            if name.is_empty() { "(unnamed)" } else { name }
        ),
        e,
    )
}
