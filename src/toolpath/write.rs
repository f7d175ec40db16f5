//! Writers: NX-style CLSF with contact data and contact12 CSV, posture by posture.
//!
//! Numbers are printed in fixed point: lengths with 4 to 6 decimals, unit vectors with 7
//! to 9 (NX writes 4 and 7; trailing zeros beyond that are dropped). A number read from a
//! file with at most that many decimals prints back to the same digits, so contact12 →
//! CLSF → contact12 is exact to the printed digits.

use super::{MotionKind, Posture, ToolData, Toolpath};
use crate::parse::Written;
use crate::parse::number::Form;
use std::io::{self, Write};

/// Decimals of lengths: at least, at most.
pub const LENGTH_DECIMALS: (u32, u32) = (4, 6);
/// Decimals of unit vectors: at least, at most.
pub const UNIT_DECIMALS: (u32, u32) = (7, 9);

const POW10: [u64; 10] = [
    1,
    10,
    100,
    1_000,
    10_000,
    100_000,
    1_000_000,
    10_000_000,
    100_000_000,
    1_000_000_000,
];

/// Append `v` in fixed point with between `min` and `max` decimals (`max ≤ 9`), rounded
/// half away from zero; `-0` prints as `0`.
pub fn push_fixed(out: &mut Vec<u8>, v: f64, decimals: (u32, u32)) {
    let mut s = [0u8; FIXED_ROOM];
    match fixed_digits(&mut s, v, decimals) {
        Some(n) => out.extend_from_slice(&s[..n]),
        // Values too large for the decimals to be meaningful (beyond 2.8e8 mm), or not
        // finite: the shortest form that reads back exactly.
        None => {
            let _ = write!(out, "{v}");
        }
    }
}

/// Bytes [`fixed_digits`] may write: at most 17 (sign, 15 digits, point), rounded up so
/// that a scratch is a whole number of vector registers.
const FIXED_ROOM: usize = 32;

/// [`push_fixed`]'s digits, left-aligned in `s`; returns their length, or `None` for the
/// values [`push_fixed`] prints with `format!` (not finite, or 2.8e14 and more once scaled
/// by `10^max`). Writing into a fixed array (no `Vec` growth checks, no `memcpy` call per
/// number) is what makes contact12 rows cheap.
///
/// The integer part below 10^8 and the decimals are made eight digits at a time by word
/// operations ([`digit_values`]), written as whole words, and the leading and trailing
/// zeros counted from the word, with no loop and no branch per digit; larger integer parts
/// take [`fixed_digits_wide`], which gives the same bytes (unit test).
#[inline(always)]
fn fixed_digits(s: &mut [u8; FIXED_ROOM], v: f64, (min, max): (u32, u32)) -> Option<usize> {
    let max = max.min(9) as usize;
    let min = (min as usize).min(max);
    let scaled = v * POW10[max] as f64;
    // Not finite, or too large: as `fixed_digits_wide` (NaN fails the comparison).
    let in_range = scaled.abs() < 2.8e14;
    if !in_range {
        return None;
    }
    // As in `fixed_digits_wide`: round half away from zero, split at the point.
    let q = (scaled.abs() + 0.5) as i64 as u64;
    // `scaled < 0.0 && q != 0` (a zero product has `v`'s sign and `q` = 0), from the sign
    // bit without a comparison of floats.
    let neg = (v.to_bits() >> 63) as usize & usize::from(q != 0);
    s[0] = b'-';
    if (1..=7).contains(&max) && q < 100_000_000 {
        // All digits in one word: 8 - max of the integer part, then the decimals.
        let d = digit_values(q);
        let lead = ((d.trailing_zeros() / 8) as usize).min(7 - max);
        put_word(s, neg, (d | ASCII_ZEROS) >> (8 * lead));
        let int_end = neg + 8 - max - lead;
        let f = d >> (8 * (8 - max));
        s[int_end & 15] = b'.';
        put_word(s, int_end + 1, f | ASCII_ZEROS);
        let trailing = (f.leading_zeros() / 8) as usize - (8 - max);
        let keep = (max - trailing).max(min);
        return Some(if keep == 0 {
            int_end
        } else {
            int_end + 1 + keep
        });
    }
    if max == 9 && q < 1_000_000_000 {
        // "0." and nine decimals: eight in one word, then the last.
        let d = digit_values(q / 10);
        let last = (q % 10) as u8;
        s[neg] = b'0';
        s[neg + 1] = b'.';
        put_word(s, neg + 2, d | ASCII_ZEROS);
        s[neg + 10] = b'0' + last;
        let trailing = if last == 0 {
            1 + (d.leading_zeros() / 8) as usize
        } else {
            0
        };
        let keep = (9 - trailing).max(min);
        return Some(if keep == 0 { neg + 1 } else { neg + 2 + keep });
    }
    let p = POW10[max];
    let int = q / p;
    let frac = q % p;
    if int >= 100_000_000 || max == 0 {
        return fixed_digits_wide(s, v, (min as u32, max as u32));
    }
    // The integer part: eight digits with leading zeros, the zeros shifted out (one digit
    // kept), stored as one word.
    let d = digit_values(int);
    let lead = ((d.trailing_zeros() / 8) as usize).min(7);
    put_word(s, neg, (d | ASCII_ZEROS) >> (8 * lead));
    let int_end = neg + 8 - lead;
    s[int_end & 15] = b'.';
    let at = (int_end + 1) & 15;
    // The decimals, all `max` of them, then the trailing zeros beyond `min` dropped.
    let trailing = if max <= 8 {
        // Eight digits of which the first 8 - max are zeros: shifted out.
        let f = digit_values(frac) >> (8 * (8 - max));
        put_word(s, at, f | ASCII_ZEROS);
        // Zero bytes above the digits, then the digits' trailing zeros (all for 0).
        (f.leading_zeros() / 8) as usize - (8 - max)
    } else {
        // Nine: the first digit, then eight.
        let head = frac / 100_000_000;
        let f = digit_values(frac % 100_000_000);
        s[at] = b'0' + head as u8;
        put_word(s, at + 1, f | ASCII_ZEROS);
        let t = (f.leading_zeros() / 8) as usize;
        t + usize::from(t == 8 && head == 0)
    };
    let keep = (max - trailing).max(min);
    // No decimal left: no point either.
    Some(if keep == 0 { int_end } else { at + keep })
}

