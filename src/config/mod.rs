//! Configuration files and their schemas, at the edge of the library: `tool.toml`,
//! `process.toml`, `machine.toml`, the designed-experiment file, the run-out study file and
//! the regression study file. Each module holds one file's serde schema and its checks and
//! turns it into the plain types of the stage that uses it (a [`crate::tool::Cutter`], a
//! [`crate::kinematics::Machine`], a [`crate::study::design::Design`], …); no stage before
//! this one derives serde for a file.
//!
//! Errors name the file, the 1-based line and column of the offending key or value (a
//! [`crate::parse::Span`]; a TOML reader's error through [`toml_span`]) and what is wrong.
//! Reading the text from disk is the caller's (see `crate::io`).

pub mod design;
pub mod machine;
pub mod process;
pub mod regression;
pub mod runout;
pub mod tool;
pub mod uncertainty;

pub use machine::MachineError;
pub use process::ProcessConfig;
pub use tool::{
    MAX_TEETH, RunoutConfig, ShapeName, ToolConfig, ToolConfigError, load_tool_min_chip,
    load_tool_toml, parse_tool_config,
};

use crate::parse::{Located, Span};

/// A configuration file that does not parse or breaks a rule: a [`Located`] message in the
/// file (line and column 0 when the error has no position).
#[derive(Debug, Clone, PartialEq, thiserror::Error, miette::Diagnostic)]
#[error("{}:{}:{}: {}", .0.file.as_deref().unwrap_or_default(), .0.span.line, .0.span.column, .0.problem)]
pub struct ConfigError(pub Box<Located>);

impl ConfigError {
    /// `message` at `span` of `file`.
    pub fn new(file: &str, span: Span, message: impl Into<String>) -> ConfigError {
        ConfigError(Box::new(Located::message(span, message).in_file(file)))
    }

    /// An error at byte offset `at` of `text`.
    pub fn at(file: &str, text: &str, at: usize, message: impl Into<String>) -> ConfigError {
        ConfigError::new(file, Span::at(text, at), message)
    }

    /// An error about the whole file (no position).
    pub fn whole(file: &str, message: impl Into<String>) -> ConfigError {
        ConfigError::new(file, Span::NONE, message)
    }

    /// The file name as given.
    pub fn file(&self) -> &str {
        self.0.file.as_deref().unwrap_or_default()
    }

    /// What is wrong, without the place.
    pub fn message(&self) -> String {
        self.0.message_text()
    }
}

/// Where a TOML reader's error is in `text`: the one mapping of the `toml` crate's byte
/// spans to [`Span`] for every configuration file (line 1, column 1 when it gives none).
pub(crate) fn toml_span(text: &str, e: &toml::de::Error) -> Span {
    e.span()
        .map_or(Span::line_column(1, 1), |s| Span::of(text, s))
}

/// The message of a TOML error: its own message, or, when that is empty (a document cut
/// off after `key =`), the first line of its full text.
pub(crate) fn toml_message(e: &toml::de::Error) -> String {
    let m = e.message().trim();
    if !m.is_empty() {
        return m.to_string();
    }
    e.to_string()
        .lines()
        .find(|l| !l.trim().is_empty())
        .map_or_else(|| "invalid TOML".to_string(), |l| l.trim().to_string())
}

/// Deserialize a TOML document, turning a syntax or schema error into a [`ConfigError`]
/// at its position.
pub(crate) fn from_toml<T: serde::de::DeserializeOwned>(
    text: &str,
    file: &str,
) -> Result<T, ConfigError> {
    toml::from_str(text).map_err(|e| ConfigError::new(file, toml_span(text, &e), toml_message(&e)))
}

/// A fixed-length array of numbers in a file: exactly `N` values, no more, no fewer (serde's
/// own arrays accept extra elements from TOML).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fixed<const N: usize>(pub [f64; N]);

impl<'de, const N: usize> serde::Deserialize<'de> for Fixed<N> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v: Vec<f64> = Vec::deserialize(d)?;
        let a: [f64; N] = v.as_slice().try_into().map_err(|_| {
            serde::de::Error::custom(format!("expected {N} numbers, found {}", v.len()))
        })?;
        Ok(Fixed(a))
    }
}

impl<const N: usize> std::ops::Deref for Fixed<N> {
    type Target = [f64; N];
    fn deref(&self) -> &[f64; N] {
        &self.0
    }
}
