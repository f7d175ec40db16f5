//! The nom grammar of one logical CLSF record (`grammars/clsf.ebnf`).

use super::record::{Arg, FeedUnit, LengthUnit, MAX_NUMBERS, Numbers, RecordKind};
use crate::parse::error::describe_found;
use crate::parse::number::{Form, SHORT_WINDOW, scan_number, scan_short_form};
use nom::IResult;
use nom::bytes::complete::take_while1;
use nom::character::complete::{char as ch, space0, space1};
use nom_locate::LocatedSpan;

/// Input type of the record grammar: the logical line with its byte offset.
pub type Span<'a> = LocatedSpan<&'a str>;

/// Error of the record grammar: where, what was expected, optionally what was found.
#[derive(Debug)]
pub(super) struct PErr<'a> {
    pub(super) at: Span<'a>,
    pub(super) expected: String,
    pub(super) found: Option<String>,
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
pub(super) fn fast_numbers(b: &[u8], max: usize, word_tail: bool) -> Option<(Numbers, usize)> {
    let mut forms = 0;
    if word_tail {
        fast_numbers_of::<true, false>(b, max, &mut forms)
    } else {
        fast_numbers_of::<false, false>(b, max, &mut forms)
    }
}

/// [`fast_numbers`] of a `GOTO`'s arguments (up to [`MAX_NUMBERS`], no word after
/// them), inlined into the reader's loop.
#[inline]
pub(super) fn goto_numbers(b: &[u8]) -> Option<(Numbers, usize)> {
    let mut forms = 0;
    fast_numbers_of::<false, false>(b, MAX_NUMBERS, &mut forms)
}

/// [`goto_numbers`] and how each number is written: the [`Form::bits`] of number `k` in
/// bits `4k..4k + 4` of `forms` ([`Form::OTHER`] for those the word scan does not read),
/// zeros above the last.
#[inline]
pub(super) fn goto_numbers_with_forms(b: &[u8], forms: &mut u64) -> Option<(Numbers, usize)> {
    fast_numbers_of::<false, true>(b, MAX_NUMBERS, forms)
}