/// Eight ASCII zeros.
const ASCII_ZEROS: u64 = 0x3030_3030_3030_3030;

/// Store `w`'s eight bytes (lowest first) at `s[at..]` (`at` masked into the scratch).
#[inline(always)]
fn put_word(s: &mut [u8; FIXED_ROOM], at: usize, w: u64) {
    let at = at & 15;
    s[at..at + 8].copy_from_slice(&w.to_le_bytes());
}

/// The eight decimal digits of `n < 10^8` (with leading zeros) as byte values 0-9, the
/// most significant in the lowest byte: halves of four digits, quarters of two, then
/// single digits, each step a multiply-shift division on all lanes at once.
#[inline(always)]
fn digit_values(n: u64) -> u64 {
    // 32-bit lanes: the first four digits, the last four.
    let x = (n / 10_000) | ((n % 10_000) << 32);
    // 16-bit lanes: ⌊x/100⌋ then x mod 100 (x·10486 >> 20 = ⌊x/100⌋ for x < 10^4).
    let h = ((x * 10_486) >> 20) & 0x0000_007F_0000_007F;
    let x = h | ((x - h * 100) << 16);
    // Bytes: ⌊x/10⌋ then x mod 10 (x·103 >> 10 = ⌊x/10⌋ for x < 100).
    let t = ((x * 103) >> 10) & 0x000F_000F_000F_000F;
    t | ((x - t * 10) << 8)
}

/// [`fixed_digits`] with a digit loop: any integer part (the reference of its fast
/// form, and the way for integer parts of 10^8 and more).
#[inline(never)]
fn fixed_digits_wide(s: &mut [u8; FIXED_ROOM], v: f64, (min, max): (u32, u32)) -> Option<usize> {
    let max = max.min(9) as usize;
    let min = (min as usize).min(max);
    let scaled = v * POW10[max] as f64;
    if !scaled.is_finite() || scaled.abs() >= 2.8e14 {
        return None;
    }
    // Round half away from zero without a libm call, then split at the decimal point
    // (0 ≤ the rounded value < 2.8e14: the conversion through i64 is exact).
    let q = (scaled.abs() + 0.5) as i64 as u64;
    let p = POW10[max];
    let int = q / p;
    let frac = q % p;
    let neg = usize::from(scaled < 0.0 && q != 0);
    s[0] = b'-';
    // `int` < 2.8e14: at most 15 digits.
    let digits = if int < 10 {
        1
    } else {
        int.ilog10() as usize + 1
    };
    let int_end = neg + digits;
    put_digits(s, int_end, int, digits);
    s[int_end] = b'.';
    // All `max` decimals, then the trailing zeros beyond `min` dropped (with the point when
    // no decimal is left).
    let mut end = int_end + 1 + max;
    put_digits(s, end, frac, max);
    let keep = int_end + 1 + min;
    while end > keep && s[end - 1] == b'0' {
        end -= 1;
    }
    if end == int_end + 1 {
        end = int_end;
    }
    Some(end)
}

/// Write exactly `count` decimal digits of `v` (zero-padded; `v < 10^count`) ending just
/// before `s[end]`, two at a time (a fixed number of steps for a fixed `count`, so the
/// decimals of a row's numbers unroll without branches).
#[inline(always)]
fn put_digits(s: &mut [u8; FIXED_ROOM], end: usize, mut v: u64, count: usize) {
    let mut k = end;
    for _ in 0..count / 2 {
        let r = (v % 100) as usize * 2;
        v /= 100;
        k -= 2;
        s[k] = DIGIT_PAIRS[r];
        s[k + 1] = DIGIT_PAIRS[r + 1];
    }
    if count % 2 == 1 {
        s[k - 1] = b'0' + (v % 10) as u8;
    }
}

/// "00", "01", …, "99".
const DIGIT_PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// Append `v` with exactly `dec` decimals (`dec ≤ 9`) as `format!("{v:.dec$}")` does:
/// the sign of negative values (and −0) kept, ties to even. The integer part is split off
/// exactly, so only a fraction within 2^-33 of a half-way point of the last digit could
/// round differently from `format!`. Values of 2^53 and beyond and non-finite ones go
/// through `format!` itself. No libm calls and one copy a number: this prints 40 numbers
/// a sample in `crest resample`. [`push_fixed`] is the
/// variant that trims trailing zeros and rounds half away from zero (CLSF and contact12).
pub fn push_decimals(out: &mut Vec<u8>, v: f64, dec: u32) {
    let dec = dec.min(9) as usize;
    let a = v.abs();
    if a.is_nan() || a >= 9_007_199_254_740_992.0 {
        let _ = write!(out, "{v:.dec$}");
        return;
    }
    // Exact: the truncation, and the fraction (a − ⌊a⌋ is representable).
    let mut int = a as u64;
    let frac = a - int as f64;
    let p = POW10[dec];
    let scaled = frac * p as f64;
    let mut q = scaled as u64;
    let rem = scaled - q as f64;
    let odd = if dec == 0 { int % 2 == 1 } else { q % 2 == 1 };
    if rem > 0.5 || (rem == 0.5 && odd) {
        q += 1;
    }
    if q >= p {
        int += 1;
        q -= p;
    }
    // Right to left into one buffer: fraction, point, integer, sign.
    let mut buf = [b'0'; 32];
    let mut k = buf.len();
    if dec > 0 {
        let start = k - dec;
        while k > start + 1 {
            let r = (q % 100) as usize * 2;
            q /= 100;
            k -= 2;
            buf[k] = DIGIT_PAIRS[r];
            buf[k + 1] = DIGIT_PAIRS[r + 1];
        }
        if k > start {
            k -= 1;
            buf[k] = b'0' + (q % 10) as u8;
        }
        k -= 1;
        buf[k] = b'.';
    }
    loop {
        k -= 1;
        buf[k] = b'0' + (int % 10) as u8;
        int /= 10;
        if int == 0 {
            break;
        }
    }
    if v.is_sign_negative() {
        k -= 1;
        buf[k] = b'-';
    }
    out.extend_from_slice(&buf[k..]);
}

