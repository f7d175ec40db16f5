//! `crest runout study.toml -o DIR`: a run-out what-if study (full factorial over run-out
//! offset, phase, axis tilt, lead and fz), written as `DIR/runout.csv` and SVG/PNG plots.
//! The study format is documented in [`crate::report::runout`] and
//! `samples/studies/runout.toml`.

use super::Outcome;
use super::tool::read_tool;
use crate::report::runout::{StudyError, parse_study, run_study, write_outputs};
use miette::{NamedSource, SourceSpan};
use std::path::{Path, PathBuf};

/// Options of `crest runout`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Study description (`study.toml`).
    #[arg(value_name = "STUDY.TOML")]
    pub study: PathBuf,
    /// Output folder (created if missing).
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    pub out: PathBuf,
    /// Print one JSON object on stdout (the rows and the files written).
    #[arg(long)]
    pub json: bool,
}

/// A rejected study file, with the file name, line and column.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[error("{file}:{line}:{column}: {message}")]
struct StudyFileError {
    file: String,
    line: usize,
    column: usize,
    message: String,
    #[source_code]
    src: NamedSource<String>,
    #[label("here")]
    span: Option<SourceSpan>,
}

fn study_error(path: &Path, text: &str, e: StudyError) -> StudyFileError {
    let file = path.display().to_string();
    StudyFileError {
        file: file.clone(),
        line: e.line,
        column: e.column,
        message: e.message,
        src: NamedSource::new(file, text.to_string()),
        span: e
            .span
            .map(|s| SourceSpan::from((s.start, s.end.saturating_sub(s.start)))),
    }
}

/// Run `crest runout`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let text = std::fs::read_to_string(&args.study).map_err(|e| {
        miette::miette!("{}: cannot read the study file: {e}", args.study.display())
    })?;
    let study = parse_study(&text).map_err(|e| study_error(&args.study, &text, e))?;
    let base = args.study.parent().unwrap_or(Path::new("."));
    let tool_path = base.join(&study.tool);
    let cutter = read_tool(&tool_path)?;
    let rows = run_study(&cutter, &study).map_err(|e| miette::miette!("{e}"))?;
    std::fs::create_dir_all(&args.out).map_err(|e| {
        miette::miette!(
            "{}: cannot create the output folder: {e}",
            args.out.display()
        )
    })?;
    let tool_name = tool_path
        .file_stem()
        .map_or_else(|| "tool".to_string(), |s| s.to_string_lossy().into_owned());
    let written = write_outputs(&args.out, &cutter, &study, &rows, &tool_name)
        .map_err(|e| miette::miette!("{}: cannot write the outputs: {e}", args.out.display()))?;
    if args.json {
        let out = serde_json::json!({
            "study": args.study.display().to_string(),
            "tool": tool_path.display().to_string(),
            "rule": study.rule.name(),
            "x": study.x.key(),
            "cases": rows.len(),
            "files": written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "rows": rows,
        });
        outln!("{out}");
    } else {
        let min_zc = rows.iter().map(|r| r.zc).min().unwrap_or(0);
        let max_zc = rows.iter().map(|r| r.zc).max().unwrap_or(0);
        outln!(
            "{} cases ({} rule, tool {}): zc from {min_zc} to {max_zc} of {} teeth",
            rows.len(),
            study.rule.name(),
            tool_path.display(),
            cutter.teeth()
        );
        for p in &written {
            outln!("wrote {}", p.display());
        }
    }
    Ok(Outcome::Ok)
}
