//! The streaming resampler: postures in, samples out, one pass, one sample at a time.
//!
//! Memory does not depend on the path length: [`Resampler`] keeps the postures of the move
//! it is about to walk and their neighbours (for the spline tangents), the current move,
//! the last sample (held back so that a grid sample falling on the end of a run is replaced
//! by the exact end) and the last feed direction (a fallback when the tangent is
//! degenerate). [`resample_with`] is its in-memory form.

use super::curve::{Curve, above};
use super::{AxisInterpolation, Mode, Options, ResampleError, Sample};
use crate::math::{Point3, Vec3, any_perpendicular, nlerp, normalize_or_none};
use crate::toolpath::{MotionKind, Posture, Toolpath};
use std::f64::consts::{PI, TAU};

/// Where the spindle speed came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpindleSource {
    /// [`Options::rpm`].
    Option,
    /// n = V_ref/(Z·fz) from the highest programmed feed of the cutting moves.
    DerivedFromFeed,
    /// The path's SPINDL (the path has no feed at all).
    Path,
}

/// Counts of a resampling: samples, runs, and every degenerate case met.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Stats {
    /// Samples delivered to the sink.
    pub samples: u64,
    /// Cutting runs that produced samples.
    pub runs: usize,
    /// Cutting moves walked (including zero-length ones).
    pub moves: u64,
    /// Cutting arc length, mm.
    pub length_mm: f64,
    /// Cutting time, s.
    pub duration_s: f64,
    /// Spindle speed used, rpm (`None` when the path has no cutting move).
    pub spindle_rpm: Option<f64>,
    /// Where the spindle speed came from.
    pub spindle_source: Option<SpindleSource>,
    /// Lowest feed at a sample, mm/min.
    pub feed_min_mm_min: Option<f64>,
    /// Highest feed at a sample, mm/min.
    pub feed_max_mm_min: Option<f64>,
    /// Lowest local feed per tooth V/(Z·n) at a sample, mm.
    pub fz_min_mm: Option<f64>,
    /// Highest local feed per tooth V/(Z·n) at a sample, mm.
    pub fz_max_mm: Option<f64>,
    /// Arc moves.
    pub arcs: u64,
    /// Moves whose feed changes along the move (linear in time, model.md §5.3).
    pub variable_feed_moves: u64,
    /// Cutting moves shorter than 1e-12 mm (skipped; an axis change there is lost).
    pub zero_length_moves: u64,
    /// Cutting runs of zero total length (no samples).
    pub zero_length_runs: u64,
    /// Arcs with a zero axis or an end on the axis, walked as straight lines.
    pub degenerate_arcs: u64,
    /// Moves whose tool axis turns by 180° (the great circle is not unique).
    pub axis_flips: u64,
    /// Moves whose surface normal turns by 180°.
    pub normal_flips: u64,
    /// Samples where the path tangent is parallel to the surface normal (f taken from
    /// g = n × axis, or the previous f).
    pub normal_parallel_to_feed: u64,
    /// Samples without contact data where the tangent is parallel to the tool axis.
    pub feed_parallel_to_axis: u64,
    /// Moves with contact data at one end only (no CC point or normal on their samples).
    pub partial_contact_moves: u64,
    /// Moves that are not cutting moves (rapids, cycles, …), skipped.
    pub non_cutting_moves: u64,
    /// Maximal stretches of non-cutting moves, skipped; resampling restarts after them.
    pub non_cutting_runs: u64,
}

/// Resample a path into a `Vec` (see [`resample_with`]).
pub fn resample(path: &Toolpath, opts: &Options) -> Result<Vec<Sample>, ResampleError> {
    let mut out = Vec::new();
    resample_with(path, opts, |s| out.push(s.clone()))?;
    Ok(out)
}

/// Resample every cutting run of `path`, handing each sample to `sink` in order.
///
/// The in-memory form of [`Resampler`]: the spindle speed is resolved from the whole path
/// first ([`SpindleScan`]), then the postures are pushed one by one. Returns the counts of
/// samples, runs and degenerate cases. Fails on invalid options, a missing feed and
/// spindle speed, a move with zero feed at both ends, or a non-finite posture.
pub fn resample_with(
    path: &Toolpath,
    opts: &Options,
    mut sink: impl FnMut(&Sample),
) -> Result<Stats, ResampleError> {
    validate(opts)?;
    let feeds = opts.posture_feed_mm_min.as_deref();
    if let Some(feeds) = feeds {
        if feeds.len() != path.postures.len() {
            return Err(ResampleError::PostureFeedLength {
                expected: path.postures.len(),
                got: feeds.len(),
            });
        }
    }
    let mut scan = SpindleScan::new();
    for (i, p) in path.postures.iter().enumerate() {
        scan.push_entry(p, feeds.map(|f| f[i]));
    }
    let mut r = Resampler::new(opts)?;
    if let Some((rpm, source)) = scan.resolve(opts)? {
        r = r.with_spindle(rpm, source);
    }
    for (i, p) in path.postures.iter().enumerate() {
        r.push_entry(p, feeds.map(|f| f[i]), &mut sink)?;
    }
    r.finish(&mut sink)
}

fn validate(opts: &Options) -> Result<(), ResampleError> {
    if !(opts.fz_mm.is_finite() && opts.fz_mm > 0.0) {
        return Err(ResampleError::InvalidFeedPerTooth(opts.fz_mm));
    }
    if opts.teeth == 0 {
        return Err(ResampleError::NoTeeth);
    }
    if let Mode::SpindleStep { dtheta_rad } = opts.mode {
        if !(dtheta_rad.is_finite() && dtheta_rad > 0.0) {
            return Err(ResampleError::InvalidSpindleStep(dtheta_rad));
        }
    }
    if let Some(rpm) = opts.rpm {
        if !(rpm.is_finite() && rpm > 0.0) {
            return Err(ResampleError::InvalidSpindle(rpm));
        }
    }
    if let Some(v) = opts.feed_mm_min {
        if !(v.is_finite() && v > 0.0) {
            return Err(ResampleError::InvalidFeed { line: 0, value: v });
        }
    }
    Ok(())
}

/// The spindle-speed rule of the module docs, fed one posture at a time: n = `--rpm`,
/// else V_ref/(Z·fz) with V_ref the highest feed of the cutting moves, else the first
/// SPINDL met in a cutting run.
///
/// V_ref is a maximum over the whole path, so a streaming caller that does not know the
/// spindle speed beforehand either scans the path first or lets [`Resampler`] resolve it
/// from the postures seen so far and compares with this scan at the end
/// (`crest resample` does the latter and resamples again in the rare case they differ).
#[derive(Debug, Clone, Default)]
pub struct SpindleScan {
    index: usize,
    in_run: bool,
    any_run: bool,
    prev_spindle: Option<f64>,
    max_fedrat: Option<f64>,
    max_posture_feed: Option<f64>,
    first_spindle: Option<f64>,
}

impl SpindleScan {
    /// An empty scan.
    pub fn new() -> SpindleScan {
        SpindleScan::default()
    }

    /// Take the next posture of the path into account.
    pub fn push(&mut self, p: &Posture) {
        self.push_entry(p, None);
    }