/// Format one number (tests, messages).
pub fn fixed(v: f64, decimals: (u32, u32)) -> String {
    let mut b = Vec::new();
    push_fixed(&mut b, v, decimals);
    String::from_utf8(b).unwrap_or_default()
}

/// Whether a number written with `form` and read as its value prints back, through
/// [`push_fixed`] with `decimals`, to the very bytes it was written with: a fixed-point
/// number written as [`push_fixed`] writes it (see [`Form::fixed`]) with exactly the
/// least number of decimals (so a last `0` is printed too). Its at most five digits before
/// the point and seven after make an integer below 10^12, read exactly and scaled back to
/// it exactly, and a size below 10^5, printed in fixed point with any decimals (a unit test
/// checks every form). More decimals are printed without trailing zeros;
/// those numbers are printed, not copied.
#[inline(always)]
pub fn prints_as_written(form: Form, decimals: (u32, u32)) -> bool {
    form == written_form(decimals)
}

/// The one form [`prints_as_written`] accepts for `decimals`: fixed point with the least.
const fn written_form((min, _): (u32, u32)) -> Form {
    Form::fixed(min)
}

/// The contact12 CSV header.
pub const CONTACT12_HEADER: &str = "x,y,z,i,j,k,cx,cy,cz,nx,ny,nz";

/// Streams contact12 rows. Rows are collected in the writer and handed to the output in
/// pieces of about 128 KiB: call [`Contact12Writer::flush`] after the last posture.
pub struct Contact12Writer {
    all_moves: bool,
    line: Vec<u8>,
    /// Rows not yet handed on, `used` bytes of them, each built in place (the buffer's
    /// length is fixed; it keeps room for one more row after `used`).
    pending: Vec<u8>,
    used: usize,
}

/// Bytes of one row built in place: 12 numbers of at most 17 bytes and their separators,
/// and the room of one more number's scratch.
const ROW_ROOM: usize = 12 * 18 + 1 + FIXED_ROOM;

/// Bytes of [`Contact12Writer`]'s collected rows: more than a 64 KiB `BufWriter` holds,
/// so that one passes them on without copying.
const PENDING_ROOM: usize = 1 << 17;

/// Append one number of a row at `at` (followed by `sep` when it is not 0); `None` when the
/// number needs `format!` (then the row is printed by the slow path).
#[inline(always)]
fn put_number(
    row: &mut [u8; ROW_ROOM],
    at: usize,
    v: f64,
    d: (u32, u32),
    sep: u8,
) -> Option<usize> {
    let s: &mut [u8; FIXED_ROOM] = row.get_mut(at..at + FIXED_ROOM)?.try_into().ok()?;
    let n = fixed_digits(s, v, d)?;
    if sep == 0 {
        return Some(at + n);
    }
    s[n] = sep;
    Some(at + n + 1)
}

/// The row of `p` built in `r` (its length), or `None` when a number needs `format!`.
#[inline]
fn fast_row(r: &mut [u8; ROW_ROOM], p: &Posture) -> Option<usize> {
    // Written out, not looped: a loop of three mispredicts its exit, once a triple.
    let at = put_number(r, 0, p.position.x, LENGTH_DECIMALS, b',')?;
    let at = put_number(r, at, p.position.y, LENGTH_DECIMALS, b',')?;
    let at = put_number(r, at, p.position.z, LENGTH_DECIMALS, b',')?;
    let at = put_number(r, at, p.axis.x, UNIT_DECIMALS, b',')?;
    let at = put_number(r, at, p.axis.y, UNIT_DECIMALS, b',')?;
    let mut at = put_number(r, at, p.axis.z, UNIT_DECIMALS, b',')?;
    match &p.contact {
        Some(c) => {
            at = put_number(r, at, c.point.x, LENGTH_DECIMALS, b',')?;
            at = put_number(r, at, c.point.y, LENGTH_DECIMALS, b',')?;
            at = put_number(r, at, c.point.z, LENGTH_DECIMALS, b',')?;
            at = put_number(r, at, c.normal.x, UNIT_DECIMALS, b',')?;
            at = put_number(r, at, c.normal.y, UNIT_DECIMALS, b',')?;
            at = put_number(r, at, c.normal.z, UNIT_DECIMALS, b'\n')?;
        }
        None => {
            r.get_mut(at..at + 6)?.copy_from_slice(b",,,,,\n");
            at += 6;
        }
    }
    Some(at)
}

