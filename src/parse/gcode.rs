//! ISO G-code (RS-274 / ISO 6983 blocks, `grammars/gcode.ebnf`): one block a line, split
//! into address words (`G1`, `X-12.5`, `N10`), keywords (`TRAORI`, `CYCLE832(…)`) and
//! comments (`(…)` and `; …`), with the line and column of each. No geometry, no units:
//! what the words mean is decided by the lowering (`crate::nc`).
//!
//! A comment whose text is a CLSF `TLDATA/…` or `CONTACT/…` record is parsed as that
//! record (the contact data and tool crest writes into its G-code), with its position.

use super::clsf::{RecordKind, parse_line};
use super::error::{ParseError, describe_found};
use super::position::Problem;
use std::io::BufRead;

/// One address word: a letter and its number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Word {
    /// The address letter, upper case (`b'G'`, `b'X'`, …).
    pub letter: u8,
    /// The number as written.
    pub value: f64,
    /// 1-based column of the letter.
    pub column: u32,
}

impl Word {
    /// The code of a `G` or `M` word in tenths (`G43.4` → 434, `G1` → 10), or `None` when
    /// the value is not a whole number of tenths.
    pub fn code(&self) -> Option<i64> {
        let t = self.value * 10.0;
        let r = t.round();
        ((t - r).abs() < 1e-6 && r.abs() < 1e9).then_some(r as i64)
    }
}

/// A word of letters that is not an address word: a controller keyword (`TRAORI`,
/// `TRAFOOF`) or a call (`CYCLE832(0.01,1)`), as written.
#[derive(Debug, Clone, PartialEq)]
pub struct Keyword {
    /// The name, upper case (`TRAORI`, `CYCLE832`).
    pub name: String,
    /// The whole text of the keyword with its arguments, as written.
    pub text: String,
    /// 1-based column of its first letter.
    pub column: u32,
}

/// A CLSF record written in a comment (`(CONTACT/x,y,z,nx,ny,nz)`, `(TLDATA/MILL,…)`).
#[derive(Debug, Clone, PartialEq)]
pub struct CommentRecord {
    /// The record.
    pub kind: RecordKind,
    /// 1-based column of its first character.
    pub column: u32,
}

/// One block (line) of G-code.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Block {
    /// 1-based line.
    pub line: u32,
    /// The block starts with `/` (block delete: skipped when the operator switches it on).
    pub block_delete: bool,
    /// Address words in order.
    pub words: Vec<Word>,
    /// Keywords and calls in order.
    pub keywords: Vec<Keyword>,
    /// Comment texts in order, trimmed.
    pub comments: Vec<String>,
    /// CLSF records found in comments.
    pub records: Vec<CommentRecord>,
}

impl Block {
    /// The last word with `letter`.
    pub fn word(&self, letter: u8) -> Option<&Word> {
        self.words.iter().rev().find(|w| w.letter == letter)
    }

    /// True when the block holds nothing (a blank line, a `%` line or comments only).
    pub fn is_empty(&self) -> bool {
        self.words.is_empty() && self.keywords.is_empty() && self.records.is_empty()
    }
}

use super::position::{Span, column_in_line as column_of};

/// The number of an address word: `[+|-] (digits [. [digits]] | . digits)`, no exponent
/// (`E` is an address letter). Returns the value and the bytes used.
fn word_number(b: &[u8]) -> Option<(f64, usize)> {
    let mut i = 0;
    if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
        i += 1;
    }
    let digits_start = i;
    while i < b.len() && b[i].is_ascii_digit() {
        i += 1;
    }
    let mut digits = i - digits_start;
    if i < b.len() && b[i] == b'.' {
        i += 1;
        let f = i;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        digits += i - f;
    }
    if digits == 0 {
        return None;
    }
    let (v, n) = super::number::scan_number(&b[..i])?;
    (n == i && v.is_finite()).then_some((v, i))
}

