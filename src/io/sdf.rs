//! ISO 25178-71 / BCR surface data file (`.sdf`).
//!
//! Text form (written and read): the version line (`aBCR-1.0`, `aISO-1.0`, …), the header
//! keys `ManufacID CreateDate ModDate NumPoints NumProfiles Xscale Yscale Zscale Zresolution
//! Compression DataType CheckType` as `Key = value` lines (`;` comment lines skipped, extra
//! keys allowed), a line `*`, then `NumPoints·NumProfiles` whitespace-separated values
//! (profile 0 first = row 0, y ascending; `NumPoints` along x), then `*` and an optional
//! trailer. Height in metres = value·`Zscale`; `Xscale`/`Yscale` are the spacings in metres.
//! We write `aISO-1.0` (the version ISO 25178-71 gives, which surfalize requires) with
//! `DataType = 7` (double) and `Zscale = 1e-6`, so the values are µm, and `NaN`
//! for missing nodes.
//!
//! Binary form (read only): the 81-byte little-endian header (`bBCR`/`bISO` version, 8 bytes;
//! manufacturer 10; dates 12 + 12; NumPoints, NumProfiles u16; Xscale, Yscale, Zscale,
//! Zresolution f64; Compression, DataType, CheckType u8) followed by the raw values; the
//! largest unsigned / smallest signed integer marks a missing node, as Gwyddion reads it,
//! and so does the lowest float (`-f32::MAX`, `-f64::MAX`), the standard's invalid value
//! that surfalize writes.

use std::io::Write;

use super::FormatError;
use crate::surface::HeightMap;

const BIN_HEADER: usize = 81;

pub(crate) fn parse(bytes: &[u8]) -> Result<HeightMap, FormatError> {
    match bytes.first() {
        Some(b'a') => parse_text(super::as_text(bytes)?),
        Some(b'b') => parse_binary(bytes),
        _ => Err(FormatError::byte(
            0,
            "not an SDF file (expected a version like \"aBCR-1.0\" or \"bISO-1.0\")",
        )),
    }
}

struct Header {
    nx: usize,
    ny: usize,
    xscale: f64,
    yscale: f64,
    zscale: f64,
    data_type: u8,
}

fn check_header(h: &Header, compression: i64, check_type: i64) -> Result<(), FormatError> {
    if compression != 0 {
        return Err(FormatError::file(format!(
            "Compression = {compression} is not supported (only 0)"
        )));
    }
    if check_type != 0 {
        return Err(FormatError::file(format!(
            "CheckType = {check_type} is not supported (only 0)"
        )));
    }
    if h.data_type > 7 {
        return Err(FormatError::file(format!(
            "DataType = {} is unknown (0-7)",
            h.data_type
        )));
    }
    Ok(())
}

