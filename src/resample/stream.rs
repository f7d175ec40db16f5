//! The streaming resampler: postures in, samples out, one pass, one sample at a time.
//!
//! Memory does not depend on the path length: [`Resampler`] keeps the postures of the move
//! it is about to walk and their neighbours (for the spline tangents), the current move,
//! the last sample (held back so that a grid sample falling on the end of a run is replaced
//! by the exact end) and the last feed direction (a fallback when the tangent is
//! degenerate). [`resample_with`] is its in-memory form.
use super::spindle::{SpindleScan, SpindleSource};
use super::walker::{Clock, Entry, Params, RunWalker};
use super::{Mode, Options, ResampleError, Sample, Stats, Streamed};
use crate::toolpath::{MotionKind, Posture, Toolpath};
use std::f64::consts::TAU;

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
    resample_streamed(path, opts, |s| {
        if let Streamed::Sample(s) = s {
            sink(s);
        }
    })
}

/// [`resample_with`], handing on the clock of every sample of a move far from
/// [`Options::near`] as [`Streamed::Far`] instead of building it.
pub fn resample_streamed(
    path: &Toolpath,
    opts: &Options,
    mut sink: impl FnMut(Streamed<'_>),
) -> Result<Stats, ResampleError> {
    validate(opts)?;
    let feeds = opts.posture_feed_mm_min.as_deref();
    if let Some(feeds) = feeds
        && feeds.len() != path.postures.len()
    {
        return Err(ResampleError::PostureFeedLength {
            expected: path.postures.len(),
            got: feeds.len(),
        });
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
    r.finish_streamed(&mut sink)
}

fn validate(opts: &Options) -> Result<(), ResampleError> {
    if !(opts.fz_mm.is_finite() && opts.fz_mm > 0.0) {
        return Err(ResampleError::InvalidFeedPerTooth(opts.fz_mm));
    }
    if opts.teeth == 0 {
        return Err(ResampleError::NoTeeth);
    }
    if let Mode::SpindleStep { dtheta_rad } = opts.mode
        && !(dtheta_rad.is_finite() && dtheta_rad > 0.0)
    {
        return Err(ResampleError::InvalidSpindleStep(dtheta_rad));
    }
    if let Some(rpm) = opts.rpm
        && !(rpm.is_finite() && rpm > 0.0)
    {
        return Err(ResampleError::InvalidSpindle(rpm));
    }
    if let Some(v) = opts.feed_mm_min
        && !(v.is_finite() && v > 0.0)
    {
        return Err(ResampleError::InvalidOptionFeed(v));
    }
    Ok(())
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
    spindle_from_path: bool,
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
                near: opts.near,
            },
            opts_rpm: opts.rpm,
            spindle_from_path: opts.spindle_from_path,
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
        self.push_entry(p, None, built(sink))
    }

    /// [`Resampler::push`] with the posture's own feed, mm/min (per-posture feeds,
    /// [`Options::posture_feed_mm_min`]).
    pub fn push_with_feed(
        &mut self,
        p: &Posture,
        feed_mm_min: f64,
        sink: impl FnMut(&Sample),
    ) -> Result<(), ResampleError> {
        self.push_entry(p, Some(feed_mm_min), built(sink))
    }

    fn push_entry(
        &mut self,
        p: &Posture,
        feed: Option<f64>,
        mut sink: impl FnMut(Streamed<'_>),
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
        let (rpm, source) = match self.spindle {
            Some(s) => s,
            None => {
                let opts = Options {
                    rpm: self.opts_rpm,
                    feed_mm_min: self.params.feed_mm_min,
                    teeth: self.teeth,
                    fz_mm: self.params.fz_mm,
                    mode: self.params.mode,
                    spindle_from_path: self.spindle_from_path,
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
            timeless: source == SpindleSource::Nominal,
        };
        self.clock = Some(clock);
        Ok(clock)
    }

    fn close_run(&mut self, sink: &mut impl FnMut(Streamed<'_>)) -> Result<(), ResampleError> {
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
    pub fn finish(self, sink: impl FnMut(&Sample)) -> Result<Stats, ResampleError> {
        self.finish_streamed(built(sink))
    }

    fn finish_streamed(
        mut self,
        mut sink: impl FnMut(Streamed<'_>),
    ) -> Result<Stats, ResampleError> {
        self.close_run(&mut sink)?;
        let mut stats = self.stats;
        if self.runs_seen == 0 {
            stats.spindle_rpm = self.opts_rpm;
            stats.spindle_source = self.opts_rpm.map(|_| SpindleSource::Option);
        } else {
            stats.spindle_rpm = self.spindle.map(|s| s.0);
            stats.spindle_source = self.spindle.map(|s| s.1);
        }
        if self.clock.is_some_and(|c| c.timeless) {
            stats.duration_s = f64::NAN;
            stats.spindle_rpm = None;
        }
        Ok(stats)
    }
}

/// A sink of built samples as a sink of streamed ones (there are no far ones without
/// [`Options::near`]).
fn built(mut sink: impl FnMut(&Sample)) -> impl FnMut(Streamed<'_>) {
    move |s| {
        if let Streamed::Sample(s) = s {
            sink(s);
        }
    }
}

/// The sample sink with the per-sample counts (feed and feed-per-tooth range).
fn emitter<'s>(
    sink: &'s mut impl FnMut(Streamed<'_>),
) -> impl FnMut(Streamed<'_>, &Clock, &mut Stats) + 's {
    move |s: Streamed<'_>, clock: &Clock, stats: &mut Stats| {
        stats.samples += s.count();
        let feed = s.feed_mm_min();
        let fz = feed / (clock.teeth * clock.rpm);
        stats.feed_min_mm_min = Some(stats.feed_min_mm_min.map_or(feed, |m| m.min(feed)));
        stats.feed_max_mm_min = Some(stats.feed_max_mm_min.map_or(feed, |m| m.max(feed)));
        stats.fz_min_mm = Some(stats.fz_min_mm.map_or(fz, |m| m.min(fz)));
        stats.fz_max_mm = Some(stats.fz_max_mm.map_or(fz, |m| m.max(fz)));
        sink(s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Point3, Vec3};
    use crate::resample::AxisInterpolation;
    use crate::resample::Streamed;
    use crate::toolpath::{ArcMove, Contact};
    use approx::assert_relative_eq;
    use std::f64::consts::PI;

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
        // Feed per tooth needs no clock: θ follows the arc length, no time, no feed.
        let samples = resample(&path, &opts).unwrap();
        assert!(samples.len() > 2);
        for s in &samples {
            assert!(s.t_s.is_nan() && s.feed_mm_min.is_nan());
            assert_relative_eq!(
                s.theta_rad,
                std::f64::consts::TAU * s.s_mm / (4.0 * 0.05),
                epsilon = 1e-9
            );
        }
        // A spindle step does.
        let dtheta = Options::new(Mode::SpindleStep { dtheta_rad: 0.1 }, 0.05, 4);
        let err = resample(&path, &dtheta).unwrap_err();
        assert_eq!(err, ResampleError::MissingFeedAndSpindle);
        let msg = err.to_string();
        assert!(
            msg.contains("‹feed_mm_min›") && msg.contains("‹rpm›"),
            "{msg}"
        );
        assert!(resample(&path, &dtheta.clone().with_feed_mm_min(600.0)).is_ok());
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

    /// A zig-zag of straight passes joined by half circles, its feed changing from posture
    /// to posture, the axis tilting, contacts on every posture, a rapid halfway.
    fn zigzag() -> Toolpath {
        use MotionKind::*;
        let mut ps = vec![posture(0.0, 0.0, 5.0, Rapid)];
        ps.push(posture(0.0, 0.0, 0.0, Cut));
        for pass in 0..6 {
            let y = pass as f64;
            let (x0, x1) = if pass % 2 == 0 {
                (0.0, 10.0)
            } else {
                (10.0, 0.0)
            };
            for k in 1..=8 {
                let x = x0 + (x1 - x0) * k as f64 / 8.0;
                let mut p = posture(x, y, 0.1 * (x * 0.7).sin(), Cut);
                p.feed_mm_min = Some(800.0 + 300.0 * (k as f64 * 1.3 + y).sin());
                let t = 0.3 * (x / 10.0 - 0.5);
                p.axis = Vec3::new(t.sin(), 0.0, t.cos());
                p.contact = Some(Contact {
                    point: p.position - p.axis * 0.5,
                    normal: Vec3::new(0.1 * t, 0.05, 1.0),
                    normal_derived: false,
                });
                ps.push(p);
            }
            if pass == 2 {
                ps.push(posture(x1, y, 5.0, Rapid));
                ps.push(posture(x1, y + 1.0, 5.0, Rapid));
                ps.push(posture(x1, y + 1.0, 0.0, Rapid));
            } else {
                // Half a circle to the next pass (clockwise about ±z).
                let mut p = posture(x1, y + 1.0, 0.0, Cut);
                p.arc = Some(ArcMove {
                    centre: Point3::new(x1, y + 0.5, 0.0),
                    axis: if pass % 2 == 0 { -Vec3::z() } else { Vec3::z() },
                    radius_mm: 0.5,
                    extra_turns: 0,
                });
                ps.push(p);
            }
        }
        Toolpath {
            postures: ps,
            ..Default::default()
        }
    }

    #[test]
    fn far_moves_stream_their_clock_and_near_ones_the_same_samples() {
        let path = zigzag();
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for (mode, spline) in [
            (Mode::FeedPerTooth, false),
            (dtheta(7.0), false),
            (Mode::FeedPerTooth, true),
        ] {
            let opts = Options::new(mode, 0.05, 2)
                .with_rpm(6000.0)
                .with_spline(spline);
            let mut full = Vec::new();
            let full_stats = resample_with(&path, &opts, |s| full.push(s.clone())).unwrap();
            for _ in 0..12 {
                let c = Point3::new(12.0 * next() - 1.0, 7.0 * next() - 1.0, 0.0);
                let h = Vec3::new(0.1 + 2.0 * next(), 0.1 + 2.0 * next(), 0.2);
                let (lo, hi) = (c - h, c + h);
                let inside = |p: &Point3| (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k]);
                let near = opts.clone().with_near(lo, hi);
                let (mut built, mut far, mut together) = (0, 0, 0);
                let mut i = 0;
                let stats = resample_streamed(&path, &near, |s| {
                    if let Streamed::FarRun(r) = s {
                        // Samples of one move at one feed, together: each is as built.
                        let n = usize::try_from(r.count).unwrap();
                        assert!(n >= 1);
                        for f in &full[i..i + n] {
                            assert!(!inside(&f.position), "sample {i} in the box left unbuilt");
                            assert_eq!(f.run, r.run, "sample {i}");
                            assert_eq!(f.feed_mm_min.to_bits(), r.feed_mm_min.to_bits());
                        }
                        assert_eq!(full[i + n - 1].t_s.to_bits(), r.t_s.to_bits());
                        i += n;
                        far += n;
                        together += 1;
                        return;
                    }
                    let f = &full[i];
                    match s {
                        Streamed::Sample(s) => {
                            assert_eq!(s, f, "sample {i}");
                            built += 1;
                        }
                        Streamed::Far(x) => {
                            assert!(!inside(&f.position), "sample {i} in the box left unbuilt");
                            assert_eq!(
                                (x.run, x.s_mm, x.theta_rad),
                                (f.run, f.s_mm, f.theta_rad),
                                "sample {i}"
                            );
                            assert_eq!(x.t_s.to_bits(), f.t_s.to_bits());
                            assert_eq!(x.feed_mm_min.to_bits(), f.feed_mm_min.to_bits());
                            far += 1;
                        }
                        Streamed::FarRun(_) => unreachable!(),
                    }
                    i += 1;
                })
                .unwrap();
                assert_eq!(i, full.len());
                // The same counts, but for the feed directions of unbuilt samples.
                let directions = |s: &Stats| {
                    let mut s = s.clone();
                    s.normal_parallel_to_feed = 0;
                    s.feed_parallel_to_axis = 0;
                    s
                };
                assert_eq!(directions(&stats), directions(&full_stats));
                // Every sample in the box was built, and boxes away from the path skip most.
                let wanted = full.iter().filter(|s| inside(&s.position)).count();
                assert!(built >= wanted, "{built} < {wanted}");
                assert_eq!(built + far, full.len());
                // Even feed per tooth hands the far samples of a move on together.
                if mode == Mode::FeedPerTooth && far > 20 {
                    assert!(together > 0, "{far} far samples, none together");
                }
            }
            // A box beside the path builds nothing but the ends of the runs.
            let near = opts
                .clone()
                .with_near(Point3::new(20.0, 20.0, -1.0), Point3::new(21.0, 21.0, 1.0));
            let mut built = 0;
            resample_streamed(&path, &near, |s| {
                built += usize::from(matches!(s, Streamed::Sample(_)))
            })
            .unwrap();
            assert_eq!(built, 2, "{mode:?}");
        }
    }
}