/// Parse one line of G-code; `line` is its 1-based number.
pub fn parse_block(text: &str, line: u32) -> Result<Block, ParseError> {
    let text = text.trim_end_matches(['\r', '\n']);
    let b = text.as_bytes();
    let mut block = Block {
        line,
        ..Default::default()
    };
    let err = |at: usize, expected: &str, found: String| {
        ParseError::at(Span::in_line(line, text, at..at), expected, found, text)
    };
    let mut i = 0;
    let skip_blanks = |i: &mut usize| {
        while *i < b.len() && (b[*i] == b' ' || b[*i] == b'\t') {
            *i += 1;
        }
    };
    skip_blanks(&mut i);
    if b.get(i) == Some(&b'%') {
        // Program start/end marker; anything after it is a comment.
        return Ok(block);
    }
    if b.get(i) == Some(&b'/') {
        block.block_delete = true;
        i += 1;
    }
    loop {
        skip_blanks(&mut i);
        let Some(&c) = b.get(i) else {
            return Ok(block);
        };
        match c {
            b'(' => {
                let Some(close) = text[i + 1..].find(')') else {
                    return Err(err(
                        text.len(),
                        "`)` closing the comment",
                        "end of line".into(),
                    ));
                };
                let body_start = i + 1;
                let body = &text[body_start..body_start + close];
                comment(&mut block, text, body, body_start, line)?;
                i = body_start + close + 1;
            }
            b';' => {
                let body = &text[i + 1..];
                comment(&mut block, text, body, i + 1, line)?;
                return Ok(block);
            }
            c if c.is_ascii_alphabetic() => {
                let start = i;
                while i < b.len() && b[i].is_ascii_alphabetic() {
                    i += 1;
                }
                if i - start == 1 {
                    let rest = &b[i..];
                    let mut k = 0;
                    while k < rest.len() && (rest[k] == b' ' || rest[k] == b'\t') {
                        k += 1;
                    }
                    match word_number(&rest[k..]) {
                        Some((value, n)) => {
                            block.words.push(Word {
                                letter: c.to_ascii_uppercase(),
                                value,
                                column: column_of(text, start),
                            });
                            i += k + n;
                        }
                        None => {
                            return Err(err(
                                i + k,
                                &format!("a number after {}", c.to_ascii_uppercase() as char),
                                describe_found(&text[i + k..]),
                            ));
                        }
                    }
                } else {
                    while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                        i += 1;
                    }
                    let name = text[start..i].to_ascii_uppercase();
                    if b.get(i) == Some(&b'(') {
                        i = call_end(text, i).ok_or_else(|| {
                            err(text.len(), "`)` closing the call", "end of line".into())
                        })?;
                    }
                    block.keywords.push(Keyword {
                        name,
                        text: text[start..i].to_string(),
                        column: column_of(text, start),
                    });
                }
            }
            _ => {
                return Err(err(
                    i,
                    "a word (letter and number), a keyword, a comment or the end of the block",
                    describe_found(&text[i..]),
                ));
            }
        }
    }
}

/// The byte after the `)` matching the `(` at `open`, skipping quoted strings.
fn call_end(text: &str, open: usize) -> Option<usize> {
    let b = text.as_bytes();
    let mut depth = 0usize;
    let mut quoted = false;
    for (k, &c) in b.iter().enumerate().skip(open) {
        match c {
            b'"' => quoted = !quoted,
            b'(' if !quoted => depth += 1,
            b')' if !quoted => {
                depth -= 1;
                if depth == 0 {
                    return Some(k + 1);
                }
            }
            _ => {}
        }
    }
    None
}

