//! Positions in input text, for every reader: [`Span`] (byte offset and length, 1-based line
//! and column in characters), made from a whole text and a byte range ([`Span::of`]) or by a
//! line-by-line reader from its line ([`Span::in_line`]); and [`Located`], the one
//! diagnostic of a problem at a place in an input (the input's name, the span, what is
//! wrong, the text for a code frame), that every input error carries instead of its own
//! line and column.

use miette::{LabeledSpan, MietteError, MietteSpanContents, SourceCode, SourceSpan, SpanContents};
use std::fmt;
use std::ops::Range;

/// Where something is in an input: a byte range and the 1-based line and column (in
/// characters) of its start. `offset` counts bytes in the text the span was taken from: the
/// whole text ([`Span::of`]) or the one line of a line-by-line reader ([`Span::in_line`]).
/// A line of 0 means no position; a column of 0, a line without a column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Span {
    /// Byte offset of the start.
    pub offset: usize,
    /// Length in bytes (0: a point).
    pub len: usize,
    /// 1-based line (0: no position).
    pub line: u32,
    /// 1-based column in characters (0: none).
    pub column: u32,
}

fn to_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

impl Span {
    /// No position.
    pub const NONE: Span = Span {
        offset: 0,
        len: 0,
        line: 0,
        column: 0,
    };

    /// The byte range `range` of `text`, with the line and column of its start
    /// ([`line_column`]).
    pub fn of(text: &str, range: Range<usize>) -> Span {
        let (line, column) = line_column(text, range.start);
        Span {
            offset: range.start,
            len: range.end.saturating_sub(range.start),
            line: to_u32(line),
            column: to_u32(column),
        }
    }

    /// The point at byte `at` of `text`.
    pub fn at(text: &str, at: usize) -> Span {
        Span::of(text, at..at)
    }

    /// Bytes `range` of `text`, the text of line `line` (1-based) read on its own by a
    /// line-by-line reader; the column counts characters within the line
    /// ([`column_in_line`]) and the offset is within the line.
    pub fn in_line(line: u32, text: &str, range: Range<usize>) -> Span {
        Span {
            offset: range.start,
            len: range.end.saturating_sub(range.start),
            line,
            column: column_in_line(text, range.start),
        }
    }

    /// A line and column known without the text (bytes unknown: a point at offset 0).
    pub fn line_column(line: u32, column: u32) -> Span {
        Span {
            line,
            column,
            ..Span::NONE
        }
    }

    /// A whole line, known by its number only (no column).
    pub fn line(line: u32) -> Span {
        Span::line_column(line, 0)
    }

    /// A line number counted as `u64` (CSV readers), as a line span.
    pub fn line_u64(line: u64) -> Span {
        Span::line(u32::try_from(line).unwrap_or(u32::MAX))
    }

    /// The byte range.
    pub fn range(&self) -> Range<usize> {
        self.offset..self.offset + self.len
    }

    /// The byte range for miette's code frames.
    pub fn source_span(&self) -> SourceSpan {
        SourceSpan::new(self.offset.into(), self.len)
    }
}

/// What is wrong at a [`Located`] place.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Problem {
    /// What a reader expected there and what it found (`expected a number, found `abc``).
    Expected {
        /// What was expected, e.g. "a number".
        expected: String,
        /// What was found, e.g. "`abc`" or "end of line".
        found: String,
    },
    /// What is wrong, in words.
    Message(String),
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Problem::Expected { expected, found } => {
                write!(f, "expected {expected}, found {found}")
            }
            Problem::Message(m) => f.write_str(m),
        }
    }
}

/// The text a code frame shows: a whole input, or one line of it (`first_line` lines
/// before it), named `name`; a [`Located`]'s span counts bytes in `text`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame {
    /// The input's name (a file as given).
    pub name: String,
    /// The text shown.
    pub text: String,
    /// 0-based line number of `text`'s first line in the input.
    pub first_line: usize,
}

