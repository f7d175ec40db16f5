//! How many samples a resampling will make, estimated before any work from the cutting
//! length, the number of runs and the range of feeds: what the commands check against their
//! budgets (a typo that makes a path 100 km long must not stream gigabytes first).

use super::Mode;

/// What a path gives the estimate: cutting length, cutting runs, the slowest and fastest
/// programmed feed of its cutting moves (mm/min, `None` when it has none).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PathExtent {
    /// Length of the cutting moves, mm.
    pub cutting_mm: f64,
    /// Cutting runs (both ends of a run are kept).
    pub runs: usize,
    /// Slowest and fastest programmed feed, mm/min.
    pub feed_range_mm_min: Option<(f64, f64)>,
    /// The highest programmed spindle speed (SPINDL), rpm.
    pub spindle_rpm: Option<f64>,
}

/// An upper estimate of the samples a resampling of `extent` makes in `mode` with feed per
/// tooth `fz_mm`, `teeth` teeth and, when given, spindle speed `rpm` (then a Δθ step's
/// length follows the slowest feed).
pub fn estimate_samples(
    extent: &PathExtent,
    mode: Mode,
    fz_mm: f64,
    teeth: usize,
    rpm: Option<f64>,
) -> f64 {
    let per_rev = fz_mm * teeth.max(1) as f64;
    let step = match mode {
        Mode::FeedPerTooth => fz_mm,
        Mode::SpindleStep { dtheta_rad } => {
            let travel_per_rev = match (rpm, extent.feed_range_mm_min) {
                (Some(n), Some((lo, _))) if n > 0.0 && lo > 0.0 => lo / n,
                _ => per_rev,
            };
            travel_per_rev * dtheta_rad / std::f64::consts::TAU
        }
    };
    if !(step > 0.0 && step.is_finite()) {
        return f64::INFINITY;
    }
    extent.cutting_mm / step + 2.0 * extent.runs as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_follow_length_and_step() {
        let e = PathExtent {
            cutting_mm: 100.0,
            runs: 5,
            feed_range_mm_min: Some((1000.0, 2000.0)),
            spindle_rpm: None,
        };
        assert_eq!(
            estimate_samples(&e, Mode::FeedPerTooth, 0.05, 4, None),
            2010.0
        );
        // Δθ = 1°, Z fz = 0.2 mm per turn: 0.2/360 mm per sample.
        let d = Mode::SpindleStep {
            dtheta_rad: 1f64.to_radians(),
        };
        assert!((estimate_samples(&e, d, 0.05, 4, None) - (100.0 * 1800.0 + 10.0)).abs() < 1e-6);
        // With the spindle speed given the slowest feed sets the step: 1000/10000 mm per turn.
        assert!(
            (estimate_samples(&e, d, 0.05, 4, Some(10000.0)) - (100.0 * 3600.0 + 10.0)).abs()
                < 1e-6
        );
    }
}