fn parse_text(text: &str) -> Result<HeightMap, FormatError> {
    let mut lines = text.lines().enumerate();
    let (_, version) = lines
        .next()
        .ok_or_else(|| FormatError::file("empty file"))?;
    if !version.trim().starts_with('a') {
        return Err(FormatError::line(1, 0, "not a text SDF version line"));
    }
    let mut keys: Vec<(String, String, usize)> = Vec::new();
    let mut star = false;
    for (idx, raw) in lines.by_ref() {
        let l = raw.trim();
        if l.is_empty() || l.starts_with(';') {
            continue;
        }
        if l == "*" {
            star = true;
            break;
        }
        let (k, v) = match l.split_once('=') {
            Some((k, v)) => (k.trim(), v.trim()),
            None => match l.split_once(char::is_whitespace) {
                Some((k, v)) => (k.trim(), v.trim()),
                None => {
                    return Err(FormatError::line(
                        idx + 1,
                        0,
                        format!("header line {l:?} is not `Key = value`"),
                    ));
                }
            },
        };
        keys.push((k.to_ascii_lowercase(), v.to_string(), idx + 1));
    }
    if !star {
        return Err(FormatError::file(
            "missing the `*` line that ends the header",
        ));
    }
    let get = |name: &str| {
        keys.iter()
            .find(|(k, _, _)| k == &name.to_ascii_lowercase())
            .map(|(_, v, l)| (v.as_str(), *l))
    };
    let num = |name: &str, positive: bool| -> Result<f64, FormatError> {
        let (v, l) = get(name).ok_or_else(|| FormatError::file(format!("header has no {name}")))?;
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite() && (!positive || *x > 0.0))
            .ok_or_else(|| FormatError::line(l, 0, format!("{name} = {v:?} is not a valid number")))
    };
    let int = |name: &str, default: i64| -> Result<i64, FormatError> {
        match get(name) {
            None => Ok(default),
            Some((v, l)) => v
                .parse::<i64>()
                .map_err(|_| FormatError::line(l, 0, format!("{name} = {v:?} is not an integer"))),
        }
    };
    let nx = int("NumPoints", -1)?;
    let ny = int("NumProfiles", -1)?;
    for (name, v) in [("NumPoints", nx), ("NumProfiles", ny)] {
        if v <= 0 {
            return Err(match get(name) {
                None => FormatError::file(format!("header has no {name}")),
                Some((_, l)) => FormatError::line(l, 0, format!("{name} must be positive")),
            });
        }
    }
    let data_type = int("DataType", 7)?;
    let h = Header {
        nx: nx as usize,
        ny: ny as usize,
        xscale: num("Xscale", true)?,
        yscale: num("Yscale", true)?,
        zscale: num("Zscale", false)?,
        data_type: u8::try_from(data_type).unwrap_or(255),
    };
    check_header(&h, int("Compression", 0)?, int("CheckType", 0)?)?;
    let n =
        h.nx.checked_mul(h.ny)
            .filter(|&n| n < (1 << 32))
            .ok_or_else(|| FormatError::file("NumPoints×NumProfiles is too large"))?;
    let mut z = Vec::with_capacity(n);
    let zf = h.zscale * 1e6;
    let mut last_line = 0;
    'outer: for (idx, raw) in lines.by_ref() {
        last_line = idx + 1;
        for tok in raw.split_whitespace() {
            if tok == "*" {
                break 'outer;
            }
            if z.len() == n {
                return Err(FormatError::line(
                    idx + 1,
                    0,
                    format!("more than NumPoints×NumProfiles = {n} values before the closing `*`"),
                ));
            }
            let v = super::parse_value(tok).ok_or_else(|| {
                FormatError::line(idx + 1, 0, format!("expected a number, found {tok:?}"))
            })?;
            z.push(v * zf);
        }
    }
    if z.len() != n {
        return Err(FormatError::line(
            last_line.max(1),
            0,
            format!(
                "data ends after {} of NumPoints×NumProfiles = {}×{} values",
                z.len(),
                h.nx,
                h.ny
            ),
        ));
    }
    // The trailer after the closing `*`: crest writes the map's origin there
    // (`XOffset`/`YOffset`, metres); other keys are kept by nobody and ignored.
    let mut offset = [0.0f64; 2];
    for (idx, raw) in lines {
        let Some((k, v)) = raw.split_once('=') else {
            continue;
        };
        let slot = match k.trim().to_ascii_lowercase().as_str() {
            "xoffset" => 0,
            "yoffset" => 1,
            _ => continue,
        };
        let v = v.trim();
        offset[slot] = v
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite() && x.abs() < 1e3)
            .ok_or_else(|| {
                FormatError::line(
                    idx + 1,
                    0,
                    format!("{} = {v:?} is not a valid offset in metres", k.trim()),
                )
            })?;
    }
    let mut map = finish(h, z)?;
    map.x0_mm = super::tidy(offset[0] * 1e3);
    map.y0_mm = super::tidy(offset[1] * 1e3);
    Ok(map)
}

fn finish(h: Header, z: Vec<f64>) -> Result<HeightMap, FormatError> {
    HeightMap::from_rows(
        h.nx,
        h.ny,
        super::tidy(h.xscale * 1e6),
        super::tidy(h.yscale * 1e6),
        z,
    )
    .ok_or_else(|| FormatError::file("internal: size mismatch"))
}

