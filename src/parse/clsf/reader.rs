//! The streaming CLSF reader: physical lines joined into logical records (`$`
//! continuations, `$$` comments), parsed one at a time, with line and column.

use super::grammar::{Span, goto_numbers, goto_numbers_with_forms, parse_record};
use super::record::{Numbers, Record, RecordKind, Written};
use crate::parse::error::{ParseError, describe_found};
use crate::parse::position::Span as At;
use std::io::BufRead;

/// One physical line that went into a logical record: where it starts in the joined text.
#[derive(Debug, Clone, Copy)]
struct Piece {
    offset: usize,
    line: u32,
    /// Byte offset in the physical line of the piece's first byte.
    column_base: usize,
}

/// Streams [`Record`]s out of CLSF text, one logical line at a time.
pub struct ClsfReader<R> {
    src: R,
    buf: Vec<u8>,
    line: u32,
    joined: String,
    pieces: Vec<Piece>,
    /// Physical lines of the current joined record (for error frames).
    joined_lines: Vec<String>,
    done: bool,
}

impl<R: BufRead> ClsfReader<R> {
    /// Read from `src` (wrap files in a `BufReader`).
    pub fn new(src: R) -> Self {
        ClsfReader {
            src,
            buf: Vec::with_capacity(256),
            line: 0,
            joined: String::new(),
            pieces: Vec::new(),
            joined_lines: Vec::new(),
            done: false,
        }
    }

    /// Number of physical lines read so far.
    pub fn lines_read(&self) -> u32 {
        self.line
    }

    /// The next record if it is a `GOTO/` line of bare-comma numbers (3, 6, 9 or 12) that
    /// lies whole in the reader's buffer: its numbers and line, parsed where they lie
    /// (no copy of the line, no UTF-8 check, no [`Record`] built). `Ok(None)`, nothing
    /// consumed, for anything else, which the iterator reads ([`Iterator::next`] takes
    /// this path too). Readers that lower a file record by record call this first, in a
    /// loop, for the bulk of it.
    pub fn next_goto(&mut self) -> Result<Option<(Numbers, u32)>, ParseError> {
        self.next_goto_as::<false>(None)
    }

    /// [`Self::next_goto`], keeping the line's numbers as written in `written` (its text,
    /// the forms of its numbers, the values and the line; see [`Written`]).
    pub fn next_goto_written(
        &mut self,
        written: &mut Written,
    ) -> Result<Option<(Numbers, u32)>, ParseError> {
        self.next_goto_as::<true>(Some(written))
    }

    #[inline(always)]
    fn next_goto_as<const KEEP: bool>(
        &mut self,
        written: Option<&mut Written>,
    ) -> Result<Option<(Numbers, u32)>, ParseError> {
        // After the first line (which may carry a byte-order mark) and outside a
        // continued record.
        if self.done || self.line == 0 || !self.joined.is_empty() {
            return Ok(None);
        }
        let r = self.next_goto_in_place::<KEEP>(written);
        if r.is_err() {
            // As `next`: after an error the stream ends.
            self.done = true;
        }
        r
    }

    #[inline(always)]
    fn next_goto_in_place<const KEEP: bool>(
        &mut self,
        written: Option<&mut Written>,
    ) -> Result<Option<(Numbers, u32)>, ParseError> {
        let avail = self.src.fill_buf()?;
        let Some(rest) = avail.strip_prefix(b"GOTO/") else {
            return Ok(None);
        };
        // Numbers and commas up to the line end: no blank, no `$`, no other byte, so the
        // record starts in column 1 and the slow path would take its own fast path too.
        // The scan sees the buffer past the line (the line end stops every number), so the
        // last number too is read eight bytes at a time; a line cut by the buffer's end
        // stops at it, and is left to the line reader.
        let mut forms = 0;
        let found = if KEEP {
            goto_numbers_with_forms(rest, &mut forms)
        } else {
            goto_numbers(rest)
        };
        let Some((n, used)) = found else {
            return Ok(None);
        };
        let eol = match rest.get(used..) {
            Some([b'\n', ..]) => 1,
            Some([b'\r', b'\n', ..]) => 2,
            _ => return Ok(None),
        };
        if !matches!(n.len(), 3 | 6 | 9 | 12) {
            return Ok(None);
        }
        let line = self.line.saturating_add(1);
        if let Some(w) = written {
            w.forms = forms;
            w.keep(&rest[..used], line, n);
        }
        self.src.consume(5 + used + eol);
        self.line = line;
        Ok(Some((n, line)))
    }

