//! The 12-column contact file (contact12) of the 002 paper (`grammars/contact12.ebnf`).
//!
//! One line per posture: CL point x y z, tool axis i j k, CC point, surface normal.
//! Fields are separated by blanks (spaces/tabs), or by one comma or semicolon with
//! optional blanks around it. The first non-blank line may be a header (its first field
//! is not a number). In the CC and normal columns `NA`, `N/A` (any case) or an empty field
//! (between commas or semicolons) mean "no value"; further columns after the twelfth are
//! ignored. Whether a line is cutting is decided by the lowering (`toolpath`), not here.

use super::error::{ParseError, describe_found};
use super::number::scan_number;
use std::io::BufRead;

/// One data line of a contact12 file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact12Row {
    /// Columns 1-6: CL point and tool axis, as written.
    pub cl_axis: [f64; 6],
    /// Columns 7-12: CC point and normal; `None` = `NA`, `N/A` or empty.
    pub contact: [Option<f64>; 6],
    /// 1-based line.
    pub line: u32,
    /// 1-based column of each of the 12 fields.
    pub columns: [u32; 12],
}

fn is_blank(b: u8) -> bool {
    b == b' ' || b == b'\t'
}

/// Split one line into fields: `(start byte, text)`. Empty fields appear only between
/// commas/semicolons.
fn fields(line: &str) -> Vec<(usize, &str)> {
    let b = line.as_bytes();
    let mut out = Vec::with_capacity(13);
    let mut i = 0;
    while i < b.len() && is_blank(b[i]) {
        i += 1;
    }
    if i == b.len() {
        return out;
    }
    loop {
        let start = i;
        while i < b.len() && !is_blank(b[i]) && b[i] != b',' && b[i] != b';' {
            i += 1;
        }
        out.push((start, &line[start..i]));
        while i < b.len() && is_blank(b[i]) {
            i += 1;
        }
        if i == b.len() {
            return out;
        }
        if b[i] == b',' || b[i] == b';' {
            i += 1;
            while i < b.len() && is_blank(b[i]) {
                i += 1;
            }
            if i == b.len() {
                // A trailing separator leaves one empty field.
                out.push((i, ""));
                return out;
            }
        }
    }
}

fn full_number(s: &str) -> Option<f64> {
    match scan_number(s.as_bytes()) {
        Some((v, n)) if n == s.len() && v.is_finite() => Some(v),
        _ => None,
    }
}

fn is_missing(s: &str) -> bool {
    s.is_empty() || s.eq_ignore_ascii_case("NA") || s.eq_ignore_ascii_case("N/A")
}

use super::position::{Span, column_in_line as column_of};

/// Parse one data line (not a header). `line_no` is 1-based.
pub fn parse_row(line: &str, line_no: u32) -> Result<Contact12Row, ParseError> {
    let f = fields(line);
    let mut row = Contact12Row {
        cl_axis: [0.0; 6],
        contact: [None; 6],
        line: line_no,
        columns: [0; 12],
    };
    for k in 0..12 {
        let Some(&(start, text)) = f.get(k) else {
            return Err(ParseError::at(
                Span::in_line(line_no, line, line.len()..line.len()),
                format!(
                    "12 fields (CL x y z, axis i j k, CC x y z, normal), field {}",
                    k + 1
                ),
                "end of line",
                line,
            ));
        };
        row.columns[k] = column_of(line, start);
        let value = full_number(text);
        if k < 6 {
            match value {
                Some(v) => row.cl_axis[k] = v,
                None => {
                    return Err(ParseError::at(
                        Span::in_line(line_no, line, start..start + text.len()),
                        "a number",
                        if text.is_empty() {
                            "an empty field".to_string()
                        } else {
                            describe_found(text)
                        },
                        line,
                    ));
                }
            }
        } else {
            match value {
                Some(v) => row.contact[k - 6] = Some(v),
                None if is_missing(text) => row.contact[k - 6] = None,
                None => {
                    return Err(ParseError::at(
                        Span::in_line(line_no, line, start..start + text.len()),
                        "a number, NA, N/A or an empty field",
                        describe_found(text),
                        line,
                    ));
                }
            }
        }
    }
    Ok(row)
}

/// True when `line` looks like a header: its first field is neither a number nor NA.
fn is_header(line: &str) -> bool {
    match fields(line).first() {
        Some((_, t)) => full_number(t).is_none() && !is_missing(t),
        None => false,
    }
}

/// Streams [`Contact12Row`]s out of a contact12 text.
pub struct Contact12Reader<R> {
    src: R,
    buf: Vec<u8>,
    line: u32,
    seen_data_or_header: bool,
    header: Option<String>,
    done: bool,
}

impl<R: BufRead> Contact12Reader<R> {
    /// Read from `src`.
    pub fn new(src: R) -> Self {
        Contact12Reader {
            src,
            buf: Vec::with_capacity(256),
            line: 0,
            seen_data_or_header: false,
            header: None,
            done: false,
        }
    }

    /// The header line, once it has been read.
    pub fn header(&self) -> Option<&str> {
        self.header.as_deref()
    }

