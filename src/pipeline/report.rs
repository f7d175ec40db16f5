//! `crest report`: a regression study and its measured table read from disk (the height
//! maps its rows name in `measured_file` read and measured, relative to the table), the
//! study's tool loaded (relative to the study file) with the study's run-out, and every case
//! predicted and held against its measurement.

use crate::io::text::read_text;
use crate::pipeline::{Error, Result};
use crate::study::calibrate::{Calibration, Free};
use crate::study::compare::{Provenance, Regression, regress};
use std::path::Path;

/// Why a measured file a table names cannot be used: the table, the row's line and the file
/// as written, and the cause.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[non_exhaustive]
pub enum MeasuredFileError {
    /// The file is missing or cannot be read as a height map.
    #[error("{table}:{}: measured_file `{file}` cannot be read", at.line)]
    Read {
        /// The measured table, as given.
        table: String,
        /// The row's line.
        at: crate::parse::Span,
        /// The file as written in the table.
        file: String,
        /// The reader's error (it names the path relative to the working directory).
        #[source]
        source: Box<crate::io::HeightMapError>,
    },
    /// The map was read but its parameters cannot be computed.
    #[error("{table}:{}: measured_file `{file}` cannot be measured", at.line)]
    Measure {
        /// The measured table, as given.
        table: String,
        /// The row's line.
        at: crate::parse::Span,
        /// The file as written in the table.
        file: String,
        /// Why.
        #[source]
        source: crate::metrics::MetricsError,
    },
}

/// Read and measure every height map the rows of `table` name (`measured_file`, relative to
/// the directory of `table_path`), with the predictions' filters
/// ([`crate::study::measured::measure_map`]), and fill the values the rows leave empty.
pub fn measure_files(
    table: &mut crate::study::measured::MeasuredTable,
    table_path: &Path,
) -> Result<(), MeasuredFileError> {
    let dir = table_path.parent().unwrap_or(Path::new("."));
    let name = table_path.display().to_string();
    for row in &mut table.rows {
        let Some(file) = row.measured_file.clone() else {
            continue;
        };
        let map = crate::io::read_heightmap(&dir.join(&file), &crate::io::ReadOptions::default())
            .map_err(|source| MeasuredFileError::Read {
            table: name.clone(),
            at: crate::parse::Span::line_u64(row.line),
            file: file.clone(),
            source: Box::new(source),
        })?;
        let values = crate::study::measured::measure_map(&map).map_err(|source| {
            MeasuredFileError::Measure {
                table: name.clone(),
                at: crate::parse::Span::line_u64(row.line),
                file: file.clone(),
                source,
            }
        })?;
        row.fill_from_file(&values);
    }
    table.note_file_columns();
    Ok(())
}

/// The inputs of a regression: the measured table, the study and its tool (run-out applied).
pub struct Inputs {
    /// The measured table.
    pub table: crate::study::measured::MeasuredTable,
    /// The study.
    pub study: crate::study::regression::Study,
    /// The study's tool with its run-out.
    pub cutter: crate::tool::Cutter,
    /// Measured table file, as given.
    pub measured_name: String,
    /// Study file, as given.
    pub study_name: String,
}

/// Read the measured table and the study and load the study's tool (relative to the study
/// file) with the study's run-out.
pub fn load(measured: &Path, study_path: &Path) -> Result<Inputs> {
    let measured_name = measured.display().to_string();
    let study_name = study_path.display().to_string();
    let mut table = crate::io::measured::parse_measured(
        &read_text(measured, "measured table", crate::io::input::TABLE)?,
        &measured_name,
    )?;
    measure_files(&mut table, measured)?;
    let mut study = crate::config::regression::parse_study(
        &read_text(study_path, "study", crate::io::input::CONFIG)?,
        &study_name,
    )?;
    let tool_path = study_path
        .parent()
        .unwrap_or(Path::new("."))
        .join(&study.tool);
    let mut cutter = super::load_tool(&tool_path).map_err(|e| Error::StudyTool {
        study: study_name.clone(),
        tool: study.tool.clone(),
        source: Box::new(e),
    })?;
    if study.process.min_chip_mm == 0.0
        && let Some(h) = super::tool_min_chip(Some(&tool_path))?
    {
        study.process.min_chip_mm = h;
    }
    if let Some(r) = &study.runout {
        let n = r.tooth_radius_dev_mm.len();
        if n != 0 && n != cutter.teeth() {
            return Err(Error::Input(format!(
                "{study_name}: [runout] tooth_radius_deviation_um has {n} values for {} teeth",
                cutter.teeth()
            )));
        }
        cutter.runout = r.clone();
    }
    Ok(Inputs {
        table,
        study,
        cutter,
        measured_name,
        study_name,
    })
}

