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

/// A value beyond a limit of this module. Each message is the rule the value breaks; the
/// range error names the value (`what`, a request field or a file's key), the others leave
/// the key or record to the caller.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LimitError {
    /// Not finite or outside an inclusive range ([`within`]).
    #[error("{what} must lie between {} and {} {unit}, got {}", .range.0, .range.1, shown(*.got))]
    Range {
        /// The value's name.
        what: String,
        /// Its unit ("" for none).
        unit: String,
        /// The value.
        got: f64,
        /// The allowed range, inclusive.
        range: (f64, f64),
    },
    /// A tool radius outside (0, [`MAX_TOOL_RADIUS_MM`]] ([`tool_radius`]).
    #[error("must lie in (0, {MAX_TOOL_RADIUS_MM}] mm")]
    ToolRadius,
    /// A corner radius that is NaN or infinite ([`corner_radius`]).
    #[error("must be finite")]
    NotFinite,
    /// A negative corner radius ([`corner_radius`]).
    #[error("must not be negative")]
    Negative,
    /// A corner radius over the tool radius, mm ([`corner_radius`]).
    #[error("must not exceed the radius ({0} mm)")]
    OverRadius(f64),
    /// A coordinate that is NaN or beyond ±[`MAX_COORD_MM`], mm ([`coordinates`]).
    #[error("coordinate {} mm is beyond the ±{MAX_COORD_MM} mm (100 m) limit", shown(*.0))]
    Coordinate(f64),
}

/// `v` if it lies in `range` (inclusive) and is finite, else an error naming `what` with its
/// unit.
pub fn within(what: &str, unit: &str, v: f64, range: (f64, f64)) -> Result<f64, LimitError> {
    if v.is_finite() && v >= range.0 && v <= range.1 {
        Ok(v)
    } else {
        Err(LimitError::Range {
            what: what.to_string(),
            unit: unit.to_string(),
            got: v,
            range,
        })
    }
}

/// A tool radius R (also D/2 of a CLSF `TLDATA` or `CUTTER`): finite, in
/// (0, [`MAX_TOOL_RADIUS_MM`]]. The error is the rule it breaks ("must …"), for the caller
/// to name the key or record and the value: tool.toml and the lowering share this rule.
pub fn tool_radius(r: f64) -> Result<f64, LimitError> {
    if r > 0.0 && r <= MAX_TOOL_RADIUS_MM {
        Ok(r)
    } else {
        Err(LimitError::ToolRadius)
    }
}

/// A corner radius `rc` of a tool of radius `r`: finite, in [0, r]. The error is the rule
/// it breaks, as for [`tool_radius`].
pub fn corner_radius(rc: f64, r: f64) -> Result<f64, LimitError> {
    if !rc.is_finite() {
        Err(LimitError::NotFinite)
    } else if rc < 0.0 {
        Err(LimitError::Negative)
    } else if rc > r {
        Err(LimitError::OverRadius(r))
    } else {
        Ok(rc)
    }
}

/// The first coordinate of `p` that is NaN or beyond ±[`MAX_COORD_MM`], as an error
/// naming the limit.
pub fn coordinates(p: &[f64]) -> Result<(), LimitError> {
    match p.iter().find(|c| c.is_nan() || c.abs() > MAX_COORD_MM) {
        Some(c) => Err(LimitError::Coordinate(*c)),
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
                .to_string()
                .ends_with("got 1e300")
        );
        assert!(
            coordinates(&[0.0, 1e300])
                .unwrap_err()
                .to_string()
                .contains("coordinate 1e300 mm")
        );
    }

    #[test]
    fn within_names_the_value_and_its_range() {
        assert_eq!(within("fz", "mm", 0.05, FZ_MM), Ok(0.05));
        let e = within("fz_mm", "mm", 1e305, FZ_MM).unwrap_err().to_string();
        assert!(
            e.contains("fz_mm") && e.contains("1e305") || e.contains("100000"),
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
                .to_string()
                .contains("exceed the radius (5 mm)")
        );
        assert!(corner_radius(-1.0, 5.0).is_err());
        assert!(coordinates(&[0.0, 1e5, -1e5]).is_ok());
        assert!(
            coordinates(&[0.0, 1e6, 0.0])
                .unwrap_err()
                .to_string()
                .contains("1000000")
        );
        assert!(coordinates(&[f64::NAN]).is_err());
    }
}