    fn push_entry(&mut self, p: &Posture, posture_feed: Option<f64>) {
        let cut = p.motion == MotionKind::Cut && self.index > 0;
        self.index += 1;
        let keep_max = |m: &mut Option<f64>, v: Option<f64>| {
            if let Some(v) = v.filter(|v| v.is_finite() && *v > 0.0) {
                *m = Some(m.map_or(v, |m: f64| m.max(v)));
            }
        };
        if cut {
            if !self.in_run {
                self.in_run = true;
                self.any_run = true;
                // The run starts at the previous posture.
                if self.first_spindle.is_none() {
                    self.first_spindle = self.prev_spindle;
                }
            }
            if self.first_spindle.is_none() {
                self.first_spindle = p.spindle_rpm;
            }
            keep_max(&mut self.max_fedrat, p.feed_mm_min);
            keep_max(&mut self.max_posture_feed, posture_feed);
        } else {
            self.in_run = false;
        }
        self.prev_spindle = p.spindle_rpm;
    }

    /// The spindle speed (rpm) and where it came from; `None` when no cutting move has
    /// been seen (and [`Options::rpm`] is not set).
    pub fn resolve(&self, opts: &Options) -> Result<Option<(f64, SpindleSource)>, ResampleError> {
        if let Some(rpm) = opts.rpm {
            return Ok(Some((rpm, SpindleSource::Option)));
        }
        if !self.any_run {
            return Ok(None);
        }
        let v_ref = opts
            .feed_mm_min
            .or(self.max_fedrat)
            .or(self.max_posture_feed);
        if let Some(v) = v_ref {
            let rpm = v / (opts.teeth as f64 * opts.fz_mm);
            return Ok(Some((rpm, SpindleSource::DerivedFromFeed)));
        }
        match self.first_spindle {
            Some(rpm) if rpm.is_finite() && rpm > 0.0 => Ok(Some((rpm, SpindleSource::Path))),
            Some(rpm) => Err(ResampleError::InvalidSpindle(rpm)),
            None => Err(ResampleError::MissingFeedAndSpindle),
        }
    }
}

/// The options a walker needs (everything but the per-posture feeds).
#[derive(Debug, Clone, Copy)]
struct Params {
    mode: Mode,
    fz_mm: f64,
    feed_mm_min: Option<f64>,
    axis_interpolation: AxisInterpolation,
    spline: bool,
    posture_feeds: bool,
}

/// A posture held by the resampler, with its per-posture feed.
#[derive(Debug, Clone)]
struct Entry {
    p: Posture,
    feed: Option<f64>,
}

/// The open cutting run: its walker and the postures of the moves not walked yet.
struct OpenRun {
    walker: RunWalker,
    /// The posture before `a` in the run (for the spline tangent at `a`).
    before: Option<Entry>,
    /// Start of the next move to walk.
    a: Entry,
    /// End of that move, once known (walked when the posture after it arrives).
    b: Option<Entry>,
}

/// The incremental resampler: postures in, samples out, in constant memory.
///
/// Push the postures of one tool path in order with [`Resampler::push`], then call
/// [`Resampler::finish`]. It keeps only the postures its current move needs (the move's
/// ends and their neighbours, for the spline tangents) and the state of the current run,
/// and produces exactly the samples and [`Stats`] of [`resample_with`] on the whole path
/// when given the same spindle speed ([`Resampler::with_spindle`]). Without it, the
/// spindle speed is resolved at the first cutting move from the postures seen so far
/// ([`SpindleScan`]): the same as the whole path's unless a later cutting move is faster.
///
/// ```
/// use crest::math::{Point3, Vec3};
/// use crest::resample::{Mode, Options, Resampler};
/// use crest::toolpath::{MotionKind, Posture};
///
/// let posture = |x: f64, motion| Posture {
///     position: Point3::new(x, 0.0, 0.0),
///     axis: Vec3::z(),
///     motion,
///     arc: None,
///     contact: None,
///     feed_mm_min: Some(1000.0),
///     spindle_rpm: None,
///     line: 0,
/// };
/// let mut r = Resampler::new(&Options::new(Mode::FeedPerTooth, 0.05, 4)).unwrap();
/// let mut n = 0;
/// r.push(&posture(0.0, MotionKind::Rapid), |_| n += 1).unwrap();
/// r.push(&posture(1.0, MotionKind::Cut), |_| n += 1).unwrap();
/// let stats = r.finish(|_| n += 1).unwrap();
/// assert_eq!((n, stats.samples), (21, 21));
/// ```
pub struct Resampler {
    params: Params,
    opts_rpm: Option<f64>,
    teeth: usize,
    spindle: Option<(f64, SpindleSource)>,
    clock: Option<Clock>,
    scan: SpindleScan,
    index: usize,
    prev: Option<Entry>,
    in_gap: bool,
    run: Option<OpenRun>,
    runs_seen: usize,
    s_offset: f64,
    stats: Stats,
}

impl Resampler {
    /// A resampler for one tool path. Fails on invalid options. With
    /// [`Options::posture_feed_mm_min`], push the postures with
    /// [`Resampler::push_with_feed`] (the vector itself is not used).
    pub fn new(opts: &Options) -> Result<Resampler, ResampleError> {
        validate(opts)?;
        Ok(Resampler {
            params: Params {
                mode: opts.mode,
                fz_mm: opts.fz_mm,
                feed_mm_min: opts.feed_mm_min,
                axis_interpolation: opts.axis_interpolation,
                spline: opts.spline,
                posture_feeds: opts.posture_feed_mm_min.is_some(),
            },
            opts_rpm: opts.rpm,
            teeth: opts.teeth,
            spindle: opts.rpm.map(|rpm| (rpm, SpindleSource::Option)),
            clock: None,
            scan: SpindleScan::new(),
            index: 0,
            prev: None,
            in_gap: false,
            run: None,
            runs_seen: 0,
            s_offset: 0.0,
            stats: Stats {
                samples: 0,
                runs: 0,
                moves: 0,
                length_mm: 0.0,
                duration_s: 0.0,
                spindle_rpm: None,
                spindle_source: None,
                feed_min_mm_min: None,
                feed_max_mm_min: None,
                fz_min_mm: None,
                fz_max_mm: None,
                arcs: 0,
                variable_feed_moves: 0,
                zero_length_moves: 0,
                zero_length_runs: 0,
                degenerate_arcs: 0,
                axis_flips: 0,
                normal_flips: 0,
                normal_parallel_to_feed: 0,
                feed_parallel_to_axis: 0,
                partial_contact_moves: 0,
                non_cutting_moves: 0,
                non_cutting_runs: 0,
            },
        })
    }

    /// Use this spindle speed (rpm, from `source`) instead of resolving it at the first
    /// cutting move (e.g. from a [`SpindleScan`] of the whole path).
    pub fn with_spindle(mut self, rpm: f64, source: SpindleSource) -> Resampler {
        self.spindle = Some((rpm, source));
        self
    }

    /// The spindle speed in use (rpm, source), once known.
    pub fn spindle(&self) -> Option<(f64, SpindleSource)> {
        self.spindle
    }

    /// The next posture of the path; samples that are complete go to `sink`.
    pub fn push(&mut self, p: &Posture, sink: impl FnMut(&Sample)) -> Result<(), ResampleError> {
        self.push_entry(p, None, sink)
    }

    /// [`Resampler::push`] with the posture's own feed, mm/min (per-posture feeds,
    /// [`Options::posture_feed_mm_min`]).
    pub fn push_with_feed(
        &mut self,
        p: &Posture,
        feed_mm_min: f64,
        sink: impl FnMut(&Sample),
    ) -> Result<(), ResampleError> {
        self.push_entry(p, Some(feed_mm_min), sink)
    }

