//! Keyence `.vk4` files (VK-X laser confocal microscopes): the height layer.
//!
//! The file starts `VK4_`; after 12 bytes comes a table of uint32 offsets (little-endian):
//! the measurement conditions at byte 12, the height layer at byte 36. In the conditions,
//! `x_length_per_pixel`, `y_length_per_pixel` and `z_length_per_digit` (uint32, pm) are at
//! bytes 168, 172 and 176. The height layer is `width`, `height`, `bit_depth` (16 or 32),
//! `compression` (0) and `data_byte_size` (uint32), two palette values and 768 bytes, then
//! the unsigned heights, x fastest, row 0 first. Height = value × `z_length_per_digit`;
//! the file marks no point as not measured. This is the layout surfalize and Gwyddion
//! read.

use super::FormatError;
use super::binary::{self, Le};
use crate::surface::HeightMap;

/// The first bytes of a `.vk4`.
pub(crate) const MAGIC: &[u8] = b"VK4_";

pub(crate) fn parse(bytes: &[u8]) -> Result<HeightMap, FormatError> {
    if !bytes.starts_with(MAGIC) {
        return Err(FormatError::byte(0, "not a .vk4 (no VK4_ magic)"));
    }
    let le = Le::new(bytes);
    let conds = le.u32(12, "the offset of the measurement conditions")? as usize;
    let layer = le.u32(36, "the offset of the height layer")? as usize;
    let pm = |o: usize, field: &str| -> Result<f64, FormatError> {
        le.u32(conds.saturating_add(o), field).map(f64::from)
    };
    let xp = pm(168, "x_length_per_pixel")?;
    let yp = pm(172, "y_length_per_pixel")?;
    let zp = pm(176, "z_length_per_digit")?;
    let nx = le.u32(layer, "the height layer's width")?;
    let ny = le.u32(layer.saturating_add(4), "the height layer's height")?;
    let bits = le.u32(layer.saturating_add(8), "the height layer's bit_depth")?;
    let compression = le.u32(layer.saturating_add(12), "the height layer's compression")?;
    let size = le.u32(
        layer.saturating_add(16),
        "the height layer's data_byte_size",
    )? as usize;
    let item = match bits {
        16 => 2,
        32 => 4,
        b => {
            return Err(FormatError::byte(
                (layer + 8) as u64,
                format!("the height layer's bit_depth is {b}: only 16 or 32 are read"),
            ));
        }
    };
    if compression != 0 {
        return Err(FormatError::byte(
            (layer + 12) as u64,
            format!(
                "the height layer's compression is {compression}: only uncompressed (0) is read"
            ),
        ));
    }
    let data = layer.saturating_add(796);
    let n = binary::nodes(
        i64::from(nx),
        i64::from(ny),
        item,
        bytes.len().saturating_sub(data),
        "the height layer's width × height",
    )?;
    if size != n * item {
        return Err(FormatError::byte(
            (layer + 16) as u64,
            format!(
                "the height layer's data_byte_size is {size} but width × height × {item} is {}",
                n * item
            ),
        ));
    }
    let scale = 1e-6 * zp;
    let z = bytes[data..data + n * item]
        .chunks_exact(item)
        .map(|b| {
            let v = if item == 2 {
                f64::from(u16::from_le_bytes([b[0], b[1]]))
            } else {
                f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            };
            v * scale
        })
        .collect();
    let dx = binary::spacing(xp * 1e-6, "x_length_per_pixel")?;
    let dy = binary::spacing(yp * 1e-6, "y_length_per_pixel")?;
    binary::finish(nx as usize, ny as usize, (dx, dy), (0.0, 0.0), z)
}
