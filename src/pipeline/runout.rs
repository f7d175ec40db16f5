//! `crest runout`: a run-out study file read from disk, its tool loaded (relative to the
//! study file) and every case of the sweep evaluated; the outputs (`runout.csv` and the
//! charts) rendered. The study and tool texts ([`RunoutTexts`]) are all a run needs, so
//! the sweep splits into tasks evaluated elsewhere ([`super::tasks::runout`]).

use crate::io::text::read_text;
use crate::parse::Located;
use crate::pipeline::{Error, Result};
use crate::study::runout::{LateralCurve, RunoutRow, Study, lateral_curves, run_study};
use crate::tool::Cutter;
use std::path::{Path, PathBuf};

/// A rejected run-out study file: a [`Located`] message in the file, the file's text for
/// the frame.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[error("{}:{}:{}: {}", .0.file.as_deref().unwrap_or_default(), .0.span.line, .0.span.column, .0.problem)]
#[diagnostic(transparent)]
pub struct StudyFileError(pub Located);

/// A finished run-out study.
#[derive(Debug, Clone)]
pub struct RunoutRun {
    /// The study.
    pub study: Study,
    /// The tool file, resolved against the study file.
    pub tool_path: PathBuf,
    /// The tool with its own run-out.
    pub cutter: Cutter,
    /// One row per case, in case order.
    pub rows: Vec<RunoutRow>,
    /// The lateral run-out curves of the tool's own run-out, one per lead.
    pub lateral: Vec<LateralCurve>,
}

impl RunoutRun {
    /// The tool's name for titles: the tool file's stem.
    pub fn tool_name(&self) -> String {
        self.tool_path
            .file_stem()
            .map_or_else(|| "tool".to_string(), |s| s.to_string_lossy().into_owned())
    }
}

/// The texts of a run-out study and of its tool, with their names.
#[derive(Debug, Clone, PartialEq)]
pub struct RunoutTexts {
    /// The study file's name, as given (for messages and `--json`).
    pub study_file: String,
    /// The study file's text.
    pub study_toml: String,
    /// The tool file's name, resolved against the study file (its stem titles the charts).
    pub tool_file: String,
    /// The tool file's text.
    pub tool_toml: String,
}

/// A study, its tool file and its tool, checked: ready to run.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The study.
    pub study: Study,
    /// The tool file, resolved against the study file.
    pub tool_path: PathBuf,
    /// The tool with its own run-out.
    pub cutter: Cutter,
}

fn parse(text: &str, file: &str) -> Result<Study> {
    Ok(crate::config::runout::parse_study(text)
        .map_err(|e| StudyFileError(super::inputs::located_in(file, text, e.at, e.message)))?)
}

/// Read the study `path` and the tool file it names (relative to the study file).
pub fn load_runout_texts(path: &Path) -> Result<RunoutTexts> {
    let study_toml = read_text(path, "study file", crate::io::input::CONFIG)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    runout_texts(&path.display().to_string(), study_toml, dir)
}

/// The texts of the study `study_toml` (named `study_file`) and of the tool file it names,
/// read relative to `dir`.
pub fn runout_texts(study_file: &str, study_toml: String, dir: &Path) -> Result<RunoutTexts> {
    let study = parse(&study_toml, study_file)?;
    let tool_path = dir.join(&study.tool);
    let tool_toml = read_text(&tool_path, "tool file", crate::io::input::CONFIG)?;
    Ok(RunoutTexts {
        study_file: study_file.to_string(),
        study_toml,
        tool_file: tool_path.display().to_string(),
        tool_toml,
    })
}

/// Parse the study and its tool from their texts.
pub fn prepare(t: &RunoutTexts) -> Result<Prepared> {
    let study = parse(&t.study_toml, &t.study_file)?;
    let cutter = super::tool_from_text(&t.tool_toml, &t.tool_file)?;
    Ok(Prepared {
        study,
        tool_path: PathBuf::from(&t.tool_file),
        cutter,
    })
}

/// The finished study from its rows (in case order): the lateral curves added.
pub fn finish(p: Prepared, rows: Vec<RunoutRow>) -> RunoutRun {
    let lateral = lateral_curves(&p.cutter, &p.study);
    RunoutRun {
        study: p.study,
        tool_path: p.tool_path,
        cutter: p.cutter,
        rows,
        lateral,
    }
}

/// Read and run the study `path`.
pub fn runout(path: &Path) -> Result<RunoutRun> {
    let p = prepare(&load_runout_texts(path)?)?;
    let rows = run_study(&p.cutter, &p.study).map_err(Error::stage)?;
    Ok(finish(p, rows))
}

/// The files `crest runout` writes, in order: `runout.csv`, then each chart as SVG and PNG.
pub fn render_outputs(run: &RunoutRun) -> Result<Vec<(String, Vec<u8>)>> {
    let teeth = run.cutter.teeth();
    let mut csv = Vec::new();
    crate::io::tables::write_runout_csv(&run.rows, teeth, &mut csv)
        .map_err(|e| Error::output("write runout.csv", e))?;
    let mut files = vec![("runout.csv".to_string(), csv)];
    files.extend(
        crate::plot::runout::figures(&run.rows, &run.study, teeth, &run.lateral, &run.tool_name())
            .map_err(|e| Error::output("draw the run-out charts", e))?,
    );
    Ok(files)
}