/// The forms of a contact12 row's twelve numbers that print as written
/// ([`prints_as_written`]), packed as [`Written::forms`] packs them.
const ROW_FORMS: u64 = {
    let (l, u) = (
        written_form(LENGTH_DECIMALS).bits() as u64,
        written_form(UNIT_DECIMALS).bits() as u64,
    );
    let mut f = 0;
    let mut k = 0;
    while k < 12 {
        f |= if (k / 3) % 2 == 0 { l } else { u } << (4 * k);
        k += 1;
    }
    f
};

/// The text of `w` when the row of `p` (with contact data) would print as exactly that:
/// `w` holds the line of `p`, its twelve values are `p`'s, bit for bit (nothing was scaled
/// or replaced in the lowering), and every number prints back as written.
#[inline]
fn row_as_written<'w>(p: &Posture, w: &'w Written) -> Option<&'w [u8]> {
    let c = p.contact.as_ref()?;
    if w.line != p.line || w.numbers.len() != 12 || w.forms != ROW_FORMS {
        return None;
    }
    let values = [
        p.position.x,
        p.position.y,
        p.position.z,
        p.axis.x,
        p.axis.y,
        p.axis.z,
        c.point.x,
        c.point.y,
        c.point.z,
        c.normal.x,
        c.normal.y,
        c.normal.z,
    ]
    .map(f64::to_bits);
    let read = w.numbers.as_slice().iter().map(|v| v.to_bits());
    values.into_iter().eq(read).then(|| w.text())
}

impl Contact12Writer {
    /// A writer; `all_moves` writes every posture (CC/normal empty without contact),
    /// otherwise only cutting moves with contact data.
    pub fn new(all_moves: bool) -> Contact12Writer {
        Contact12Writer {
            all_moves,
            line: Vec::with_capacity(160),
            pending: vec![0; PENDING_ROOM],
            used: 0,
        }
    }

    /// Write the header line.
    pub fn header(&mut self, out: &mut dyn Write) -> io::Result<()> {
        self.flush(out)?;
        out.write_all(CONTACT12_HEADER.as_bytes())?;
        out.write_all(b"\n")
    }

    /// Write the row of one posture, if it qualifies (collected; see [`Self::flush`]).
    pub fn posture(&mut self, p: &Posture, out: &mut dyn Write) -> io::Result<()> {
        let cutting_contact = p.motion == MotionKind::Cut && p.contact.is_some();
        if !(self.all_moves || cutting_contact) {
            return Ok(());
        }
        if self.used + ROW_ROOM > self.pending.len() {
            self.flush(out)?;
        }
        let at = self.used;
        let row = self
            .pending
            .get_mut(at..at + ROW_ROOM)
            .and_then(|r| <&mut [u8; ROW_ROOM]>::try_from(r).ok());
        match row.and_then(|r| fast_row(r, p)) {
            Some(n) => {
                self.used += n;
                Ok(())
            }
            None => {
                self.flush(out)?;
                self.slow_row(p, out)
            }
        }
    }

    /// [`Self::posture`], given the numbers of the posture's `GOTO` as written when the
    /// reader kept them: a row that would print as they are written is copied (the same
    /// bytes, without printing twelve numbers).
    pub fn posture_written(
        &mut self,
        p: &Posture,
        written: Option<&Written>,
        out: &mut dyn Write,
    ) -> io::Result<()> {
        let text = written.and_then(|w| row_as_written(p, w));
        let Some(text) = text.filter(|_| p.motion == MotionKind::Cut || self.all_moves) else {
            return self.posture(p, out);
        };
        if self.used + ROW_ROOM > self.pending.len() {
            self.flush(out)?;
        }
        let at = self.used;
        match self.pending.get_mut(at..at + text.len() + 1) {
            Some(row) => {
                row[..text.len()].copy_from_slice(text);
                row[text.len()] = b'\n';
                self.used += text.len() + 1;
                Ok(())
            }
            None => self.posture(p, out),
        }
    }

    /// Hand the collected rows to `out` (after the last posture, and before writing to
    /// `out` directly).
    pub fn flush(&mut self, out: &mut dyn Write) -> io::Result<()> {
        let n = std::mem::take(&mut self.used);
        out.write_all(&self.pending[..n])
    }

    /// The row of `p` through [`push_fixed`] (any value).
    fn slow_row(&mut self, p: &Posture, out: &mut dyn Write) -> io::Result<()> {
        let l = &mut self.line;
        l.clear();
        for v in [p.position.x, p.position.y, p.position.z] {
            push_fixed(l, v, LENGTH_DECIMALS);
            l.push(b',');
        }
        for v in [p.axis.x, p.axis.y, p.axis.z] {
            push_fixed(l, v, UNIT_DECIMALS);
            l.push(b',');
        }
        match &p.contact {
            Some(c) => {
                for v in [c.point.x, c.point.y, c.point.z] {
                    push_fixed(l, v, LENGTH_DECIMALS);
                    l.push(b',');
                }
                for (k, v) in [c.normal.x, c.normal.y, c.normal.z].into_iter().enumerate() {
                    push_fixed(l, v, UNIT_DECIMALS);
                    if k < 2 {
                        l.push(b',');
                    }
                }
            }
            None => l.extend_from_slice(b",,,,,"),
        }
        l.push(b'\n');
        out.write_all(l)
    }
}

/// Streams NX-style CLSF: header records per path, then one or two records per posture
/// (`RAPID`, `CIRCLE`, `FEDRAT`, `SPINDL`, `CYCLE` where needed), `END-OF-PATH`.
pub struct ClsfWriter {
    line: Vec<u8>,
    feed: Option<f64>,
    spindle: Option<f64>,
    axis: Option<[u8; 64]>,
    axis_len: usize,
    cycle: bool,
    tool: Option<ToolData>,
    /// The last `PAINT/COLOR` written in this path (colours are written once a path has
    /// an approach, engage, retract or departure move, so the kinds read back).
    colour: Option<u32>,
    kind: Option<MotionKind>,
}