    fn push_entry(
        &mut self,
        p: &Posture,
        feed: Option<f64>,
        mut sink: impl FnMut(&Sample),
    ) -> Result<(), ResampleError> {
        let first = self.index == 0;
        self.index += 1;
        if self.spindle.is_none() {
            self.scan.push_entry(p, feed);
        }
        let cut = p.motion == MotionKind::Cut && !first;
        if !first {
            if cut {
                self.in_gap = false;
            } else {
                self.stats.non_cutting_moves += 1;
                if !self.in_gap {
                    self.stats.non_cutting_runs += 1;
                }
                self.in_gap = true;
            }
        }
        let entry = Entry { p: p.clone(), feed };
        if cut {
            if self.run.is_none() {
                let clock = self.clock()?;
                let Some(start) = self.prev.take() else {
                    return Err(ResampleError::InvalidPosture {
                        line: p.line,
                        what: "cutting move without a start",
                    });
                };
                self.run = Some(OpenRun {
                    walker: RunWalker::new(self.params, clock, self.runs_seen, self.s_offset),
                    before: None,
                    a: start,
                    b: None,
                });
                self.runs_seen += 1;
            }
            let Some(run) = self.run.as_mut() else {
                return Ok(());
            };
            if let Some(b) = run.b.take() {
                self.stats.moves += 1;
                let mut emit = emitter(&mut sink);
                run.walker.walk_move(
                    run.before.as_ref(),
                    &run.a,
                    &b,
                    Some(&entry),
                    &mut self.stats,
                    &mut emit,
                )?;
                run.before = Some(std::mem::replace(&mut run.a, b));
            }
            run.b = Some(entry.clone());
        } else {
            self.close_run(&mut sink)?;
        }
        self.prev = Some(entry);
        Ok(())
    }

    /// The clock, resolving the spindle speed now if it is not known yet.
    fn clock(&mut self) -> Result<Clock, ResampleError> {
        if let Some(c) = self.clock {
            return Ok(c);
        }
        let (rpm, _) = match self.spindle {
            Some(s) => s,
            None => {
                let opts = Options {
                    rpm: self.opts_rpm,
                    feed_mm_min: self.params.feed_mm_min,
                    teeth: self.teeth,
                    fz_mm: self.params.fz_mm,
                    ..Options::default()
                };
                let s = self
                    .scan
                    .resolve(&opts)?
                    .ok_or(ResampleError::MissingFeedAndSpindle)?;
                self.spindle = Some(s);
                s
            }
        };
        let clock = Clock {
            omega: rpm * TAU / 60.0,
            rpm,
            teeth: self.teeth as f64,
            fz_mm: self.params.fz_mm,
        };
        self.clock = Some(clock);
        Ok(clock)
    }

    fn close_run(&mut self, sink: &mut impl FnMut(&Sample)) -> Result<(), ResampleError> {
        let Some(mut run) = self.run.take() else {
            return Ok(());
        };
        let mut emit = emitter(sink);
        if let Some(b) = run.b.take() {
            self.stats.moves += 1;
            run.walker.walk_move(
                run.before.as_ref(),
                &run.a,
                &b,
                None,
                &mut self.stats,
                &mut emit,
            )?;
        }
        let walker = &mut run.walker;
        let length = walker.s_end;
        if walker.finish(&mut self.stats, &mut emit) {
            self.stats.runs += 1;
            self.stats.length_mm += length;
            self.stats.duration_s += walker.t_end;
        } else {
            self.stats.zero_length_runs += 1;
        }
        self.s_offset += length;
        Ok(())
    }

    /// Finish the path: emit the end of the open run and return the counts.
    pub fn finish(mut self, mut sink: impl FnMut(&Sample)) -> Result<Stats, ResampleError> {
        self.close_run(&mut sink)?;
        let mut stats = self.stats;
        if self.runs_seen == 0 {
            stats.spindle_rpm = self.opts_rpm;
            stats.spindle_source = self.opts_rpm.map(|_| SpindleSource::Option);
        } else {
            stats.spindle_rpm = self.spindle.map(|s| s.0);
            stats.spindle_source = self.spindle.map(|s| s.1);
        }
        Ok(stats)
    }
}

/// The sample sink with the per-sample counts (feed and feed-per-tooth range).
fn emitter<'s>(sink: &'s mut impl FnMut(&Sample)) -> impl FnMut(&Sample, &Clock, &mut Stats) + 's {
    move |s: &Sample, clock: &Clock, stats: &mut Stats| {
        stats.samples += 1;
        let fz = s.feed_mm_min / (clock.teeth * clock.rpm);
        stats.feed_min_mm_min = Some(
            stats
                .feed_min_mm_min
                .map_or(s.feed_mm_min, |m| m.min(s.feed_mm_min)),
        );
        stats.feed_max_mm_min = Some(
            stats
                .feed_max_mm_min
                .map_or(s.feed_mm_min, |m| m.max(s.feed_mm_min)),
        );
        stats.fz_min_mm = Some(stats.fz_min_mm.map_or(fz, |m| m.min(fz)));
        stats.fz_max_mm = Some(stats.fz_max_mm.map_or(fz, |m| m.max(fz)));
        sink(s);
    }
}

#[derive(Debug, Clone, Copy)]
struct Clock {
    /// Ω, rad/s.
    omega: f64,
    rpm: f64,
    teeth: f64,
    fz_mm: f64,
}

/// Interpolation of unit vectors with per-move precomputation (one `sin_cos` a sample).
#[derive(Debug, Clone, Copy)]
struct SphereInterp {
    a: Vec3,
    b: Vec3,
    perp: Vec3,
    angle: f64,
    slerp: bool,
}

impl SphereInterp {
    /// Returns the interpolator and whether the vectors are antipodal (a 180° flip).
    fn new(a: Vec3, b: Vec3, kind: AxisInterpolation) -> (SphereInterp, bool) {
        let cos = a.dot(&b);
        let cross = a.cross(&b);
        // atan2 keeps small angles accurate (acos loses half the digits near 1).
        let angle = cross.norm().atan2(cos);
        let flipped = PI - angle < 1e-6;
        let perp = if angle < 1e-9 {
            Vec3::zeros()
        } else if PI - angle < 1e-9 {
            any_perpendicular(&a)
        } else {
            (b - a * cos).normalize()
        };
        let interp = SphereInterp {
            a,
            b,
            perp,
            angle,
            slerp: kind == AxisInterpolation::Slerp,
        };
        (interp, flipped)
    }

    /// Same values as [`crate::math::slerp`] / [`crate::math::nlerp`].
    fn eval(&self, u: f64) -> Vec3 {
        if self.slerp && self.angle >= 1e-9 {
            // `a` and `perp` are orthonormal, so the result is unit to rounding (~1e-16).
            let (s, c) = sin_cos(self.angle * u);
            self.a * c + self.perp * s
        } else {
            nlerp(&self.a, &self.b, u)
        }
    }
}

