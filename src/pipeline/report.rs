//! `crest report`: a regression study and its measured table read from disk, the study's
//! tool loaded (relative to the study file) with the study's run-out, and every case
//! predicted and held against its measurement.

use crate::io::text::read_text;
use crate::study::regression::{Provenance, Regression, regress};
use miette::{WrapErr, miette};
use std::path::Path;

/// Read the measured table and the study, load the tool and run the regression.
/// `tolerance_pct` is the pass band in percent of the measured mean; `command` is recorded
/// in the report.
pub fn regression(
    measured: &Path,
    study_path: &Path,
    tolerance_pct: f64,
    command: String,
) -> miette::Result<Regression> {
    if !(tolerance_pct.is_finite() && tolerance_pct >= 0.0) {
        return Err(miette!(
            "--tolerance-pct must be a non-negative number, found {tolerance_pct}"
        ));
    }
    let measured_name = measured.display().to_string();
    let study_name = study_path.display().to_string();
    let table = crate::io::measured::parse_measured(
        &read_text(measured, "measured table")?,
        &measured_name,
    )?;
    let study =
        crate::config::regression::parse_study(&read_text(study_path, "study")?, &study_name)?;
    let tool_path = study_path
        .parent()
        .unwrap_or(Path::new("."))
        .join(&study.tool);
    let mut cutter = super::load_tool(&tool_path)
        .wrap_err_with(|| format!("{study_name}: tool = \"{}\"", study.tool))?;
    if let Some(r) = &study.runout {
        let n = r.tooth_radius_dev_mm.len();
        if n != 0 && n != cutter.teeth() {
            return Err(miette!(
                "{study_name}: [runout] tooth_radius_deviation_um has {n} values for {} teeth",
                cutter.teeth()
            ));
        }
        cutter.runout = r.clone();
    }
    Ok(regress(
        &table,
        &study,
        &cutter,
        tolerance_pct,
        Provenance {
            measured_file: measured_name,
            study_file: study_name,
            command,
        },
    )?)
}