    fn next_record(&mut self) -> Result<Option<Record>, ParseError> {
        if let Some((n, line)) = self.next_goto()? {
            return Ok(Some(Record {
                kind: RecordKind::Goto(n),
                line,
                column: 1,
            }));
        }
        loop {
            self.buf.clear();
            let n = self.src.read_until(b'\n', &mut self.buf)?;
            if n == 0 {
                self.done = true;
                if self.joined.is_empty() {
                    return Ok(None);
                }
                // A `$` on the last line: parse what was joined.
                return self.parse_joined().map(Some);
            }
            self.line = self.line.saturating_add(1);
            // A UTF-8 byte-order mark at the start of the file is not part of the text.
            if self.line == 1 && self.buf.starts_with(b"\xEF\xBB\xBF") {
                self.buf.drain(..3);
            }
            let mut end = self.buf.len();
            if end > 0 && self.buf[end - 1] == b'\n' {
                end -= 1;
            }
            if end > 0 && self.buf[end - 1] == b'\r' {
                end -= 1;
            }
            let text = match std::str::from_utf8(&self.buf[..end]) {
                Ok(t) => t,
                Err(e) => {
                    let bad = e.valid_up_to();
                    let shown = String::from_utf8_lossy(&self.buf[..end]).into_owned();
                    return Err(ParseError::at(
                        At::in_line(self.line, &shown, bad..bad + 1),
                        "ASCII or UTF-8 text",
                        format!("byte 0x{:02X}", self.buf[bad]),
                        &shown,
                    ));
                }
            };
            let trimmed = text.trim_end_matches([' ', '\t']);
            let lead = trimmed.len() - trimmed.trim_start_matches([' ', '\t']).len();
            let body = &trimmed[lead..];
            if self.joined.is_empty() {
                if body.is_empty() {
                    continue;
                }
                if body.starts_with("$$") {
                    return parse_physical(body, self.line, lead, text).map(Some);
                }
            }
            // Drop a trailing `$$` comment, then look for a `$` continuation mark.
            let code = if body.find('$').is_none() {
                body
            } else {
                match body.find("$$") {
                    Some(k) => body[..k].trim_end_matches([' ', '\t']),
                    None => body,
                }
            };
            if let Some(stripped) = code.strip_suffix('$') {
                if self.joined.is_empty() {
                    self.joined_lines.clear();
                }
                self.pieces.push(Piece {
                    offset: self.joined.len(),
                    line: self.line,
                    column_base: lead,
                });
                self.joined.push_str(stripped);
                // A continued line's end acts as a blank between arguments.
                self.joined_lines.push(text.to_string());
                continue;
            }
            if self.joined.is_empty() {
                if code.is_empty() {
                    continue;
                }
                return parse_physical(code, self.line, lead, text).map(Some);
            }
            self.pieces.push(Piece {
                offset: self.joined.len(),
                line: self.line,
                column_base: lead,
            });
            self.joined.push_str(code);
            self.joined_lines.push(text.to_string());
            return self.parse_joined().map(Some);
        }
    }

