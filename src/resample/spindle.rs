//! The spindle speed of a resampling: where it comes from ([`SpindleSource`]) and the
//! rule that resolves it from the postures of a path ([`SpindleScan`]).

use super::{Options, ResampleError};
use crate::toolpath::{MotionKind, Posture};

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
    /// None known (no feed, no spindle speed) for a feed-per-tooth spacing, which needs no
    /// clock: a nominal 1 rpm makes θ follow the arc length (θ = 2π s / (Z fz)); the
    /// samples carry no time and no feed.
    Nominal,
}

/// The spindle-speed rule of the module docs, fed one posture at a time: n = `--rpm`,
/// else V_ref/(Z·fz) with V_ref the highest feed of the cutting moves, else the first
/// SPINDL met in a cutting run.
///
/// V_ref is a maximum over the whole path, so a streaming caller that does not know the
/// spindle speed beforehand either scans the path first or lets
/// [`Resampler`](super::Resampler) resolve it from the postures seen so far and compares
/// with this scan at the end (`crest resample` does the latter and resamples again in the
/// rare case they differ).
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

    pub(super) fn push_entry(&mut self, p: &Posture, posture_feed: Option<f64>) {
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
        if opts.spindle_from_path {
            return match self.first_spindle {
                Some(rpm) if rpm.is_finite() && rpm > 0.0 => Ok(Some((rpm, SpindleSource::Path))),
                Some(rpm) => Err(ResampleError::InvalidSpindle(rpm)),
                None => Err(ResampleError::MissingSpindle),
            };
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
            None if opts.mode == super::Mode::FeedPerTooth => {
                Ok(Some((1.0, SpindleSource::Nominal)))
            }
            None => Err(ResampleError::MissingFeedAndSpindle),
        }
    }
}