fn parse_binary(b: &[u8]) -> Result<HeightMap, FormatError> {
    if b.len() < BIN_HEADER {
        return Err(FormatError::byte(
            b.len() as u64,
            format!(
                "binary SDF header needs {BIN_HEADER} bytes, file has {}",
                b.len()
            ),
        ));
    }
    let u16_at = |o: usize| u16::from_le_bytes([b[o], b[o + 1]]) as usize;
    let f64_at = |o: usize| {
        let mut a = [0u8; 8];
        a.copy_from_slice(&b[o..o + 8]);
        f64::from_le_bytes(a)
    };
    let h = Header {
        nx: u16_at(42),
        ny: u16_at(44),
        xscale: f64_at(46),
        yscale: f64_at(54),
        zscale: f64_at(62),
        data_type: b[79],
    };
    for (off, name, v) in [
        (42, "NumPoints", h.nx as f64),
        (44, "NumProfiles", h.ny as f64),
    ] {
        if v <= 0.0 {
            return Err(FormatError::byte(off, format!("{name} must be positive")));
        }
    }
    for (off, name, v) in [(46, "Xscale", h.xscale), (54, "Yscale", h.yscale)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(FormatError::byte(
                off,
                format!("{name} = {v} is not a positive number"),
            ));
        }
    }
    if !(h.zscale.is_finite() && h.zscale != 0.0) {
        return Err(FormatError::byte(62, "Zscale is zero or not finite"));
    }
    check_header(&h, i64::from(b[78]), i64::from(b[80]))?;
    let size = [1usize, 2, 4, 4, 1, 2, 4, 8][h.data_type as usize];
    let n = h.nx * h.ny;
    let need = n * size;
    let have = b.len() - BIN_HEADER;
    if have < need {
        return Err(FormatError::byte(
            b.len() as u64,
            format!(
                "data has {have} bytes, {}×{} values of DataType {} need {need}",
                h.nx, h.ny, h.data_type
            ),
        ));
    }
    let zf = h.zscale * 1e6;
    let d = &b[BIN_HEADER..BIN_HEADER + need];
    let z: Vec<f64> = d
        .chunks_exact(size)
        .map(|c| {
            let v = match h.data_type {
                0 => f64::from(c[0]),
                1 => match u16::from_le_bytes([c[0], c[1]]) {
                    u16::MAX => f64::NAN,
                    x => f64::from(x),
                },
                2 => match u32::from_le_bytes([c[0], c[1], c[2], c[3]]) {
                    u32::MAX => f64::NAN,
                    x => f64::from(x),
                },
                3 => match f32::from_le_bytes([c[0], c[1], c[2], c[3]]) {
                    f32::MIN => f64::NAN,
                    x => f64::from(x),
                },
                4 => match c[0] as i8 {
                    i8::MIN => f64::NAN,
                    x => f64::from(x),
                },
                5 => match i16::from_le_bytes([c[0], c[1]]) {
                    i16::MIN => f64::NAN,
                    x => f64::from(x),
                },
                6 => match i32::from_le_bytes([c[0], c[1], c[2], c[3]]) {
                    i32::MIN => f64::NAN,
                    x => f64::from(x),
                },
                _ => {
                    let mut a = [0u8; 8];
                    a.copy_from_slice(c);
                    match f64::from_le_bytes(a) {
                        f64::MIN => f64::NAN,
                        x => x,
                    }
                }
            };
            v * zf
        })
        .collect();
    finish(h, z)
}

/// Day, month, year, hour, minute (UTC) of now, for the SDF date fields.
fn now_ddmmyyyyhhmm() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    let [y, m, d, hh, mm, _] = super::civil_utc(secs);
    format!("{d:02}{m:02}{y:04}{hh:02}{mm:02}")
}