impl Default for ClsfWriter {
    fn default() -> Self {
        ClsfWriter::new()
    }
}

impl ClsfWriter {
    /// A new writer.
    pub fn new() -> ClsfWriter {
        ClsfWriter {
            line: Vec::with_capacity(200),
            feed: None,
            spindle: None,
            axis: None,
            axis_len: 0,
            cycle: false,
            tool: None,
            colour: None,
            kind: None,
        }
    }

    fn name(s: &str, fallback: &str) -> String {
        let t: String = s
            .chars()
            .map(|c| {
                if c == ',' || c == '/' || c == '$' || c.is_control() {
                    '_'
                } else {
                    c
                }
            })
            .collect();
        let t = t.trim().to_string();
        if t.is_empty() {
            fallback.to_string()
        } else {
            t
        }
    }

    /// Write the header of a path (`TOOL PATH`, `TLDATA`, `MSYS` unless applied).
    pub fn begin_path(&mut self, path: &Toolpath, out: &mut dyn Write) -> io::Result<()> {
        self.feed = None;
        self.spindle = None;
        self.axis = None;
        self.cycle = false;
        self.colour = None;
        self.kind = None;
        self.tool = path.tool.clone();
        writeln!(
            out,
            "TOOL PATH/{},TOOL,{}",
            Self::name(&path.name, "PATH"),
            Self::name(&path.tool_name, "NONE")
        )?;
        let l = &mut self.line;
        if let Some(t) = &path.tool {
            l.clear();
            l.extend_from_slice(b"TLDATA/");
            l.extend_from_slice(Self::name(&t.kind, "MILL").as_bytes());
            for v in [t.diameter_mm, t.corner_radius_mm, t.length_mm] {
                l.push(b',');
                push_fixed(l, v, LENGTH_DECIMALS);
            }
            if t.kind != "DRILL" {
                l.push(b',');
                push_fixed(l, t.taper_rad.to_degrees(), LENGTH_DECIMALS);
            }
            l.push(b',');
            push_fixed(l, t.tip_rad.to_degrees(), LENGTH_DECIMALS);
            // NX's seven-parameter mill: the corner centre X1, Y1.
            if let (Some(p), "MILL") = (t.apt_profile(), t.kind.as_str()) {
                for v in [p[2], p[3]] {
                    l.push(b',');
                    push_fixed(l, v, LENGTH_DECIMALS);
                }
            }
            l.push(b'\n');
            out.write_all(l)?;
        }
        if let Some(m) = &path.msys
            && !path.msys_applied
        {
            l.clear();
            l.extend_from_slice(b"MSYS/");
            for (k, v) in m.iter().enumerate() {
                if k > 0 {
                    l.push(b',');
                }
                push_fixed(
                    l,
                    *v,
                    if k < 3 {
                        LENGTH_DECIMALS
                    } else {
                        UNIT_DECIMALS
                    },
                );
            }
            l.push(b'\n');
            out.write_all(l)?;
        }
        out.write_all(b"$$ centerline data\n")?;
        out.write_all(
            b"$$ crest: GOTO/x,y,z,i,j,k,cx,cy,cz[,nx,ny,nz] carries the CC point and normal\n",
        )
    }