impl SourceCode for Frame {
    fn read_span<'a>(
        &'a self,
        span: &SourceSpan,
        context_lines_before: usize,
        context_lines_after: usize,
    ) -> Result<Box<dyn SpanContents<'a> + 'a>, MietteError> {
        let inner = self
            .text
            .read_span(span, context_lines_before, context_lines_after)?;
        Ok(Box::new(MietteSpanContents::new_named(
            self.name.clone(),
            inner.data(),
            *inner.span(),
            inner.line() + self.first_line,
            inner.column(),
            inner.line_count(),
        )))
    }
}

/// A problem at a place in an input: the one located diagnostic of every reader (CLSF,
/// G-code, contact12, TOML, tables, meshes). Shown as `file:line:column: problem` (without a
/// file, `line L, column C: problem`; without a column, `file:line: problem`), and on a
/// terminal with a code frame of its [`Frame`] when it has one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Located {
    /// The input's name, when the reader knows it.
    pub file: Option<String>,
    /// Where.
    pub span: Span,
    /// What is wrong.
    pub problem: Problem,
    /// The text for a code frame, when kept.
    pub frame: Option<Frame>,
}

impl Located {
    /// `problem` at `span`, in no named input and without a frame.
    pub fn new(span: Span, problem: Problem) -> Located {
        Located {
            file: None,
            span,
            problem,
            frame: None,
        }
    }

    /// A reader's syntax error at `span`: what it `expected` and what it `found`, with the
    /// text of the offending line (`line_text`, the text `span`'s offset counts in) for a
    /// code frame.
    pub fn expected(
        span: Span,
        expected: impl Into<String>,
        found: impl Into<String>,
        line_text: &str,
    ) -> Located {
        Located {
            file: None,
            span,
            problem: Problem::Expected {
                expected: expected.into(),
                found: found.into(),
            },
            frame: Some(Frame {
                name: String::new(),
                text: line_text.to_string(),
                first_line: span.line.saturating_sub(1) as usize,
            }),
        }
    }

    /// `message` at `span`, in no named input and without a frame.
    pub fn message(span: Span, message: impl Into<String>) -> Located {
        Located::new(span, Problem::Message(message.into()))
    }

    /// The same, in the input `file`.
    pub fn in_file(mut self, file: &str) -> Located {
        self.file = Some(file.to_string());
        if let Some(frame) = &mut self.frame {
            frame.name = file.to_string();
        }
        self
    }

    /// The same, with the whole `text` of its input (the text `span` counts in) for a code
    /// frame.
    pub fn with_text(mut self, text: &str) -> Located {
        self.frame = Some(Frame {
            name: self.file.clone().unwrap_or_default(),
            text: text.to_string(),
            first_line: 0,
        });
        self
    }

    /// What was expected, for a syntax error.
    pub fn expected_text(&self) -> Option<&str> {
        match &self.problem {
            Problem::Expected { expected, .. } => Some(expected),
            Problem::Message(_) => None,
        }
    }

    /// What was found, for a syntax error.
    pub fn found(&self) -> Option<&str> {
        match &self.problem {
            Problem::Expected { found, .. } => Some(found),
            Problem::Message(_) => None,
        }
    }

    /// The text of the frame (for a line-by-line reader's error, the offending line); empty
    /// without one.
    pub fn line_text(&self) -> &str {
        self.frame.as_ref().map_or("", |f| &f.text)
    }

    /// The problem's text without the place.
    pub fn message_text(&self) -> String {
        self.problem.to_string()
    }
}

impl fmt::Display for Located {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Span { line, column, .. } = self.span;
        match (&self.file, line, column) {
            (Some(file), 0, _) => write!(f, "{file}: ")?,
            (Some(file), l, 0) => write!(f, "{file}:{l}: ")?,
            (Some(file), l, c) => write!(f, "{file}:{l}:{c}: ")?,
            (None, 0, _) => {}
            (None, l, 0) => write!(f, "line {l}: ")?,
            (None, l, c) => write!(f, "line {l}, column {c}: ")?,
        }
        write!(f, "{}", self.problem)
    }
}

impl std::error::Error for Located {}

