//! CLSF records and their nom grammar (`grammars/clsf.ebnf`).
//!
//! [`ClsfReader`] streams logical records out of any [`BufRead`]: it reads one physical
//! line at a time into a reused buffer, joins `$` continuation lines, drops trailing `$$`
//! comments and blanks, and parses each logical line with [`parse_record`]. Nothing but
//! the current line is held, so memory stays flat whatever the file size.
//!
//! Records are syntax only: numbers as written, words upper-cased, no units and no
//! geometry. Unknown major words become [`RecordKind::Unknown`] (the raw text is kept);
//! the lowering turns them into warnings.

use super::error::{ParseError, describe_found};
use super::number::scan_number;
use nom::IResult;
use nom::bytes::complete::take_while1;
use nom::character::complete::{char as ch, space0, space1};
use nom_locate::LocatedSpan;
use std::fmt;
use std::io::BufRead;

/// Input type of the record grammar: the logical line with its byte offset.
pub type Span<'a> = LocatedSpan<&'a str>;

/// At most this many numbers in one fixed-size record (a GOTO with contact data).
pub const MAX_NUMBERS: usize = 12;

/// A short list of numbers stored inline (no allocation): GOTO, FROM, GOHOME, CONTACT,
/// CIRCLE and CNTRL arguments.
#[derive(Clone, Copy, PartialEq)]
pub struct Numbers {
    values: [f64; MAX_NUMBERS],
    len: u8,
}

impl Numbers {
    /// Copy up to [`MAX_NUMBERS`] values; `None` when there are more.
    pub fn from_slice(values: &[f64]) -> Option<Numbers> {
        if values.len() > MAX_NUMBERS {
            return None;
        }
        let mut n = Numbers {
            values: [0.0; MAX_NUMBERS],
            len: values.len() as u8,
        };
        n.values[..values.len()].copy_from_slice(values);
        Some(n)
    }

    /// The values.
    pub fn as_slice(&self) -> &[f64] {
        &self.values[..self.len as usize]
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// True when there are no values.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Three values starting at `k` (caller checks the length).
    pub fn triple(&self, k: usize) -> [f64; 3] {
        [self.values[k], self.values[k + 1], self.values[k + 2]]
    }
}

impl fmt::Debug for Numbers {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

/// A generic argument: a number or a word/name as written.
#[derive(Debug, Clone, PartialEq)]
pub enum Arg {
    /// A number.
    Num(f64),
    /// Anything else, trimmed (words are kept as written; compare case-insensitively).
    Word(String),
}

impl Arg {
    /// True when this is a word equal to `w` ignoring ASCII case.
    pub fn is_word(&self, w: &str) -> bool {
        matches!(self, Arg::Word(s) if s.eq_ignore_ascii_case(w))
    }
}

/// Feed-rate unit word of `FEDRAT`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FeedUnit {
    /// mm per minute.
    Mmpm,
    /// inch per minute.
    Ipm,
    /// mm per revolution.
    Mmpr,
    /// inch per revolution.
    Ipr,
    /// per minute in the file's length unit.
    Permin,
    /// per revolution in the file's length unit.
    Perrev,
}

impl FeedUnit {
    fn from_word(w: &str) -> Option<FeedUnit> {
        Some(match w.to_ascii_uppercase().as_str() {
            "MMPM" => FeedUnit::Mmpm,
            "IPM" => FeedUnit::Ipm,
            "MMPR" => FeedUnit::Mmpr,
            "IPR" => FeedUnit::Ipr,
            "PERMIN" => FeedUnit::Permin,
            "PERREV" => FeedUnit::Perrev,
            _ => return None,
        })
    }

    /// The word as written in CLSF.
    pub fn word(self) -> &'static str {
        match self {
            FeedUnit::Mmpm => "MMPM",
            FeedUnit::Ipm => "IPM",
            FeedUnit::Mmpr => "MMPR",
            FeedUnit::Ipr => "IPR",
            FeedUnit::Permin => "PERMIN",
            FeedUnit::Perrev => "PERREV",
        }
    }
}

/// Length unit of `UNITS`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthUnit {
    /// Millimetres.
    Mm,
    /// Inches (`INCH` or `INCHES`).
    Inch,
}

