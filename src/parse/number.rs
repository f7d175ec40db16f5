//! Fast decimal number scanning for the APT number syntax
//! `[+|-] (digits [. [digits]] | . digits) [(E|e) [+|-] digits]`.
//!
//! CLSF files are mostly numbers, so this is the hot loop of reading. Fixed-point numbers
//! with at most 15 significant digits (every number NX writes) take an exact fast path:
//! the digits form an integer `m < 2^53` and the value is `m / 10^k` with `k <= 22`, one
//! correctly rounded division of two exact doubles. Anything else falls back to the
//! standard library's correctly rounded parser, so results never depend on the path.

/// Powers of ten exactly representable as `f64`.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// `10^n` for `n ≤ 8`, as integers.
const POW10_U64: [u64; 9] = [
    1,
    10,
    100,
    1_000,
    10_000,
    100_000,
    1_000_000,
    10_000_000,
    100_000_000,
];

/// The run of ASCII digits starting at `bytes[i]`: where it ends, and `mantissa` with its
/// digits appended (wrapping, as the caller only trusts up to 18 digits).
///
/// Eight bytes at a time where eight are left: which of them are digits and their value
/// come from a few word operations, so a run of any length up to 8 costs one branch
/// instead of one (mispredicted at the end) per digit.
#[inline(always)]
fn digit_run(bytes: &[u8], mut i: usize, mut mantissa: u64) -> (usize, u64) {
    while let Some(w) = bytes.get(i..i + 8) {
        let mut word = [0u8; 8];
        word.copy_from_slice(w);
        let w = u64::from_le_bytes(word);
        let n = leading_digits(w);
        if n == 0 {
            return (i, mantissa);
        }
        // The n digits as the low end of an eight-digit number with leading zeros.
        let d = w.wrapping_sub(0x3030_3030_3030_3030) << (8 * (8 - n));
        mantissa = mantissa
            .wrapping_mul(POW10_U64[n])
            .wrapping_add(eight_digits(d));
        i += n;
        if n < 8 {
            return (i, mantissa);
        }
    }
    while i < bytes.len() && bytes[i].is_ascii_digit() {
        mantissa = mantissa
            .wrapping_mul(10)
            .wrapping_add(u64::from(bytes[i] - b'0'));
        i += 1;
    }
    (i, mantissa)
}

/// How many of the eight bytes of `w` (first byte lowest) are ASCII digits before the
/// first one that is not.
#[inline(always)]
fn leading_digits(w: u64) -> usize {
    // A byte's top bit ends up set when it is below b'0' (the subtraction borrows) or above
    // b'9' (adding 0x46 reaches 0x80, or wraps for bytes ≥ 0xBA, which the subtraction then
    // flags). Borrows and carries only run into later bytes, past the first non-digit.
    let below = w.wrapping_sub(0x3030_3030_3030_3030);
    let above = w.wrapping_add(0x4646_4646_4646_4646);
    let non_digit = (below | above) & 0x8080_8080_8080_8080;
    (non_digit.trailing_zeros() / 8) as usize
}

/// The value of eight digit values (0-9, one per byte, the first and most significant in
/// the lowest byte).
#[inline(always)]
fn eight_digits(d: u64) -> u64 {
    // Pairs, then quadruples, then the whole (each step multiplies adjacent fields by their
    // weight; no field overflows into the next).
    let d = d.wrapping_mul(10).wrapping_add(d >> 8) & 0x00FF_00FF_00FF_00FF;
    let d = d.wrapping_mul(100).wrapping_add(d >> 16) & 0x0000_FFFF_0000_FFFF;
    d.wrapping_mul(10_000).wrapping_add(d >> 32) & 0xFFFF_FFFF
}

/// Bytes [`scan_short`] is given: a number of up to 16 bytes, the byte after it, and room
/// for whole-word reads (indices are masked to the window, so no read needs a bounds
/// check).
pub const SHORT_WINDOW: usize = 32;

