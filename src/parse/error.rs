//! Errors of the parse stage: a syntax error is a [`Located`] (where, what was expected,
//! what was found, and the text of the offending line for a code frame).

use super::position::{Located, Span};

/// Why reading a CLSF or contact12 text failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ParseError {
    /// Malformed text.
    #[error("line {}, column {}: {}", .0.span.line, .0.span.column, .0.problem)]
    Syntax(Box<Located>),
    /// The underlying reader failed.
    #[error("reading failed: {0}")]
    Io(#[from] std::io::Error),
}

impl ParseError {
    /// The syntax error, if this is one.
    pub fn syntax(&self) -> Option<&Located> {
        match self {
            ParseError::Syntax(s) => Some(s),
            ParseError::Io(_) => None,
        }
    }

    /// A syntax error at `span` of the line `line_text`.
    pub fn at(
        span: Span,
        expected: impl Into<String>,
        found: impl Into<String>,
        line_text: &str,
    ) -> ParseError {
        ParseError::Syntax(Box::new(Located::expected(
            span, expected, found, line_text,
        )))
    }
}

/// Describe the token at the start of `rest` for a "found …" message.
pub(crate) fn describe_found(rest: &str) -> String {
    let rest = rest.trim_start_matches([' ', '\t']);
    if rest.is_empty() {
        return "end of line".to_string();
    }
    let mut end = 0;
    for (k, c) in rest.char_indices() {
        if k > 0 && (c == ',' || c == '/' || c == ';' || c == ' ' || c == '\t') {
            break;
        }
        if k == 0 && (c == ',' || c == '/' || c == ';') {
            end = c.len_utf8();
            break;
        }
        end = k + c.len_utf8();
        if k >= 24 {
            break;
        }
    }
    format!("`{}`", &rest[..end])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn found_tokens() {
        assert_eq!(describe_found(""), "end of line");
        assert_eq!(describe_found("  abc,1"), "`abc`");
        assert_eq!(describe_found(",1"), "`,`");
        assert_eq!(describe_found("1.0x/"), "`1.0x`");
    }
}
