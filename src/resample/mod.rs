//! Resampling the tool path onto the cutting edge's own clock (002 §2.4, 001 Eqs 1-6):
//! even feed per tooth (`fz` mode) or a constant spindle step Δθ (`dtheta` mode), with the
//! tool axis interpolated on the unit sphere and the local frame (f, g, n) at every sample.

use crate::math::{Point3, Vec3};

/// One resampled posture.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// Index of the cutting run this sample belongs to (0-based; runs restart the clock).
    pub run: usize,
    /// Arc length of the CL point from the start of the path's first cutting run, mm.
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
}
