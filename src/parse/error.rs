//! Errors of the parse stage: where (1-based line and column), what was expected, what
//! was found, and the text of the offending line for a code frame.

/// A syntax error with its position.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SyntaxError {
    /// 1-based line of the error.
    pub line: u32,
    /// 1-based column (characters) of the error.
    pub column: u32,
    /// What the grammar expected there, e.g. "a number".
    pub expected: String,
    /// What was found there, e.g. "`abc`" or "end of line".
    pub found: String,
    /// The text of the physical line, without its line ending.
    pub line_text: String,
}

/// Why reading a CLSF or contact12 text failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ParseError {
    /// Malformed text.
    #[error("line {}, column {}: expected {}, found {}", .0.line, .0.column, .0.expected, .0.found)]
    Syntax(Box<SyntaxError>),
    /// The underlying reader failed.
    #[error("reading failed: {0}")]
    Io(#[from] std::io::Error),
}

impl ParseError {
    /// The syntax error, if this is one.
    pub fn syntax(&self) -> Option<&SyntaxError> {
        match self {
            ParseError::Syntax(s) => Some(s),
            ParseError::Io(_) => None,
        }
    }

    /// Build a syntax error.
    pub fn at(
        line: u32,
        column: u32,
        expected: impl Into<String>,
        found: impl Into<String>,
        line_text: &str,
    ) -> ParseError {
        ParseError::Syntax(Box::new(SyntaxError {
            line,
            column,
            expected: expected.into(),
            found: found.into(),
            line_text: line_text.to_string(),
        }))
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
