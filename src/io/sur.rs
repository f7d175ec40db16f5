//! Digital Surf `.sur` files (MountainsMap, and the instruments that write it): the height
//! layer of a surface, uncompressed (`DIGITAL SURF`) or zlib-compressed (`DSCOMPRESSED`).
//!
//! A file is one or more objects, each a 512-byte header (little-endian), a comment and a
//! private zone of the lengths the header gives, then its points: `n_total_points` 16- or
//! 32-bit integers, row after row (x fastest), or, compressed, a count of streams, each
//! stream's raw and zipped lengths, and the zlib streams, which together hold the points.
//! Height = (point × `spacing_z` + `offset_z`) in the unit `unit_step_z`; spacing
//! `spacing_x`/`spacing_y` and origin `offset_x`/`offset_y` in `unit_step_x`/`unit_step_y`.
//! With `non_measured_points` = 1 a point equal to `min_point − 2` was not measured (NaN).
//! Of several objects (a multilayer surface, a surface with its colour or intensity
//! layers), the first surface whose z unit is a length is the height layer. Row 0 is the
//! file's first line, as surfalize and Gwyddion read it.

use std::io::Read;

use super::FormatError;
use super::binary::{self, Le};
use crate::surface::HeightMap;

/// The header of each object, bytes.
const HEADER: usize = 512;

/// Whether the first bytes are a `.sur` object header.
pub(crate) fn is_sur(head: &[u8]) -> bool {
    head.starts_with(b"DIGITAL SURF") || head.starts_with(b"DSCOMPRESSED")
}

/// One object's header fields that the reader uses.
struct Object {
    /// Byte offset of the header.
    at: usize,
    compressed: bool,
    studiable: i16,
    n_objects: i16,
    non_measured: i16,
    bits: i16,
    min_point: i32,
    nx: i32,
    ny: i32,
    total: i32,
    step: [f32; 3],
    unit_step: [String; 3],
    compressed_size: u32,
    offset: [f32; 3],
    /// Byte offset of the points (after the comment and private zones).
    data: usize,
}

fn header(le: &Le, at: usize) -> Result<Object, FormatError> {
    let code = le.slice(at, 12, "code")?;
    let compressed = match code {
        b"DIGITAL SURF" => false,
        b"DSCOMPRESSED" => true,
        _ => {
            return Err(FormatError::byte(
                at as u64,
                format!(
                    "code: {:?} is not DIGITAL SURF or DSCOMPRESSED (not an object of a .sur file)",
                    binary::latin1(code)
                ),
            ));
        }
    };
    le.slice(at, HEADER, "the 512-byte object header")?;
    let f = |o: usize| at + o;
    let format = le.i16(f(12), "format")?;
    if format != 0 {
        return Err(FormatError::byte(
            f(12) as u64,
            format!("format is {format}: only the PC (little-endian, 0) layout is read"),
        ));
    }
    let text = |o: usize, name: &str| le.text(f(o), 16, name);
    let comment = le.i16(f(334), "length_comment")?;
    let private = le.i16(f(336), "length_private")?;
    if comment < 0 || private < 0 {
        return Err(FormatError::byte(
            f(334) as u64,
            format!("length_comment {comment} or length_private {private} is negative"),
        ));
    }
    let data = f(HEADER) + comment as usize + private as usize;
    Ok(Object {
        at,
        compressed,
        n_objects: le.i16(f(14), "n_objects")?,
        studiable: le.i16(f(18), "studiable_type")?,
        non_measured: le.i16(f(86), "non_measured_points")?,
        bits: le.i16(f(98), "bits_per_point")?,
        min_point: le.i32(f(100), "min_point")?,
        nx: le.i32(f(108), "n_points_per_line")?,
        ny: le.i32(f(112), "n_lines")?,
        total: le.i32(f(116), "n_total_points")?,
        step: [
            le.f32(f(120), "spacing_x")?,
            le.f32(f(124), "spacing_y")?,
            le.f32(f(128), "spacing_z")?,
        ],
        unit_step: [
            text(180, "unit_step_x")?,
            text(196, "unit_step_y")?,
            text(212, "unit_step_z")?,
        ],
        compressed_size: le.u32(f(324), "compressed_data_size")?,
        offset: [
            le.f32(f(466), "offset_x")?,
            le.f32(f(470), "offset_y")?,
            le.f32(f(474), "offset_z")?,
        ],
        data,
    })
}

