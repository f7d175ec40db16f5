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

/// `v` as a message shows it: plain decimals for ordinary magnitudes, scientific notation
/// (`1e300`, `3e-9`) past them, where Rust's `Display` would write every digit (a hostile
/// `1e300` is 301 characters).
pub fn shown(v: f64) -> String {
    let a = v.abs();
    if v.is_finite() && v != 0.0 && !(1e-4..1e9).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// `v` if it lies in `range` (inclusive) and is finite, else an error naming `what` with its
/// unit.
pub fn within(what: &str, unit: &str, v: f64, range: (f64, f64)) -> Result<f64, String> {
    if v.is_finite() && v >= range.0 && v <= range.1 {
        Ok(v)
    } else {
        Err(format!(
            "{what} must lie between {} and {} {unit}, got {}",
            range.0,
            range.1,
            shown(v)
        ))
    }
}

/// A tool radius R (also D/2 of a CLSF `TLDATA` or `CUTTER`): finite, in
/// (0, [`MAX_TOOL_RADIUS_MM`]]. The error is the rule it breaks ("must …"), for the caller
/// to name the key or record and the value: tool.toml and the lowering share this rule.
pub fn tool_radius(r: f64) -> Result<f64, String> {
    if r > 0.0 && r <= MAX_TOOL_RADIUS_MM {
        Ok(r)
    } else {
        Err(format!("must lie in (0, {MAX_TOOL_RADIUS_MM}] mm"))
    }
}

/// A corner radius `rc` of a tool of radius `r`: finite, in [0, r]. The error is the rule
/// it breaks, as for [`tool_radius`].
pub fn corner_radius(rc: f64, r: f64) -> Result<f64, String> {
    if !rc.is_finite() {
        Err("must be finite".to_string())
    } else if rc < 0.0 {
        Err("must not be negative".to_string())
    } else if rc > r {
        Err(format!("must not exceed the radius ({r} mm)"))
    } else {
        Ok(rc)
    }
}

/// The first coordinate of `p` that is NaN or beyond ±[`MAX_COORD_MM`], as an error
/// message naming the limit.
pub fn coordinates(p: &[f64]) -> Result<(), String> {
    match p.iter().find(|c| c.is_nan() || c.abs() > MAX_COORD_MM) {
        Some(c) => Err(format!(
            "coordinate {} mm is beyond the ±{MAX_COORD_MM} mm (100 m) limit",
            shown(*c)
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_and_tiny_values_are_shown_short() {
        assert_eq!(shown(1e300), "1e300");
        assert_eq!(shown(-3e38), "-3e38");
        assert_eq!(shown(2.5e-9), "2.5e-9");
        assert_eq!(shown(0.05), "0.05");
        assert_eq!(shown(12345.5), "12345.5");
        assert_eq!(shown(0.0), "0");
        assert!(
            within("fz", "mm", 1e300, FZ_MM)
                .unwrap_err()
                .ends_with("got 1e300")
        );
        assert!(
            coordinates(&[0.0, 1e300])
                .unwrap_err()
                .contains("coordinate 1e300 mm")
        );
    }

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

    #[test]
    fn tool_radii_and_coordinates() {
        assert_eq!(tool_radius(5.0), Ok(5.0));
        for r in [0.0, -1.0, 5e299, f64::NAN, f64::INFINITY] {
            assert!(tool_radius(r).is_err(), "{r}");
        }
        assert_eq!(corner_radius(5.0, 5.0), Ok(5.0));
        assert!(
            corner_radius(50.0, 5.0)
                .unwrap_err()
                .contains("exceed the radius (5 mm)")
        );
        assert!(corner_radius(-1.0, 5.0).is_err());
        assert!(coordinates(&[0.0, 1e5, -1e5]).is_ok());
        assert!(
            coordinates(&[0.0, 1e6, 0.0])
                .unwrap_err()
                .contains("1000000")
        );
        assert!(coordinates(&[f64::NAN]).is_err());
    }
}