/// Keep a comment; parse it as a CLSF record when it is `TLDATA/…` or `CONTACT/…`.
fn comment(
    block: &mut Block,
    text: &str,
    body: &str,
    body_start: usize,
    line: u32,
) -> Result<(), ParseError> {
    let lead = body.len() - body.trim_start().len();
    let t = body.trim();
    let upper: String = t.chars().take(8).collect::<String>().to_ascii_uppercase();
    if upper.starts_with("TLDATA/") || upper.starts_with("CONTACT/") {
        let at = body_start + lead;
        let rec = parse_line(t, line).map_err(|e| match e {
            ParseError::Syntax(s) => {
                // Bytes of the comment text → bytes of the G-code line.
                let range = s.span.range();
                let span = Span::in_line(line, text, at + range.start..at + range.end);
                let (expected, found) = match s.problem {
                    Problem::Expected { expected, found } => (expected, found),
                    Problem::Message(m) => (m, String::new()),
                };
                ParseError::at(span, expected, found, text)
            }
            other => other,
        })?;
        block.records.push(CommentRecord {
            kind: rec.kind,
            column: column_of(text, at),
        });
    }
    block.comments.push(t.to_string());
    Ok(())
}

/// Streams [`Block`]s out of G-code text, one line at a time (empty lines included, as
/// empty blocks are skipped).
pub struct GcodeReader<R> {
    src: R,
    buf: Vec<u8>,
    line: u32,
    done: bool,
}

impl<R: BufRead> GcodeReader<R> {
    /// Read from `src`.
    pub fn new(src: R) -> Self {
        GcodeReader {
            src,
            buf: Vec::with_capacity(128),
            line: 0,
            done: false,
        }
    }

    fn next_block(&mut self) -> Result<Option<Block>, ParseError> {
        loop {
            self.buf.clear();
            if self.src.read_until(b'\n', &mut self.buf)? == 0 {
                return Ok(None);
            }
            self.line = self.line.saturating_add(1);
            let text = match std::str::from_utf8(&self.buf) {
                Ok(t) => t,
                Err(e) => {
                    let at = e.valid_up_to();
                    let shown = String::from_utf8_lossy(&self.buf).into_owned();
                    let shown = shown.trim_end_matches(['\r', '\n']);
                    return Err(ParseError::at(
                        Span::in_line(self.line, shown, at..at + 1),
                        "ASCII or UTF-8 text",
                        format!("byte 0x{:02X}", self.buf[at]),
                        shown,
                    ));
                }
            };
            let block = parse_block(text, self.line)?;
            if !block.is_empty() {
                return Ok(Some(block));
            }
        }
    }
}

impl<R: BufRead> Iterator for GcodeReader<R> {
    type Item = Result<Block, ParseError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        match self.next_block() {
            Ok(Some(b)) => Some(Ok(b)),
            Ok(None) => {
                self.done = true;
                None
            }
            Err(e) => {
                self.done = true;
                Some(Err(e))
            }
        }
    }
}

/// True when `text` (the head of a file) reads as G-code: no line has the `WORD/` form of
/// an APT record or a `$$` comment, and some lines hold nothing but address words and
/// comments, with at least one G, M, X, Y or Z word among them.
pub fn looks_like_gcode(text: &str) -> bool {
    let mut words_only = 0usize;
    let mut motion = false;
    for raw in text.lines().take(400) {
        let t = raw.trim();
        if t.is_empty() || t.starts_with('%') {
            continue;
        }
        if t.starts_with("$$") || looks_like_apt_record(t) {
            return false;
        }
        match parse_block(t, 1) {
            Ok(b) if !b.words.is_empty() && b.keywords.is_empty() => {
                words_only += 1;
                motion |= b
                    .words
                    .iter()
                    .any(|w| matches!(w.letter, b'G' | b'M' | b'X' | b'Y' | b'Z'));
            }
            Ok(_) => {}
            // A line that does not lex may be a controller extension (`R1=5`): it counts
            // against nothing, but neither for G-code.
            Err(_) => {}
        }
    }
    words_only > 0 && motion
}

