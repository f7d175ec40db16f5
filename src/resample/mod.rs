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
