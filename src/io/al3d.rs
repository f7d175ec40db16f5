//! Alicona `.al3d` files (focus variation, Bruker Alicona): the depth image.
//!
//! The file starts `AliconaImaging\0\r\n`, then tags of 52 bytes (a key of 20 bytes, a
//! value of 30, `\r\n`; both NUL-terminated Latin-1): `Version`, `TagCount`, then that many
//! tags. `Cols`, `Rows`, `PixelSizeXMeter`, `PixelSizeYMeter` and `DepthImageOffset` are
//! needed. The depth image is float32 metres (little-endian) at `DepthImageOffset`, each
//! row padded to a multiple of 8 bytes (the last row's padding may be missing). A depth
//! not below `InvalidPixelValue` (3e15 when the tag is missing or not finite), NaN
//! included, was not measured. When the file holds a repeatability plane
//! (`DepthImageResPtr`, `DepthResFilterVal`, a `TextureImageOffset`), a depth whose
//! repeatability passes the filter is not measured either, as surfalize reads it.

use std::collections::HashMap;

use super::FormatError;
use super::binary::{self, Le};
use crate::surface::HeightMap;

/// The first bytes of an `.al3d`.
pub(crate) const MAGIC: &[u8] = b"AliconaImaging\x00\r\n";
const TAG: usize = 52;
/// Rows are padded to a multiple of this many bytes.
const ALIGN: usize = 8;
/// The invalid depth when the file gives none: 3e15 as float32.
const INVALID: f32 = 3.0e15;

fn row_bytes(nx: usize, item: usize) -> usize {
    (nx * item).div_ceil(ALIGN) * ALIGN
}

struct Tags {
    map: HashMap<String, (String, usize)>,
}

impl Tags {
    fn get(&self, key: &str) -> Option<&str> {
        self.map.get(key).map(|(v, _)| v.as_str())
    }

    fn number(&self, key: &str) -> Result<f64, FormatError> {
        let (v, at) = self
            .map
            .get(key)
            .ok_or_else(|| FormatError::file(format!("the header has no {key} tag")))?;
        v.trim()
            .parse::<f64>()
            .map_err(|_| FormatError::byte(*at as u64, format!("tag {key} is {v:?}, not a number")))
    }

    fn count(&self, key: &str) -> Result<i64, FormatError> {
        let v = self.number(key)?;
        if v.fract() != 0.0 || !(0.0..=1e12).contains(&v) {
            let at = self.map.get(key).map_or(0, |x| x.1);
            return Err(FormatError::byte(
                at as u64,
                format!("tag {key} is {v}, not a whole number"),
            ));
        }
        Ok(v as i64)
    }
}

fn tag(le: &Le, at: usize) -> Result<(String, String), FormatError> {
    let b = le.slice(at, TAG, "a header tag")?;
    if &b[50..52] != b"\r\n" {
        return Err(FormatError::byte(
            (at + 50) as u64,
            "a header tag does not end in CR LF",
        ));
    }
    Ok((
        le.text(at, 20, "a tag key")?,
        le.text(at + 20, 30, "a tag value")?,
    ))
}

