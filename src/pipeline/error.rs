//! The one error of the pipeline's steps: what went wrong, by kind (the request, an input, a
//! result, a study's tasks, an output), and the stages' and readers' own typed errors, shown
//! as they stand (their message, causes and code frame) or named by the file or step they
//! came from. Messages name request fields `‹field›` ([`super::fields`]).

use std::fmt::Display;

/// A stage's error kept as it is, shown inline (its own causes are not repeated).
pub type Cause = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Why a step of the pipeline failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// One request field out of range.
    #[error(transparent)]
    Field(#[from] super::request::RequestError),
    /// Request fields that do not go together, or one the inputs do not stand in for; the
    /// message names them `‹field›`.
    #[error("{0}")]
    Request(String),
    /// An input that does not hold what the step needs (no tool data, no cutting moves, a
    /// tool path or point that is not there); the message names the file.
    #[error("{0}")]
    Input(String),
    /// A result that is empty or implausible (nothing in reach, too large, failed runs).
    #[error("{0}")]
    Result(String),
    /// Tasks or task results that do not make one study, run-out study, part map or atlas.
    #[error("{0}")]
    Tasks(String),
    /// A step that did not end as it must (an internal error; the message says so).
    #[error("{0}")]
    Internal(String),
    /// A stage's error in a file or step, named on the same line: `place: error`.
    #[error("{place}: {error}")]
    In {
        /// The file (or the files, or the step) the error came from.
        place: String,
        /// The stage's error.
        error: Cause,
    },
    /// A stage's error that names its place itself, shown as its one line.
    #[error("{0}")]
    Stage(Cause),
    /// An output that could not be encoded, written or drawn: `cannot what: error`.
    #[error("cannot {what}: {error}")]
    Output {
        /// What was being done (`write runout.csv`, `draw bands.svg`).
        what: String,
        /// Why it failed.
        error: Cause,
    },
    /// The tool file a design names could not be read or does not describe a cutter (a
    /// line of its own above the tool file's error).
    #[error("{design}: cannot read tool file {tool} (the path is relative to the design file)")]
    DesignTool {
        /// The design file.
        design: String,
        /// The tool file, as found beside the design.
        tool: String,
        /// The tool file's error, with its causes and code frame.
        #[source]
        source: Box<Error>,
    },
    /// The tool file a regression study names could not be read or does not describe a
    /// cutter (a line of its own above the tool file's error).
    #[error("{study}: tool = \"{tool}\"")]
    StudyTool {
        /// The study file.
        study: String,
        /// The tool file as the study names it.
        tool: String,
        /// The tool file's error, with its causes and code frame.
        #[source]
        source: Box<Error>,
    },
    /// A tool-path file that could not be read.
    #[error(transparent)]
    ToolPath(Box<crate::io::toolpath::ReadError>),
    /// A text file (a configuration, a table) that could not be read.
    #[error(transparent)]
    Text(Box<crate::io::text::TextError>),
    /// An input over its budget, or that could not be opened.
    #[error(transparent)]
    Budget(Box<crate::io::input::InputError>),
    /// A configuration file that does not follow its schema.
    #[error(transparent)]
    Config(Box<crate::config::ConfigError>),
    /// A tool file that does not describe a cutter.
    #[error(transparent)]
    ToolFile(Box<super::inputs::ToolFileError>),
    /// A run-out study file that does not describe a study.
    #[error(transparent)]
    StudyFile(Box<super::runout::StudyFileError>),
    /// A mesh file (a part) that could not be read.
    #[error(transparent)]
    MeshFile(Box<crate::io::mesh::MeshFileError>),
    /// A measured table that could not be parsed.
    #[error(transparent)]
    Measured(Box<crate::io::measured::MeasuredError>),
    /// A measured table whose cases name measurement files that could not be read.
    #[error(transparent)]
    MeasuredFile(Box<super::report::MeasuredFileError>),
    /// A regression study that cannot be predicted or compared.
    #[error(transparent)]
    Regression(Box<crate::study::compare::RegressionError>),
}

