//! Sensofar `.plu` files (confocal and interferometric profilers, SensoSCAN): the height
//! layer.
//!
//! The file has no magic: a 128-byte date text, a 256-byte comment and 4 bytes, then the
//! calibration (uint32 `yres`, `xres`, `N_tall`, float32 `dy_multip`, `mppx`, `mppy`, `x_0`,
//! `y_0`, `mpp_tall`, `z0`; all little-endian) and 72 bytes of measure configuration; the
//! heights follow at byte 500: `xres × yres` float32 µm, x fastest, row 0 first. The value
//! 1000001 marks a point that was not measured (NaN). Spacing `mppx`/`mppy` µm. This is
//! the layout surfalize and Gwyddion read; it is told by its extension only.

use super::FormatError;
use super::binary::{self, Le};
use crate::surface::HeightMap;

/// Byte offset of the calibration block.
const CALIBRATION: usize = 128 + 256 + 4;
/// Byte offset of the heights.
const DATA: usize = CALIBRATION + 40 + 72;
/// The value of a point not measured.
const NOT_MEASURED: f32 = 1_000_001.0;

pub(crate) fn parse(bytes: &[u8]) -> Result<HeightMap, FormatError> {
    let le = Le::new(bytes);
    le.slice(0, DATA, "the 500-byte header")?;
    let ny = le.u32(CALIBRATION, "yres")?;
    let nx = le.u32(CALIBRATION + 4, "xres")?;
    let n = binary::nodes(
        i64::from(nx),
        i64::from(ny),
        4,
        bytes.len() - DATA,
        "xres × yres",
    )?;
    let z = bytes[DATA..DATA + 4 * n]
        .chunks_exact(4)
        .map(|b| {
            let v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            if v == NOT_MEASURED {
                f64::NAN
            } else {
                f64::from(v)
            }
        })
        .collect();
    let dx = binary::spacing(f64::from(le.f32(CALIBRATION + 16, "mppx")?), "mppx")?;
    let dy = binary::spacing(f64::from(le.f32(CALIBRATION + 20, "mppy")?), "mppy")?;
    binary::finish(nx as usize, ny as usize, (dx, dy), (0.0, 0.0), z)
}