/// The little-endian word of the eight bytes of `c` from `k & 15` (the mask keeps every
/// read inside the window, so the compiler needs no bounds check).
#[inline(always)]
fn word_at(c: &[u8; SHORT_WINDOW], k: usize) -> u64 {
    let k = k & 15;
    let mut w = [0u8; 8];
    w.copy_from_slice(&c[k..k + 8]);
    u64::from_le_bytes(w)
}

/// The digit values (0-9, one per byte) of the first `n < 8` bytes of `w` (ASCII digits,
/// first lowest), moved to the top of the word with zeros below: an eight-digit number
/// with leading zeros, as [`eight_digits`] reads it. Two shifts, so that `n = 0` shifts
/// everything out.
#[inline(always)]
fn top_digits(w: u64, n: usize) -> u64 {
    (w.wrapping_sub(0x3030_3030_3030_3030) << (8 * (7 - n))) << 8
}

/// The common short number `[+|-] digits . digits` (fewer than 8 digits on each side of
/// the point, or digits alone, no exponent) in the window `c`: the value and the bytes
/// used. `None` when the number is anything else, which [`scan_number`] then reads; when
/// this returns a value, [`scan_number`] returns the same (the digits form an integer
/// below 10^14, exact in `f64`, and the value is one correctly rounded division by an
/// exact power of ten, as on its fast path). A handful of word operations and no branch
/// per digit: this is the inner loop of reading a CLSF.
#[inline(always)]
pub fn scan_short(c: &[u8; SHORT_WINDOW]) -> Option<(f64, usize)> {
    let (v, end) = scan_short_digits(c)?;
    if c[end & 31] | 0x20 == b'e' {
        return None;
    }
    Some((v, end))
}

/// [`scan_short`] without its look at the byte after the number: the caller refuses a
/// number followed by `e` or `E` (an exponent, which only [`scan_number`] reads). A list
/// of numbers looks at that byte anyway (for the comma), so this saves the second look.
#[inline(always)]
pub fn scan_short_digits(c: &[u8; SHORT_WINDOW]) -> Option<(f64, usize)> {
    scan_short_form(c).map(|(v, end, _)| (v, end))
}

/// How a number is written, as far as a fixed-point printer cares (see
/// [`Form::decimals`]); what [`scan_short_form`] reports beside the value. Four bits, so
/// that a line's forms pack into one word ([`Form::bits`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Form(u8);

impl Form {
    /// Any other way of writing a number (an exponent, a `+`, a leading zero more, no
    /// point, no digit before it, a negative zero, more than five digits before the point
    /// or seven after it).
    pub const OTHER: Form = Form(0x8);

    /// The form of `[-]digits.digits` with one to five digits before the point (one `0`
    /// or no leading zero) and `decimals` (1-7) after it, no `+`, not a negative zero
    /// (`-0.000`): a number written as a fixed-point printer writes it, below 10^5 in
    /// size.
    pub const fn fixed(decimals: u32) -> Form {
        if decimals < 8 {
            Form(decimals as u8)
        } else {
            Form::OTHER
        }
    }

    /// `Some(decimals)` for [`Form::fixed`]`(decimals)`, `None` for [`Form::OTHER`].
    pub fn decimals(self) -> Option<u32> {
        (self.0 < 8).then_some(u32::from(self.0))
    }

    /// The four bits of the form.
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// The form of four bits.
    pub const fn from_bits(b: u8) -> Form {
        Form::fixed((b & 0xF) as u32)
    }
}

