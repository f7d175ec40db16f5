//! Loading the inputs a command names on disk: `tool.toml`, `machine.toml`,
//! `process.toml`, each read through [`crate::io::text`] and checked by [`crate::config`],
//! with errors that name the file, line and column (and show the offending text).

use crate::config::{ConfigError, MachineError, ProcessConfig, ToolConfigError};
use crate::io::text::read_text;
use crate::kinematics::Machine;
use crate::tool::Cutter;
use miette::{NamedSource, SourceSpan};
use std::path::Path;

/// A rejected `tool.toml`, with the file name, line and column, and the offending text.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[error("{file}:{line}:{column}: {message}")]
pub struct ToolFileError {
    file: String,
    line: usize,
    column: usize,
    message: String,
    #[source_code]
    src: NamedSource<String>,
    #[label("here")]
    span: Option<SourceSpan>,
}

impl ToolFileError {
    /// A [`ToolConfigError`] on `text`, read from `file`.
    pub fn new(file: &str, text: &str, e: &ToolConfigError) -> ToolFileError {
        ToolFileError {
            file: file.to_string(),
            line: e.line(),
            column: e.column(),
            message: e.message(),
            src: NamedSource::new(file, text.to_string()),
            span: e
                .span()
                .map(|s| SourceSpan::from((s.start, s.end.saturating_sub(s.start)))),
        }
    }
}

/// Read `path` as a `tool.toml`.
pub fn load_tool(path: &Path) -> miette::Result<Cutter> {
    let text = read_text(path, "tool file")?;
    tool_from_text(&text, &path.display().to_string())
}

/// Read `tool.toml` text that came from `file`.
pub fn tool_from_text(text: &str, file: &str) -> miette::Result<Cutter> {
    crate::config::load_tool_toml(text).map_err(|e| ToolFileError::new(file, text, &e).into())
}

/// Read `path` as a machine description.
pub fn load_machine(path: &Path) -> miette::Result<Machine> {
    let text = read_text(path, "machine file")?;
    let file = path.display().to_string();
    Machine::from_toml_str(&text).map_err(|e| {
        let e = match &e {
            MachineError::Missing { line, .. } | MachineError::Invalid { line, .. } => {
                let msg = e.to_string();
                let msg = msg
                    .strip_prefix(&format!("line {line}: "))
                    .unwrap_or(&msg)
                    .to_string();
                ConfigError {
                    file: file.clone(),
                    line: *line,
                    column: 1,
                    message: msg,
                }
            }
            _ => ConfigError::whole(&file, e.to_string()),
        };
        e.into()
    })
}

/// Read `path` as a `process.toml`.
pub fn load_process(path: &Path) -> miette::Result<ProcessConfig> {
    let text = read_text(path, "process file")?;
    Ok(ProcessConfig::parse(&text, &path.display().to_string())?)
}