pub(crate) fn write(w: &mut dyn Write, map: &HeightMap) -> std::io::Result<()> {
    let date = now_ddmmyyyyhhmm();
    let header = format!(
        "aISO-1.0\nManufacID   = crest\nCreateDate  = {date}\nModDate     = {date}\n\
         NumPoints   = {}\nNumProfiles = {}\nXscale      = {:e}\nYscale      = {:e}\n\
         Zscale      = 1.0e-6\nZresolution = -1\nCompression = 0\nDataType    = 7\n\
         CheckType   = 0\n*\n",
        map.nx,
        map.ny,
        map.dx_um * 1e-6,
        map.dy_um * 1e-6
    );
    w.write_all(header.as_bytes())?;
    let mut line = String::new();
    for row in 0..map.ny {
        line.clear();
        for (k, v) in map.row(row).iter().enumerate() {
            if k > 0 {
                line.push(' ');
            }
            line.push_str(&super::fmt_value(*v));
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;
    }
    w.write_all(b"*\n")?;
    // Trailer: the origin, so that the map reads back where it was.
    w.write_all(
        format!(
            "XOffset = {:e}\nYOffset = {:e}\n",
            map.x0_mm * 1e-3,
            map.y0_mm * 1e-3
        )
        .as_bytes(),
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::Location;

    const HEAD: &str = "aBCR-1.0\nManufacID = x\nCreateDate = 010120250000\nModDate = 010120250000\nNumPoints = 3\nNumProfiles = 2\nXscale = 5e-7\nYscale = 1e-6\nZscale = 1e-9\nZresolution = -1\nCompression = 0\nDataType = 5\nCheckType = 0\n*\n";

    #[test]
    fn reads_integer_text_with_zscale() {
        let m = parse(format!("{HEAD}1 2 3\n4 5 NaN\n*\nTrailer = 1\n").as_bytes()).unwrap();
        assert_eq!((m.nx, m.ny), (3, 2));
        assert!((m.dx_um - 0.5).abs() < 1e-12 && (m.dy_um - 1.0).abs() < 1e-12);
        assert!((m.get(2, 0) - 0.003).abs() < 1e-15);
        assert!(m.get(2, 1).is_nan());
    }

    #[test]
    fn short_and_long_data_name_lines() {
        let e = parse(format!("{HEAD}1 2 3\n4 5\n").as_bytes()).unwrap_err();
        assert!(e.message.contains("after 5 of"), "{e}");
        let e = parse(format!("{HEAD}1 2 3\n4 5 6 7\n*\n").as_bytes()).unwrap_err();
        assert_eq!(e.at, Location::Line { line: 16, field: 0 });
        let e = parse(format!("{HEAD}1 2 3\n4 x 6\n*\n").as_bytes()).unwrap_err();
        assert_eq!(e.at, Location::Line { line: 16, field: 0 });
        assert!(e.message.contains("\"x\""), "{e}");
    }

    #[test]
    fn header_errors() {
        let e = parse(
            HEAD.replace("NumPoints = 3", "NumPoints = three")
                .as_bytes(),
        )
        .unwrap_err();
        assert_eq!(e.at, Location::Line { line: 5, field: 0 });
        let e = parse(
            HEAD.replace("Compression = 0", "Compression = 1")
                .as_bytes(),
        )
        .unwrap_err();
        assert!(e.message.contains("Compression"), "{e}");
        let e = parse(HEAD.replace("*\n", "").as_bytes()).unwrap_err();
        assert!(e.message.contains('*'), "{e}");
    }

    #[test]
    fn reads_binary_int16_with_missing_marker() {
        let mut b = b"bISO-1.0".to_vec();
        b.extend_from_slice(&[b' '; 34]);
        b.extend_from_slice(&2u16.to_le_bytes());
        b.extend_from_slice(&1u16.to_le_bytes());
        for v in [1e-6f64, 1e-6, 1e-6, 0.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&[0, 5, 0]);
        assert_eq!(b.len(), BIN_HEADER);
        b.extend_from_slice(&7i16.to_le_bytes());
        b.extend_from_slice(&i16::MIN.to_le_bytes());
        let m = parse(&b).unwrap();
        assert_eq!((m.nx, m.ny), (2, 1));
        assert!((m.z_um[0] - 7.0).abs() < 1e-12);
        assert!(m.z_um[1].is_nan());
        let e = parse(&b[..BIN_HEADER + 3]).unwrap_err();
        assert!(matches!(e.at, Location::Byte(_)), "{e}");
    }
}