/// [`scan_short_digits`] and the number's [`Form`]: the same value and length, and how the
/// number is written, from what the scan has seen anyway (its sign, where its point is, its
/// first and last digit): a few more operations and no branch.
#[inline(always)]
pub fn scan_short_form(c: &[u8; SHORT_WINDOW]) -> Option<(f64, usize, Form)> {
    let first = c[0];
    let negative = first == b'-';
    let s = usize::from(negative || first == b'+');
    let w1 = word_at(c, s);
    let n1 = leading_digits(w1);
    let dot = s + n1;
    // n1 < 8, so dot ≤ 8 and every index below stays inside the window.
    if n1 == 8 {
        return None;
    }
    let int = top_digits(w1, n1);
    let (mantissa, scale, end) = if c[dot] == b'.' {
        let w2 = word_at(c, dot + 1);
        let n2 = leading_digits(w2);
        if n2 == 8 || n1 + n2 == 0 {
            return None;
        }
        let frac = top_digits(w2, n2);
        let m = if n1 + n2 <= 8 {
            // Both runs in one eight-digit word: the integer digits right above the
            // fraction's.
            eight_digits((int >> (8 * n2)) | frac)
        } else {
            eight_digits(int) * POW10_U64[n2] + eight_digits(frac)
        };
        (m, n2, dot + 1 + n2)
    } else {
        if n1 == 0 {
            return None;
        }
        (eight_digits(int), 0, dot)
    };
    // mantissa < 10^14: the signed conversion is exact and one instruction.
    let v = mantissa as i64 as f64 / POW10[scale];
    let v = f64::from_bits(v.to_bits() | (u64::from(negative) << 63));
    // The form (`Form::fixed`): one to five digits before the point, the first not a `0`
    // unless it is alone, digits after it, no `+`, not a negative zero. Plain operations
    // on flags, no branch.
    let other = (first == b'+')
        | (n1 == 0)
        | (n1 > 5)
        | (scale == 0)
        | ((n1 > 1) & (c[s] == b'0'))
        | (negative & (mantissa == 0));
    let form = if other {
        Form::OTHER
    } else {
        Form(scale as u8)
    };
    Some((v, end, form))
}

/// Scan one number at the start of `bytes`.
///
/// Returns the value and the number of bytes consumed, or `None` when `bytes` does not
/// start with a number. The value may be infinite when the number overflows `f64`; the
/// caller decides whether that is an error.
#[inline]
pub fn scan_number(bytes: &[u8]) -> Option<(f64, usize)> {
    if let Some(c) = bytes.first_chunk::<SHORT_WINDOW>()
        && let Some(r) = scan_short(c)
    {
        return Some(r);
    }
    scan_general(bytes)
}

