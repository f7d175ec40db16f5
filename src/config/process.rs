//! `process.toml`: the cutting parameters of a run (spindle speed, feed, feed per tooth,
//! depth of cut, and the informative stepover, lead and tilt), units in the key names.
//!
//! ```toml
//! rpm = 15000.0
//! fz_mm = 0.05
//! feed_mm_min = 3000.0
//! ap_mm = 0.2
//! ae_mm = 0.2
//! lead_deg = 15.0
//! tilt_deg = 0.0
//! ```
//!
//! Every key is optional; unknown keys and impossible values are rejected with the 1-based
//! line and column of the offending key or value.

use super::ConfigError;
use serde::Deserialize;
use toml::Spanned;

/// The `process.toml` document, values checked (units in the names).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProcessConfig {
    /// Spindle speed, rpm.
    pub rpm: Option<f64>,
    /// Feed per tooth, mm.
    pub fz_mm: Option<f64>,
    /// Feed, mm/min.
    pub feed_mm_min: Option<f64>,
    /// Depth of cut, mm (the stock above the nominal surface).
    pub ap_mm: Option<f64>,
    /// Stepover (radial engagement), mm. Informative: the path sets it.
    pub ae_mm: Option<f64>,
    /// Lead angle, degrees. Informative: the path's tool axis sets it.
    pub lead_deg: Option<f64>,
    /// Side tilt angle, degrees. Informative: the path's tool axis sets it.
    pub tilt_deg: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ProcessFile {
    rpm: Option<Spanned<f64>>,
    fz_mm: Option<Spanned<f64>>,
    feed_mm_min: Option<Spanned<f64>>,
    ap_mm: Option<Spanned<f64>>,
    ae_mm: Option<Spanned<f64>>,
    lead_deg: Option<Spanned<f64>>,
    tilt_deg: Option<Spanned<f64>>,
}

impl ProcessConfig {
    /// Parse `process.toml` text; `file` names it in errors, which give line and column.
    pub fn parse(text: &str, file: &str) -> Result<ProcessConfig, ConfigError> {
        let f: ProcessFile = super::from_toml(text, file)?;
        let positive = |key: &str, v: &Option<Spanned<f64>>| -> Result<Option<f64>, ConfigError> {
            match v {
                Some(s) if !(s.get_ref().is_finite() && *s.get_ref() > 0.0) => {
                    Err(ConfigError::at(
                        file,
                        text,
                        s.span().start,
                        format!("{key} must be positive, got {}", s.get_ref()),
                    ))
                }
                Some(s) => Ok(Some(*s.get_ref())),
                None => Ok(None),
            }
        };
        let angle = |key: &str, v: &Option<Spanned<f64>>| -> Result<Option<f64>, ConfigError> {
            match v {
                Some(s) if !(s.get_ref().is_finite() && s.get_ref().abs() <= 90.0) => {
                    Err(ConfigError::at(
                        file,
                        text,
                        s.span().start,
                        format!("{key} must be within ±90°, got {}", s.get_ref()),
                    ))
                }
                Some(s) => Ok(Some(*s.get_ref())),
                None => Ok(None),
            }
        };
        Ok(ProcessConfig {
            rpm: positive("rpm", &f.rpm)?,
            fz_mm: positive("fz_mm", &f.fz_mm)?,
            feed_mm_min: positive("feed_mm_min", &f.feed_mm_min)?,
            ap_mm: positive("ap_mm", &f.ap_mm)?,
            ae_mm: positive("ae_mm", &f.ae_mm)?,
            lead_deg: angle("lead_deg", &f.lead_deg)?,
            tilt_deg: angle("tilt_deg", &f.tilt_deg)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn process_toml_rejects_unknown_keys_with_position() {
        let err = ProcessConfig::parse("rpm = 15000\nspeed = 3\n", "p.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("p.toml:2:"), "{err}");
        assert!(err.contains("speed"), "{err}");
        let err = ProcessConfig::parse("fz_mm = -0.05\n", "p.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("p.toml:1:9") && err.contains("fz_mm"), "{err}");
        let ok = ProcessConfig::parse(
            "rpm = 15000\nfz_mm = 0.05\nfeed_mm_min = 3000\nap_mm = 0.2\nae_mm = 0.2\nlead_deg = 15\ntilt_deg = 0\n",
            "p.toml",
        )
        .unwrap();
        assert_eq!(ok.rpm, Some(15000.0));
        assert_eq!(ok.lead_deg, Some(15.0));
    }

    #[test]
    fn a_bad_value_is_reported_at_its_own_line_not_at_a_comment() {
        // The key also appears in the comment of line 1.
        let err = ProcessConfig::parse("# rpm is the spindle speed\nrpm = 0.0\n", "p.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("p.toml:2:7"), "{err}");
    }
}