    fn next_row(&mut self) -> Result<Option<Contact12Row>, ParseError> {
        loop {
            self.buf.clear();
            if self.src.read_until(b'\n', &mut self.buf)? == 0 {
                return Ok(None);
            }
            self.line = self.line.saturating_add(1);
            // A UTF-8 byte-order mark at the start of the file is not part of the text.
            if self.line == 1 && self.buf.starts_with(b"\xEF\xBB\xBF") {
                self.buf.drain(..3);
            }
            let mut end = self.buf.len();
            while end > 0 && (self.buf[end - 1] == b'\n' || self.buf[end - 1] == b'\r') {
                end -= 1;
            }
            let text = match std::str::from_utf8(&self.buf[..end]) {
                Ok(t) => t,
                Err(e) => {
                    let at = e.valid_up_to();
                    let shown = String::from_utf8_lossy(&self.buf[..end]);
                    return Err(ParseError::at(
                        Span::in_line(self.line, &shown, at..at + 1),
                        "ASCII or UTF-8 text",
                        format!("byte 0x{:02X}", self.buf[at]),
                        &shown,
                    ));
                }
            };
            let text = text.trim_end_matches([' ', '\t']);
            if text.trim_start_matches([' ', '\t']).is_empty() {
                continue;
            }
            if !self.seen_data_or_header {
                self.seen_data_or_header = true;
                if is_header(text) {
                    self.header = Some(text.to_string());
                    continue;
                }
            }
            return parse_row(text, self.line).map(Some);
        }
    }
}

impl<R: BufRead> Iterator for Contact12Reader<R> {
    type Item = Result<Contact12Row, ParseError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        match self.next_row() {
            Ok(Some(r)) => Some(Ok(r)),
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

/// Does this text look like contact12 rather than CLSF? Decided on the first line that
/// is neither blank nor a `$$` comment: contact12 when its first field is a number or NA,
/// or when it is a header of at least 12 fields without a `/`.
pub fn looks_like_contact12(head: &str) -> bool {
    for line in head.trim_start_matches('\u{feff}').lines() {
        let t = line.trim();
        if t.is_empty() || t.starts_with("$$") {
            continue;
        }
        let f = fields(t);
        let first = f.first().map(|x| x.1).unwrap_or("");
        if full_number(first).is_some() || is_missing(first) {
            return true;
        }
        return !t.contains('/') && f.len() >= 12;
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_byte_order_mark_is_not_a_header() {
        let text = "\u{feff}1 2 3 0 0 1 1 2 3 0 0 1\n4 5 6 0 0 1 4 5 6 0 0 1\n";
        assert!(looks_like_contact12(text));
        let r = rows(text).unwrap();
        assert_eq!(r.len(), 2);
    }

    fn rows(s: &str) -> Result<Vec<Contact12Row>, ParseError> {
        Contact12Reader::new(s.as_bytes()).collect()
    }

    #[test]
    fn separators_header_and_missing_values() {
        let text = "x,y,z,i,j,k,cx,cy,cz,nx,ny,nz\n\
                    1,2,3,0,0,1,1,2,2,0,0,1\r\n\
                    1\t2  3 0 0 1 NA n/a NA NA NA NA\n\
                    1;2;3;0;0;1;;;;;;\n\
                    1 , 2 , 3 , 0 , 0 , 1 , 0 , 0 , 0 , 0 , 0 , 0, 250\n";
        let r = rows(text).unwrap();
        assert_eq!(r.len(), 4);
        assert_eq!(r[0].contact[5], Some(1.0));
        assert_eq!(r[1].contact, [None; 6]);
        assert_eq!(r[2].contact, [None; 6]);
        assert_eq!(r[3].contact[0], Some(0.0));
        assert_eq!(r[1].line, 3);
        assert_eq!(r[1].columns[1], 3);
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = rows("1 2 3 0 0 1 1 2 3 0 0 1\n1 2 3 0 x 1 1 2 3 0 0 1\n").unwrap_err();
        let s = e.syntax().unwrap();
        assert_eq!((s.span.line, s.span.column), (2, 9));
        assert_eq!((s.span.offset, s.span.len), (8, 1));
        assert_eq!(s.found(), Some("`x`"));
        let e = rows("1 2 3 0 0 1 1 2 3\n").unwrap_err();
        assert_eq!(e.syntax().unwrap().found(), Some("end of line"));
        let e = rows("1,2,,0,0,1,1,2,3,0,0,1\n").unwrap_err();
        assert_eq!(e.syntax().unwrap().span.column, 5);
    }

    #[test]
    fn detection() {
        assert!(looks_like_contact12("x y z i j k cx cy cz nx ny nz\n"));
        assert!(looks_like_contact12("\n1,2,3,0,0,1,,,,,,\n"));
        assert!(!looks_like_contact12("$$ISO\nUNITS/MM\n"));
        assert!(!looks_like_contact12("TOOL PATH/A,TOOL,B\n"));
        assert!(!looks_like_contact12(""));
    }
}
