//! Little-endian fields of the instruments' binary height-map files, read at byte offsets
//! with the field named in every error, their length units, and the checks every reader
//! makes before it allocates a grid (nodes within the limit and within the data the file
//! holds) and after (spacing positive, not every height missing).

use super::FormatError;
use crate::math::limits::MAX_NODES;
use crate::surface::HeightMap;

/// A file's bytes, read field by field at offsets; every read is checked against the end.
#[derive(Clone, Copy)]
pub(crate) struct Le<'a> {
    pub(crate) bytes: &'a [u8],
}

impl<'a> Le<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Le<'a> {
        Le { bytes }
    }

    /// `len` bytes at `at`, or the error that the file ends inside `field`.
    pub(crate) fn slice(
        &self,
        at: usize,
        len: usize,
        field: &str,
    ) -> Result<&'a [u8], FormatError> {
        at.checked_add(len)
            .and_then(|end| self.bytes.get(at..end))
            .ok_or_else(|| {
                FormatError::byte(
                    at as u64,
                    format!(
                        "{field}: the file ends at byte {} inside it ({len} bytes needed)",
                        self.bytes.len()
                    ),
                )
            })
    }

    fn array<const N: usize>(&self, at: usize, field: &str) -> Result<[u8; N], FormatError> {
        let s = self.slice(at, N, field)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    pub(crate) fn u16(&self, at: usize, field: &str) -> Result<u16, FormatError> {
        self.array(at, field).map(u16::from_le_bytes)
    }
    pub(crate) fn i16(&self, at: usize, field: &str) -> Result<i16, FormatError> {
        self.array(at, field).map(i16::from_le_bytes)
    }
    pub(crate) fn u32(&self, at: usize, field: &str) -> Result<u32, FormatError> {
        self.array(at, field).map(u32::from_le_bytes)
    }
    pub(crate) fn i32(&self, at: usize, field: &str) -> Result<i32, FormatError> {
        self.array(at, field).map(i32::from_le_bytes)
    }
    pub(crate) fn i64(&self, at: usize, field: &str) -> Result<i64, FormatError> {
        self.array(at, field).map(i64::from_le_bytes)
    }
    pub(crate) fn f32(&self, at: usize, field: &str) -> Result<f32, FormatError> {
        self.array(at, field).map(f32::from_le_bytes)
    }
    pub(crate) fn f64(&self, at: usize, field: &str) -> Result<f64, FormatError> {
        self.array(at, field).map(f64::from_le_bytes)
    }

    /// A fixed-width text field: up to the first NUL, trailing spaces dropped, Latin-1.
    pub(crate) fn text(&self, at: usize, len: usize, field: &str) -> Result<String, FormatError> {
        let s = self.slice(at, len, field)?;
        let end = s.iter().position(|&b| b == 0).unwrap_or(s.len());
        Ok(latin1(&s[..end]).trim_end().to_string())
    }
}

/// Bytes as ISO 8859-1 text (every byte a character), so that no byte is an error.
pub(crate) fn latin1(b: &[u8]) -> String {
    match std::str::from_utf8(b) {
        Ok(s) => s.to_string(),
        Err(_) => b.iter().map(|&c| char::from(c)).collect(),
    }
}

/// µm per unit of a length unit as instruments spell it (`m`, `mm`, `um`, `µm`, `nm`, …),
/// `None` for anything else.
pub(crate) fn um_per(unit: &str) -> Option<f64> {
    let u = unit.trim();
    // µ as Latin-1 0xB5 read as UTF-8 or Latin-1, the Greek mu, and the ㎛ sign.
    let u = u
        .replace(['\u{b5}', '\u{3bc}'], "u")
        .replace('\u{339b}', "um")
        .to_ascii_lowercase();
    Some(match u.as_str() {
        "m" | "meter" | "metre" => 1e6,
        "dm" => 1e5,
        "cm" => 1e4,
        "mm" | "millimeter" | "millimetre" => 1e3,
        "um" | "micrometer" | "micrometre" | "micron" => 1.0,
        "nm" | "nanometer" | "nanometre" => 1e-3,
        "pm" | "picometer" | "picometre" => 1e-6,
        _ => return None,
    })
}

/// The number of nodes `nx × ny` of a header, refused when a size is not positive, the
/// product passes the node limit, or the `stored` bytes per node would not fit in the
/// `available` bytes of the file (checked before anything is allocated).
pub(crate) fn nodes(
    nx: i64,
    ny: i64,
    bytes_per_node: usize,
    available: usize,
    what: &str,
) -> Result<usize, FormatError> {
    if nx <= 0 || ny <= 0 {
        return Err(FormatError::file(format!(
            "{what}: the size is {nx} × {ny} nodes, not positive"
        )));
    }
    let n = (nx as u128) * (ny as u128);
    if n > MAX_NODES as u128 {
        return Err(FormatError::file(format!(
            "{what}: {nx} × {ny} nodes is more than crest reads ({MAX_NODES})"
        )));
    }
    let n = n as usize;
    if n.saturating_mul(bytes_per_node) > available {
        return Err(FormatError::file(format!(
            "{what}: {nx} × {ny} nodes of {bytes_per_node} bytes need {} bytes, but the file holds {available}: the header and the data disagree (a truncated file?)",
            n * bytes_per_node
        )));
    }
    Ok(n)
}

/// A spacing in µm checked positive and finite, naming the field.
pub(crate) fn spacing(v: f64, field: &str) -> Result<f64, FormatError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(FormatError::file(format!(
            "{field} gives a spacing of {} µm: it must be positive",
            crate::math::limits::shown(v)
        )))
    }
}

/// The map, refused when every height is missing.
pub(crate) fn finish(
    nx: usize,
    ny: usize,
    (dx_um, dy_um): (f64, f64),
    (x0_mm, y0_mm): (f64, f64),
    z_um: Vec<f64>,
) -> Result<HeightMap, FormatError> {
    if !z_um.iter().any(|v| v.is_finite()) {
        return Err(FormatError::file(
            "every height of the map is missing (not measured): there is no surface to read",
        ));
    }
    Ok(HeightMap {
        nx,
        ny,
        dx_um,
        dy_um,
        x0_mm: if x0_mm.is_finite() { x0_mm } else { 0.0 },
        y0_mm: if y0_mm.is_finite() { y0_mm } else { 0.0 },
        z_um,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_past_the_end_are_errors_naming_them() {
        let le = Le::new(&[1, 0, 0]);
        assert_eq!(le.u16(0, "a").unwrap(), 1);
        let e = le.u32(1, "n_lines").unwrap_err();
        assert!(e.message.contains("n_lines"), "{e}");
        assert_eq!(e.at, super::super::Location::Byte(1));
        assert!(le.slice(usize::MAX, 2, "x").is_err());
    }

    #[test]
    fn units() {
        assert_eq!(um_per("µm"), Some(1.0));
        assert_eq!(um_per("\u{3bc}m"), Some(1.0));
        assert_eq!(um_per("nm"), Some(1e-3));
        assert_eq!(um_per("m"), Some(1e6));
        assert_eq!(um_per("mm"), Some(1e3));
        assert_eq!(um_per("V"), None);
    }

    #[test]
    fn sizes_are_checked_before_allocating() {
        assert!(nodes(1 << 30, 1 << 30, 4, 100, "h").is_err());
        assert!(nodes(10, 10, 4, 399, "h").is_err());
        assert_eq!(nodes(10, 10, 4, 400, "h").unwrap(), 100);
        assert!(nodes(0, 10, 4, 400, "h").is_err());
    }
}