/// The result of a step of the pipeline.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// The request field `field` out of range: `‹field› message`.
    pub fn field(field: &'static str, message: impl Into<String>) -> Error {
        Error::Field(super::request::RequestError {
            field,
            message: message.into(),
        })
    }

    /// A stage's `error` in `place` (a file, files or a step), on one line.
    pub fn within(place: impl Display, error: impl Into<Cause>) -> Error {
        Error::In {
            place: place.to_string(),
            error: error.into(),
        }
    }

    /// A stage's `error` shown as its own line.
    pub fn stage(error: impl Into<Cause>) -> Error {
        Error::Stage(error.into())
    }

    /// An output that could not be made: `cannot {what}: {error}`.
    pub fn output(what: impl Display, error: impl Into<Cause>) -> Error {
        Error::Output {
            what: what.to_string(),
            error: error.into(),
        }
    }

    /// Name the output in a failure to write it ([`crate::io::toolpath::name_output`]).
    pub fn name_output(self, output: &std::path::Path) -> Error {
        match self {
            Error::ToolPath(e) => crate::io::toolpath::name_output(*e, output).into(),
            e => e,
        }
    }

    /// The typed error this one shows as it stands, if any (for [`super::located`]).
    pub fn transparent(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(self.typed()? as &(dyn std::error::Error + 'static))
    }

    fn typed(&self) -> Option<&(dyn miette::Diagnostic + 'static)> {
        match self {
            Error::Field(e) => Some(e),
            Error::ToolPath(e) => Some(e.as_ref()),
            Error::Text(e) => Some(e.as_ref()),
            Error::Budget(e) => Some(e.as_ref()),
            Error::Config(e) => Some(e.as_ref()),
            Error::ToolFile(e) => Some(e.as_ref()),
            Error::StudyFile(e) => Some(e.as_ref()),
            Error::MeshFile(e) => Some(e.as_ref()),
            Error::Measured(e) => Some(e.as_ref()),
            Error::MeasuredFile(e) => Some(e.as_ref()),
            Error::Regression(e) => Some(e.as_ref()),
            _ => None,
        }
    }

    /// The diagnostic whose code, help, labels and code frame this error shows: the typed
    /// error it shows as it stands, or the one under a step's line (as miette's own context
    /// shows the error it wraps).
    fn shown(&self) -> Option<&dyn miette::Diagnostic> {
        match self {
            Error::DesignTool { source, .. } | Error::StudyTool { source, .. } => {
                Some(source.as_ref())
            }
            _ => self.typed(),
        }
    }
}

// The stages' and readers' errors, boxed (a step's result stays small).
impl From<crate::io::toolpath::ReadError> for Error {
    fn from(e: crate::io::toolpath::ReadError) -> Error {
        Error::ToolPath(Box::new(e))
    }
}

impl From<crate::io::text::TextError> for Error {
    fn from(e: crate::io::text::TextError) -> Error {
        Error::Text(Box::new(e))
    }
}

impl From<crate::io::input::InputError> for Error {
    fn from(e: crate::io::input::InputError) -> Error {
        Error::Budget(Box::new(e))
    }
}

impl From<crate::config::ConfigError> for Error {
    fn from(e: crate::config::ConfigError) -> Error {
        Error::Config(Box::new(e))
    }
}

impl From<super::inputs::ToolFileError> for Error {
    fn from(e: super::inputs::ToolFileError) -> Error {
        Error::ToolFile(Box::new(e))
    }
}

impl From<super::runout::StudyFileError> for Error {
    fn from(e: super::runout::StudyFileError) -> Error {
        Error::StudyFile(Box::new(e))
    }
}

impl From<crate::io::mesh::MeshFileError> for Error {
    fn from(e: crate::io::mesh::MeshFileError) -> Error {
        Error::MeshFile(Box::new(e))
    }
}

impl From<crate::io::measured::MeasuredError> for Error {
    fn from(e: crate::io::measured::MeasuredError) -> Error {
        Error::Measured(Box::new(e))
    }
}

impl From<super::report::MeasuredFileError> for Error {
    fn from(e: super::report::MeasuredFileError) -> Error {
        Error::MeasuredFile(Box::new(e))
    }
}

impl From<crate::study::compare::RegressionError> for Error {
    fn from(e: crate::study::compare::RegressionError) -> Error {
        Error::Regression(Box::new(e))
    }
}

impl miette::Diagnostic for Error {
    fn code<'a>(&'a self) -> Option<Box<dyn Display + 'a>> {
        self.shown()?.code()
    }
    fn severity(&self) -> Option<miette::Severity> {
        self.shown()?.severity()
    }
    fn help<'a>(&'a self) -> Option<Box<dyn Display + 'a>> {
        self.shown()?.help()
    }
    fn url<'a>(&'a self) -> Option<Box<dyn Display + 'a>> {
        self.shown()?.url()
    }
    fn source_code(&self) -> Option<&dyn miette::SourceCode> {
        self.shown()?.source_code()
    }
    fn labels(&self) -> Option<Box<dyn Iterator<Item = miette::LabeledSpan> + '_>> {
        self.shown()?.labels()
    }
    fn related<'a>(&'a self) -> Option<Box<dyn Iterator<Item = &'a dyn miette::Diagnostic> + 'a>> {
        self.shown()?.related()
    }
    fn diagnostic_source(&self) -> Option<&dyn miette::Diagnostic> {
        match self {
            Error::DesignTool { .. } | Error::StudyTool { .. } => None,
            _ => self.shown()?.diagnostic_source(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use miette::Diagnostic;

    fn chain(e: &Error) -> Vec<String> {
        std::iter::successors(Some(e as &dyn std::error::Error), |e| e.source())
            .map(ToString::to_string)
            .collect()
    }

    #[test]
    fn a_typed_error_keeps_its_code_frame_under_a_step_line() {
        let text = "shape = \"ball\"\nradius_mm = -5.0\nteeth = 2\nhelix_deg = 0.0\n";
        let e = crate::pipeline::tool_from_text(text, "t.toml").unwrap_err();
        assert!(e.labels().is_some() && e.source_code().is_some());
        let first = e.to_string();
        assert!(first.starts_with("t.toml:2:13: "), "{first}");
        let wrapped = Error::DesignTool {
            design: "d.toml".into(),
            tool: "t.toml".into(),
            source: Box::new(e),
        };
        assert!(wrapped.labels().is_some() && wrapped.source_code().is_some());
        let lines = chain(&wrapped);
        assert_eq!(
            lines[0],
            "d.toml: cannot read tool file t.toml (the path is relative to the design file)"
        );
        assert_eq!(lines[1], first);
    }

    #[test]
    fn a_cause_named_on_the_same_line_is_not_repeated() {
        let e = Error::within("f.cls", std::io::Error::other("bad"));
        assert_eq!(chain(&e), ["f.cls: bad"]);
        let e = Error::output("write runs.csv", std::io::Error::other("full"));
        assert_eq!(chain(&e), ["cannot write runs.csv: full"]);
        assert_eq!(
            Error::field("grid_um", "must be positive, got -1").to_string(),
            "‹grid_um› must be positive, got -1"
        );
        assert!(Error::Input("x".into()).labels().is_none());
    }
}