/// Calibrate the comma-separated `free` parameters of the inputs' study.
pub fn calibrate(inputs: &Inputs, free: &str) -> Result<Calibration> {
    let free =
        Free::parse_list(free, inputs.cutter.teeth()).map_err(|e| Error::within("‹free›", e))?;
    let measured = crate::study::measured::summarize(&inputs.table);
    crate::study::calibrate::calibrate(&measured, &inputs.study, &inputs.cutter, &free)
        .map_err(|e| Error::within(&inputs.study_name, e))
}

/// Options of a report beyond the files.
#[derive(Debug, Clone, Default)]
pub struct ReportOptions {
    /// Free parameters to calibrate (comma-separated), if any.
    pub free: Option<String>,
    /// Monte Carlo samples and seed, if any.
    pub monte_carlo: Option<(usize, u64)>,
}

/// Read the measured table and the study, load the tool and run the regression.
/// `tolerance_pct` is the pass band in percent of the measured mean; `command` is recorded
/// in the report. With `opts.free` the parameters are calibrated and a case counts as
/// explained only by its leave-one-out prediction; with `opts.monte_carlo` every prediction
/// gets its P5/P50/P95 band.
pub fn regression(
    measured: &Path,
    study_path: &Path,
    tolerance_pct: f64,
    command: String,
    opts: &ReportOptions,
) -> Result<Regression> {
    if !(tolerance_pct.is_finite() && tolerance_pct >= 0.0) {
        return Err(Error::field(
            "tolerance_pct",
            format!("must be a non-negative number, found {tolerance_pct}"),
        ));
    }
    let inputs = load(measured, study_path)?;
    // With --free, the model columns show the calibrated model (fitted on every case); the
    // comparisons are then replaced by the leave-one-out values (`judge_by_loo`).
    let calibration = match &opts.free {
        Some(f) => Some(calibrate(&inputs, f)?),
        None => None,
    };
    let (study, cutter) = match (&calibration, &opts.free) {
        (Some(cal), Some(f)) => {
            let free = Free::parse_list(f, inputs.cutter.teeth())
                .map_err(|e| Error::within("‹free›", e))?;
            let (process, cutter) = crate::study::calibrate::apply(
                &free,
                &cal.values(),
                &inputs.study.process,
                &inputs.cutter,
            );
            let mut study = inputs.study.clone();
            study.process = process;
            (study, cutter)
        }
        _ => (inputs.study.clone(), inputs.cutter.clone()),
    };
    let mut reg = regress(
        &inputs.table,
        &study,
        &cutter,
        tolerance_pct,
        Provenance {
            measured_file: inputs.measured_name.clone(),
            study_file: inputs.study_name.clone(),
            command,
        },
    )?;
    let free = match &opts.free {
        Some(f) => Some(
            Free::parse_list(f, inputs.cutter.teeth()).map_err(|e| Error::within("‹free›", e))?,
        ),
        None => None,
    };
    if let Some(cal) = calibration {
        crate::study::compare::judge_by_loo(&mut reg, cal);
    }
    if let Some((n, seed)) = opts.monte_carlo {
        let bands = crate::study::montecarlo::case_bands(
            &inputs.study,
            &inputs.cutter,
            reg.calibration.as_ref().zip(free.as_deref()),
            n,
            seed,
        )
        .map_err(|e| Error::within(format_args!("{}: Monte Carlo", inputs.study_name), e))?;
        reg.monte_carlo = Some(bands);
    }
    Ok(reg)
}