/// [`scan_number`] for any input.
#[inline]
fn scan_general(bytes: &[u8]) -> Option<(f64, usize)> {
    let len = bytes.len();
    // The sign without a branch (signs of coordinates follow no pattern).
    let first = bytes.first().copied().unwrap_or(0);
    let negative = first == b'-';
    let mut i = usize::from(negative || first == b'+');
    // Accumulate all digits; with at most 18 of them the u64 cannot overflow.
    let (end, mut mantissa) = digit_run(bytes, i, 0);
    let mut digits = end - i;
    i = end;
    let mut scale: i32 = 0;
    if i < len && bytes[i] == b'.' {
        i += 1;
        let (end, m) = digit_run(bytes, i, mantissa);
        mantissa = m;
        let frac = end - i;
        i = end;
        digits += frac;
        scale = -(frac.min(100_000) as i32);
    }
    // A lone "." (or a sign alone) is not a number.
    if digits == 0 {
        return None;
    }
    let exact = digits <= 18;
    if i < len && (bytes[i] == b'e' || bytes[i] == b'E') {
        let mut j = i + 1;
        let mut exp_negative = false;
        if j < len && (bytes[j] == b'+' || bytes[j] == b'-') {
            exp_negative = bytes[j] == b'-';
            j += 1;
        }
        let exp_start = j;
        let mut exp: i32 = 0;
        while j < len && bytes[j].is_ascii_digit() {
            if exp < 100_000 {
                exp = exp * 10 + i32::from(bytes[j] - b'0');
            }
            j += 1;
        }
        if j > exp_start {
            scale += if exp_negative { -exp } else { exp };
            i = j;
        }
        // "1E" without digits: the number ends before the "E".
    }
    if exact && mantissa < (1u64 << 53) && (-22..=22).contains(&scale) {
        let m = mantissa as f64;
        let v = if scale < 0 {
            m / POW10[(-scale) as usize]
        } else {
            m * POW10[scale as usize]
        };
        // v ≥ 0: the sign bit set is the negation (−0 for 0, as `-v` gives).
        let v = f64::from_bits(v.to_bits() | (u64::from(negative) << 63));
        return Some((v, i));
    }
    // Slow path: the standard library parses exactly this syntax correctly rounded.
    let text = std::str::from_utf8(&bytes[..i]).ok()?;
    let v: f64 = text.parse().ok()?;
    Some((v, i))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(s: &str, expected: Option<(f64, usize)>) {
        assert_eq!(scan_number(s.as_bytes()), expected, "input {s:?}");
    }

    #[test]
    fn fixed_point_numbers() {
        check("0.0600", Some((0.06, 6)));
        check("-297.5000,", Some((-297.5, 9)));
        check("1000", Some((1000.0, 4)));
        check("+1.", Some((1.0, 3)));
        check(".5x", Some((0.5, 2)));
        check("1E3", Some((1000.0, 3)));
        check("1e-3,", Some((0.001, 4)));
        check("2E", Some((2.0, 1)));
        check("-", None);
        check(".", None);
        check("-.", None);
        check("abc", None);
        check("", None);
    }

    #[test]
    fn digit_runs_of_every_length_and_position() {
        // Runs of 0-20 digits followed by each kind of byte, at every offset of a word, and
        // ending at the end of the slice.
        for len in 0..=20usize {
            let digits: String = (0..len)
                .map(|k| char::from(b'0' + (k * 7 % 10) as u8))
                .collect();
            let want: u64 = digits.bytes().fold(0u64, |m, c| {
                m.wrapping_mul(10).wrapping_add(u64::from(c - b'0'))
            });
            for tail in [
                "", ",", ".", "/", ":", "a", " ", "\u{e9}", "\u{ff}", "12345678",
            ] {
                for pad in 0..9 {
                    let text = format!("{}{digits}{tail}", "x".repeat(pad));
                    let b = text.as_bytes();
                    let (end, m) = digit_run(b, pad, 0);
                    let run = b[pad..].iter().take_while(|c| c.is_ascii_digit()).count();
                    let all: u64 = b[pad..pad + run].iter().fold(0u64, |m, c| {
                        m.wrapping_mul(10).wrapping_add(u64::from(c - b'0'))
                    });
                    assert_eq!((end, m), (pad + run, all), "{text:?}");
                    if !tail.starts_with('1') {
                        assert_eq!(m, want);
                    }
                }
            }
        }
        // Every byte value right after a digit.
        for c in 0..=255u8 {
            let b = [b'4', c, b'x', b'x', b'x', b'x', b'x', b'x', b'x'];
            let n = 1 + usize::from(c.is_ascii_digit());
            assert_eq!(digit_run(&b, 0, 0).0, n, "{c}");
        }
    }

    #[test]
    fn agrees_with_std_on_long_and_awkward_numbers() {
        for s in [
            "123456789012345678901234567890",
            "0.1234567890123456789",
            "9007199254740993",
            "1e300",
            "4.9e-324",
            "1e-400",
            "-0.0000",
            "0.30000000000000004",
        ] {
            let (v, n) = scan_number(s.as_bytes()).unwrap();
            assert_eq!(n, s.len());
            let want: f64 = s.parse().unwrap();
            assert_eq!(v.to_bits(), want.to_bits(), "{s}");
        }
        assert!(scan_number(b"1e400").unwrap().0.is_infinite());
    }

    /// `scan_short` on `text` padded to a window with `tail`, against `str::parse`.
    /// The form of a number's text, by the words of [`Form::fixed`].
    fn form_of(t: &str) -> Form {
        let (negative, body) = match t.strip_prefix('-') {
            Some(b) => (true, b),
            None => (false, t),
        };
        let Some((int, frac)) = body.split_once('.') else {
            return Form::OTHER;
        };
        let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
        let zero = body.bytes().all(|b| b == b'0' || b == b'.');
        if !digits(int) || !digits(frac) || int.len() > 5 || (int.len() > 1 && int.starts_with('0'))
        {
            return Form::OTHER;
        }
        if negative && zero {
            return Form::OTHER;
        }
        Form::fixed(frac.len() as u32)
    }

    #[test]
    fn forms_of_written_numbers() {
        let form = |t: &str| {
            let mut c = [b','; SHORT_WINDOW];
            c[..t.len()].copy_from_slice(t.as_bytes());
            scan_short_form(&c).map(|(_, _, f)| f)
        };
        assert_eq!(form("0.2588190"), Some(Form::fixed(7)));
        assert_eq!(form("-1.7916"), Some(Form::fixed(4)));
        assert_eq!(form("0.0000"), Some(Form::fixed(4)));
        assert_eq!(form("12345.1"), Some(Form::fixed(1)));
        assert_eq!(form("123456.1"), Some(Form::OTHER));
        assert_eq!(Form::fixed(4).decimals(), Some(4));
        for other in [
            "-0.0000", "+1.0000", "01.0000", ".5000", "-.5", "7.", "12", "00.1",
        ] {
            assert_eq!(form(other), Some(Form::OTHER), "{other}");
        }
        assert_eq!(Form::OTHER.decimals(), None);
        assert_eq!(Form::fixed(8), Form::OTHER);
        assert_eq!(Form::from_bits(Form::fixed(7).bits()), Form::fixed(7));
    }

    fn short_agrees(text: &str, tail: u8) {
        let mut c = [tail; SHORT_WINDOW];
        c[..text.len()].copy_from_slice(text.as_bytes());
        let general = scan_general(&c);
        // `scan_short_digits` is `scan_short` but for an exponent it does not look at.
        let digits = scan_short_digits(&c);
        assert_eq!(
            scan_short(&c),
            digits.filter(|&(_, n)| c[n] | 0x20 != b'e'),
            "{text:?}"
        );
        // The form is the written number's, by the rules of `Form::fixed`.
        if let Some((v, n, form)) = scan_short_form(&c) {
            assert_eq!(Some((v, n)), digits, "{text:?}");
            assert_eq!(
                form,
                form_of(std::str::from_utf8(&c[..n]).unwrap()),
                "{text:?}"
            );
        }
        if let Some((v, n)) = scan_short(&c) {
            let want: f64 = std::str::from_utf8(&c[..n]).unwrap().parse().unwrap();
            assert_eq!(v.to_bits(), want.to_bits(), "{text:?}");
            assert_eq!(Some((v, n)), general, "{text:?}");
            assert_eq!(scan_number(&c), general, "{text:?}");
        } else {
            assert_eq!(scan_number(&c), general, "{text:?}");
        }
    }

    #[test]
    fn short_numbers_agree_with_std() {
        for s in [
            "0",
            "-0",
            "+0",
            "-0.0000",
            "0.0600",
            "-297.5000",
            "1.",
            "-1.",
            ".5",
            "-.5",
            "+.25",
            "1234567",
            "12345678",
            "1234567.1234567",
            "-9999999.9999999",
            "0.12345678",
            "1.5E3",
            "1.5e-3",
            "7e",
            "-",
            "+",
            ".",
            "-.",
            "",
            "1..2",
            "12.34.5",
            "99999999.5",
        ] {
            for tail in [b',', b'\n', b'0', b'.', b'e', b'x', b' '] {
                if s.len() < SHORT_WINDOW {
                    short_agrees(s, tail);
                }
            }
        }
    }

    proptest::proptest! {
        #[test]
        fn short_fixed_point_numbers_agree_with_std(
            sign in 0usize..3, int in 0u64..100_000_000, int_len in 0usize..9,
            frac in 0u64..100_000_000, frac_len in 0usize..9, dot: bool,
            tail in proptest::sample::select(vec![b',', b'\n', b'\r', b'5', b'E', b'$', b' ']),
        ) {
            let int = format!("{int:08}");
            let frac = format!("{frac:08}");
            let mut text = String::from(["", "-", "+"][sign]);
            text.push_str(&int[8 - int_len..]);
            if dot {
                text.push('.');
                text.push_str(&frac[..frac_len]);
            }
            short_agrees(&text, tail);
        }
    }
}