pub(crate) fn parse(bytes: &[u8]) -> Result<HeightMap, FormatError> {
    if !bytes.starts_with(MAGIC) {
        return Err(FormatError::byte(
            0,
            "not an .al3d (no AliconaImaging magic)",
        ));
    }
    let le = Le::new(bytes);
    let mut at = MAGIC.len();
    let mut tags = Tags {
        map: HashMap::new(),
    };
    for expected in ["Version", "TagCount"] {
        let (k, v) = tag(&le, at)?;
        if k != expected {
            return Err(FormatError::byte(
                at as u64,
                format!("the tag here is {k:?}, not {expected}"),
            ));
        }
        tags.map.insert(k, (v, at + 20));
        at += TAG;
    }
    let count = tags.count("TagCount")? as usize;
    if count.saturating_mul(TAG) > bytes.len() {
        return Err(FormatError::byte(
            (MAGIC.len() + TAG + 20) as u64,
            format!("TagCount is {count}: more tags than the file holds"),
        ));
    }
    for _ in 0..count {
        let (k, v) = tag(&le, at)?;
        tags.map.insert(k, (v, at + 20));
        at += TAG;
    }
    let nx = tags.count("Cols")?;
    let ny = tags.count("Rows")?;
    let offset = tags.count("DepthImageOffset")? as usize;
    let available = bytes.len().saturating_sub(offset);
    let n = binary::nodes(nx, ny, 4, available, "Cols × Rows")?;
    let (nx, ny) = (nx as usize, ny as usize);
    let stride = row_bytes(nx, 4);
    // Every row but the last with its padding, the last without.
    let need = stride * (ny - 1) + nx * 4;
    le.slice(
        offset,
        need,
        "the depth image (DepthImageOffset, Cols, Rows)",
    )?;
    let invalid = match tags.get("InvalidPixelValue") {
        Some(v) => match v.trim().parse::<f64>() {
            Ok(x) if x.is_finite() => x,
            Ok(_) => f64::from(INVALID),
            Err(_) => tags.number("InvalidPixelValue")?,
        },
        None => f64::from(INVALID),
    };
    let unrepeatable = repeatability(&le, &tags, nx, ny)?;
    let mut z = Vec::with_capacity(n);
    for i in 0..ny {
        let row = &bytes[offset + i * stride..offset + i * stride + nx * 4];
        for (j, b) in row.chunks_exact(4).enumerate() {
            let v = f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
            let masked = unrepeatable.as_ref().is_some_and(|m| m[i * nx + j]);
            z.push(if v < invalid && !masked {
                v * 1e6
            } else {
                f64::NAN
            });
        }
    }
    let dx = binary::spacing(tags.number("PixelSizeXMeter")? * 1e6, "PixelSizeXMeter")?;
    let dy = binary::spacing(tags.number("PixelSizeYMeter")? * 1e6, "PixelSizeYMeter")?;
    binary::finish(nx, ny, (dx, dy), (0.0, 0.0), z)
}

/// The depths whose repeatability passes `DepthResFilterVal`, when the file has the plane.
fn repeatability(
    le: &Le,
    tags: &Tags,
    nx: usize,
    ny: usize,
) -> Result<Option<Vec<bool>>, FormatError> {
    let (Some(plane), Some(_)) = (tags.get("DepthImageResPtr"), tags.get("DepthResFilterVal"))
    else {
        return Ok(None);
    };
    if plane.trim().is_empty() || plane.trim() == "0" {
        return Ok(None);
    }
    let texture = match tags.get("TextureImageOffset") {
        Some(_) => tags.count("TextureImageOffset")? as usize,
        None => 0,
    };
    if texture == 0 {
        return Ok(None);
    }
    let plane = tags.count("DepthImageResPtr")? as usize;
    let filter = tags.number("DepthResFilterVal")?;
    let shift = match tags.get("DepthResShiftVal") {
        Some(_) => tags.number("DepthResShiftVal")?,
        None => 0.0,
    };
    let min = match tags.get("DepthResMinVal") {
        Some(_) => tags.number("DepthResMinVal")?,
        None => 0.0,
    };
    let stride = row_bytes(nx, 1);
    let start = plane
        .checked_mul(stride * ny)
        .and_then(|p| p.checked_add(texture))
        .ok_or_else(|| FormatError::file("DepthImageResPtr places the plane past any file"))?;
    le.slice(
        start,
        stride * (ny - 1) + nx,
        "the repeatability plane (TextureImageOffset, DepthImageResPtr)",
    )?;
    let mut mask = Vec::with_capacity(nx * ny);
    for i in 0..ny {
        for j in 0..nx {
            let code = f64::from(le.bytes[start + i * stride + j]);
            mask.push(code * shift + min > filter);
        }
    }
    Ok(Some(mask))
}
