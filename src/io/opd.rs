//! Bruker / Veeco Vision `.opd` files (white-light interferometers, Wyko, ContourGT): the
//! height array.
//!
//! The file starts with two bytes and a directory of 24-byte block entries: a 16-byte
//! NUL-padded name, an int16 type, an int32 size and a uint16 flag (little-endian). The
//! first entry is `Directory`, whose size / 24 is the number of entries; the blocks' data
//! follow the directory in the entries' order. `RAW_DATA` (type 3, an array) holds uint16
//! `nx`, `ny` and the item size (1: uint8, 2: int16, 4: float32), then the values, `ny`
//! fastest; the map is that array turned a quarter (surfalize's `rot90`): row `i`, column
//! `j` is the value `j × ny + (ny − 1 − i)`. Height = value × `Wavelength` (nm) / `Mult`;
//! int16 32767 and float32 from 1e38 (and NaN) are non-measured points (NaN). Spacing
//! `Pixel_size` (mm) along x, times `Aspect` along y. Numbers are blocks of type 6
//! (int16), 7 (float32), 8 (float64) or 12 (int32).

use super::FormatError;
use super::binary::{self, Le};
use crate::surface::HeightMap;

/// The first bytes of an `.opd`.
pub(crate) const MAGIC: &[u8] = b"\x01\x00Directory";
const ENTRY: usize = 24;

struct Block {
    name: String,
    kind: i16,
    size: usize,
    /// Byte offset of the entry (for messages) and of the data.
    entry: usize,
    data: usize,
}

fn number(le: &Le, b: &Block) -> Result<f64, FormatError> {
    let field = b.name.as_str();
    let v = match (b.kind, b.size) {
        (6, s) if s >= 2 => f64::from(le.i16(b.data, field)?),
        (7, s) if s >= 4 => f64::from(le.f32(b.data, field)?),
        (8, s) if s >= 8 => le.f64(b.data, field)?,
        (12, s) if s >= 4 => f64::from(le.i32(b.data, field)?),
        (k, s) => {
            return Err(FormatError::byte(
                b.entry as u64,
                format!("block {field} has type {k} and {s} bytes: not a number"),
            ));
        }
    };
    if v.is_finite() {
        Ok(v)
    } else {
        Err(FormatError::byte(
            b.data as u64,
            format!("block {field} is {v}, not a finite number"),
        ))
    }
}

pub(crate) fn parse(bytes: &[u8]) -> Result<HeightMap, FormatError> {
    if !bytes.starts_with(MAGIC) {
        return Err(FormatError::byte(
            0,
            "not an .opd (no Directory block first)",
        ));
    }
    let le = Le::new(bytes);
    let dir_size = le.i32(2 + 18, "the Directory block's size")?;
    if dir_size < ENTRY as i32 || dir_size as usize > bytes.len() {
        return Err(FormatError::byte(
            20,
            format!(
                "the Directory block's size is {dir_size}: not 24 bytes per entry within the file's {} bytes",
                bytes.len()
            ),
        ));
    }
    let count = dir_size as usize / ENTRY;
    let mut data = 2 + ENTRY * count;
    let mut blocks = Vec::with_capacity(count);
    for k in 1..count {
        let at = 2 + ENTRY * k;
        let name = le.text(at, 16, "a block name")?;
        let kind = le.i16(at + 16, "a block type")?;
        let size = le.i32(at + 18, "a block size")?;
        if size < 0 {
            return Err(FormatError::byte(
                (at + 18) as u64,
                format!("block {name:?} has a negative size ({size})"),
            ));
        }
        blocks.push(Block {
            name,
            kind,
            size: size as usize,
            entry: at,
            data,
        });
        data = data.saturating_add(size as usize);
    }
    let find = |name: &str| blocks.iter().find(|b| b.name == name);
    let raw =
        find("RAW_DATA").ok_or_else(|| FormatError::file("the directory has no RAW_DATA block"))?;
    if raw.kind != 3 {
        return Err(FormatError::byte(
            raw.entry as u64,
            format!("RAW_DATA has type {}, not an array (3)", raw.kind),
        ));
    }
    le.slice(raw.data, raw.size, "RAW_DATA (its size in the directory)")?;
    if raw.size < 6 {
        return Err(FormatError::byte(
            raw.entry as u64,
            format!("RAW_DATA is {} bytes, too short for its sizes", raw.size),
        ));
    }
    let nx = le.u16(raw.data, "RAW_DATA nx")? as usize;
    let ny = le.u16(raw.data + 2, "RAW_DATA ny")? as usize;
    let item = le.u16(raw.data + 4, "RAW_DATA item size")? as usize;
    if !matches!(item, 1 | 2 | 4) {
        return Err(FormatError::byte(
            (raw.data + 4) as u64,
            format!("RAW_DATA has items of {item} bytes: only 1, 2 or 4 are read"),
        ));
    }
    let n = binary::nodes(nx as i64, ny as i64, item, raw.size - 6, "RAW_DATA nx × ny")?;
    if n * item != raw.size - 6 {
        return Err(FormatError::byte(
            raw.entry as u64,
            format!(
                "RAW_DATA is {} bytes but nx × ny × item size + 6 is {}",
                raw.size,
                n * item + 6
            ),
        ));
    }
    let required = |name: &str| -> Result<f64, FormatError> {
        let b = find(name).ok_or_else(|| {
            FormatError::file(format!(
                "the directory has no {name} block: the scale is unknown"
            ))
        })?;
        number(&le, b)
    };
    let optional =
        |name: &str| -> Result<f64, FormatError> { find(name).map_or(Ok(1.0), |b| number(&le, b)) };
    let wavelength = required("Wavelength")?;
    let mult = optional("Mult")?;
    if mult == 0.0 {
        return Err(FormatError::file(
            "the Mult block is 0: the heights cannot be scaled",
        ));
    }
    let scale = wavelength * 0.001 / mult;
    let values = &bytes[raw.data + 6..raw.data + 6 + n * item];
    let value = |k: usize| -> f64 {
        let b = &values[k * item..k * item + item];
        match item {
            1 => f64::from(b[0]),
            2 => match i16::from_le_bytes([b[0], b[1]]) {
                32767 => f64::NAN,
                v => f64::from(v) * scale,
            },
            _ => {
                let v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                if v.is_nan() || v >= 1e38 {
                    f64::NAN
                } else {
                    f64::from(v) * scale
                }
            }
        }
    };
    // The stored array is nx lines of ny values; the map is it turned a quarter.
    let (cols, rows) = (nx, ny);
    let mut z = Vec::with_capacity(n);
    for i in 0..rows {
        for j in 0..cols {
            let v = value(j * ny + (ny - 1 - i));
            z.push(if item == 1 { v * scale } else { v });
        }
    }
    let dx = binary::spacing(required("Pixel_size")? * 1000.0, "Pixel_size")?;
    let dy = binary::spacing(dx * optional("Aspect")?, "Pixel_size × Aspect")?;
    binary::finish(cols, rows, (dx, dy), (0.0, 0.0), z)
}