/// `x.sin_cos()`, by Taylor series for |x| ≤ 0.1 (exact to rounding there: the first
/// omitted terms are below 3e-19), which is most of a 5-axis path's axis changes.
fn sin_cos(x: f64) -> (f64, f64) {
    if x.abs() > 0.1 {
        return x.sin_cos();
    }
    // Taylor coefficients 1/3!, 1/5!, … and 1/2!, 1/4!, … (Horner, no divisions).
    const S: [f64; 4] = [1.0 / 6.0, 1.0 / 120.0, 1.0 / 5040.0, 1.0 / 362_880.0];
    const C: [f64; 5] = [
        1.0 / 2.0,
        1.0 / 24.0,
        1.0 / 720.0,
        1.0 / 40_320.0,
        1.0 / 3_628_800.0,
    ];
    let x2 = x * x;
    let s = x * (1.0 - x2 * (S[0] - x2 * (S[1] - x2 * (S[2] - x2 * S[3]))));
    let c = 1.0 - x2 * (C[0] - x2 * (C[1] - x2 * (C[2] - x2 * (C[3] - x2 * C[4]))));
    (s, c)
}

/// One cutting move ready for sampling.
#[derive(Debug, Clone, Copy)]
struct Move {
    curve: Curve,
    len: f64,
    axis: SphereInterp,
    contact: Option<(Point3, Point3, SphereInterp)>,
    /// Feeds at the start and end, mm/s.
    va: f64,
    vb: f64,
    /// Duration, s.
    dt: f64,
    /// Run-relative arc length, time and θ at the start.
    s0: f64,
    t0: f64,
    theta0: f64,
}

impl Move {
    /// Time since the start of the move at arc length σ (feed linear in time).
    fn tau_at(&self, sigma: f64) -> f64 {
        if sigma <= 0.0 {
            return 0.0;
        }
        if self.va == self.vb {
            return (sigma / self.va).min(self.dt);
        }
        let a = (self.vb - self.va) / (2.0 * self.dt);
        let disc = (self.va * self.va + 4.0 * a * sigma).max(0.0);
        let den = self.va + disc.sqrt();
        if den > 0.0 {
            (2.0 * sigma / den).min(self.dt)
        } else {
            0.0
        }
    }

    /// Arc length since the start of the move at time τ (model.md §5.3, Eq 6).
    fn sigma_at(&self, tau: f64) -> f64 {
        let s = self.va * tau + (self.vb - self.va) * tau * tau / (2.0 * self.dt);
        s.clamp(0.0, self.len)
    }

    /// Feed at time τ, mm/s (Eq 5).
    fn feed_at(&self, tau: f64) -> f64 {
        self.va + (self.vb - self.va) * (tau / self.dt).clamp(0.0, 1.0)
    }
}

struct RunWalker {
    params: Params,
    clock: Clock,
    run_idx: usize,
    s_offset: f64,
    /// Index of the next grid sample of the run.
    k: u64,
    /// Run-relative arc length, time and θ at the end of the last move walked.
    s_end: f64,
    t_end: f64,
    theta_end: f64,
    last: Option<Move>,
    pending: Option<Sample>,
    pending_is_first: bool,
    prev_feed_dir: Option<Vec3>,
}

fn checked_axis(p: &Posture) -> Result<Vec3, ResampleError> {
    let finite = p.position.coords.iter().all(|c| c.is_finite());
    if !finite {
        return Err(ResampleError::InvalidPosture {
            line: p.line,
            what: "non-finite coordinate",
        });
    }
    if !p.axis.iter().all(|c| c.is_finite()) {
        return Err(ResampleError::InvalidPosture {
            line: p.line,
            what: "non-finite tool axis",
        });
    }
    normalize_or_none(&p.axis, 1e-12).ok_or(ResampleError::InvalidPosture {
        line: p.line,
        what: "zero tool axis",
    })
}

fn checked_feed(line: u32, v: f64) -> Result<f64, ResampleError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(ResampleError::InvalidFeed { line, value: v })
    }
}

/// The unit tangent of the spline at a posture, from the moves into it and out of it
/// (within the run): an adjacent arc's own tangent, else Bessel's (the tangent of the
/// parabola through the neighbours), one-sided at the ends of the run.
fn posture_tangent(
    incoming: Option<(&Posture, &Posture)>,
    outgoing: Option<(&Posture, &Posture)>,
) -> Option<Vec3> {
    let neighbour = |a: &Posture, b: &Posture, out: bool| -> Option<(Vec3, f64, bool)> {
        if let Some(arc) = &b.arc {
            if let Some(c) = Curve::arc(a.position, b.position, arc) {
                let (t0, t1) = c.end_tangents();
                return Some((if out { t0 } else { t1 }, c.len(), true));
            }
        }
        let d = b.position - a.position;
        let len = d.norm();
        normalize_or_none(&d, 1e-12).map(|d| (d, len, false))
    };
    let incoming = incoming.and_then(|(a, b)| neighbour(a, b, false));
    let outgoing = outgoing.and_then(|(a, b)| neighbour(a, b, true));
    match (incoming, outgoing) {
        (Some((t, _, true)), _) | (_, Some((t, _, true))) => Some(t),
        (Some((din, lin, _)), Some((dout, lout, _))) => {
            normalize_or_none(&(din * lout + dout * lin), 1e-9).or(Some(dout))
        }
        (Some((t, _, _)), None) | (None, Some((t, _, _))) => Some(t),
        (None, None) => None,
    }
}

impl RunWalker {
    fn new(params: Params, clock: Clock, run_idx: usize, s_offset: f64) -> RunWalker {
        RunWalker {
            params,
            clock,
            run_idx,
            s_offset,
            k: 0,
            s_end: 0.0,
            t_end: 0.0,
            theta_end: 0.0,
            last: None,
            pending: None,
            pending_is_first: false,
            prev_feed_dir: None,
        }
    }

    /// The feeds at the start and end of the move `a → b`, mm/min.
    fn move_feeds(&self, a: &Entry, b: &Entry) -> Result<(f64, f64), ResampleError> {
        if self.params.posture_feeds {
            return Ok((
                checked_feed(a.p.line, a.feed.unwrap_or(f64::NAN))?,
                checked_feed(b.p.line, b.feed.unwrap_or(f64::NAN))?,
            ));
        }
        let v = match (self.params.feed_mm_min, b.p.feed_mm_min) {
            (Some(v), _) | (None, Some(v)) => v,
            (None, None) => self.clock.teeth * self.clock.fz_mm * self.clock.rpm,
        };
        let v = checked_feed(b.p.line, v)?;
        Ok((v, v))
    }

    /// The geometry of the move `a → b` (`before` precedes `a` and `next` follows `b`
    /// in the run), or `None` for a zero-length move.
    fn curve(
        &self,
        before: Option<&Posture>,
        a: &Posture,
        b: &Posture,
        next: Option<&Posture>,
        stats: &mut Stats,
    ) -> Option<Curve> {
        if let Some(arc) = &b.arc {
            stats.arcs += 1;
            if let Some(c) = Curve::arc(a.position, b.position, arc) {
                return Some(c);
            }
            stats.degenerate_arcs += 1;
            return Curve::line(a.position, b.position);
        }
        if self.params.spline {
            let t0 = posture_tangent(before.map(|x| (x, a)), Some((a, b)));
            let t1 = posture_tangent(Some((a, b)), next.map(|n| (b, n)));
            if let (Some(t0), Some(t1)) = (t0, t1) {
                return Curve::hermite(a.position, b.position, t0, t1);
            }
        }
        Curve::line(a.position, b.position)
    }