    /// Write the records of one posture.
    pub fn posture(&mut self, p: &Posture, out: &mut dyn Write) -> io::Result<()> {
        let in_cycle = p.motion == MotionKind::Cycle;
        if in_cycle != self.cycle {
            out.write_all(if in_cycle {
                b"CYCLE/DRILL\n"
            } else {
                b"CYCLE/OFF\n"
            })?;
            self.cycle = in_cycle;
        }
        if p.spindle_rpm != self.spindle {
            match p.spindle_rpm {
                Some(s) => {
                    self.line.clear();
                    self.line.extend_from_slice(b"SPINDL/RPM,");
                    push_fixed(&mut self.line, s, LENGTH_DECIMALS);
                    self.line.extend_from_slice(b",CLW\n");
                    out.write_all(&self.line)?;
                }
                None => out.write_all(b"SPINDL/OFF\n")?,
            }
            self.spindle = p.spindle_rpm;
        }
        // NX's colour of the move kind, once the path has a kind beyond rapid and cut,
        // and again at every change of kind (two 211 groups in a row are two groups).
        let marked = !matches!(
            p.motion,
            MotionKind::Rapid
                | MotionKind::Cut
                | MotionKind::From
                | MotionKind::GoHome
                | MotionKind::Cycle
        );
        if let Some(c) = p.motion.nx_colour()
            && (self.colour.is_some() || marked)
            && (self.colour != Some(c) || self.kind != Some(p.motion))
        {
            self.line.clear();
            let _ = writeln!(self.line, "PAINT/COLOR,{c}");
            out.write_all(&self.line)?;
            self.colour = Some(c);
        }
        self.kind = Some(p.motion);
        if p.motion.is_feed()
            && let Some(f) = p.feed_mm_min
            && Some(f) != self.feed
        {
            self.line.clear();
            self.line.extend_from_slice(b"FEDRAT/MMPM,");
            push_fixed(&mut self.line, f, LENGTH_DECIMALS);
            self.line.push(b'\n');
            out.write_all(&self.line)?;
            self.feed = Some(f);
        }
        if p.motion.is_rapid() {
            out.write_all(b"RAPID\n")?;
        }
        let l = &mut self.line;
        if let Some(a) = &p.arc {
            l.clear();
            l.extend_from_slice(b"CIRCLE/");
            for v in [a.centre.x, a.centre.y, a.centre.z] {
                push_fixed(l, v, LENGTH_DECIMALS);
                l.push(b',');
            }
            for v in [a.axis.x, a.axis.y, a.axis.z] {
                push_fixed(l, v, UNIT_DECIMALS);
                l.push(b',');
            }
            let (d, r) = self
                .tool
                .as_ref()
                .map(|t| (t.diameter_mm, t.corner_radius_mm))
                .unwrap_or((0.0, 0.0));
            for (k, v) in [a.radius_mm, 0.06, 0.5, d, r].into_iter().enumerate() {
                if k > 0 {
                    l.push(b',');
                }
                push_fixed(l, v, LENGTH_DECIMALS);
            }
            if a.extra_turns > 0 {
                l.extend_from_slice(b",TIMES,");
                let _ = write!(l, "{}", u64::from(a.extra_turns) + 1);
            }
            l.push(b'\n');
            out.write_all(l)?;
        }
        l.clear();
        l.extend_from_slice(match p.motion {
            MotionKind::From => b"FROM/".as_slice(),
            MotionKind::GoHome => b"GOHOME/".as_slice(),
            _ => b"GOTO/".as_slice(),
        });
        for (k, v) in [p.position.x, p.position.y, p.position.z]
            .into_iter()
            .enumerate()
        {
            if k > 0 {
                l.push(b',');
            }
            push_fixed(l, v, LENGTH_DECIMALS);
        }
        // The axis as it would be printed; written when it changes (or with contact data).
        let mut axis_text = [0u8; 64];
        let mut tmp = Vec::with_capacity(48);
        for v in [p.axis.x, p.axis.y, p.axis.z] {
            tmp.push(b',');
            push_fixed(&mut tmp, v, UNIT_DECIMALS);
        }
        let n = tmp.len().min(64);
        axis_text[..n].copy_from_slice(&tmp[..n]);
        let axis_changed = self.axis.is_none_or(|a| a[..self.axis_len] != tmp[..]);
        let with_contact =
            p.contact.is_some() && !matches!(p.motion, MotionKind::From | MotionKind::GoHome);
        if axis_changed || with_contact {
            l.extend_from_slice(&tmp);
            self.axis = Some(axis_text);
            self.axis_len = n;
        }
        if with_contact && let Some(c) = &p.contact {
            for v in [c.point.x, c.point.y, c.point.z] {
                l.push(b',');
                push_fixed(l, v, LENGTH_DECIMALS);
            }
            if !c.normal_derived {
                for v in [c.normal.x, c.normal.y, c.normal.z] {
                    l.push(b',');
                    push_fixed(l, v, UNIT_DECIMALS);
                }
            }
        }
        l.push(b'\n');
        out.write_all(l)
    }

    /// Close the path.
    pub fn end_path(&mut self, out: &mut dyn Write) -> io::Result<()> {
        if self.cycle {
            out.write_all(b"CYCLE/OFF\n")?;
            self.cycle = false;
        }
        out.write_all(b"END-OF-PATH\n")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_digits() {
        assert_eq!(fixed(1.5, LENGTH_DECIMALS), "1.5000");
        assert_eq!(fixed(-297.5, LENGTH_DECIMALS), "-297.5000");
        assert_eq!(fixed(1.234567, LENGTH_DECIMALS), "1.234567");
        assert_eq!(fixed(1.2345678, LENGTH_DECIMALS), "1.234568");
        assert_eq!(fixed(-0.00000001, LENGTH_DECIMALS), "0.0000");
        assert_eq!(
            fixed(std::f64::consts::FRAC_1_SQRT_2, UNIT_DECIMALS),
            "0.707106781"
        );
        assert_eq!(fixed(1.0, UNIT_DECIMALS), "1.0000000");
        assert_eq!(fixed(25.400000000000002, LENGTH_DECIMALS), "25.4000");
        assert_eq!(fixed(1e300, LENGTH_DECIMALS), format!("{}", 1e300));
        assert_eq!(
            fixed(-4364844.847241433, UNIT_DECIMALS),
            "-4364844.847241433"
        );
    }

    #[test]
    fn printed_digits_survive_reading() {
        // Any value with at most 6 decimals prints back to itself after a parse.
        for s in [
            "0.000001",
            "-1234.5678",
            "99999.999999",
            "0.1",
            "-0.5",
            "123456789.123456",
        ] {
            let v: f64 = s.parse().unwrap_or(f64::NAN);
            let printed = fixed(v, LENGTH_DECIMALS);
            let again: f64 = printed.parse().unwrap_or(f64::NAN);
            assert_eq!(fixed(again, LENGTH_DECIMALS), printed);
            assert_eq!(again, v, "{s}");
        }
    }

    #[test]
    fn rows_in_place_print_as_push_fixed_does() {
        let mut seed: u64 = 11;
        let mut next = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut values = vec![
            0.0, -0.0, 0.5, -0.5, 1e-12, -1e-12, 9.9999995, 2.79e8, -2.79e8,
        ];
        for _ in 0..50_000 {
            let mag = 10f64.powf(next() * 12.0 - 4.0);
            values.push((next() - 0.5) * mag);
        }
        for v in values {
            for d in [LENGTH_DECIMALS, UNIT_DECIMALS, (0, 6), (0, 9), (0, 0)] {
                let mut s = [0u8; FIXED_ROOM];
                let n = fixed_digits(&mut s, v, d).unwrap_or(0);
                let mut want = Vec::new();
                push_fixed(&mut want, v, d);
                if n == 0 {
                    // Beyond the fixed-point range: `format!`'s shortest form.
                    assert_eq!(want, format!("{v}").into_bytes());
                    continue;
                }
                assert_eq!(&s[..n], &want[..], "{v} {d:?}");
                // The digits are those of the plain algorithm: scaled, rounded, split.
                let max = d.1;
                let q = (v.abs() * 10f64.powi(max as i32) + 0.5) as u64;
                let (int, mut frac, mut dec) = (q / 10u64.pow(max), q % 10u64.pow(max), max);
                while dec > d.0 && frac % 10 == 0 {
                    frac /= 10;
                    dec -= 1;
                }
                let sign = if v < 0.0 && q != 0 { "-" } else { "" };
                let plain = if dec == 0 {
                    format!("{sign}{int}")
                } else {
                    format!("{sign}{int}.{frac:0w$}", w = dec as usize)
                };
                assert_eq!(String::from_utf8_lossy(&want), plain, "{v} {d:?}");
            }
        }
    }

    #[test]
    fn numbers_print_as_format_does() {
        let mut seed: u64 = 7;
        let mut next = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut values = vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            1.5,
            2.5,
            0.0078125,
            -0.0078125,
            1e-12,
            -1e-12,
            999_999.999_999_5,
            1e7 + 0.25,
            3.8e8,
            38_981_340.000_002_5,
            0.999_999_999_9,
            -0.000_000_000_4,
            1e300,
            f64::NAN,
            f64::INFINITY,
        ];
        for _ in 0..20_000 {
            let mag = 10f64.powf(next() * 14.0 - 6.0);
            values.push((next() - 0.5) * mag);
        }
        for v in values {
            for dec in [0, 3, 6, 9] {
                let mut b = Vec::new();
                push_decimals(&mut b, v, dec);
                let got = String::from_utf8(b).unwrap();
                let want = format!("{v:.prec$}", prec = dec as usize);
                // Only a fraction within rounding of a half-way point may differ.
                let a = v.abs();
                let scaled = (a - a.trunc()) * 10f64.powi(dec as i32);
                let near_tie = ((scaled - scaled.floor()) - 0.5).abs() < 1e-9;
                assert!(got == want || near_tie, "{v} {dec}: {got} vs {want}");
            }
        }
    }

