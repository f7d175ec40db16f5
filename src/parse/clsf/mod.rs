//! CLSF: the records, their nom grammar (`grammars/clsf.ebnf`), the printer and the
//! streaming reader.
//!
//! [`ClsfReader`] streams logical records out of any [`BufRead`](std::io::BufRead): it
//! reads one physical line at a time into a reused buffer, joins `$` continuation lines,
//! drops trailing `$$` comments and blanks, and parses each logical line with the record
//! grammar. Nothing but the current line is held, so memory stays flat whatever the file
//! size.
//!
//! Records are syntax only: numbers as written, words upper-cased, no units and no
//! geometry. Unknown major words become [`RecordKind::Unknown`] (the raw text is kept);
//! the lowering turns them into warnings.
//!
//! The files: `record` (the record types), `grammar` (the nom grammar of one logical
//! record), `print` (records back to CLSF text), `reader` (the streaming reader).

mod grammar;
mod print;
mod reader;
mod record;

pub use grammar::Span;
pub use reader::{ClsfReader, parse_line, parse_str};
pub use record::{
    Arg, FeedUnit, LengthUnit, MAX_NUMBERS, Numbers, Record, RecordKind, WRITTEN_ROOM, Written,
};

/// Test helper of the files' unit tests: the one record of `s`.
#[cfg(test)]
fn one(s: &str) -> RecordKind {
    let v = parse_str(s).unwrap();
    assert_eq!(v.len(), 1, "{s}");
    v.into_iter().next().unwrap().kind
}

/// Test helper of the files' unit tests: the syntax error of `s` (line, column,
/// expected, found).
#[cfg(test)]
fn err(s: &str) -> (u32, u32, String, String) {
    let e = parse_str(s).unwrap_err();
    let s = e.syntax().unwrap();
    let expected = s.expected_text().unwrap_or_default().to_string();
    let found = s.found().unwrap_or_default().to_string();
    (s.span.line, s.span.column, expected, found)
}