impl miette::Diagnostic for Located {
    fn source_code(&self) -> Option<&dyn SourceCode> {
        self.frame
            .as_ref()
            .filter(|f| !f.text.is_empty())
            .map(|f| f as &dyn SourceCode)
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = LabeledSpan> + '_>> {
        self.frame.as_ref().filter(|f| !f.text.is_empty())?;
        let label = match &self.problem {
            Problem::Expected { expected, .. } => format!("expected {expected}"),
            Problem::Message(_) => "here".to_string(),
        };
        Some(Box::new(std::iter::once(LabeledSpan::new_with_span(
            Some(label),
            self.span.source_span(),
        ))))
    }
}

/// 1-based line and column (in characters) of byte offset `at` in `text`. An offset past the
/// end points just after the last character; an offset inside a multi-byte character points
/// at that character.
pub fn line_column(text: &str, at: usize) -> (usize, usize) {
    let at = at.min(text.len());
    let mut cut = at;
    while !text.is_char_boundary(cut) {
        cut -= 1;
    }
    let before = &text[..cut];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
}

/// 1-based column (in characters) of byte `at` of a single `line`; an offset past the end or
/// inside a multi-byte character counts the bytes before it.
pub fn column_in_line(line: &str, at: usize) -> u32 {
    let chars = line
        .get(..at.min(line.len()))
        .map_or(at, |s| s.chars().count());
    u32::try_from(chars).unwrap_or(u32::MAX).saturating_add(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_column_counts_characters() {
        let text = "a = 1\nµ = 2\n";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 6), (2, 1));
        // 'µ' is two bytes: the '=' after it is the third character.
        assert_eq!(line_column(text, 9), (2, 3));
        // Inside the two bytes of 'µ': the character itself.
        assert_eq!(line_column(text, 7), (2, 1));
        assert_eq!(line_column(text, 1000), (3, 1));
    }

    #[test]
    fn column_in_line_counts_characters_before_the_byte() {
        assert_eq!(column_in_line("G1 X1", 0), 1);
        assert_eq!(column_in_line("G1 X1", 3), 4);
        assert_eq!(column_in_line("µ,X", 3), 3); // 'µ' is two bytes, one character
        assert_eq!(column_in_line("ab", 10), 3); // past the end: after the last character
        assert_eq!(column_in_line("µb", 1), 2); // inside 'µ': the bytes before it
    }

    #[test]
    fn spans_from_a_text_and_from_a_line() {
        let text = "a = 1\nµ = 22\n";
        let s = Span::of(text, 11..13);
        assert_eq!((s.offset, s.len, s.line, s.column), (11, 2, 2, 5));
        assert_eq!(s.range(), 11..13);
        assert_eq!(s.source_span(), SourceSpan::new(11.into(), 2));
        let s = Span::in_line(7, "µ,X", 3..4);
        assert_eq!((s.offset, s.len, s.line, s.column), (3, 1, 7, 3));
        assert_eq!(Span::line(4), Span::line_column(4, 0));
    }

    #[test]
    fn located_messages_name_file_line_and_column() {
        let e = Located::expected(Span::line_column(3, 5), "a number", "`x`", "GOTO/x");
        assert_eq!(
            e.to_string(),
            "line 3, column 5: expected a number, found `x`"
        );
        assert_eq!(e.found(), Some("`x`"));
        assert_eq!(e.line_text(), "GOTO/x");
        let e = e.in_file("a.cls");
        assert_eq!(e.to_string(), "a.cls:3:5: expected a number, found `x`");
        assert_eq!(
            e.frame.as_ref().map(|f| (f.name.as_str(), f.first_line)),
            Some(("a.cls", 2))
        );
        let e = Located::message(Span::line(2), "bad").in_file("t.csv");
        assert_eq!(e.to_string(), "t.csv:2: bad");
        assert_eq!(
            Located::message(Span::line(2), "bad").to_string(),
            "line 2: bad"
        );
        assert_eq!(
            Located::message(Span::NONE, "bad").in_file("f").to_string(),
            "f: bad"
        );
    }
}