impl Object {
    fn bytes_per_point(&self) -> Result<usize, FormatError> {
        match self.bits {
            16 => Ok(2),
            32 => Ok(4),
            b => Err(FormatError::byte(
                (self.at + 98) as u64,
                format!("bits_per_point is {b}: only 16- and 32-bit integer points are read"),
            )),
        }
    }

    /// The byte offset just past this object.
    fn end(&self, len: usize) -> Result<usize, FormatError> {
        let end = if self.compressed {
            self.data.checked_add(self.compressed_size as usize)
        } else {
            let n = (self.total.max(0) as usize).checked_mul(self.bytes_per_point()?);
            n.and_then(|n| self.data.checked_add(n))
        };
        end.filter(|&e| e <= len).ok_or_else(|| {
            FormatError::byte(
                self.data as u64,
                format!(
                    "{}: the object's points go past the end of the file ({len} bytes)",
                    if self.compressed {
                        "compressed_data_size"
                    } else {
                        "n_total_points"
                    }
                ),
            )
        })
    }

    /// Whether this object holds heights: a surface (or a layer of one) with a length
    /// unit along z. Gwyddion writes its surfaces as "profiles" of several lines.
    fn is_height(&self) -> bool {
        let surface =
            matches!(self.studiable, 2 | 8 | 11 | 13 | 16) || (self.studiable == 1 && self.ny > 1);
        surface && binary::um_per(&self.unit_step[2]).is_some()
    }
}

pub(crate) fn parse(bytes: &[u8]) -> Result<HeightMap, FormatError> {
    let le = Le::new(bytes);
    let first = header(&le, 0)?;
    let count = first.n_objects.max(1) as usize;
    let mut obj = first;
    for k in 0..count {
        if obj.is_height() {
            return heights(&le, &obj);
        }
        if k + 1 == count {
            break;
        }
        let next = obj.end(bytes.len())?;
        obj = header(&le, next)?;
    }
    Err(FormatError::file(format!(
        "none of the file's {count} object(s) is a surface with heights in a length unit (the first is studiable_type {}, z unit {:?})",
        header(&le, 0)?.studiable,
        header(&le, 0)?.unit_step[2]
    )))
}