    fn walk_move(
        &mut self,
        before: Option<&Entry>,
        ea: &Entry,
        eb: &Entry,
        next: Option<&Entry>,
        stats: &mut Stats,
        emit: &mut impl FnMut(&Sample, &Clock, &mut Stats),
    ) -> Result<(), ResampleError> {
        let (a, b) = (&ea.p, &eb.p);
        let axis_a = checked_axis(a)?;
        let axis_b = checked_axis(b)?;
        let Some(curve) = self.curve(before.map(|e| &e.p), a, b, next.map(|e| &e.p), stats) else {
            stats.zero_length_moves += 1;
            return Ok(());
        };
        let len = curve.len();
        let (va, vb) = self.move_feeds(ea, eb)?;
        if !above(va + vb, 0.0) {
            return Err(ResampleError::ZeroFeedMove { line: b.line });
        }
        if va != vb {
            stats.variable_feed_moves += 1;
        }
        let (va, vb) = (va / 60.0, vb / 60.0);
        let dt = 2.0 * len / (va + vb);
        let kind = self.params.axis_interpolation;
        let (axis, flipped) = SphereInterp::new(axis_a, axis_b, kind);
        stats.axis_flips += u64::from(flipped);
        let contact = match (&a.contact, &b.contact) {
            (Some(ca), Some(cb)) => {
                let na = normalize_or_none(&ca.normal, 1e-12);
                let nb = normalize_or_none(&cb.normal, 1e-12);
                match (na, nb) {
                    (Some(na), Some(nb)) => {
                        let (ni, flipped) = SphereInterp::new(na, nb, kind);
                        stats.normal_flips += u64::from(flipped);
                        Some((ca.point, cb.point, ni))
                    }
                    _ => {
                        stats.partial_contact_moves += 1;
                        None
                    }
                }
            }
            (None, None) => None,
            _ => {
                stats.partial_contact_moves += 1;
                None
            }
        };
        let mv = Move {
            curve,
            len,
            axis,
            contact,
            va,
            vb,
            dt,
            s0: self.s_end,
            t0: self.t_end,
            theta0: self.theta_end,
        };
        let s_end = mv.s0 + len;
        let theta_end = mv.theta0 + self.clock.omega * dt;
        match self.params.mode {
            Mode::FeedPerTooth => {
                let step = self.params.fz_mm;
                loop {
                    let s = self.k as f64 * step;
                    if s >= s_end {
                        break;
                    }
                    let sigma = (s - mv.s0).max(0.0);
                    let tau = mv.tau_at(sigma);
                    let theta = mv.theta0 + self.clock.omega * tau;
                    self.push(&mv, s, sigma, tau, theta, stats, emit);
                }
            }
            Mode::SpindleStep { dtheta_rad } => loop {
                let theta = self.k as f64 * dtheta_rad;
                if theta >= theta_end {
                    break;
                }
                let tau = ((theta - mv.theta0) / self.clock.omega).max(0.0);
                let sigma = mv.sigma_at(tau);
                self.push(&mv, mv.s0 + sigma, sigma, tau, theta, stats, emit);
            },
        }
        self.s_end = s_end;
        self.t_end = mv.t0 + dt;
        self.theta_end = theta_end;
        self.last = Some(mv);
        Ok(())
    }