/// One logical CLSF record (syntax only).
#[derive(Debug, Clone, PartialEq)]
pub enum RecordKind {
    /// `TOOL PATH/<op>,TOOL,<tool>[,…]`.
    ToolPath {
        /// Operation name.
        name: String,
        /// Tool name (empty when the record has no `TOOL,<name>` part).
        tool: String,
    },
    /// `TLDATA/<kind>[,<subtype word>],args…`.
    Tldata {
        /// Tool kind word, upper case (`MILL`, `DRILL`, `TURN`, …).
        kind: String,
        /// Word after the kind (`TLDATA/DRILL,MILL,…`), upper case.
        subtype: Option<String>,
        /// The remaining arguments.
        args: Vec<Arg>,
    },
    /// `MSYS/ox,oy,oz,xi,xj,xk,yi,yj,yk`.
    Msys([f64; 9]),
    /// A whole-line `$$` comment (text after `$$`, trimmed).
    Comment(String),
    /// Contact data for the GOTO before it: `CONTACT/x,y,z[,nx,ny,nz]` or the same after
    /// `$$ ` (3 or 6 numbers).
    Contact(Numbers),
    /// `PAINT/<word>,args…`.
    Paint(Vec<Arg>),
    /// `FEDRAT/[unit,]value` (also `FEDRAT/value,unit`).
    Fedrat {
        /// Unit word, if written.
        unit: Option<FeedUnit>,
        /// Feed value as written.
        value: f64,
    },
    /// `RAPID`: the next GOTO only is a rapid move.
    Rapid,
    /// `GOTO/x,y,z[,i,j,k[,cx,cy,cz[,nx,ny,nz]]]` (3, 6, 9 or 12 numbers).
    Goto(Numbers),
    /// `FROM/x,y,z[,i,j,k]`.
    From(Numbers),
    /// `GOHOME/x,y,z[,i,j,k]`.
    GoHome(Numbers),
    /// `CIRCLE/xc,yc,zc,ai,aj,ak,r[,tol,intol,toolD,toolR][,TIMES,n]` (7 to 11 numbers).
    Circle {
        /// The numbers as written.
        numbers: Numbers,
        /// `TIMES,n`, if written.
        times: Option<u32>,
    },
    /// `NURBS/` (arguments, if any, are ignored).
    Nurbs,
    /// `KNOT/k1,…`.
    Knot(Vec<f64>),
    /// `CNTRL/x,y,z`.
    Cntrl([f64; 3]),
    /// `LOAD/TOOL,n[,…]`.
    LoadTool {
        /// Tool number.
        number: f64,
        /// Further arguments (`ADJUST,n`, …).
        args: Vec<Arg>,
    },
    /// `SELECT/TOOL,n[,…]`.
    SelectTool {
        /// Tool number.
        number: f64,
    },
    /// `SPINDL/…`: arguments as written.
    Spindl(Vec<Arg>),
    /// `CUTCOM/LEFT|RIGHT|ON|OFF[,…]`.
    Cutcom(Vec<Arg>),
    /// `CYCLE/<kind>[,…]` or `CYCLE/OFF`.
    Cycle(Vec<Arg>),
    /// `UNITS/MM|INCH|INCHES`.
    Units(LengthUnit),
    /// `END-OF-PATH`.
    EndOfPath,
    /// Any other record, kept raw.
    Unknown {
        /// Major word, upper case.
        word: String,
        /// The whole logical record text.
        text: String,
    },
}

/// A record with the position of its first character.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// What the record says.
    pub kind: RecordKind,
    /// 1-based line of the record's first character.
    pub line: u32,
    /// 1-based column of the record's first character.
    pub column: u32,
}

// ---------------------------------------------------------------------------------------
// Grammar
// ---------------------------------------------------------------------------------------

/// Error of the record grammar: where, what was expected, optionally what was found.
#[derive(Debug)]
pub(crate) struct PErr<'a> {
    at: Span<'a>,
    expected: String,
    found: Option<String>,
}

impl<'a> nom::error::ParseError<Span<'a>> for PErr<'a> {
    fn from_error_kind(input: Span<'a>, _kind: nom::error::ErrorKind) -> Self {
        PErr {
            at: input,
            expected: "valid record syntax".into(),
            found: None,
        }
    }
    fn append(_input: Span<'a>, _kind: nom::error::ErrorKind, other: Self) -> Self {
        other
    }
    fn or(self, other: Self) -> Self {
        if other.at.location_offset() >= self.at.location_offset() {
            other
        } else {
            self
        }
    }
}

type Res<'a, T> = IResult<Span<'a>, T, PErr<'a>>;

fn fail<'a, T>(at: Span<'a>, expected: impl Into<String>) -> Res<'a, T> {
    Err(nom::Err::Failure(PErr {
        at,
        expected: expected.into(),
        found: None,
    }))
}

fn fail_found<'a, T>(at: Span<'a>, expected: impl Into<String>, found: String) -> Res<'a, T> {
    Err(nom::Err::Failure(PErr {
        at,
        expected: expected.into(),
        found: Some(found),
    }))
}

