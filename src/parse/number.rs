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

/// Decimal powers `10^k` for `k ≤ 8` as integers.
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

/// Number of leading ASCII digits in the 8 bytes of `w` (loaded little-endian), 0 to 8.
/// A byte `b` is a digit iff neither `b − '0'` nor `b + 0x46` sets its high bit; borrows
/// and carries only move upwards, past the first non-digit, so its position is exact.
#[inline(always)]
fn digit_run(w: u64) -> usize {
    let x = w.wrapping_sub(0x3030_3030_3030_3030);
    let y = w.wrapping_add(0x4646_4646_4646_4646);
    ((x | y) & 0x8080_8080_8080_8080).trailing_zeros() as usize / 8
}

/// The value of 8 decimal digits whose values (0 to 9) are the bytes of `v`, the most
/// significant in the lowest byte (SWAR: three multiplications instead of eight).
#[inline(always)]
fn eight_digits(v: u64) -> u64 {
    const MASK: u64 = 0x0000_00FF_0000_00FF;
    const MUL1: u64 = 0x000F_4240_0000_0064;
    const MUL2: u64 = 0x0000_2710_0000_0001;
    let v = v.wrapping_mul(10).wrapping_add(v >> 8);
    let v1 = (v & MASK).wrapping_mul(MUL1);
    let v2 = ((v >> 16) & MASK).wrapping_mul(MUL2);
    u64::from((v1.wrapping_add(v2) >> 32) as u32)
}

/// Append the run of digits starting at `i` to `mantissa` (wrapping: the caller only uses
/// it with at most 18 digits); returns the index after the run. Eight bytes at a time
/// while eight are left, then byte by byte.
#[inline(always)]
fn digits(bytes: &[u8], mut i: usize, mantissa: &mut u64) -> usize {
    while let Some(chunk) = bytes.get(i..i + 8) {
        let w = u64::from_le_bytes([
            chunk[0], chunk[1], chunk[2], chunk[3], chunk[4], chunk[5], chunk[6], chunk[7],
        ]);
        let k = digit_run(w);
        if k == 0 {
            return i;
        }
        // Keep the k digits, in the high bytes (the low ones become leading zeros).
        let v = w.wrapping_sub(0x3030_3030_3030_3030) << (8 * (8 - k));
        *mantissa = mantissa
            .wrapping_mul(POW10_U64[k])
            .wrapping_add(eight_digits(v));
        i += k;
        if k < 8 {
            return i;
        }
    }
    while i < bytes.len() && bytes[i].is_ascii_digit() {
        *mantissa = mantissa
            .wrapping_mul(10)
            .wrapping_add(u64::from(bytes[i] - b'0'));
        i += 1;
    }
    i
}

/// Scan one number at the start of `bytes`.
///
/// Returns the value and the number of bytes consumed, or `None` when `bytes` does not
/// start with a number. The value may be infinite when the number overflows `f64`; the
/// caller decides whether that is an error.
pub fn scan_number(bytes: &[u8]) -> Option<(f64, usize)> {
    let len = bytes.len();
    let mut i = 0;
    let mut negative = false;
    if i < len && (bytes[i] == b'+' || bytes[i] == b'-') {
        negative = bytes[i] == b'-';
        i += 1;
    }
    // Accumulate all digits; with at most 18 of them the u64 cannot overflow.
    let mut mantissa: u64 = 0;
    let int_start = i;
    i = digits(bytes, i, &mut mantissa);
    let mut digits = i - int_start;
    let mut scale: i32 = 0;
    if i < len && bytes[i] == b'.' {
        i += 1;
        let frac_start = i;
        i = self::digits(bytes, i, &mut mantissa);
        let frac = i - frac_start;
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
        return Some((if negative { -v } else { v }, i));
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

    #[test]
    fn digit_runs_of_every_length_and_neighbour() {
        // Runs of 0 to 20 digits followed by every kind of byte, at every offset from the
        // end of the slice (the 8-byte path and the byte loop).
        for n in 0..=20usize {
            for next in [b',', b'.', b'/', b':', b'E', b' ', 0x80, 0xFF, 0x00] {
                let digits: Vec<u8> = (0..n).map(|k| b"9081726354"[k % 10]).collect();
                for tail in 0..10 {
                    let mut s = b"1.".to_vec();
                    s.extend_from_slice(&digits);
                    s.push(next);
                    s.extend(std::iter::repeat_n(b'7', tail));
                    let got = scan_number(&s);
                    let end = 2 + n;
                    let text = std::str::from_utf8(&s[..end]).unwrap();
                    let want: f64 = text.parse().unwrap();
                    let (v, used) = got.unwrap();
                    if next == b'E' && tail > 0 {
                        continue; // "1.xxxE7…": an exponent, checked elsewhere
                    }
                    assert_eq!(
                        (v.to_bits(), used),
                        (want.to_bits(), end),
                        "{text:?}+{next}"
                    );
                }
            }
        }
    }
}