fn heights(le: &Le, o: &Object) -> Result<HeightMap, FormatError> {
    let bpp = o.bytes_per_point()?;
    let end = o.end(le.bytes.len())?;
    let available = if o.compressed {
        // zlib expands at most about 1032 to 1: more nodes than that cannot be in the data.
        (end - o.data).saturating_mul(1032)
    } else {
        end - o.data
    };
    let n = binary::nodes(
        i64::from(o.nx),
        i64::from(o.ny),
        bpp,
        available,
        "n_points_per_line × n_lines",
    )?;
    if !o.compressed && o.total as usize != n {
        return Err(FormatError::byte(
            (o.at + 116) as u64,
            format!(
                "n_total_points is {} but n_points_per_line × n_lines is {n}",
                o.total
            ),
        ));
    }
    let raw: std::borrow::Cow<[u8]> = if o.compressed {
        std::borrow::Cow::Owned(inflate(le, o, n * bpp)?)
    } else {
        std::borrow::Cow::Borrowed(le.slice(o.data, n * bpp, "the points")?)
    };
    let unit = |k: usize, field: &str| {
        binary::um_per(&o.unit_step[k]).ok_or_else(|| {
            FormatError::byte(
                (o.at + 180 + 16 * k) as u64,
                format!("{field} is {:?}, not a length unit", o.unit_step[k]),
            )
        })
    };
    let (ux, uy, uz) = (
        unit(0, "unit_step_x")?,
        unit(1, "unit_step_y")?,
        unit(2, "unit_step_z")?,
    );
    let dz = f64::from(o.step[2]);
    let z0 = f64::from(o.offset[2]);
    if !dz.is_finite() || !z0.is_finite() {
        return Err(FormatError::byte(
            (o.at + 128) as u64,
            "spacing_z or offset_z is not a finite number",
        ));
    }
    let invalid = i64::from(o.min_point) - 2;
    let z: Vec<f64> = raw
        .chunks_exact(bpp)
        .map(|b| {
            let v = if bpp == 2 {
                i64::from(i16::from_le_bytes([b[0], b[1]]))
            } else {
                i64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            };
            if o.non_measured == 1 && v == invalid {
                f64::NAN
            } else {
                (v as f64 * dz + z0) * uz
            }
        })
        .collect();
    let dx = binary::spacing(f64::from(o.step[0]) * ux, "spacing_x")?;
    let dy = binary::spacing(f64::from(o.step[1]) * uy, "spacing_y")?;
    let x0 = f64::from(o.offset[0]) * ux * 1e-3;
    let y0 = f64::from(o.offset[1]) * uy * 1e-3;
    binary::finish(o.nx as usize, o.ny as usize, (dx, dy), (x0, y0), z)
}

/// The points of a compressed object: `expected` bytes from its zlib streams.
fn inflate(le: &Le, o: &Object, expected: usize) -> Result<Vec<u8>, FormatError> {
    let count = le.u32(o.data, "the compressed stream count")? as usize;
    let size = o.compressed_size as usize;
    if count == 0 || count.saturating_mul(8).saturating_add(4) > size {
        return Err(FormatError::byte(
            o.data as u64,
            format!(
                "the compressed stream count is {count}, which compressed_data_size ({size}) cannot hold"
            ),
        ));
    }
    let mut dirs = Vec::with_capacity(count);
    let mut total_zipped = 4 + 8 * count;
    let mut total_raw = 0usize;
    for k in 0..count {
        let at = o.data + 4 + 8 * k;
        let raw = le.u32(at, "a stream's raw length")? as usize;
        let zipped = le.u32(at + 4, "a stream's zipped length")? as usize;
        total_zipped = total_zipped.saturating_add(zipped);
        total_raw = total_raw.saturating_add(raw);
        dirs.push((raw, zipped));
    }
    if total_zipped != size {
        return Err(FormatError::byte(
            (o.at + 324) as u64,
            format!("compressed_data_size is {size} but the streams take {total_zipped} bytes"),
        ));
    }
    if total_raw != expected {
        return Err(FormatError::byte(
            (o.data + 4) as u64,
            format!(
                "the streams hold {total_raw} bytes but n_points_per_line × n_lines points take {expected}"
            ),
        ));
    }
    let mut out = Vec::new();
    let mut at = o.data + 4 + 8 * count;
    for (k, (raw, zipped)) in dirs.into_iter().enumerate() {
        let stream = le.slice(at, zipped, "a zlib stream")?;
        let before = out.len();
        flate2::read::ZlibDecoder::new(stream)
            .take(raw as u64 + 1)
            .read_to_end(&mut out)
            .map_err(|e| {
                FormatError::byte(at as u64, format!("zlib stream {k} is corrupt: {e}"))
            })?;
        if out.len() - before != raw {
            return Err(FormatError::byte(
                at as u64,
                format!(
                    "zlib stream {k} decompresses to {} bytes, not the {raw} its directory gives",
                    out.len() - before
                ),
            ));
        }
        at += zipped;
    }
    Ok(out)
}
