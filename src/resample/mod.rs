//! Resampling the tool path onto the cutting edge's own clock (002 §2.4, 001 Eqs 1-6):
//! even feed per tooth (`fz` mode) or a constant spindle step Δθ (`dtheta` mode), with the
//! tool axis interpolated on the unit sphere and the local frame (f, g, n) at every sample.
//!
//! The surface simulation needs the tool where each tooth actually is, not where the CAM
//! system happened to put a posture, so the path is re-cut on its own clock:
//!
//! * **Geometry.** Each cutting run
//!   ([`Toolpath::cutting_runs`](crate::toolpath::Toolpath::cutting_runs)) is walked move
//!   by move: straight lines, arcs ([`crate::toolpath::ArcMove`], clockwise about their axis, extra
//!   turns, helical when the end is higher along the axis) or, with [`Options::spline`],
//!   cubic Hermite curves through the postures. The tool axis, CC point and normal are
//!   interpolated with the move's parameter u (axis and normal by slerp or nlerp,
//!   renormalised; model.md §5.1).
//! * **Clock.** Within a move the feed is linear in time (model.md §5.3):
//!   Δt = 2L/(V_i + V_{i+1}), θ = Ω t. Programmed feeds (FEDRAT) are constant over a move
//!   (the move's own modal feed); per-posture feeds ([`Options::posture_feed_mm_min`],
//!   e.g. predicted by `kinematics`) vary linearly in time between the postures.
//! * **Spindle speed.** [`Options::rpm`] when given. Otherwise the nominal feed per tooth
//!   is authoritative: n = V_ref/(Z·fz), with V_ref the highest programmed feed of the
//!   cutting moves ([`Options::feed_mm_min`], else FEDRAT, else the highest posture feed),
//!   so that at the programmed feed θ(S) = 2πS/(Z·fz) exactly (model.md §5.2). Only a path
//!   without any feed uses its SPINDL speed, with V = Z·fz·n.
//! * **Spacing.** [`Mode::FeedPerTooth`]: every fz of arc length; [`Mode::SpindleStep`]:
//!   every Δθ of spindle angle, i.e. ΔS = V·Δθ/Ω (= Z·fz·Δθ/2π at the programmed feed, and
//!   the local fz follows the feed where it varies). Both ends of every run are kept; the
//!   last step of a run is the remainder. s accumulates over the cutting runs; t and θ
//!   restart at 0 at every run (the spindle phase between runs is unknown).
//! * **Frame.** f = path tangent projected on the tangent plane of the interpolated normal
//!   (on the plane normal to the tool axis when there is no contact data), g = n × f.
//!
//! Degenerate input is handled and counted in [`Stats`], never silently wrong.
//!
//! ```
//! use crest::math::{Point3, Vec3};
//! use crest::resample::{resample, Mode, Options};
//! use crest::toolpath::{MotionKind, Posture, Toolpath};
//!
//! let posture = |x: f64, motion| Posture {
//!     position: Point3::new(x, 0.0, 0.0),
//!     axis: Vec3::z(),
//!     motion,
//!     arc: None,
//!     contact: None,
//!     feed_mm_min: Some(1000.0),
//!     spindle_rpm: None,
//!     line: 0,
//! };
//! let path = Toolpath {
//!     postures: vec![posture(0.0, MotionKind::Rapid), posture(1.0, MotionKind::Cut)],
//!     ..Default::default()
//! };
//! // Z = 4, fz = 0.05 mm, Δθ = 1°: ΔS = 5.5556e-4 mm, θ(S = 1 mm) = 31.4159 rad.
//! let opts = Options::new(Mode::SpindleStep { dtheta_rad: 1f64.to_radians() }, 0.05, 4);
//! let samples = resample(&path, &opts).unwrap();
//! let last = samples.last().unwrap();
//! assert!((last.s_mm - 1.0).abs() < 1e-12);
//! assert!((last.theta_rad - 31.4159).abs() < 1e-4);
//! ```

mod curve;
mod estimate;
mod sphere;
mod spindle;
mod stream;
mod walker;

pub use estimate::{PathExtent, estimate_samples};
pub use spindle::{SpindleScan, SpindleSource};
pub use stream::{Resampler, resample, resample_streamed, resample_with};

use crate::math::{Point3, Vec3};
use thiserror::Error;

/// One resampled posture.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// Index of the cutting run this sample belongs to (0-based; runs restart the clock).
    pub run: usize,
    /// Arc length of the CL point along the cutting moves, mm: 0 at the start of the
    /// path's first cutting run, accumulated over the runs (non-cutting moves add nothing).
    pub s_mm: f64,
    /// Time, s.
    pub t_s: f64,
    /// Unwrapped spindle angle θ, rad (model.md §1.3).
    pub theta_rad: f64,
    /// CL point (tool tip), mm.
    pub position: Point3,
    /// Unit tool axis.
    pub axis: Vec3,
    /// CC point, when the path has contact data.
    pub contact: Option<Point3>,
    /// Unit surface normal, when the path has contact data.
    pub normal: Option<Vec3>,
    /// Unit feed direction f: the path tangent, projected on the tangent plane when the
    /// normal is known, else normal to the tool axis.
    pub feed_dir: Vec3,
    /// Local feed, mm/min.
    pub feed_mm_min: f64,
}