    /// The word-wise digits give the bytes of the digit loop.
    fn same_as_wide(v: f64, d: (u32, u32)) {
        let mut a = [0u8; FIXED_ROOM];
        let mut b = [0u8; FIXED_ROOM];
        let n = fixed_digits(&mut a, v, d);
        let m = fixed_digits_wide(&mut b, v, d);
        assert_eq!(n, m, "{v} {d:?}");
        if let Some(n) = n {
            assert_eq!(&a[..n], &b[..n], "{v} {d:?}");
        }
    }

    const ALL_DECIMALS: [(u32, u32); 12] = [
        LENGTH_DECIMALS,
        UNIT_DECIMALS,
        (0, 0),
        (0, 1),
        (1, 1),
        (0, 6),
        (0, 8),
        (3, 8),
        (0, 9),
        (9, 9),
        (2, 5),
        (12, 12),
    ];

    #[test]
    fn rows_as_written_are_copied_only_when_they_print_so() {
        use crate::math::{Point3, Vec3};
        use crate::parse::ClsfReader;
        use crate::toolpath::Contact;
        // Each line after the first as the reader keeps it, and the posture of its values.
        let read = |line: &str| {
            // A line after it, as in a file: the last number, too, is read by words.
            let text = format!(
                "TOOL PATH/A,TOOL,T\nGOTO/{line}\nEND-OF-PATH\n$$ {:64}\n",
                ""
            );
            let mut r = ClsfReader::new(text.as_bytes());
            let _ = r.next();
            let mut w = Written::default();
            let (n, at) = r
                .next_goto_written(&mut w)
                .unwrap()
                .unwrap_or_else(|| panic!("{line}"));
            let v = n.as_slice();
            let p = Posture {
                position: Point3::new(v[0], v[1], v[2]),
                axis: Vec3::new(v[3], v[4], v[5]),
                motion: MotionKind::Cut,
                arc: None,
                contact: Some(Contact {
                    point: Point3::new(v[6], v[7], v[8]),
                    normal: Vec3::new(v[9], v[10], v[11]),
                    normal_derived: false,
                }),
                feed_mm_min: None,
                spindle_rpm: None,
                line: at,
            };
            (w, p)
        };
        let printed = |p: &Posture| {
            let mut out = Vec::new();
            let mut cw = Contact12Writer::new(false);
            cw.posture(p, &mut out).unwrap();
            cw.flush(&mut out).unwrap();
            out
        };
        let nx = "-1.7916,0.0000,0.1456,0.2588190,0.0000000,0.9659258,0.0000,0.0000,0.0000,-0.0995037,0.0000000,0.9950372";
        let (w, p) = read(nx);
        assert_eq!(row_as_written(&p, &w), Some(nx.as_bytes()));
        assert_eq!(printed(&p), format!("{nx}\n").into_bytes());
        // Written otherwise than the writer writes: printed, not copied.
        for other in [
            "-1.7916,0.0000,0.1456,0.2588190,0.0000000,0.9659258,+0.0000,0.0000,0.0000,-0.0995037,0.0000000,0.9950372",
            "-1.79160,0.0000,0.1456,0.2588190,0.0000000,0.9659258,0.0000,0.0000,0.0000,-0.0995037,0.0000000,0.9950372",
            "-1.7916,-0.0000,0.1456,0.2588190,0.0000000,0.9659258,0.0000,0.0000,0.0000,-0.0995037,0.0000000,0.9950372",
            "-1.7916,0.0000,0.1456,.2588190,0.0000000,0.9659258,0.0000,0.0000,0.0000,-0.0995037,0.0000000,0.9950372",
            "-1.7916,0.0000,0.1456,0.2588190,0.0000000,0.9659258,0.0000,0.0000,00.0000,-0.0995037,0.0000000,0.9950372",
            "-1.7916,0.0000,0.1456,0.2588190,0.0000000,0.9659258,0.0000,0.0000,0.0000,-0.0995037,0.0000000,0.995037",
        ] {
            let (w, p) = read(other);
            assert_eq!(row_as_written(&p, &w), None, "{other}");
            assert_ne!(printed(&p), format!("{other}\n").into_bytes(), "{other}");
        }
        // More decimals than the least: printed (here to the same digits), not copied.
        let more = "-1.79165,0.0000,0.1456,0.2588190,0.0000000,0.9659258,0.0000,0.0000,0.0000,-0.0995037,0.0000000,0.9950372";
        let (w, p) = read(more);
        assert_eq!(row_as_written(&p, &w), None);
        assert_eq!(printed(&p), format!("{more}\n").into_bytes());
        // A value changed on the way (units, a frame) or another line: printed.
        let (w, mut p) = read(nx);
        p.position.x *= 25.4;
        assert_eq!(row_as_written(&p, &w), None);
        let (w, mut p) = read(nx);
        p.line += 1;
        assert_eq!(row_as_written(&p, &w), None);
    }

