//! Physical plausibility limits: values beyond them are not machining (a typo, a unit
//! mix-up, a hostile file) and are refused at the interface with the key or option named,
//! before they can cost unbounded time or memory. README ("Limits") lists them.

/// Largest coordinate of a tool path or part, mm (100 m).
pub const MAX_COORD_MM: f64 = 1.0e5;
/// Largest tool radius, mm.
pub const MAX_TOOL_RADIUS_MM: f64 = 500.0;
/// Feed range, mm/min (1 µm/min … 1000 m/min).
pub const FEED_MM_MIN: (f64, f64) = (1.0e-3, 1.0e6);
/// Spindle-speed range, rpm.
pub const RPM: (f64, f64) = (1.0e-3, 1.0e6);
/// Feed-per-tooth range, mm (1 nm … 100 mm).
pub const FZ_MM: (f64, f64) = (1.0e-6, 100.0);
/// Smallest ICE spindle step Δθ, degrees.
pub const MIN_DTHETA_DEG: f64 = 1.0e-3;
/// Largest number of nodes of a simulated grid or map.
pub const MAX_NODES: usize = 400_000_000;
/// Largest number of resampled poses a simulation may generate before culling.
pub const MAX_SAMPLES: u64 = 1_000_000_000;

/// `v` if it lies in `range` (inclusive) and is finite, else an error naming `what` with its
/// unit.
pub fn within(what: &str, unit: &str, v: f64, range: (f64, f64)) -> Result<f64, String> {
    if v.is_finite() && v >= range.0 && v <= range.1 {
        Ok(v)
    } else {
        Err(format!(
            "{what} must lie between {} and {} {unit}, got {v}",
            range.0, range.1
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn within_names_the_value_and_its_range() {
        assert_eq!(within("fz", "mm", 0.05, FZ_MM), Ok(0.05));
        let e = within("--fz-mm", "mm", 1e305, FZ_MM).unwrap_err();
        assert!(
            e.contains("--fz-mm") && e.contains("1e305") || e.contains("100000"),
            "{e}"
        );
        assert!(within("rpm", "rpm", f64::NAN, RPM).is_err());
    }
}