/// A sample of a move that cannot come near [`Options::near`]: its clock only (the
/// values a built [`Sample`] would carry).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Far {
    /// Index of the cutting run.
    pub run: usize,
    /// Arc length, mm.
    pub s_mm: f64,
    /// Time, s.
    pub t_s: f64,
    /// Spindle angle θ, rad.
    pub theta_rad: f64,
    /// Local feed, mm/min.
    pub feed_mm_min: f64,
}

/// Consecutive samples of one move far from [`Options::near`] at one feed: their count and
/// the clock of the last (the time grows along a run, so it is the latest).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FarRun {
    /// Index of the cutting run.
    pub run: usize,
    /// Samples (at least one).
    pub count: u64,
    /// Time of the last, s.
    pub t_s: f64,
    /// Local feed of every one, mm/min.
    pub feed_mm_min: f64,
}

/// What a resampling hands on: a built sample, or the clock of one or several far from
/// [`Options::near`].
#[derive(Debug, Clone, Copy)]
pub enum Streamed<'a> {
    /// A sample with its pose.
    Sample(&'a Sample),
    /// A sample of a move that cannot come near the box.
    Far(&'a Far),
    /// Samples of a move that cannot come near the box, at one feed (a move with the same
    /// feed at both ends), handed on together.
    FarRun(&'a FarRun),
}

impl Streamed<'_> {
    /// Index of the cutting run.
    pub fn run(&self) -> usize {
        match self {
            Streamed::Sample(s) => s.run,
            Streamed::Far(f) => f.run,
            Streamed::FarRun(r) => r.run,
        }
    }

    /// Time, s (of the last, for several).
    pub fn t_s(&self) -> f64 {
        match self {
            Streamed::Sample(s) => s.t_s,
            Streamed::Far(f) => f.t_s,
            Streamed::FarRun(r) => r.t_s,
        }
    }

    /// Local feed, mm/min.
    pub fn feed_mm_min(&self) -> f64 {
        match self {
            Streamed::Sample(s) => s.feed_mm_min,
            Streamed::Far(f) => f.feed_mm_min,
            Streamed::FarRun(r) => r.feed_mm_min,
        }
    }

    /// Samples handed on.
    pub fn count(&self) -> u64 {
        match self {
            Streamed::Sample(_) | Streamed::Far(_) => 1,
            Streamed::FarRun(r) => r.count,
        }
    }
}

/// How samples are spaced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mode {
    /// Instantaneous positions every fz of arc length (002 §2.4.1).
    FeedPerTooth,
    /// Constant spindle step Δθ, rad (002 §2.4.2, Eq 13 with Z inserted).
    SpindleStep {
        /// Δθ, rad.
        dtheta_rad: f64,
    },
}

/// How the tool axis is interpolated between postures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AxisInterpolation {
    /// Spherical linear interpolation (default).
    #[default]
    Slerp,
    /// Normalised linear interpolation (the model.md reference).
    Nlerp,
}

/// Options of a resampling.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Spacing mode.
    pub mode: Mode,
    /// Nominal feed per tooth, mm.
    pub fz_mm: f64,
    /// Number of teeth Z.
    pub teeth: usize,
    /// Spindle speed, rpm; `None` = from the path's SPINDL.
    pub rpm: Option<f64>,
    /// Feed, mm/min; `None` = from the path's FEDRAT.
    pub feed_mm_min: Option<f64>,
    /// Feed per posture, mm/min (e.g. predicted by `kinematics`), overriding the above;
    /// same length as the path's postures.
    pub posture_feed_mm_min: Option<Vec<f64>>,
    /// Tool-axis interpolation.
    pub axis_interpolation: AxisInterpolation,
    /// Interpolate positions on a cubic spline through the postures instead of lines/arcs.
    pub spline: bool,
    /// Take the spindle speed from the path's SPINDL (after [`Options::rpm`]) and never
    /// derive it from the feed: for a Δθ resampling whose feed per tooth is not known.
    pub spindle_from_path: bool,
    /// Build only the samples of moves that may come into this box (lower, upper corner):
    /// the others stream as [`Far`] (their clock only), so that a patch costs the moves
    /// near it; [`Stats`] then counts degenerate feed directions of built samples only.
    /// `None`: build every sample.
    pub near: Option<(Point3, Point3)>,
}

