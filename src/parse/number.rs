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
    while i < len && bytes[i].is_ascii_digit() {
        mantissa = mantissa
            .wrapping_mul(10)
            .wrapping_add(u64::from(bytes[i] - b'0'));
        i += 1;
    }
    let mut digits = i - int_start;
    let mut scale: i32 = 0;
    if i < len && bytes[i] == b'.' {
        i += 1;
        let frac_start = i;
        while i < len && bytes[i].is_ascii_digit() {
            mantissa = mantissa
                .wrapping_mul(10)
                .wrapping_add(u64::from(bytes[i] - b'0'));
            i += 1;
        }
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
}
