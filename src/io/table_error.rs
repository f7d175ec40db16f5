//! The one error of a line or a field of a text table (the two-column series, the planned
//! feed, the measured table): a [`Located`] in the file, shown `file:line: message` for a
//! line and `file:line:column: message` for a field.

use crate::parse::{Located, Span};
use std::fmt;

/// A line or a field of a table that could not be read (its place boxed: a reader's result
/// stays small).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TableError(pub Box<Located>);

impl TableError {
    /// `message` about line `line` (1-based; 0 when unknown) of `file`.
    pub fn line(file: &str, line: u64, message: impl Into<String>) -> TableError {
        TableError(Box::new(
            Located::message(Span::line_u64(line), message).in_file(file),
        ))
    }

    /// `message` about the field at `at` (its line and column) of `file`.
    pub fn field(file: &str, at: Span, message: impl Into<String>) -> TableError {
        TableError(Box::new(Located::message(at, message).in_file(file)))
    }
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Located {
            file,
            span,
            problem,
            ..
        } = self.0.as_ref();
        let file = file.as_deref().unwrap_or_default();
        match span.column {
            0 => write!(f, "{file}:{}: {problem}", span.line),
            c => write!(f, "{file}:{}:{c}: {problem}", span.line),
        }
    }
}

impl std::error::Error for TableError {}

impl miette::Diagnostic for TableError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_or_a_field_names_the_file_and_its_place() {
        assert_eq!(
            TableError::line("t.csv", 3, "no data").to_string(),
            "t.csv:3: no data"
        );
        // A line the csv crate could not place is line 0, still shown.
        assert_eq!(
            TableError::line("t.csv", 0, "bad").to_string(),
            "t.csv:0: bad"
        );
        let at = Span::line_column(4, 7);
        assert_eq!(
            TableError::field("t.csv", at, "expected a number").to_string(),
            "t.csv:4:7: expected a number"
        );
        assert_eq!(TableError::field("t.csv", at, "x").0.span, at);
    }
}
