//! `crest runout`: a run-out study file read from disk, its tool loaded (relative to the
//! study file) and every case of the sweep evaluated.

use crate::io::text::read_text;
use crate::study::runout::{LateralCurve, RunoutRow, Study, lateral_curves, run_study};
use crate::tool::Cutter;
use miette::{NamedSource, SourceSpan};
use std::path::{Path, PathBuf};

/// A rejected run-out study file, with the file name, line and column and the text.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[error("{file}:{line}:{column}: {message}")]
pub struct StudyFileError {
    file: String,
    line: usize,
    column: usize,
    message: String,
    #[source_code]
    src: NamedSource<String>,
    #[label("here")]
    span: Option<SourceSpan>,
}

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

/// Read and run the study `path`.
pub fn runout(path: &Path) -> miette::Result<RunoutRun> {
    let text = read_text(path, "study file")?;
    let study = crate::config::runout::parse_study(&text).map_err(|e| {
        let file = path.display().to_string();
        StudyFileError {
            file: file.clone(),
            line: e.line,
            column: e.column,
            message: e.message,
            src: NamedSource::new(file, text.clone()),
            span: e
                .span
                .map(|s| SourceSpan::from((s.start, s.end.saturating_sub(s.start)))),
        }
    })?;
    let tool_path = path.parent().unwrap_or(Path::new(".")).join(&study.tool);
    let cutter = super::load_tool(&tool_path)?;
    let rows = run_study(&cutter, &study).map_err(|e| miette::miette!("{e}"))?;
    let lateral = lateral_curves(&cutter, &study);
    Ok(RunoutRun {
        study,
        tool_path,
        cutter,
        rows,
        lateral,
    })
}