/// `WORD/…` or `TOOL PATH/…`: letters (and blanks) up to a slash.
fn looks_like_apt_record(t: &str) -> bool {
    let Some(k) = t.find('/') else {
        return false;
    };
    let head = t[..k].trim_end();
    !head.is_empty()
        && head.as_bytes()[0].is_ascii_alphabetic()
        && head
            .bytes()
            .all(|c| c.is_ascii_alphanumeric() || c == b'_' || c == b'-' || c == b' ')
        && head.bytes().filter(|c| c.is_ascii_alphabetic()).count() >= 2
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(s: &str) -> Block {
        parse_block(s, 1).unwrap_or_else(|e| panic!("{e}"))
    }

    fn err(s: &str) -> (u32, String, String) {
        let e = parse_block(s, 1).unwrap_err();
        let s = e.syntax().unwrap();
        let found = s.found().unwrap_or_default().to_string();
        (
            s.span.column,
            s.expected_text().unwrap_or_default().to_string(),
            found,
        )
    }

    #[test]
    fn words_keywords_and_comments() {
        let b = block("N10 G1X-1.5 Y.25 z10. A+30 (FINISH) F2000 ; feed");
        let letters: Vec<char> = b.words.iter().map(|w| w.letter as char).collect();
        assert_eq!(letters, ['N', 'G', 'X', 'Y', 'Z', 'A', 'F']);
        assert_eq!(b.word(b'X').map(|w| (w.value, w.column)), Some((-1.5, 7)));
        assert_eq!(b.word(b'Y').map(|w| w.value), Some(0.25));
        assert_eq!(b.word(b'Z').map(|w| w.value), Some(10.0));
        assert_eq!(b.comments, ["FINISH", "feed"]);
        let b = block("G43.4 H1 TRAORI CYCLE832(0.01,_ORI_FINISH,1) MSG(\"A (B)\")");
        assert_eq!(b.word(b'G').and_then(|w| w.code()), Some(434));
        let names: Vec<&str> = b.keywords.iter().map(|k| k.name.as_str()).collect();
        assert_eq!(names, ["TRAORI", "CYCLE832", "MSG"]);
        assert_eq!(b.keywords[1].text, "CYCLE832(0.01,_ORI_FINISH,1)");
        assert!(block("% program").is_empty());
        assert!(block("/N20 M1").block_delete);
    }

    #[test]
    fn comments_holding_clsf_records() {
        let b = block("G1 X1 (CONTACT/1,2,3,0,0,1) (TLDATA/MILL,10,5,75,0,0)");
        assert_eq!(b.records.len(), 2);
        assert!(matches!(b.records[0].kind, RecordKind::Contact(n) if n.len() == 6));
        assert_eq!(b.records[0].column, 8);
        // A bad number in the comment is named at its column in the line.
        assert_eq!(err("G1 X1 (CONTACT/1,2,x)").0, 20);
    }

    #[test]
    fn errors_name_the_column() {
        assert_eq!(
            err("G1 X1 Y-q"),
            (8, "a number after Y".into(), "`-q`".into())
        );
        // Letters together are a keyword (the lowering warns about unknown ones).
        assert_eq!(block("G1 X1 Yabc").keywords[0].name, "YABC");
        assert_eq!(err("G1 X1 (open").1, "`)` closing the comment");
        assert_eq!(err("R1=5").0, 3);
    }

    #[test]
    fn detection_by_content() {
        assert!(looks_like_gcode(
            "%\nO1000 (PART)\nN10 G90 G17 G21\nN20 T1 M6\nN30 G0 X0 Y0 Z50 A0 C0\n%\n"
        ));
        assert!(looks_like_gcode(
            "; Siemens\nTRAORI\nG1 X1 Y2 Z3 A4 C5 F100\n"
        ));
        assert!(!looks_like_gcode("TOOL PATH/A,TOOL,T\nRAPID\nGOTO/1,2,3\n"));
        assert!(!looks_like_gcode(
            "PARTNO X\nMULTAX\nGOTO / 1, 2, 3\nFINI\n"
        ));
        assert!(!looks_like_gcode("$$ header\nRAPID\n"));
        assert!(!looks_like_gcode("1 2 3 0 0 1 1 2 3 0 0 1\n"));
    }
}