    fn parse_joined(&mut self) -> Result<Record, ParseError> {
        let joined = std::mem::take(&mut self.joined);
        let pieces = std::mem::take(&mut self.pieces);
        let lines = std::mem::take(&mut self.joined_lines);
        let locate = |offset: usize| -> (u32, u32, At, &str) {
            let k = pieces.iter().rposition(|p| p.offset <= offset).unwrap_or(0);
            let p = pieces.get(k).copied().unwrap_or(Piece {
                offset: 0,
                line: self.line,
                column_base: 0,
            });
            let line_text = lines.get(k).map(String::as_str).unwrap_or("");
            let in_piece = offset - p.offset;
            let byte_col = p.column_base + in_piece;
            let at = At::in_line(p.line, line_text, byte_col..byte_col);
            (p.line, at.column, at, line_text)
        };
        let span = Span::new(joined.as_str());
        let start = joined.len() - joined.trim_start_matches([' ', '\t']).len();
        match parse_record(span) {
            Ok((_, kind)) => {
                let (line, column, _, _) = locate(start);
                Ok(Record { kind, line, column })
            }
            Err(nom::Err::Error(e) | nom::Err::Failure(e)) => {
                let (_, _, at, text) = locate(e.at.location_offset());
                let found = e.found.unwrap_or_else(|| describe_found(e.at.fragment()));
                Err(ParseError::at(at, e.expected, found, text))
            }
            Err(nom::Err::Incomplete(_)) => {
                let (_, _, at, text) = locate(joined.len());
                Err(ParseError::at(at, "more input", "end of line", text))
            }
        }
    }
}

/// Parse one record that sits on a single physical line. `lead` = byte offset of `code`
/// in `full` (the whole physical line, for columns and the code frame).
fn parse_physical(code: &str, line: u32, lead: usize, full: &str) -> Result<Record, ParseError> {
    // Fast path for the bulk of a file: `GOTO/` with bare-comma numbers. Anything
    // unusual (blanks, lower case, errors) goes through the grammar below.
    if let Some(rest) = code.strip_prefix("GOTO/")
        && let Some((n, used)) = goto_numbers(rest.as_bytes())
        && used == rest.len()
        && matches!(n.len(), 3 | 6 | 9 | 12)
    {
        return Ok(Record {
            kind: RecordKind::Goto(n),
            line,
            column: lead as u32 + 1,
        });
    }
    let at = |byte: usize| At::in_line(line, full, lead + byte..lead + byte);
    match parse_record(Span::new(code)) {
        Ok((_, kind)) => Ok(Record {
            kind,
            line,
            column: at(0).column,
        }),
        Err(nom::Err::Error(e) | nom::Err::Failure(e)) => {
            let found = e.found.unwrap_or_else(|| describe_found(e.at.fragment()));
            Err(ParseError::at(
                at(e.at.location_offset()),
                e.expected,
                found,
                full,
            ))
        }
        Err(nom::Err::Incomplete(_)) => Err(ParseError::at(
            at(code.len()),
            "more input",
            "end of line",
            full,
        )),
    }
}

/// Parse one physical line (no continuation) as a record; `line` is its 1-based number.
/// Blank lines are an error ("a record word").
pub fn parse_line(text: &str, line: u32) -> Result<Record, ParseError> {
    let text = text.trim_end_matches(['\r', '\n']);
    let trimmed = text.trim_end_matches([' ', '\t']);
    let lead = trimmed.len() - trimmed.trim_start_matches([' ', '\t']).len();
    parse_physical(&trimmed[lead..], line, lead, text)
}

impl<R: BufRead> Iterator for ClsfReader<R> {
    type Item = Result<Record, ParseError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        match self.next_record() {
            Ok(Some(r)) => Some(Ok(r)),
            Ok(None) => None,
            Err(e) => {
                // After an error the stream ends: the caller reports it.
                self.done = true;
                Some(Err(e))
            }
        }
    }
}

/// Parse a whole CLSF text into records (convenience for tests and small inputs).
pub fn parse_str(text: &str) -> Result<Vec<Record>, ParseError> {
    ClsfReader::new(text.as_bytes()).collect()
}

#[cfg(test)]
mod tests {
    use super::super::err;
    use super::super::record::Numbers;
    use super::*;