impl Default for Options {
    /// The 002 case: fz = 0.05 mm, Z = 4, `fz` mode, feed and spindle from the path,
    /// slerp, no spline.
    fn default() -> Self {
        Options {
            mode: Mode::FeedPerTooth,
            fz_mm: 0.05,
            teeth: 4,
            rpm: None,
            feed_mm_min: None,
            posture_feed_mm_min: None,
            axis_interpolation: AxisInterpolation::Slerp,
            spline: false,
            spindle_from_path: false,
            near: None,
        }
    }
}

impl Options {
    /// Options with the given mode, nominal feed per tooth (mm) and number of teeth; the
    /// rest as in [`Options::default`].
    pub fn new(mode: Mode, fz_mm: f64, teeth: usize) -> Options {
        Options {
            mode,
            fz_mm,
            teeth,
            ..Options::default()
        }
    }

    /// Set the spindle speed, rpm.
    pub fn with_rpm(mut self, rpm: f64) -> Options {
        self.rpm = Some(rpm);
        self
    }

    /// Set a constant feed, mm/min, overriding the path's FEDRAT.
    pub fn with_feed_mm_min(mut self, feed_mm_min: f64) -> Options {
        self.feed_mm_min = Some(feed_mm_min);
        self
    }

    /// Set one feed per posture, mm/min (same length as the path's postures).
    pub fn with_posture_feed_mm_min(mut self, feeds: Vec<f64>) -> Options {
        self.posture_feed_mm_min = Some(feeds);
        self
    }

    /// Build only the samples of moves that may come into the box `lo`…`hi`
    /// ([`Options::near`]).
    pub fn with_near(mut self, lo: Point3, hi: Point3) -> Options {
        self.near = Some((lo, hi));
        self
    }

    /// Set the tool-axis interpolation.
    pub fn with_axis_interpolation(mut self, axis_interpolation: AxisInterpolation) -> Options {
        self.axis_interpolation = axis_interpolation;
        self
    }

    /// Interpolate positions on cubic Hermite curves through the postures (smooth
    /// trochoid plots) instead of straight lines; arcs stay arcs.
    pub fn with_spline(mut self, spline: bool) -> Options {
        self.spline = spline;
        self
    }

    /// The arc-length step of [`Mode::SpindleStep`] at the nominal fz: ΔS = Z·fz·Δθ/2π, mm
    /// (model.md §5.2); the step itself in [`Mode::FeedPerTooth`].
    pub fn nominal_step_mm(&self) -> f64 {
        match self.mode {
            Mode::FeedPerTooth => self.fz_mm,
            Mode::SpindleStep { dtheta_rad } => {
                self.teeth as f64 * self.fz_mm * dtheta_rad / std::f64::consts::TAU
            }
        }
    }
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

/// Why a path could not be resampled.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum ResampleError {
    /// The feed per tooth is zero, negative or not finite.
    #[error("feed per tooth must be positive and finite, got {0} mm")]
    InvalidFeedPerTooth(f64),
    /// Zero teeth.
    #[error("the number of teeth must be at least 1")]
    NoTeeth,
    /// The spindle step is zero, negative or not finite.
    #[error("spindle step must be positive and finite, got {0} rad")]
    InvalidSpindleStep(f64),
    /// The spindle speed is zero, negative or not finite.
    #[error("spindle speed must be positive and finite, got {0} rpm")]
    InvalidSpindle(f64),
    /// A feed is negative or not finite (or zero where it must be positive).
    #[error("invalid feed {value} mm/min at line {line}")]
    InvalidFeed {
        /// Source line of the posture.
        line: u32,
        /// The feed, mm/min.
        value: f64,
    },
    /// The feed given in the options is zero, negative or not finite.
    #[error("the feed must be positive and finite, got {0} mm/min")]
    InvalidOptionFeed(f64),
    /// Neither a feed nor a spindle speed is known.
    #[error(
        "no feed and no spindle speed: the path has no FEDRAT or SPINDL; set a feed \
         (Options::feed_mm_min, ‹feed_mm_min›) or a spindle speed (Options::rpm, ‹rpm›)"
    )]
    MissingFeedAndSpindle,
    /// The spindle speed must come from the path, which has no SPINDL.
    #[error(
        "no spindle speed: the path has no SPINDL; give ‹rpm› (or ‹fz_mm› and ‹teeth› to \
         derive it from the feed)"
    )]
    MissingSpindle,
    /// The per-posture feeds do not match the postures.
    #[error("{got} posture feeds for {expected} postures")]
    PostureFeedLength {
        /// Number of postures.
        expected: usize,
        /// Number of feeds given.
        got: usize,
    },
    /// A move whose feed is zero at both ends has no duration (model.md §5.3).
    #[error("the move ending at line {line} has zero feed at both ends: its duration is undefined")]
    ZeroFeedMove {
        /// Source line of the posture the move ends at.
        line: u32,
    },
    /// A posture has a non-finite coordinate or a zero tool axis.
    #[error("invalid posture at line {line}: {what}")]
    InvalidPosture {
        /// Source line of the posture.
        line: u32,
        /// What is wrong, lower case.
        what: &'static str,
    },
}