/// [`fast_numbers`] with `word_tail` fixed (so that the loop over the numbers, the
/// reading of a CLSF, tests nothing it does not need), and with `FORMS` each number's
/// [`Form`] packed in `forms` as [`goto_numbers_with_forms`] does (without, `forms` is
/// not touched).
#[inline(always)]
fn fast_numbers_of<const WORD_TAIL: bool, const FORMS: bool>(
    b: &[u8],
    max: usize,
    forms: &mut u64,
) -> Option<(Numbers, usize)> {
    let max = max.min(MAX_NUMBERS);
    let mut values = [0.0; MAX_NUMBERS];
    let mut len = 0;
    // What is left of `b` (a moving slice: one length test a number for the window).
    let mut rest = b;
    loop {
        // Short numbers with a window of bytes after them (all but the last of a line
        // that lies alone in its buffer) are read by word operations; the rest, or what
        // that does not cover, by the general scanner.
        let (v, used, form) = match rest.first_chunk::<SHORT_WINDOW>().and_then(scan_short_form) {
            Some(r) => r,
            None => {
                let (v, used) = scan_number(rest)?;
                if !v.is_finite() {
                    return None;
                }
                (v, used, Form::OTHER)
            }
        };
        *values.get_mut(len)? = v;
        if FORMS {
            *forms |= u64::from(form.bits()) << (4 * (len & 15));
        }
        len += 1;
        rest = rest.get(used..)?;
        let done = |len, rest: &[u8]| {
            Some((
                Numbers {
                    values,
                    len: len as u8,
                },
                b.len() - rest.len(),
            ))
        };
        match rest.first() {
            None => return done(len, rest),
            Some(b',') => {
                if WORD_TAIL && rest.get(1).is_some_and(|c| c.is_ascii_alphabetic()) {
                    return done(len, rest);
                }
                if len >= max {
                    return None;
                }
                rest = &rest[1..];
            }
            Some(b' ' | b'\t') => return None,
            // An exponent after a number `scan_short_digits` read (it does not look), or
            // anything else after one `scan_number` read: the general parser decides.
            Some(c) if *c | 0x20 == b'e' => return None,
            Some(_) => return done(len, rest),
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
    if frag.len() >= 7 && frag.as_bytes()[..7].eq_ignore_ascii_case(b"CONTACT") {
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
pub(super) fn parse_record(i: Span<'_>) -> Res<'_, RecordKind> {
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
                && j.fragment().as_bytes()[..4].eq_ignore_ascii_case(b"PATH")
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
        "PPRINT" | "TPRINT" | "PARTNO" => Ok(text_record(w, i)),
        "MULTAX" => {
            let (j, _) = space0(i)?;
            if j.fragment().is_empty() {
                return Ok((j, RecordKind::Multax(true)));
            }
            let (j, ()) = need_slash(i, "MULTAX")?;
            let (k, a) = arg(j)?;
            let on = if a.is_word("ON") {
                true
            } else if a.is_word("OFF") {
                false
            } else {
                return fail(j, "ON or OFF");
            };
            let (k, ()) = end(k)?;
            Ok((k, RecordKind::Multax(on)))
        }
        "CUTTER" => {
            let (i, ()) = need_slash(i, "CUTTER")?;
            if starts_with_word(i) {
                // CUTTER/DISPLY,… and other non-geometric forms are kept raw.
                return Ok(raw_rest(w, i, &word_start));
            }
            let (j, n) = numbers(i, 7, false)?;
            let (j, ()) = end(j)?;
            Ok((j, RecordKind::Cutter(n)))
        }
        "TLAXIS" | "INDIRV" => {
            let (i, ()) = need_slash(i, w)?;
            if starts_with_word(i) {
                // TLAXIS/NORMPS, … (axis modes of APT source) are kept raw.
                return Ok(raw_rest(w, i, &word_start));
            }
            let (j, n) = numbers(i, 3, false)?;
            if n.len() != 3 {
                return fail_found(
                    j,
                    format!("3 numbers in {w}"),
                    format!("{} numbers", n.len()),
                );
            }
            let (j, ()) = end(j)?;
            Ok((
                j,
                if w == "TLAXIS" {
                    RecordKind::Tlaxis(n.triple(0))
                } else {
                    RecordKind::Indirv(n.triple(0))
                },
            ))
        }
        "SET" => {
            let Ok((i, ())) = slash(i) else {
                return Ok(raw_rest(w, i, &word_start));
            };
            let (j, a) = args(i)?;
            let (j, ()) = end(j)?;
            if a.len() == 2 && a[0].is_word("MODE") {
                if a[1].is_word("ABSOL") {
                    return Ok((j, RecordKind::SetMode { absolute: true }));
                }
                if a[1].is_word("INCR") {
                    return Ok((j, RecordKind::SetMode { absolute: false }));
                }
            }
            Ok((j, unknown(w, &word_start)))
        }
        "LOADTL" => {
            let (i, ()) = need_slash(i, "LOADTL")?;
            let (j, a) = args(i)?;
            let number = match a.first() {
                Some(Arg::Num(v)) => *v,
                _ => return fail(i, "a tool number"),
            };
            let (j, ()) = end(j)?;
            Ok((
                j,
                RecordKind::LoadTool {
                    number,
                    args: a[1..].to_vec(),
                },
            ))
        }
        "FINI" | "END" if i.fragment().trim().is_empty() => {
            let (j, ()) = end(i)?;
            Ok((
                j,
                if w == "FINI" {
                    RecordKind::Fini
                } else {
                    RecordKind::End
                },
            ))
        }
        _ => Ok(raw_rest(w, i, &word_start)),
    }
}

/// Unknown or pass-through record: keep the whole text.
fn raw_rest<'a>(w: &str, i: Span<'a>, start: &Span<'_>) -> (Span<'a>, RecordKind) {
    let frag = i.fragment();
    (take_n(i, frag.len()), unknown(w, start))
}

/// True when the argument list starts with a letter (a word, not a number).
fn starts_with_word(i: Span<'_>) -> bool {
    i.fragment()
        .trim_start_matches([' ', '\t'])
        .as_bytes()
        .first()
        .is_some_and(|b| b.is_ascii_alphabetic())
}

/// `PPRINT`, `TPRINT`, `PARTNO`: the text after `/` (or after the blank), trimmed.
fn text_record<'a>(w: &str, i: Span<'a>) -> (Span<'a>, RecordKind) {
    let frag = i.fragment();
    let body = frag.trim_start_matches([' ', '\t']);
    let body = body.strip_prefix('/').unwrap_or(body);
    let text = body.trim().to_string();
    let rest = take_n(i, frag.len());
    let kind = if w == "PARTNO" {
        RecordKind::Partno(text)
    } else {
        RecordKind::Print {
            word: w.to_string(),
            text,
        }
    };
    (rest, kind)
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
        if frag.len() >= 5 && frag.as_bytes()[..5].eq_ignore_ascii_case(b"TIMES") {
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

#[cfg(test)]
mod tests {
    use super::super::record::{Arg, FeedUnit, LengthUnit, RecordKind};
    use super::super::{err, one};

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
    fn apt_dialect_records() {
        use super::super::record::Numbers;
        assert_eq!(
            one("PPRINT/ OPERATION 1, ROUGH / FINISH "),
            RecordKind::Print {
                word: "PPRINT".into(),
                text: "OPERATION 1, ROUGH / FINISH".into()
            }
        );
        assert_eq!(
            one("TPRINT T1 BALL D10"),
            RecordKind::Print {
                word: "TPRINT".into(),
                text: "T1 BALL D10".into()
            }
        );
        assert_eq!(one("PARTNO BLADE 7"), RecordKind::Partno("BLADE 7".into()));
        assert_eq!(one("MULTAX"), RecordKind::Multax(true));
        assert_eq!(one("MULTAX / ON"), RecordKind::Multax(true));
        assert_eq!(one("multax/off"), RecordKind::Multax(false));
        assert_eq!(err("MULTAX/MAYBE").2, "ON or OFF");
        assert_eq!(
            one("CUTTER / 10.000000, 5.000000, 0.000000, 5.000000, 0.000000, 0.000000, 50.000000"),
            RecordKind::Cutter(
                Numbers::from_slice(&[10.0, 5.0, 0.0, 5.0, 0.0, 0.0, 50.0]).unwrap()
            )
        );
        assert!(matches!(one("CUTTER/10"), RecordKind::Cutter(n) if n.len() == 1));
        assert!(matches!(
            one("CUTTER/DISPLY,ALL"),
            RecordKind::Unknown { .. }
        ));
        assert_eq!(
            err("CUTTER/1,2,3,4,5,6,7,8").2,
            "end of record after 7 numbers"
        );
        assert_eq!(
            one("TLAXIS/ 0, 0.6, 0.8"),
            RecordKind::Tlaxis([0.0, 0.6, 0.8])
        );
        assert_eq!(one("INDIRV/1,0,0"), RecordKind::Indirv([1.0, 0.0, 0.0]));
        assert!(matches!(one("TLAXIS/NORMPS"), RecordKind::Unknown { .. }));
        assert_eq!(err("TLAXIS/0,1").2, "3 numbers in TLAXIS");
        assert_eq!(
            one("SET/MODE, ABSOL"),
            RecordKind::SetMode { absolute: true }
        );
        assert_eq!(
            one("SET/MODE,INCR"),
            RecordKind::SetMode { absolute: false }
        );
        assert!(matches!(one("SET/MODES,OFF"), RecordKind::Unknown { .. }));
        assert_eq!(
            one("LOADTL/3,ADJUST,3"),
            RecordKind::LoadTool {
                number: 3.0,
                args: vec![Arg::Word("ADJUST".into()), Arg::Num(3.0)]
            }
        );
        assert_eq!(err("LOADTL/T3").2, "a tool number");
        assert_eq!(one("FINI"), RecordKind::Fini);
        assert_eq!(one("END "), RecordKind::End);
        assert!(matches!(one("END/PROG"), RecordKind::Unknown { .. }));
        // Blanks around the slash and after the commas.
        match one("GOTO / 1.0, 2.0, 3.0, 0.0, 0.0, 1.0") {
            RecordKind::Goto(n) => assert_eq!(n.len(), 6),
            k => panic!("{k:?}"),
        }
        assert_eq!(
            one("FEDRAT/ 1200.000000, MMPM"),
            RecordKind::Fedrat {
                unit: Some(FeedUnit::Mmpm),
                value: 1200.0
            }
        );
        assert_eq!(
            one("FEDRAT/PERMIN, 50"),
            RecordKind::Fedrat {
                unit: Some(FeedUnit::Permin),
                value: 50.0
            }
        );
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
        assert!(matches!(one("DISPLY/ON"), RecordKind::Unknown { .. }));
        assert!(matches!(one("rapid"), RecordKind::Rapid));
    }
}