    /// Build the sample at run-relative arc length `s` (σ into the move, τ after its
    /// start, spindle angle θ), emit the previous one and hold this one back.
    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        mv: &Move,
        s: f64,
        sigma: f64,
        tau: f64,
        theta: f64,
        stats: &mut Stats,
        emit: &mut impl FnMut(&Sample, &Clock, &mut Stats),
    ) {
        let sample = self.sample(mv, s, sigma, tau, theta, stats);
        if let Some(p) = self.pending.take() {
            emit(&p, &self.clock, stats);
        }
        self.pending_is_first = self.k == 0;
        self.pending = Some(sample);
        self.k += 1;
    }

    fn sample(
        &mut self,
        mv: &Move,
        s: f64,
        sigma: f64,
        tau: f64,
        theta: f64,
        stats: &mut Stats,
    ) -> Sample {
        let u = mv.curve.param(sigma);
        let (position, tangent) = mv.curve.eval(u);
        let axis = mv.axis.eval(u);
        let (contact, normal) = match &mv.contact {
            Some((c0, c1, ni)) => (Some(c0 + (c1 - c0) * u), Some(ni.eval(u))),
            None => (None, None),
        };
        let feed_dir = self.feed_direction(&tangent, &axis, normal.as_ref(), stats);
        Sample {
            run: self.run_idx,
            s_mm: self.s_offset + s,
            t_s: mv.t0 + tau,
            theta_rad: theta,
            position,
            axis,
            contact,
            normal,
            feed_dir,
            feed_mm_min: mv.feed_at(tau) * 60.0,
        }
    }

    /// f: the tangent projected on the plane normal to `n` (or to the axis without
    /// contact data); the degenerate cases are counted and fall back as documented.
    fn feed_direction(
        &mut self,
        tangent: &Vec3,
        axis: &Vec3,
        normal: Option<&Vec3>,
        stats: &mut Stats,
    ) -> Vec3 {
        let plane = normal.unwrap_or(axis);
        let project = |v: &Vec3| normalize_or_none(&(v - plane * v.dot(plane)), 1e-9);
        let f = match project(tangent) {
            Some(f) => f,
            None => {
                let from_axis = match normal {
                    Some(n) => {
                        stats.normal_parallel_to_feed += 1;
                        // The paper's own rule for a lone point: g = n × axis, f = g × n.
                        normalize_or_none(&n.cross(axis), 1e-9).map(|g| g.cross(n))
                    }
                    None => {
                        stats.feed_parallel_to_axis += 1;
                        None
                    }
                };
                from_axis
                    .or_else(|| self.prev_feed_dir.as_ref().and_then(project))
                    .unwrap_or_else(|| any_perpendicular(plane))
            }
        };
        self.prev_feed_dir = Some(f);
        f
    }

    /// Emit the held-back sample and the exact end of the run; false for a run of zero
    /// length (nothing emitted).
    fn finish(
        &mut self,
        stats: &mut Stats,
        emit: &mut impl FnMut(&Sample, &Clock, &mut Stats),
    ) -> bool {
        let Some(mv) = self.last else {
            return false;
        };
        let end = self.sample(&mv, self.s_end, mv.len, mv.dt, self.theta_end, stats);
        if let Some(p) = self.pending.take() {
            // A grid sample within 1e-6 step of the end is the end itself.
            let at_end = match self.params.mode {
                Mode::FeedPerTooth => p.s_mm >= end.s_mm - 1e-6 * self.params.fz_mm,
                Mode::SpindleStep { dtheta_rad } => {
                    p.theta_rad >= end.theta_rad - 1e-6 * dtheta_rad
                }
            };
            if !at_end || self.pending_is_first {
                emit(&p, &self.clock, stats);
            }
        }
        emit(&end, &self.clock, stats);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::toolpath::{ArcMove, Contact};
    use approx::assert_relative_eq;

    fn posture(x: f64, y: f64, z: f64, motion: MotionKind) -> Posture {
        Posture {
            position: Point3::new(x, y, z),
            axis: Vec3::z(),
            motion,
            arc: None,
            contact: None,
            feed_mm_min: Some(1000.0),
            spindle_rpm: None,
            line: 1,
        }
    }

    fn line_path(len: f64) -> Toolpath {
        Toolpath {
            postures: vec![
                posture(0.0, 0.0, 0.0, MotionKind::Rapid),
                posture(len, 0.0, 0.0, MotionKind::Cut),
            ],
            ..Default::default()
        }
    }

    fn dtheta(deg: f64) -> Mode {
        Mode::SpindleStep {
            dtheta_rad: deg.to_radians(),
        }
    }

    #[test]
    fn series_sin_cos_matches_libm() {
        for k in -1000..=1000 {
            let x = k as f64 * 1e-4;
            let (s, c) = sin_cos(x);
            assert!((s - x.sin()).abs() <= 2.0 * f64::EPSILON * x.abs(), "{x}");
            assert!((c - x.cos()).abs() <= 2.0 * f64::EPSILON, "{x}");
        }
        assert_eq!(sin_cos(0.3), 0.3f64.sin_cos());
    }

    #[test]
    fn sphere_interpolation_matches_math() {
        let a = Vec3::new(0.1, -0.3, 1.0).normalize();
        for b in [
            Vec3::new(0.2, 0.1, 1.0).normalize(),
            Vec3::new(-1.0, 0.5, 0.2).normalize(),
            Vec3::new(1e-7, 0.0, 1.0).normalize(),
        ] {
            for (kind, f) in [
                (
                    AxisInterpolation::Slerp,
                    crate::math::slerp as fn(&Vec3, &Vec3, f64) -> Vec3,
                ),
                (AxisInterpolation::Nlerp, crate::math::nlerp),
            ] {
                let (si, flipped) = SphereInterp::new(a, b, kind);
                assert!(!flipped);
                for u in [0.0, 0.25, 0.5, 0.9, 1.0] {
                    assert_relative_eq!(si.eval(u), f(&a, &b, u), epsilon = 1e-9);
                }
                assert_relative_eq!(si.eval(1.0), b, epsilon = 1e-12);
            }
        }
        let (si, flipped) = SphereInterp::new(a, -a, AxisInterpolation::Slerp);
        assert!(flipped);
        assert_relative_eq!(si.eval(0.5).dot(&a), 0.0, epsilon = 1e-12);
        assert_relative_eq!(si.eval(1.0), -a, epsilon = 1e-12);
    }

    #[test]
    fn r4_advance_per_radian() {
        let opts = Options::new(Mode::SpindleStep { dtheta_rad: 1.0 }, 0.05, 4);
        assert_relative_eq!(opts.nominal_step_mm(), 0.031831, epsilon = 5e-7);
        let opts = Options::new(dtheta(1.0), 0.05, 4);
        assert_relative_eq!(opts.nominal_step_mm(), 5.5556e-4, epsilon = 5e-8);
    }

    #[test]
    fn r4_theta_at_one_mm() {
        for mode in [Mode::FeedPerTooth, dtheta(1.0)] {
            let samples = resample(&line_path(1.0), &Options::new(mode, 0.05, 4)).unwrap();
            let last = samples.last().unwrap();
            assert_relative_eq!(last.s_mm, 1.0, epsilon = 1e-12);
            assert_relative_eq!(last.theta_rad, 31.4159, epsilon = 5e-5);
            assert_relative_eq!(last.theta_rad, 10.0 * PI, epsilon = 1e-9);
        }
        // fz mode: 0.05 mm a sample, 21 samples with both ends, one tooth (π/2) a step.
        let samples =
            resample(&line_path(1.0), &Options::new(Mode::FeedPerTooth, 0.05, 4)).unwrap();
        assert_eq!(samples.len(), 21);
        for w in samples.windows(2) {
            assert_relative_eq!(w[1].s_mm - w[0].s_mm, 0.05, epsilon = 1e-12);
            assert_relative_eq!(w[1].theta_rad - w[0].theta_rad, PI / 2.0, epsilon = 1e-9);
        }
    }

    #[test]
    fn r4_nlerp_and_slerp_axis() {
        let mut path = line_path(1.0);
        path.postures[1].axis = Vec3::new(0.2f64.sin(), 0.0, 0.2f64.cos());
        for (kind, expected) in [
            (AxisInterpolation::Nlerp, 0.049875),
            (AxisInterpolation::Slerp, 0.05),
        ] {
            let opts = Options::new(Mode::FeedPerTooth, 0.25, 4).with_axis_interpolation(kind);
            let samples = resample(&path, &opts).unwrap();
            assert_eq!(samples.len(), 5);
            let a = samples[1].axis;
            assert_relative_eq!(a.x.atan2(a.z), expected, epsilon = 1e-6);
            assert_relative_eq!(a.norm(), 1.0, epsilon = 1e-14);
        }
    }

    #[test]
    fn r4_variable_feed_001_example() {
        // L = 1 mm, 4000 → 500 mm/min, 15000 rpm, dθ = 1°.
        let path = line_path(1.0);
        let opts = Options::new(dtheta(1.0), 0.05, 4)
            .with_rpm(15000.0)
            .with_posture_feed_mm_min(vec![4000.0, 500.0]);
        let mut samples = Vec::new();
        let stats = resample_with(&path, &opts, |s| samples.push(s.clone())).unwrap();
        assert_eq!(samples.len(), 2401);
        assert_eq!(stats.samples, 2401);
        assert_eq!(stats.variable_feed_moves, 1);
        let last = samples.last().unwrap();
        assert_relative_eq!(last.t_s * 1000.0, 26.6667, epsilon = 5e-5);
        assert_relative_eq!(last.theta_rad / TAU, 6.6667, epsilon = 5e-5);
        assert_relative_eq!(last.feed_mm_min, 500.0, epsilon = 1e-9);
        assert_relative_eq!(last.s_mm, 1.0, epsilon = 1e-12);
        assert_relative_eq!(samples[0].feed_mm_min, 4000.0, epsilon = 1e-9);
        // Eq 6: s(τ) = V_i τ + (V_{i+1} − V_i) τ²/(2Δt); feed linear in time.
        let dt = 2.0 / (4500.0 / 60.0);
        for s in samples.iter().step_by(97) {
            let tau = s.t_s;
            let sigma = 4000.0 / 60.0 * tau - 3500.0 / 60.0 * tau * tau / (2.0 * dt);
            assert_relative_eq!(s.s_mm, sigma, epsilon = 1e-12);
            assert_relative_eq!(s.position.x, sigma, epsilon = 1e-12);
            assert_relative_eq!(s.feed_mm_min, 4000.0 - 3500.0 * tau / dt, epsilon = 1e-9);
            assert_relative_eq!(s.theta_rad, 15000.0 * TAU / 60.0 * tau, epsilon = 1e-9);
        }
        // The feed per tooth follows the feed: 4000/(4·15000) … 500/(4·15000) mm.
        assert_relative_eq!(stats.fz_max_mm.unwrap(), 4000.0 / 60000.0, epsilon = 1e-12);
        assert_relative_eq!(stats.fz_min_mm.unwrap(), 500.0 / 60000.0, epsilon = 1e-12);
    }

    #[test]
    fn fz_mode_with_variable_feed_keeps_the_spacing() {
        let opts = Options::new(Mode::FeedPerTooth, 0.05, 4)
            .with_rpm(15000.0)
            .with_posture_feed_mm_min(vec![4000.0, 500.0]);
        let samples = resample(&line_path(1.0), &opts).unwrap();
        assert_eq!(samples.len(), 21);
        let last = samples.last().unwrap();
        assert_relative_eq!(last.t_s, 2.0 / (4500.0 / 60.0), epsilon = 1e-12);
        // Times are increasing and the spindle angle is Ω t.
        for w in samples.windows(2) {
            assert!(w[1].t_s > w[0].t_s);
            assert_relative_eq!(
                w[1].theta_rad,
                15000.0 * TAU / 60.0 * w[1].t_s,
                epsilon = 1e-9
            );
        }
    }

    #[test]
    fn fedrat_change_is_constant_over_each_move() {
        let mut path = line_path(1.0);
        let mut p = posture(2.0, 0.0, 0.0, MotionKind::Cut);
        p.feed_mm_min = Some(500.0);
        path.postures.push(p);
        let opts = Options::new(Mode::FeedPerTooth, 0.1, 2).with_rpm(5000.0);
        let mut samples = Vec::new();
        let stats = resample_with(&path, &opts, |s| samples.push(s.clone())).unwrap();
        assert_eq!(stats.variable_feed_moves, 0);
        assert_eq!(samples.len(), 21);
        // 1 mm at 1000 mm/min then 1 mm at 500 mm/min.
        assert_relative_eq!(samples.last().unwrap().t_s, 0.06 + 0.12, epsilon = 1e-12);
        assert_relative_eq!(samples[5].feed_mm_min, 1000.0);
        assert_relative_eq!(samples[15].feed_mm_min, 500.0);
        assert_relative_eq!(stats.fz_min_mm.unwrap(), 0.05, epsilon = 1e-12);
        assert_relative_eq!(stats.fz_max_mm.unwrap(), 0.1, epsilon = 1e-12);
        assert_eq!(stats.spindle_source, Some(SpindleSource::Option));
    }

    #[test]
    fn spindle_from_fz_and_feed_or_from_path() {
        let stats = resample_with(
            &line_path(1.0),
            &Options::new(Mode::FeedPerTooth, 0.05, 4),
            |_| {},
        )
        .unwrap();
        assert_eq!(stats.spindle_source, Some(SpindleSource::DerivedFromFeed));
        assert_relative_eq!(stats.spindle_rpm.unwrap(), 1000.0 / 0.2, epsilon = 1e-9);
        let mut path = line_path(1.0);
        for p in &mut path.postures {
            p.feed_mm_min = None;
            p.spindle_rpm = Some(8000.0);
        }
        let opts = Options::new(Mode::FeedPerTooth, 0.05, 4);
        let samples = resample(&path, &opts).unwrap();
        // V = Z fz n = 1600 mm/min.
        assert_relative_eq!(samples[0].feed_mm_min, 1600.0, epsilon = 1e-9);
        for p in &mut path.postures {
            p.spindle_rpm = None;
        }
        let err = resample(&path, &opts).unwrap_err();
        assert_eq!(err, ResampleError::MissingFeedAndSpindle);
        let msg = err.to_string();
        assert!(
            msg.contains("--feed-mm-min") && msg.contains("--rpm"),
            "{msg}"
        );
        assert!(resample(&path, &opts.clone().with_feed_mm_min(600.0)).is_ok());
    }

    #[test]
    fn invalid_options_and_feeds_are_errors() {
        let path = line_path(1.0);
        let e = |o: Options| resample(&path, &o).unwrap_err();
        assert_eq!(
            e(Options::new(Mode::FeedPerTooth, 0.0, 4)),
            ResampleError::InvalidFeedPerTooth(0.0)
        );
        assert_eq!(
            e(Options::new(Mode::FeedPerTooth, 0.05, 0)),
            ResampleError::NoTeeth
        );
        assert!(matches!(
            e(Options::new(
                Mode::SpindleStep {
                    dtheta_rad: f64::NAN
                },
                0.05,
                4
            )),
            ResampleError::InvalidSpindleStep(_)
        ));
        assert_eq!(
            e(Options::default().with_posture_feed_mm_min(vec![1.0])),
            ResampleError::PostureFeedLength {
                expected: 2,
                got: 1
            }
        );
        let mut zero = path.clone();
        zero.postures[1].line = 7;
        let opts = Options::default()
            .with_rpm(1000.0)
            .with_posture_feed_mm_min(vec![0.0, 0.0]);
        assert_eq!(
            resample(&zero, &opts).unwrap_err(),
            ResampleError::ZeroFeedMove { line: 7 }
        );
        // Starting from rest is fine: V = 0 at one end only.
        let opts = Options::default()
            .with_rpm(1000.0)
            .with_posture_feed_mm_min(vec![0.0, 600.0]);
        let samples = resample(&path, &opts).unwrap();
        assert_relative_eq!(samples.last().unwrap().t_s, 2.0 / 10.0, epsilon = 1e-12);
        let mut bad = path.clone();
        bad.postures[1].position.x = f64::NAN;
        assert!(matches!(
            resample(&bad, &Options::default()).unwrap_err(),
            ResampleError::InvalidPosture { line: 1, .. }
        ));
        let mut neg = path.clone();
        neg.postures[1].feed_mm_min = Some(-5.0);
        assert!(matches!(
            resample(&neg, &Options::default().with_rpm(100.0)).unwrap_err(),
            ResampleError::InvalidFeed { value: -5.0, .. }
        ));
    }

    #[test]
    fn a_path_without_cutting_moves_gives_no_samples() {
        let mut path = line_path(1.0);
        path.postures[1].motion = MotionKind::Rapid;
        path.postures[1].feed_mm_min = None;
        let stats =
            resample_with(&path, &Options::default(), |_| panic!("no sample expected")).unwrap();
        assert_eq!(
            (stats.samples, stats.runs, stats.non_cutting_moves),
            (0, 0, 1)
        );
        assert_eq!(stats.spindle_rpm, None);
    }

    #[test]
    fn arcs_are_sampled_on_the_circle() {
        // Quarter circle clockwise about +z, radius 10, at fz = 0.1.
        let mut path = line_path(0.0);
        path.postures[0].position = Point3::new(10.0, 0.0, 0.0);
        path.postures[1].position = Point3::new(0.0, -10.0, 0.0);
        path.postures[1].arc = Some(ArcMove {
            centre: Point3::origin(),
            axis: Vec3::z(),
            radius_mm: 10.0,
            extra_turns: 0,
        });
        let mut samples = Vec::new();
        let stats = resample_with(&path, &Options::new(Mode::FeedPerTooth, 0.1, 2), |s| {
            samples.push(s.clone())
        })
        .unwrap();
        assert_eq!(stats.arcs, 1);
        let len = 5.0 * PI;
        assert_relative_eq!(stats.length_mm, len, epsilon = 1e-12);
        assert_eq!(samples.len(), (len / 0.1).ceil() as usize + 1);
        for s in &samples {
            let r = s.position.coords.norm();
            assert_relative_eq!(r, 10.0, epsilon = 1e-9);
            assert!(s.position.x >= -1e-9 && s.position.y <= 1e-9);
            // Clockwise about +z: f = axis × radial direction... i.e. (y, −x)/r.
            let f = Vec3::new(s.position.y, -s.position.x, 0.0) / r;
            assert_relative_eq!(s.feed_dir, f, epsilon = 1e-9);
            let phi = s.s_mm / 10.0;
            assert_relative_eq!(
                s.position,
                Point3::new(10.0 * phi.cos(), -10.0 * phi.sin(), 0.0),
                epsilon = 1e-9
            );
        }
    }

    #[test]
    fn runs_restart_the_clock_and_rapids_are_skipped() {
        use MotionKind::*;
        let kinds = [From, Rapid, Cut, Cut, Rapid, Rapid, Cut, GoHome];
        let xs = [0.0, 1.0, 2.0, 3.0, 10.0, 11.0, 12.5, 0.0];
        let path = Toolpath {
            postures: kinds
                .iter()
                .zip(xs)
                .map(|(k, x)| posture(x, 0.0, 0.0, *k))
                .collect(),
            ..Default::default()
        };
        let mut samples = Vec::new();
        let stats = resample_with(&path, &Options::new(Mode::FeedPerTooth, 0.5, 2), |s| {
            samples.push(s.clone())
        })
        .unwrap();
        assert_eq!(stats.runs, 2);
        assert_eq!(stats.non_cutting_moves, 4);
        assert_eq!(stats.non_cutting_runs, 3);
        let run0: Vec<_> = samples.iter().filter(|s| s.run == 0).collect();
        let run1: Vec<_> = samples.iter().filter(|s| s.run == 1).collect();
        assert_eq!(run0.len(), 5);
        assert_eq!(run1.len(), 4);
        assert_eq!(run1[0].t_s, 0.0);
        assert_eq!(run1[0].theta_rad, 0.0);
        assert_relative_eq!(run1[0].s_mm, 2.0);
        assert_relative_eq!(run1[0].position.x, 11.0);
        assert_relative_eq!(run1.last().unwrap().s_mm, 3.5, epsilon = 1e-12);
        assert_relative_eq!(stats.length_mm, 3.5, epsilon = 1e-12);
    }

    #[test]
    fn degenerate_cases_are_counted() {
        use MotionKind::*;
        let mut ps = vec![
            posture(0.0, 0.0, 0.0, Rapid),
            posture(1.0, 0.0, 0.0, Cut),
            posture(1.0, 0.0, 0.0, Cut),  // zero length
            posture(1.0, 0.0, -1.0, Cut), // plunge along the axis (no contact data)
            posture(2.0, 0.0, -1.0, Cut), // axis flips to −z
            posture(2.0, 0.0, -1.0, Rapid),
            posture(2.0, 0.0, -1.0, Cut), // zero-length run
        ];
        ps[4].axis = -Vec3::z();
        let path = Toolpath {
            postures: ps,
            ..Default::default()
        };
        let mut samples = Vec::new();
        let stats = resample_with(&path, &Options::new(Mode::FeedPerTooth, 0.25, 2), |s| {
            samples.push(s.clone())
        })
        .unwrap();
        assert_eq!(stats.zero_length_moves, 2);
        assert_eq!(stats.zero_length_runs, 1);
        assert_eq!(stats.runs, 1);
        assert_eq!(stats.axis_flips, 1);
        assert!(stats.feed_parallel_to_axis >= 4, "{stats:?}");
        for s in &samples {
            assert_relative_eq!(s.axis.norm(), 1.0, epsilon = 1e-12);
            assert_relative_eq!(s.feed_dir.norm(), 1.0, epsilon = 1e-12);
            assert!(s.feed_dir.dot(&s.axis).abs() < 1e-9);
        }
        // During the plunge f keeps the previous feed direction (+x).
        let plunge: Vec<_> = samples
            .iter()
            .filter(|s| s.s_mm > 1.0 && s.s_mm < 2.0)
            .collect();
        assert!(!plunge.is_empty());
        for s in plunge {
            assert_relative_eq!(s.feed_dir, Vec3::x(), epsilon = 1e-12);
        }
    }

    #[test]
    fn contact_points_normals_and_frames() {
        let mut path = line_path(2.0);
        let lead = 15f64.to_radians();
        for (i, p) in path.postures.iter_mut().enumerate() {
            p.axis = Vec3::new(lead.sin(), 0.0, lead.cos());
            let x = 2.0 * i as f64;
            p.contact = Some(Contact {
                point: Point3::new(x, 0.0, -1.0),
                normal: Vec3::new(0.0, 0.1 * i as f64, 1.0).normalize(),
                normal_derived: false,
            });
        }
        let samples = resample(&path, &Options::new(Mode::FeedPerTooth, 0.5, 2)).unwrap();
        assert_eq!(samples.len(), 5);
        let mid = &samples[2];
        assert_relative_eq!(
            mid.contact.unwrap(),
            Point3::new(1.0, 0.0, -1.0),
            epsilon = 1e-12
        );
        let n = mid.normal.unwrap();
        // Slerp: half of the normal's turn of atan(0.1).
        let half = 0.5 * 0.1f64.atan();
        assert_relative_eq!(n, Vec3::new(0.0, half.sin(), half.cos()), epsilon = 1e-12);
        for s in &samples {
            let n = s.normal.unwrap();
            let f = s.feed_dir;
            let g = n.cross(&f);
            assert_relative_eq!(f.norm(), 1.0, epsilon = 1e-12);
            assert_relative_eq!(g.norm(), 1.0, epsilon = 1e-12);
            assert!(f.dot(&n).abs() < 1e-12);
            assert!(f.x > 0.99);
        }
        // Feed along the normal: f = (n × axis) × n, counted.
        let mut up = line_path(0.0);
        up.postures[1].position = Point3::new(0.0, 0.0, 1.0);
        for p in &mut up.postures {
            p.axis = Vec3::new(lead.sin(), 0.0, lead.cos());
            p.contact = Some(Contact {
                point: p.position,
                normal: Vec3::z(),
                normal_derived: true,
            });
        }
        let mut samples = Vec::new();
        let stats = resample_with(&up, &Options::new(Mode::FeedPerTooth, 0.5, 2), |s| {
            samples.push(s.clone())
        })
        .unwrap();
        assert_eq!(stats.normal_parallel_to_feed, 3);
        for s in &samples {
            assert_relative_eq!(s.feed_dir, Vec3::x(), epsilon = 1e-12);
        }
    }

    #[test]
    fn spline_passes_through_postures_and_is_smooth() {
        use MotionKind::*;
        let pts = [(0.0, 0.0), (1.0, 0.5), (2.0, 0.0), (3.0, 0.5), (4.0, 0.0)];
        let mut ps: Vec<_> = pts.iter().map(|(x, y)| posture(*x, *y, 0.0, Cut)).collect();
        ps[0].motion = Rapid;
        let path = Toolpath {
            postures: ps,
            ..Default::default()
        };
        let opts = Options::new(Mode::FeedPerTooth, 0.01, 2).with_spline(true);
        let samples = resample(&path, &opts).unwrap();
        let last = samples.last().unwrap();
        assert_relative_eq!(last.position, Point3::new(4.0, 0.0, 0.0), epsilon = 1e-12);
        // Longer than the polyline, and the direction turns by small steps only.
        assert!(last.s_mm > 4.0 * 1.25f64.sqrt());
        for w in samples.windows(2) {
            assert!(w[0].feed_dir.dot(&w[1].feed_dir) > 0.99);
            let chord = (w[1].position - w[0].position).norm();
            assert!(chord <= 0.01 + 1e-9 && chord > 0.0099 || w[1].s_mm == last.s_mm);
        }
        // It passes through the interior postures.
        for (x, y) in &pts[1..4] {
            let p = Point3::new(*x, *y, 0.0);
            let d = samples
                .iter()
                .map(|s| (s.position - p).norm())
                .fold(f64::MAX, f64::min);
            assert!(d < 0.006, "{d}");
        }
    }
}
