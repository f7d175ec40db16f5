//! The `[uncertainty]` table of a study file (the inputs of `--monte-carlo`: standard
//! uncertainties of the run-out and whether the spindle phase is drawn): one schema and one
//! check for the regression study of `crest report` and the design of `crest study`, read
//! into a [`crate::study::uncertainty::Uncertainty`].
//!
//! ```toml
//! [uncertainty]
//! runout_offset_um = 1.0      # 2-D error of the offset vector, per component
//! tooth_deviation_um = 1.0    # error of every tooth's radial deviation
//! spindle_phase = true        # draw the spindle phase of every pass (default)
//! parameter_scale = 1.0       # times the calibrated parameters' uncertainties (report only)
//! ```

use super::ConfigError;
use crate::study::uncertainty::Uncertainty;
use serde::Deserialize;
use toml::Spanned;

/// The `[uncertainty]` table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct UncertaintyFile {
    runout_offset_um: Option<Spanned<f64>>,
    tooth_deviation_um: Option<Spanned<f64>>,
    spindle_phase: Option<bool>,
    parameter_scale: Option<Spanned<f64>>,
}

impl UncertaintyFile {
    /// The byte offset of `parameter_scale` in the file, when it is given (a study without
    /// calibrated parameters refuses it there).
    pub(crate) fn parameter_scale_at(&self) -> Option<usize> {
        self.parameter_scale.as_ref().map(|v| v.span().start)
    }

    /// The checked uncertainty (every standard uncertainty finite and ≥ 0; keys left out keep
    /// [`Uncertainty::default`]); errors at the value's line and column of `text`.
    pub(crate) fn to_uncertainty(
        &self,
        text: &str,
        file: &str,
    ) -> Result<Uncertainty, ConfigError> {
        let nonneg = |key: &str, v: &Option<Spanned<f64>>| -> Result<Option<f64>, ConfigError> {
            match v {
                Some(x) if !(x.get_ref().is_finite() && *x.get_ref() >= 0.0) => {
                    Err(ConfigError::at(
                        file,
                        text,
                        x.span().start,
                        format!("uncertainty.{key} must be ≥ 0, found {}", x.get_ref()),
                    ))
                }
                Some(x) => Ok(Some(*x.get_ref())),
                None => Ok(None),
            }
        };
        let mut u = Uncertainty::default();
        if let Some(v) = nonneg("runout_offset_um", &self.runout_offset_um)? {
            u.runout_offset_um = v;
        }
        if let Some(v) = nonneg("tooth_deviation_um", &self.tooth_deviation_um)? {
            u.tooth_deviation_um = v;
        }
        if let Some(v) = nonneg("parameter_scale", &self.parameter_scale)? {
            u.parameter_scale = v;
        }
        if let Some(b) = self.spindle_phase {
            u.spindle_phase = b;
        }
        Ok(u)
    }
}