fn take_n(i: Span<'_>, n: usize) -> Span<'_> {
    use nom::InputTake;
    i.take_split(n).0
}

/// A number (`grammars/clsf.ebnf` `num`), finite.
fn num(i: Span<'_>) -> Res<'_, f64> {
    match scan_number(i.fragment().as_bytes()) {
        Some((v, n)) if v.is_finite() => Ok((take_n(i, n), v)),
        Some(_) => fail(i, "a finite number"),
        None => Err(nom::Err::Error(PErr {
            at: i,
            expected: "a number".into(),
            found: None,
        })),
    }
}

/// A number where nothing else is allowed (turns a soft error into a hard one).
fn num_cut(i: Span<'_>) -> Res<'_, f64> {
    nom::combinator::cut(num)(i)
}

/// `ws , "," , ws`.
fn comma(i: Span<'_>) -> Res<'_, ()> {
    let (i, _) = space0(i)?;
    let (i, _) = ch(',')(i)?;
    let (i, _) = space0(i)?;
    Ok((i, ()))
}

/// `ws , "/" , ws`.
fn slash(i: Span<'_>) -> Res<'_, ()> {
    let (i, _) = space0(i)?;
    let (i, _) = ch('/')(i)?;
    let (i, _) = space0(i)?;
    Ok((i, ()))
}

/// A list of numbers `num { cm num }` into `Numbers` (at most `max`). With `word_tail`,
/// the list ends softly before a `,` followed by a word (`CIRCLE/…,TIMES,n`).
fn numbers(i: Span<'_>, max: usize, word_tail: bool) -> Res<'_, Numbers> {
    if let Some((n, used)) = fast_numbers(i.fragment().as_bytes(), max, word_tail) {
        return Ok((take_n(i, used), n));
    }
    let mut out = Numbers {
        values: [0.0; MAX_NUMBERS],
        len: 0,
    };
    let (mut i, v) = num_cut(i)?;
    out.values[0] = v;
    out.len = 1;
    loop {
        let Ok((after_comma, ())) = comma(i) else {
            return Ok((i, out));
        };
        if word_tail
            && after_comma
                .fragment()
                .as_bytes()
                .first()
                .is_some_and(|b| b.is_ascii_alphabetic())
        {
            return Ok((i, out));
        }
        if out.len() >= max {
            return fail_found(
                after_comma,
                format!("end of record after {max} numbers"),
                describe_found(after_comma.fragment()),
            );
        }
        let (rest, v) = num_cut(after_comma)?;
        out.values[out.len()] = v;
        out.len += 1;
        i = rest;
    }
}

/// The common case of [`numbers`] on raw bytes: numbers separated by bare commas (no
/// blanks). Returns `None` whenever the general parser must decide (blanks, errors, too
/// many numbers); when it returns a value, the general parser would return the same.
fn fast_numbers(b: &[u8], max: usize, word_tail: bool) -> Option<(Numbers, usize)> {
    let mut out = Numbers {
        values: [0.0; MAX_NUMBERS],
        len: 0,
    };
    let mut pos = 0;
    loop {
        let (v, used) = scan_number(&b[pos..])?;
        if !v.is_finite() {
            return None;
        }
        out.values[out.len()] = v;
        out.len += 1;
        pos += used;
        match b.get(pos) {
            None => return Some((out, pos)),
            Some(b',') => {
                if word_tail && b.get(pos + 1).is_some_and(|c| c.is_ascii_alphabetic()) {
                    return Some((out, pos));
                }
                if out.len() >= max {
                    return None;
                }
                pos += 1;
            }
            Some(b' ' | b'\t') => return None,
            Some(_) => return Some((out, pos)),
        }
    }
}

/// A list of numbers of any length.
fn number_vec(i: Span<'_>) -> Res<'_, Vec<f64>> {
    let (mut i, v) = num_cut(i)?;
    let mut out = vec![v];
    while let Ok((after_comma, ())) = comma(i) {
        let (rest, v) = num_cut(after_comma)?;
        out.push(v);
        i = rest;
    }
    Ok((i, out))
}

/// One generic argument: everything up to the next `,` (trimmed); a number if the whole
/// token is one.
fn arg(i: Span<'_>) -> Res<'_, Arg> {
    let frag = i.fragment();
    let end = frag.find(',').unwrap_or(frag.len());
    let token = frag[..end].trim_end_matches([' ', '\t']);
    if token.is_empty() {
        return fail(i, "an argument");
    }
    let rest = take_n(i, token.len());
    if let Some((v, n)) = scan_number(token.as_bytes())
        && n == token.len()
        && v.is_finite()
    {
        return Ok((rest, Arg::Num(v)));
    }
    Ok((rest, Arg::Word(token.to_string())))
}

/// `arg { cm arg }` (possibly empty when the input is empty).
fn args(i: Span<'_>) -> Res<'_, Vec<Arg>> {
    if i.fragment().is_empty() {
        return Ok((i, Vec::new()));
    }
    let (mut i, a) = arg(i)?;
    let mut out = vec![a];
    while let Ok((after_comma, ())) = comma(i) {
        let (rest, a) = arg(after_comma)?;
        out.push(a);
        i = rest;
    }
    Ok((i, out))
}

fn is_word_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_' || c == '-'
}

/// Require the end of the record.
fn end(i: Span<'_>) -> Res<'_, ()> {
    let (i, _) = space0(i)?;
    if i.fragment().is_empty() {
        Ok((i, ()))
    } else {
        fail(i, "end of record")
    }
}

/// Parse the arguments of a point record (`GOTO`, `FROM`, `GOHOME`, `CONTACT`): the
/// count must be one of `allowed`.
fn point_numbers<'a>(i: Span<'a>, allowed: &'static [usize], what: &str) -> Res<'a, Numbers> {
    let (rest, n) = numbers(i, *allowed.last().unwrap_or(&3), false)?;
    if !allowed.contains(&n.len()) {
        let list = match allowed {
            [3, 6] => "3 or 6 numbers".to_string(),
            [3, 6, 9, 12] => "3, 6, 9 or 12 numbers".to_string(),
            _ => format!("{allowed:?} numbers"),
        };
        return fail_found(
            rest,
            format!("{list} in {what}"),
            format!("{} numbers", n.len()),
        );
    }
    Ok((rest, n))
}

/// The body of a `$$` comment: a contact record or plain text.
fn comment_body(after: Span<'_>) -> Res<'_, RecordKind> {
    let (i, _) = space0(after)?;
    let frag = i.fragment();
    if frag.len() >= 7 && frag[..7].eq_ignore_ascii_case("CONTACT") {
        let rest = take_n(i, 7);
        if let Ok((j, ())) = slash(rest) {
            let (j, n) = point_numbers(j, &[3, 6], "CONTACT")?;
            let (j, ()) = end(j)?;
            return Ok((j, RecordKind::Contact(n)));
        }
    }
    let text = frag.trim_end();
    Ok((take_n(i, frag.len()), RecordKind::Comment(text.to_string())))
}

/// Parse one logical record (comments and continuation already handled by the reader,
/// except whole-line `$$` comments, which this also accepts).
pub(crate) fn parse_record(i: Span<'_>) -> Res<'_, RecordKind> {
    let (i, _) = space0(i)?;
    if i.fragment().starts_with("$$") {
        return comment_body(take_n(i, 2));
    }
    let word_start = i;
    let (i, word) = take_while1(is_word_char)(i).map_err(|_: nom::Err<PErr>| {
        nom::Err::Failure(PErr {
            at: word_start,
            expected: "a record word".into(),
            found: None,
        })
    })?;
    let w = word.fragment();
    let upper;
    let w: &str = if w.bytes().any(|b| b.is_ascii_lowercase()) {
        upper = w.to_ascii_uppercase();
        &upper
    } else {
        w
    };
    // Fast path first: the bulk of a file is GOTO records.
    match w {
        "GOTO" => {
            let (i, ()) = need_slash(i, "GOTO")?;
            let (i, n) = point_numbers(i, &[3, 6, 9, 12], "GOTO")?;
            let (i, ()) = end(i)?;
            return Ok((i, RecordKind::Goto(n)));
        }
        "RAPID" => {
            let (i, ()) = bare_end(i)?;
            return Ok((i, RecordKind::Rapid));
        }
        "END-OF-PATH" => {
            let (i, ()) = bare_end(i)?;
            return Ok((i, RecordKind::EndOfPath));
        }
        "TOOL" => {
            if let Ok((j, _)) = space1::<_, PErr>(i)
                && j.fragment().len() >= 4
                && j.fragment()[..4].eq_ignore_ascii_case("PATH")
            {
                let j = take_n(j, 4);
                let (j, ()) = need_slash(j, "TOOL PATH")?;
                return tool_path(j);
            }
        }
        _ => {}
    }
    match w {
        "FROM" | "GOHOME" | "CONTACT" => {
            let (i, ()) = need_slash(i, w)?;
            let (i, n) = point_numbers(i, &[3, 6], w)?;
            let (i, ()) = end(i)?;
            let kind = match w {
                "FROM" => RecordKind::From(n),
                "GOHOME" => RecordKind::GoHome(n),
                _ => RecordKind::Contact(n),
            };
            Ok((i, kind))
        }
        "CIRCLE" => {
            let (i, ()) = need_slash(i, "CIRCLE")?;
            circle(i)
        }
        "FEDRAT" => {
            let (i, ()) = need_slash(i, "FEDRAT")?;
            fedrat(i)
        }
        "MSYS" => {
            let (i, ()) = need_slash(i, "MSYS")?;
            let (j, n) = numbers(i, 9, false)?;
            if n.len() != 9 {
                return fail_found(j, "9 numbers in MSYS", format!("{} numbers", n.len()));
            }
            let (j, ()) = end(j)?;
            let mut m = [0.0; 9];
            m.copy_from_slice(n.as_slice());
            Ok((j, RecordKind::Msys(m)))
        }
        "NURBS" => {
            // `NURBS/` with an empty (or ignored) argument list.
            let j = match slash(i) {
                Ok((j, ())) => {
                    let (j, _) = args(j)?;
                    j
                }
                Err(_) => i,
            };
            let (j, ()) = end(j)?;
            Ok((j, RecordKind::Nurbs))
        }
        "KNOT" => {
            let (i, ()) = need_slash(i, "KNOT")?;
            let (i, v) = number_vec(i)?;
            let (i, ()) = end(i)?;
            Ok((i, RecordKind::Knot(v)))
        }
        "CNTRL" => {
            let (i, ()) = need_slash(i, "CNTRL")?;
            let (j, n) = numbers(i, 3, false)?;
            if n.len() != 3 {
                return fail_found(j, "3 numbers in CNTRL", format!("{} numbers", n.len()));
            }
            let (j, ()) = end(j)?;
            Ok((j, RecordKind::Cntrl(n.triple(0))))
        }
        "TLDATA" => {
            let (i, ()) = need_slash(i, "TLDATA")?;
            tldata(i)
        }
        "UNITS" => {
            let (i, ()) = need_slash(i, "UNITS")?;
            let (j, a) = arg(i)?;
            let unit = if a.is_word("MM") {
                LengthUnit::Mm
            } else if a.is_word("INCH") || a.is_word("INCHES") {
                LengthUnit::Inch
            } else {
                return fail(i, "MM, INCH or INCHES");
            };
            let (j, ()) = end(j)?;
            Ok((j, RecordKind::Units(unit)))
        }
        "PAINT" => {
            let (i, ()) = need_slash(i, "PAINT")?;
            let (j, a) = args_with_word(i, "a PAINT word")?;
            Ok((j, RecordKind::Paint(a)))
        }
        "SPINDL" => {
            let (i, ()) = need_slash(i, "SPINDL")?;
            spindl(i)
        }
        "CUTCOM" => {
            let (i, ()) = need_slash(i, "CUTCOM")?;
            let (j, a) = args(i)?;
            let ok = a
                .first()
                .is_some_and(|f| ["LEFT", "RIGHT", "ON", "OFF"].iter().any(|w| f.is_word(w)));
            if !ok {
                return fail(i, "LEFT, RIGHT, ON or OFF");
            }
            let (j, ()) = end(j)?;
            Ok((j, RecordKind::Cutcom(a)))
        }
        "CYCLE" => {
            let (i, ()) = need_slash(i, "CYCLE")?;
            let (j, a) = args_with_word(i, "a cycle word")?;
            Ok((j, RecordKind::Cycle(a)))
        }
        "LOAD" | "SELECT" => {
            let (i, ()) = need_slash(i, w)?;
            let (j, a) = args(i)?;
            if !a.first().is_some_and(|f| f.is_word("TOOL")) {
                // LOAD/… and SELECT/… of other things (heads, turrets) are kept raw.
                let (j, ()) = end(j)?;
                return Ok((j, unknown(w, &word_start)));
            }
            let number = match a.get(1) {
                Some(Arg::Num(v)) => *v,
                _ => {
                    let (at, _) = comma_after_first(i);
                    return fail(at, "a tool number");
                }
            };
            let (j, ()) = end(j)?;
            if w == "LOAD" {
                Ok((
                    j,
                    RecordKind::LoadTool {
                        number,
                        args: a[2..].to_vec(),
                    },
                ))
            } else {
                Ok((j, RecordKind::SelectTool { number }))
            }
        }
        _ => {
            // Unknown or pass-through record: keep the whole text.
            let frag = i.fragment();
            let rest = take_n(i, frag.len());
            Ok((rest, unknown(w, &word_start)))
        }
    }
}

fn unknown(word: &str, start: &Span<'_>) -> RecordKind {
    RecordKind::Unknown {
        word: word.to_string(),
        text: start.fragment().trim_end().to_string(),
    }
}

/// The position right after the first argument's comma (for "tool number" errors).
fn comma_after_first(i: Span<'_>) -> (Span<'_>, ()) {
    match arg(i).and_then(|(j, _)| comma(j)) {
        Ok((j, ())) => (j, ()),
        Err(_) => (i, ()),
    }
}

fn need_slash<'a>(i: Span<'a>, word: &str) -> Res<'a, ()> {
    match slash(i) {
        Ok(r) => Ok(r),
        Err(_) => {
            let (j, _) = space0(i)?;
            fail(j, format!("`/` after {word}"))
        }
    }
}

fn bare_end(i: Span<'_>) -> Res<'_, ()> {
    end(i)
}

/// Generic arguments whose first one must be a word.
fn args_with_word<'a>(i: Span<'a>, what: &str) -> Res<'a, Vec<Arg>> {
    let (j, a) = args(i)?;
    if !matches!(a.first(), Some(Arg::Word(_))) {
        return fail(i, what.to_string());
    }
    let (j, ()) = end(j)?;
    Ok((j, a))
}

fn tool_path(i: Span<'_>) -> Res<'_, RecordKind> {
    let (j, a) = args(i)?;
    let (j, ()) = end(j)?;
    let text = |a: &Arg| match a {
        Arg::Word(s) => s.clone(),
        Arg::Num(_) => String::new(),
    };
    // Names are kept exactly as written, even when they look like numbers.
    let raw: Vec<&str> = i.fragment().split(',').map(|s| s.trim()).collect();
    let name = raw.first().map(|s| s.to_string()).unwrap_or_default();
    let tool = if a.len() >= 3 && a[1].is_word("TOOL") {
        raw.get(2)
            .map(|s| s.to_string())
            .unwrap_or_else(|| text(&a[2]))
    } else {
        String::new()
    };
    Ok((j, RecordKind::ToolPath { name, tool }))
}

fn circle(i: Span<'_>) -> Res<'_, RecordKind> {
    let (j, n) = numbers(i, 11, true)?;
    if n.len() < 7 {
        return fail_found(
            j,
            "7 to 11 numbers in CIRCLE (centre, axis, radius, …)",
            format!("{} numbers", n.len()),
        );
    }
    let mut times = None;
    let mut j = j;
    if let Ok((k, ())) = comma(j) {
        let frag = k.fragment();
        if frag.len() >= 5 && frag[..5].eq_ignore_ascii_case("TIMES") {
            let (k, ()) = comma(take_n(k, 5)).map_err(|_| {
                nom::Err::Failure(PErr {
                    at: take_n(k, 5),
                    expected: "`,` after TIMES".into(),
                    found: None,
                })
            })?;
            let (k2, v) = num_cut(k)?;
            if v < 1.0 || v.fract() != 0.0 || v > u32::MAX as f64 {
                return fail(k, "a whole number of times ≥ 1");
            }
            times = Some(v as u32);
            j = k2;
        } else {
            return fail(k, "TIMES or end of record");
        }
    }
    let (j, ()) = end(j)?;
    Ok((j, RecordKind::Circle { numbers: n, times }))
}

fn fedrat(i: Span<'_>) -> Res<'_, RecordKind> {
    let (j, a) = args(i)?;
    let (j, ()) = end(j)?;
    let mut unit = None;
    let mut value = None;
    for x in &a {
        match x {
            Arg::Num(v) if value.is_none() => value = Some(*v),
            Arg::Word(w) if unit.is_none() => match FeedUnit::from_word(w) {
                Some(u) => unit = Some(u),
                None => return fail(i, "MMPM, IPM, MMPR, IPR, PERMIN or PERREV"),
            },
            _ => return fail(i, "a unit word and one feed value"),
        }
    }
    match value {
        Some(value) => Ok((j, RecordKind::Fedrat { unit, value })),
        None => fail(i, "a feed value"),
    }
}

fn spindl(i: Span<'_>) -> Res<'_, RecordKind> {
    let (j, a) = args(i)?;
    if a.is_empty() {
        return fail(i, "RPM, SFM, SMM, ON, OFF or a speed");
    }
    let (j, ()) = end(j)?;
    Ok((j, RecordKind::Spindl(a)))
}

fn tldata(i: Span<'_>) -> Res<'_, RecordKind> {
    let (j, mut a) = args(i)?;
    let (j, ()) = end(j)?;
    let kind = match a.first() {
        Some(Arg::Word(w)) => w.to_ascii_uppercase(),
        _ => return fail(i, "a tool kind word (MILL, DRILL, …)"),
    };
    a.remove(0);
    let subtype = match a.first() {
        Some(Arg::Word(w)) if kind == "DRILL" => {
            let s = w.to_ascii_uppercase();
            a.remove(0);
            Some(s)
        }
        _ => None,
    };
    if kind == "MILL" || kind == "DRILL" {
        // Milling and drilling tools: numbers only after the words.
        if let Some(pos) = a.iter().position(|x| matches!(x, Arg::Word(_))) {
            // Find the column of the offending argument.
            let mut k = i;
            for _ in 0..(pos + 1 + usize::from(subtype.is_some())) {
                if let Ok((after, _)) = arg(k)
                    && let Ok((after, ())) = comma(after)
                {
                    k = after;
                }
            }
            return fail(k, "a number");
        }
    }
    Ok((
        j,
        RecordKind::Tldata {
            kind,
            subtype,
            args: a,
        },
    ))
}

// ---------------------------------------------------------------------------------------
// Printing (the canonical form parses back to the same record)
// ---------------------------------------------------------------------------------------

fn write_nums(f: &mut fmt::Formatter<'_>, v: &[f64]) -> fmt::Result {
    for (k, x) in v.iter().enumerate() {
        if k > 0 {
            f.write_str(",")?;
        }
        write!(f, "{x}")?;
    }
    Ok(())
}

fn write_args(f: &mut fmt::Formatter<'_>, a: &[Arg]) -> fmt::Result {
    for (k, x) in a.iter().enumerate() {
        if k > 0 {
            f.write_str(",")?;
        }
        match x {
            Arg::Num(v) => write!(f, "{v}")?,
            Arg::Word(w) => f.write_str(w)?,
        }
    }
    Ok(())
}

impl fmt::Display for RecordKind {
    /// The record as CLSF text (numbers in the shortest form that reads back exactly).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RecordKind::ToolPath { name, tool } => {
                write!(f, "TOOL PATH/{name}")?;
                if !tool.is_empty() {
                    write!(f, ",TOOL,{tool}")?;
                }
                Ok(())
            }
            RecordKind::Tldata {
                kind,
                subtype,
                args,
            } => {
                write!(f, "TLDATA/{kind}")?;
                if let Some(s) = subtype {
                    write!(f, ",{s}")?;
                }
                if !args.is_empty() {
                    f.write_str(",")?;
                    write_args(f, args)?;
                }
                Ok(())
            }
            RecordKind::Msys(m) => {
                f.write_str("MSYS/")?;
                write_nums(f, m)
            }
            RecordKind::Comment(t) => write!(f, "$$ {t}"),
            RecordKind::Contact(n) => {
                f.write_str("CONTACT/")?;
                write_nums(f, n.as_slice())
            }
            RecordKind::Paint(a) => {
                f.write_str("PAINT/")?;
                write_args(f, a)
            }
            RecordKind::Fedrat { unit, value } => match unit {
                Some(u) => write!(f, "FEDRAT/{},{value}", u.word()),
                None => write!(f, "FEDRAT/{value}"),
            },
            RecordKind::Rapid => f.write_str("RAPID"),
            RecordKind::Goto(n) => {
                f.write_str("GOTO/")?;
                write_nums(f, n.as_slice())
            }
            RecordKind::From(n) => {
                f.write_str("FROM/")?;
                write_nums(f, n.as_slice())
            }
            RecordKind::GoHome(n) => {
                f.write_str("GOHOME/")?;
                write_nums(f, n.as_slice())
            }
            RecordKind::Circle { numbers, times } => {
                f.write_str("CIRCLE/")?;
                write_nums(f, numbers.as_slice())?;
                if let Some(t) = times {
                    write!(f, ",TIMES,{t}")?;
                }
                Ok(())
            }
            RecordKind::Nurbs => f.write_str("NURBS/"),
            RecordKind::Knot(v) => {
                f.write_str("KNOT/")?;
                write_nums(f, v)
            }
            RecordKind::Cntrl(p) => {
                f.write_str("CNTRL/")?;
                write_nums(f, p)
            }
            RecordKind::LoadTool { number, args } => {
                write!(f, "LOAD/TOOL,{number}")?;
                if !args.is_empty() {
                    f.write_str(",")?;
                    write_args(f, args)?;
                }
                Ok(())
            }
            RecordKind::SelectTool { number } => write!(f, "SELECT/TOOL,{number}"),
            RecordKind::Spindl(a) => {
                f.write_str("SPINDL/")?;
                write_args(f, a)
            }
            RecordKind::Cutcom(a) => {
                f.write_str("CUTCOM/")?;
                write_args(f, a)
            }
            RecordKind::Cycle(a) => {
                f.write_str("CYCLE/")?;
                write_args(f, a)
            }
            RecordKind::Units(u) => f.write_str(match u {
                LengthUnit::Mm => "UNITS/MM",
                LengthUnit::Inch => "UNITS/INCH",
            }),
            RecordKind::EndOfPath => f.write_str("END-OF-PATH"),
            RecordKind::Unknown { text, .. } => f.write_str(text),
        }
    }
}

// ---------------------------------------------------------------------------------------
// Streaming reader
// ---------------------------------------------------------------------------------------

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

    fn next_record(&mut self) -> Result<Option<Record>, ParseError> {
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
                    let good = &self.buf[..e.valid_up_to()];
                    let good = String::from_utf8_lossy(good).into_owned();
                    let column = good.chars().count() as u32 + 1;
                    let shown = String::from_utf8_lossy(&self.buf[..end]).into_owned();
                    return Err(ParseError::at(
                        self.line,
                        column,
                        "ASCII or UTF-8 text",
                        format!("byte 0x{:02X}", self.buf[e.valid_up_to()]),
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
        let locate = |offset: usize| -> (u32, u32, &str) {
            let k = pieces.iter().rposition(|p| p.offset <= offset).unwrap_or(0);
            let p = pieces.get(k).copied().unwrap_or(Piece {
                offset: 0,
                line: self.line,
                column_base: 0,
            });
            let line_text = lines.get(k).map(String::as_str).unwrap_or("");
            let in_piece = offset - p.offset;
            let byte_col = p.column_base + in_piece;
            let col = line_text
                .get(..byte_col.min(line_text.len()))
                .map(|s| s.chars().count())
                .unwrap_or(byte_col) as u32
                + 1;
            (p.line, col, line_text)
        };
        let span = Span::new(joined.as_str());
        let start = joined.len() - joined.trim_start_matches([' ', '\t']).len();
        match parse_record(span) {
            Ok((_, kind)) => {
                let (line, column, _) = locate(start);
                Ok(Record { kind, line, column })
            }
            Err(nom::Err::Error(e) | nom::Err::Failure(e)) => {
                let (line, column, text) = locate(e.at.location_offset());
                let found = e.found.unwrap_or_else(|| describe_found(e.at.fragment()));
                Err(ParseError::at(line, column, e.expected, found, text))
            }
            Err(nom::Err::Incomplete(_)) => {
                let (line, column, text) = locate(joined.len());
                Err(ParseError::at(
                    line,
                    column,
                    "more input",
                    "end of line",
                    text,
                ))
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
        && let Some((n, used)) = fast_numbers(rest.as_bytes(), MAX_NUMBERS, false)
        && used == rest.len()
        && matches!(n.len(), 3 | 6 | 9 | 12)
    {
        return Ok(Record {
            kind: RecordKind::Goto(n),
            line,
            column: lead as u32 + 1,
        });
    }
    let column_of = |byte: usize| -> u32 {
        let byte = lead + byte;
        full.get(..byte.min(full.len()))
            .map(|s| s.chars().count())
            .unwrap_or(byte) as u32
            + 1
    };
    match parse_record(Span::new(code)) {
        Ok((_, kind)) => Ok(Record {
            kind,
            line,
            column: column_of(0),
        }),
        Err(nom::Err::Error(e) | nom::Err::Failure(e)) => {
            let found = e.found.unwrap_or_else(|| describe_found(e.at.fragment()));
            Err(ParseError::at(
                line,
                column_of(e.at.location_offset()),
                e.expected,
                found,
                full,
            ))
        }
        Err(nom::Err::Incomplete(_)) => Err(ParseError::at(
            line,
            column_of(code.len()),
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
    use super::*;

    fn one(s: &str) -> RecordKind {
        let v = parse_str(s).unwrap();
        assert_eq!(v.len(), 1, "{s}");
        v.into_iter().next().unwrap().kind
    }

    fn err(s: &str) -> (u32, u32, String, String) {
        let e = parse_str(s).unwrap_err();
        let s = e.syntax().unwrap().clone();
        (s.line, s.column, s.expected, s.found)
    }

    #[test]
    fn goto_forms() {
        for (s, n) in [
            ("GOTO/1,2,3", 3),
            (
                "GOTO/1.0000,2.0000,-3.5000,0.0000000,0.0000000,1.0000000",
                6,
            ),
            ("GOTO/1,2,3,0,0,1,4,5,6", 9),
            ("GOTO / 1 , 2 , 3 ,0,0,1,4,5,6,0,0,1  ", 12),
        ] {
            match one(s) {
                RecordKind::Goto(v) => assert_eq!(v.len(), n),
                k => panic!("{k:?}"),
            }
        }
        assert_eq!(
            err("GOTO/1,2"),
            (
                1,
                9,
                "3, 6, 9 or 12 numbers in GOTO".into(),
                "2 numbers".into()
            )
        );
        assert_eq!(err("GOTO/1,2,x"), (1, 10, "a number".into(), "`x`".into()));
        assert_eq!(err("GOTO 1,2,3").2, "`/` after GOTO");
        assert_eq!(err("\n\nGOTO/1,2,3,4,5,6,7,8,9,1,2,3,4").1, 30);
    }

    #[test]
    fn header_records() {
        assert_eq!(
            one("TOOL PATH/8_KONTUR_NAR_40_N2,TOOL,BPR-SNR-323S32"),
            RecordKind::ToolPath {
                name: "8_KONTUR_NAR_40_N2".into(),
                tool: "BPR-SNR-323S32".into()
            }
        );
        match one("TLDATA/DRILL,MILL,63.0000,0.0000,239.0000,178.0000,35.0000") {
            RecordKind::Tldata {
                kind,
                subtype,
                args,
            } => {
                assert_eq!(kind, "DRILL");
                assert_eq!(subtype.as_deref(), Some("MILL"));
                assert_eq!(args.len(), 5);
            }
            k => panic!("{k:?}"),
        }
        assert!(matches!(one("MSYS/1,2,3,1,0,0,0,1,0"), RecordKind::Msys(_)));
        assert_eq!(
            one("$$ centerline data"),
            RecordKind::Comment("centerline data".into())
        );
        assert_eq!(one("UNITS/INCH"), RecordKind::Units(LengthUnit::Inch));
        assert_eq!(
            one("LOAD/TOOL,2,ADJUST,2 "),
            RecordKind::LoadTool {
                number: 2.0,
                args: vec![Arg::Word("ADJUST".into()), Arg::Num(2.0)]
            }
        );
    }

    #[test]
    fn feeds_and_circles() {
        assert_eq!(
            one("FEDRAT/MMPM,250.0000"),
            RecordKind::Fedrat {
                unit: Some(FeedUnit::Mmpm),
                value: 250.0
            }
        );
        assert_eq!(
            one("FEDRAT/10,IPM"),
            RecordKind::Fedrat {
                unit: Some(FeedUnit::Ipm),
                value: 10.0
            }
        );
        match one(
            "CIRCLE/1287.5000,-341.2500,413.0000,0.0000000,0.0000000,-1.0000000,56.2500,0.0600,0.5000,125.0000,1.0000,TIMES,2",
        ) {
            RecordKind::Circle { numbers, times } => {
                assert_eq!(numbers.len(), 11);
                assert_eq!(times, Some(2));
            }
            k => panic!("{k:?}"),
        }
        assert_eq!(
            err("CIRCLE/1,2,3,0,0,1,5,0.06,0.5,10,1,TIMES,0").2,
            "a whole number of times ≥ 1"
        );
    }

    #[test]
    fn contact_forms() {
        assert!(matches!(one("$$ CONTACT/1,2,3"), RecordKind::Contact(n) if n.len() == 3));
        assert!(matches!(one("$$contact/1,2,3,0,0,1"), RecordKind::Contact(n) if n.len() == 6));
        assert!(matches!(one("CONTACT/1,2,3,0,0,1"), RecordKind::Contact(n) if n.len() == 6));
        assert_eq!(err("CONTACT/1,2,3,4").2, "3 or 6 numbers in CONTACT");
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

    #[test]
    fn unknown_records_are_kept() {
        assert_eq!(
            one("COOLNT/ON"),
            RecordKind::Unknown {
                word: "COOLNT".into(),
                text: "COOLNT/ON".into()
            }
        );
        assert!(matches!(one("FINI"), RecordKind::Unknown { .. }));
        assert!(matches!(one("rapid"), RecordKind::Rapid));
    }

    #[test]
    fn printed_records_parse_back() {
        for s in [
            "GOTO/1.5,2,-3",
            "CIRCLE/1,2,3,0,0,1,5,0.06,0.5,10,1,TIMES,2",
            "FEDRAT/MMPM,250",
            "SPINDL/RPM,1000,CLW",
            "KNOT/0.1,0.5,1",
            "TOOL PATH/A-1,TOOL,B_2",
        ] {
            let r = one(s);
            assert_eq!(r.to_string(), s);
        }
    }
}