    proptest::proptest! {
        /// A number the reader says prints as written does, for lengths and unit vectors;
        /// and every number written as the writer writes it is said to.
        #[test]
        fn numbers_said_to_print_as_written_do(
            sign in 0usize..3, int in 0u64..10_000_000, int_len in 0usize..8,
            frac in 0u64..10_000_000, frac_len in 0usize..8, dot: bool,
        ) {
            use crate::parse::number::{SHORT_WINDOW, scan_short_form};
            let int = format!("{int:07}");
            let frac = format!("{frac:07}");
            let mut text = String::from(["", "-", "+"][sign]);
            text.push_str(&int[7 - int_len..]);
            if dot {
                text.push('.');
                text.push_str(&frac[..frac_len]);
            }
            let mut c = [b','; SHORT_WINDOW];
            c[..text.len()].copy_from_slice(text.as_bytes());
            if let Some((v, n, form)) = scan_short_form(&c) {
                proptest::prop_assert_eq!(n, text.len());
                for d in [LENGTH_DECIMALS, UNIT_DECIMALS] {
                    let mut out = Vec::new();
                    push_fixed(&mut out, v, d);
                    if prints_as_written(form, d) {
                        proptest::prop_assert_eq!(&out, text.as_bytes(), "{:?}", d);
                    }
                    // The writer's own text of the value, with its least decimals, is said
                    // to print as written, and does.
                    let mut parts = out.split(|&b| b == b'.');
                    let int_len = parts.next().map_or(0, |i| i.iter().filter(|b| b.is_ascii_digit()).count());
                    if int_len <= 5 && parts.next().map(<[u8]>::len) == Some(d.0 as usize) {
                        let mut c = [b','; SHORT_WINDOW];
                        c[..out.len()].copy_from_slice(&out);
                        if let Some((back, n, f)) = scan_short_form(&c) {
                            proptest::prop_assert_eq!(n, out.len());
                            proptest::prop_assert!(
                                prints_as_written(f, d),
                                "{}",
                                String::from_utf8_lossy(&out)
                            );
                            let mut again = Vec::new();
                            push_fixed(&mut again, back, d);
                            proptest::prop_assert_eq!(&again, &out);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn digits_made_by_words_match_the_digit_loop() {
        let mut values = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1e-12,
            -4e-10,
            5e-10,
            9.9999995,
            99_999_999.999_999_5,
            99_999_999.4,
            100_000_000.0,
            -99_999_999.0,
            12_345_678.9,
            0.000_000_001,
            0.999_999_999_6,
            2.79e8,
            2.8e5,
            -2.8e5,
            1e300,
            f64::NAN,
            f64::INFINITY,
        ];
        for k in 0..=9 {
            let p = 10f64.powi(k);
            for v in [1.0, 0.5, 0.05, 1.5, 9.5, 99.5, 123.25] {
                values.extend([v / p, -v / p, v * p, -v * p]);
            }
        }
        for v in values {
            for d in ALL_DECIMALS {
                same_as_wide(v, d);
            }
        }
    }

    proptest::proptest! {
        #[test]
        fn words_match_the_digit_loop_anywhere(
            mantissa in -1.0f64..1.0, exp in -10i32..10, any in proptest::num::f64::ANY,
        ) {
            let v = mantissa * 10f64.powi(exp);
            for d in ALL_DECIMALS {
                same_as_wide(v, d);
                same_as_wide(any, d);
            }
        }

        #[test]
        fn fixed_decimals_read_back_to_their_digits(
            int in 0u64..280_000, frac in 0u64..1_000_000_000, neg: bool,
        ) {
            // A number written with 9 decimals, read, and printed with (0, 9).
            let text = format!("{}{int}.{frac:09}", if neg { "-" } else { "" });
            let v: f64 = text.parse().unwrap();
            let mut s = [0u8; FIXED_ROOM];
            let n = fixed_digits(&mut s, v, (9, 9)).unwrap();
            let zero = int == 0 && frac == 0;
            let want = if neg && !zero { text.clone() } else { text.trim_start_matches('-').to_string() };
            // At most 15 significant digits: the printed digits are those read.
            proptest::prop_assert_eq!(std::str::from_utf8(&s[..n]).unwrap(), want);
        }
    }
}