    #[test]
    fn a_byte_order_mark_is_skipped() {
        let recs = parse_str("\u{feff}TOOL PATH/A,TOOL,T\nGOTO/1,2,3\nEND-OF-PATH\n").unwrap();
        assert_eq!(recs.len(), 3);
        assert_eq!((recs[1].line, recs[1].column), (2, 1));
    }

    #[test]
    fn continuation_comments_and_line_endings() {
        let v = parse_str("GOTO/1,$\r\n  2,3 $$ note\r\n\r\nRAPID  \r\nGOTO/4,5,6$$x\n").unwrap();
        assert_eq!(v.len(), 3);
        assert!(matches!(&v[0].kind, RecordKind::Goto(n) if n.as_slice() == [1.0, 2.0, 3.0]));
        assert_eq!((v[1].line, v[1].column), (4, 1));
        assert_eq!(
            v[2].kind,
            RecordKind::Goto(Numbers::from_slice(&[4.0, 5.0, 6.0]).unwrap())
        );
        // An error on a continued line points at that line.
        let (line, col, _, found) = err("GOTO/1,$\n  2,x\n");
        assert_eq!((line, col, found.as_str()), (2, 5, "`x`"));
    }

    /// Records as `io::toolpath::stream_from` reads them: `GOTO` lines through
    /// `next_goto` while it finds them, the rest through the iterator.
    fn read_as_streamed(text: &str, capacity: usize) -> Vec<Result<Record, String>> {
        let src = std::io::BufReader::with_capacity(capacity, text.as_bytes());
        let mut r = ClsfReader::new(src);
        let mut out = Vec::new();
        loop {
            match r.next_goto() {
                Ok(Some((n, line))) => {
                    out.push(Ok(Record {
                        kind: RecordKind::Goto(n),
                        line,
                        column: 1,
                    }));
                    continue;
                }
                Ok(None) => {}
                Err(e) => {
                    out.push(Err(e.to_string()));
                    break;
                }
            }
            match r.next() {
                None => break,
                Some(Ok(rec)) => out.push(Ok(rec)),
                Some(Err(e)) => {
                    out.push(Err(e.to_string()));
                    break;
                }
            }
        }
        out
    }

    proptest::proptest! {
        /// GOTO lines read in place from the buffer (any buffer size, so lines are cut by
        /// its end anywhere) give the records of the lines parsed one by one: numbers of
        /// every form (exponents, lone points, signs), counts past 12, CR LF, other records.
        #[test]
        fn goto_lines_read_in_place_parse_as_single_lines(
            lines in proptest::collection::vec(
                (proptest::collection::vec(0usize..16, 1..14), proptest::bool::ANY, 0usize..8),
                1..40,
            ),
            capacity in 1usize..300,
        ) {
            const NUMBERS: [&str; 16] = [
                "-1.7916", "0.2588190", "0", "-0.0000", "12.5", "1.5E3", "2e", "-.5", "7.",
                "+3", "123456789.123", "0.9950372", "-99.9999", "x", "1e-3", "5",
            ];
            let mut text = String::new();
            let mut expected = Vec::new();
            for (k, (nums, crlf, kind)) in lines.iter().enumerate() {
                let line = match kind {
                    0 => "RAPID".to_string(),
                    1 => "$$ a comment".to_string(),
                    _ => {
                        let n: Vec<&str> = nums.iter().map(|&i| NUMBERS[i]).collect();
                        format!("GOTO/{}", n.join(","))
                    }
                };
                text.push_str(&line);
                text.push_str(if *crlf { "\r\n" } else { "\n" });
                let rec = parse_line(&line, k as u32 + 1).map_err(|e| e.to_string());
                let failed = rec.is_err();
                expected.push(rec);
                if failed {
                    break;
                }
            }
            proptest::prop_assert_eq!(read_as_streamed(&text, capacity), expected);
        }
    }
}
