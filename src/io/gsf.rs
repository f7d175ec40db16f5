//! Gwyddion Simple Field (`.gsf`, version 1.0).
//!
//! Layout: the text line `Gwyddion Simple Field 1.0`, then `Key = Value` lines (`XRes`,
//! `YRes` required; `XReal`, `YReal` in `XYUnits`, default 1; `XOffset`, `YOffset`,
//! `ZUnits`, `Title`, …), then 1 to 4 NUL bytes so that the header length including them is
//! a multiple of 4, then `XRes·YRes` little-endian float32 values, row by row (row 0 first,
//! y ascending), nothing after. Gwyddion treats samples as pixels: `dx = XReal/XRes`.
//! Units: `m` (the default and what we write), `mm`, `um`/`µm`, `nm`; heights are written in
//! metres. NaN marks a missing node.

use std::io::Write;

use super::FormatError;
use crate::surface::HeightMap;

const MAGIC: &[u8] = b"Gwyddion Simple Field 1.0";

/// Factor from a unit name to µm.
fn unit_to_um(unit: Option<&str>, line: usize) -> Result<f64, FormatError> {
    match unit.map(str::trim) {
        None | Some("") | Some("m") => Ok(1e6),
        Some("mm") => Ok(1e3),
        Some("um") | Some("µm") | Some("μm") => Ok(1.0),
        Some("nm") => Ok(1e-3),
        Some(u) => Err(FormatError::line(
            line,
            0,
            format!("unsupported unit {u:?} (expected m, mm, um or nm)"),
        )),
    }
}

/// The header of a `.gsf`: the grid, the height scale and where the data start.
struct Header {
    nx: usize,
    ny: usize,
    dx_um: f64,
    dy_um: f64,
    x0_mm: f64,
    y0_mm: f64,
    /// Factor from the stored values to µm (applied in `f32`, as stored).
    z_um: f32,
    data_start: usize,
}

/// Parse the header from `bytes`, the file's first bytes (at least through the padding, or
/// the whole file when it is shorter); `len` is the file's whole length (`None`: not known,
/// the size not checked and the lateral scale left at zero, see [`stored_len`]).
fn header(bytes: &[u8], len: Option<usize>) -> Result<Header, FormatError> {
    if !bytes.starts_with(MAGIC) {
        return Err(FormatError::byte(
            0,
            "not a Gwyddion Simple Field file (missing \"Gwyddion Simple Field 1.0\")",
        ));
    }
    let Some(hlen) = bytes.iter().position(|&b| b == 0) else {
        return Err(FormatError::file(
            "header is not terminated by NUL padding (truncated file?)",
        ));
    };
    let header = std::str::from_utf8(&bytes[..hlen])
        .map_err(|e| FormatError::byte(e.valid_up_to() as u64, "header is not UTF-8 text"))?;
    let mut keys: Vec<(&str, &str, usize)> = Vec::new();
    for (idx, line) in header.lines().enumerate().skip(1) {
        let l = line.trim();
        if l.is_empty() {
            continue;
        }
        let Some((k, v)) = l.split_once('=') else {
            return Err(FormatError::line(
                idx + 1,
                0,
                format!("header line {l:?} is not `Key = Value`"),
            ));
        };
        keys.push((k.trim(), v.trim(), idx + 1));
    }
    let get = |name: &str| {
        keys.iter()
            .find(|(k, _, _)| *k == name)
            .map(|(_, v, l)| (*v, *l))
    };
    let int = |name: &str| -> Result<usize, FormatError> {
        let (v, l) = get(name).ok_or_else(|| FormatError::file(format!("header has no {name}")))?;
        v.parse::<usize>().ok().filter(|&n| n > 0).ok_or_else(|| {
            FormatError::line(l, 0, format!("{name} = {v:?} is not a positive integer"))
        })
    };
    let real = |name: &str, default: f64, positive: bool| -> Result<f64, FormatError> {
        match get(name) {
            None => Ok(default),
            Some((v, l)) => v
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && (!positive || *x > 0.0))
                .ok_or_else(|| {
                    FormatError::line(
                        l,
                        0,
                        format!(
                            "{name} = {v:?} is not a {}number",
                            if positive { "positive " } else { "" }
                        ),
                    )
                }),
        }
    };
    let nx = int("XRes")?;
    let ny = int("YRes")?;
    let xreal = real("XReal", 1.0, true)?;
    let yreal = real("YReal", 1.0, true)?;
    let xoff = real("XOffset", 0.0, false)?;
    let yoff = real("YOffset", 0.0, false)?;
    let xy_um = unit_to_um(
        get("XYUnits").map(|p| p.0),
        get("XYUnits").map_or(0, |p| p.1),
    )?;
    let z_um = unit_to_um(get("ZUnits").map(|p| p.0), get("ZUnits").map_or(0, |p| p.1))? as f32;

    let pad = 4 - hlen % 4;
    let data_start = hlen + pad;
    if bytes.len() < data_start {
        return Err(FormatError::byte(
            bytes.len() as u64,
            format!("file ends inside the NUL padding (header {hlen} bytes needs {pad} NULs)"),
        ));
    }
    if let Some(p) = bytes[hlen..data_start].iter().position(|&b| b != 0) {
        return Err(FormatError::byte(
            (hlen + p) as u64,
            format!(
                "header padding must be {pad} NUL bytes (header length {hlen} + padding = multiple of 4)"
            ),
        ));
    }
    let n = nx
        .checked_mul(ny)
        .filter(|n| *n <= (usize::MAX >> 3))
        .ok_or_else(|| FormatError::file(format!("XRes×YRes = {nx}×{ny} is too large")))?;
    let need = n * 4;
    let Some(len) = len else {
        return Ok(Header {
            nx,
            ny,
            dx_um: 0.0,
            dy_um: 0.0,
            x0_mm: 0.0,
            y0_mm: 0.0,
            z_um,
            data_start,
        });
    };
    let have = len - data_start;
    if have != need {
        return Err(FormatError::byte(
            (data_start + have.min(need)) as u64,
            format!(
                "data has {have} bytes, XRes×YRes = {nx}×{ny} float32 needs {need} (data start at byte {data_start})"
            ),
        ));
    }
    Ok(Header {
        nx,
        ny,
        dx_um: super::tidy(xreal * xy_um / nx as f64),
        dy_um: super::tidy(yreal * xy_um / ny as f64),
        x0_mm: super::tidy(xoff * xy_um / 1000.0),
        y0_mm: super::tidy(yoff * xy_um / 1000.0),
        z_um,
        data_start,
    })
}

/// The length of the whole file whose header is in `head` (its first bytes): the header
/// and `XRes·YRes` float32 values; `None` when `head` holds no valid header.
pub(crate) fn stored_len(head: &[u8]) -> Option<u64> {
    let h = header(head, None).ok()?;
    Some(h.data_start as u64 + (h.nx as u64).saturating_mul(h.ny as u64).saturating_mul(4))
}

pub(crate) fn parse(bytes: &[u8]) -> Result<HeightMap, FormatError> {
    let h = header(bytes, Some(bytes.len()))?;
    let z: Vec<f64> = bytes[h.data_start..]
        .chunks_exact(4)
        .map(|c| f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]]) * h.z_um))
        .collect();
    let mut map = HeightMap::from_rows(h.nx, h.ny, h.dx_um, h.dy_um, z)
        .ok_or_else(|| FormatError::file("internal: size mismatch"))?;
    map.x0_mm = h.x0_mm;
    map.y0_mm = h.y0_mm;
    Ok(map)
}

/// Why opening a `.gsf` ([`GsfRows::open`]) failed.
pub(crate) enum ReadError {
    Io(std::io::Error),
    Format(FormatError),
}

impl From<std::io::Error> for ReadError {
    fn from(e: std::io::Error) -> Self {
        ReadError::Io(e)
    }
}

impl From<FormatError> for ReadError {
    fn from(e: FormatError) -> Self {
        ReadError::Format(e)
    }
}

/// A `.gsf` opened for reading its rows in pieces ([`GsfRows::for_each_piece_of`]): the header
/// read, the heights not yet.
#[derive(Debug)]
pub struct GsfRows {
    /// Columns (x).
    pub nx: usize,
    /// Rows (y).
    pub ny: usize,
    /// Spacing along x, µm.
    pub dx_um: f64,
    /// Spacing along y, µm.
    pub dy_um: f64,
    /// x of column 0, mm.
    pub x0_mm: f64,
    /// y of row 0, mm.
    pub y0_mm: f64,
    file: std::fs::File,
    path: std::path::PathBuf,
    z_um: f32,
    data_start: u64,
}

/// Read exactly `buf.len()` bytes at offset `off` without moving a shared cursor, so that
/// threads read their ranges of one open file side by side (`pread` on Unix, `seek_read`
/// on Windows).
fn read_exact_at(file: &std::fs::File, buf: &mut [u8], off: u64) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileExt;
        file.read_exact_at(buf, off)
    }
    #[cfg(windows)]
    {
        use std::os::windows::fs::FileExt;
        let (mut buf, mut off) = (buf, off);
        while !buf.is_empty() {
            match file.seek_read(buf, off) {
                Ok(0) => return Err(std::io::ErrorKind::UnexpectedEof.into()),
                Ok(n) => {
                    buf = &mut buf[n..];
                    off += n as u64;
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }
}

/// Read the header of the `.gsf` in `file` (growing prefixes until the NUL padding is in).
fn read_header(file: &std::fs::File) -> Result<Header, ReadError> {
    let len = file.metadata()?.len();
    let len = usize::try_from(len)
        .map_err(|_| FormatError::file("the file is too large for this machine"))?;
    let mut head = vec![0u8; len.min(4096)];
    read_exact_at(file, &mut head, 0)?;
    while head.len() < len {
        match head.iter().position(|&b| b == 0) {
            Some(h) if head.len() >= h + 4 => break,
            _ => {
                let old = head.len();
                head.resize(len.min(old * 2), 0);
                read_exact_at(file, &mut head[old..], old as u64)?;
            }
        }
    }
    Ok(header(&head, Some(len))?)
}

/// A height beyond the limit: its index in the map and its value (µm).
pub(crate) type Beyond = (usize, f32);

/// Why [`GsfRows::for_each_piece_of`] stopped.
pub(crate) enum PieceError {
    Io(std::io::Error),
    Beyond(Beyond),
}

impl GsfRows {
    pub(crate) fn open(file: std::fs::File, path: &std::path::Path) -> Result<GsfRows, ReadError> {
        let h = read_header(&file)?;
        Ok(GsfRows {
            nx: h.nx,
            ny: h.ny,
            dx_um: h.dx_um,
            dy_um: h.dy_um,
            x0_mm: h.x0_mm,
            y0_mm: h.y0_mm,
            file,
            path: path.to_path_buf(),
            z_um: h.z_um,
            data_start: h.data_start as u64,
        })
    }

    /// Hand the heights of the rows `rows` (the stored float32 values scaled to µm in
    /// float32, which [`parse`] widens to `f64` exactly; rows past the map's end are not
    /// there) to `each` in pieces of `piece` whole rows (the last may be shorter), in order,
    /// read on the caller's thread (`pread` into one reused buffer), so that several threads
    /// may each read their own rows of the file at once. Stops at the first piece holding a
    /// finite height beyond `±limit_um` (before handing it on).
    pub(crate) fn for_each_piece_of(
        &self,
        rows: std::ops::Range<usize>,
        piece: usize,
        limit_um: f64,
        mut each: impl FnMut(&[f32]),
    ) -> Result<(), PieceError> {
        let (nx, piece) = (self.nx, piece.max(1));
        let rows = rows.start..rows.end.min(self.ny);
        let mut buf = Vec::with_capacity(piece.min(rows.len()) * nx);
        for first in rows.clone().step_by(piece) {
            buf.resize(piece.min(rows.end - first) * nx, 0.0);
            self.read_piece(first * nx, &mut buf, limit_um)?;
            each(&buf);
        }
        Ok(())
    }

    /// The file's path.
    pub fn path(&self) -> &std::path::Path {
        &self.path
    }

    /// Read the heights from index `start` on into `buf`, scaled to µm, checked against
    /// `±limit_um`.
    fn read_piece(&self, start: usize, buf: &mut [f32], limit_um: f64) -> Result<(), PieceError> {
        let off = self.data_start + 4 * start as u64;
        read_exact_at(&self.file, bytemuck::cast_slice_mut(buf), off).map_err(PieceError::Io)?;
        let scale = self.z_um;
        // Compared in float32 when the limit is a float32 value (±1e6 µm is): the same
        // answer as in f64, four values per instruction.
        let lim32 = limit_um as f32;
        let mut over = false;
        if f64::from(lim32) == limit_um {
            over = crate::math::wide::run(ScaleCheck {
                buf: &mut *buf,
                scale,
                lim: lim32,
            });
        } else {
            for v in buf.iter_mut() {
                *v = f32::from_bits(u32::from_le(v.to_bits())) * scale;
                over |= f64::from(v.abs()) > limit_um;
            }
        }
        if over {
            let i = buf
                .iter()
                .position(|v| f64::from(v.abs()) > limit_um)
                .unwrap_or(0);
            return Err(PieceError::Beyond((start + i, buf[i])));
        }
        Ok(())
    }
}

/// Scale the stored values (little-endian float32) in place to µm in float32 and say
/// whether one lies beyond `±lim` (an infinite one too: a stored value of 3e38 m is no height): a kernel for [`crate::math::wide::run`] (eight
/// values an instruction with AVX2; the same values on any path).
struct ScaleCheck<'a> {
    buf: &'a mut [f32],
    scale: f32,
    lim: f32,
}

impl crate::math::wide::Kernel for ScaleCheck<'_> {
    type Output = bool;
    #[inline(always)]
    fn call(self) -> bool {
        let ScaleCheck { buf, scale, lim } = self;
        let mut over = false;
        for v in buf.iter_mut() {
            *v = f32::from_bits(u32::from_le(v.to_bits())) * scale;
            over |= v.abs() > lim;
        }
        over
    }
}

pub(crate) fn write(w: &mut dyn Write, map: &HeightMap) -> std::io::Result<()> {
    let mut h = String::new();
    h.push_str("Gwyddion Simple Field 1.0\n");
    h.push_str(&format!("XRes = {}\n", map.nx));
    h.push_str(&format!("YRes = {}\n", map.ny));
    h.push_str(&format!("XReal = {:e}\n", map.nx as f64 * map.dx_um * 1e-6));
    h.push_str(&format!("YReal = {:e}\n", map.ny as f64 * map.dy_um * 1e-6));
    h.push_str(&format!("XOffset = {:e}\n", map.x0_mm * 1e-3));
    h.push_str(&format!("YOffset = {:e}\n", map.y0_mm * 1e-3));
    h.push_str("XYUnits = m\nZUnits = m\nTitle = crest height map\n");
    let pad = 4 - h.len() % 4;
    w.write_all(h.as_bytes())?;
    w.write_all(&[0u8; 4][..pad])?;
    let mut buf = Vec::with_capacity(map.nx * 4);
    for row in 0..map.ny {
        buf.clear();
        for &v in map.row(row) {
            buf.extend_from_slice(&((v * 1e-6) as f32).to_le_bytes());
        }
        w.write_all(&buf)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::Location;

    fn file(header: &str, pad: usize, values: &[f32]) -> Vec<u8> {
        let mut b = header.as_bytes().to_vec();
        b.extend(std::iter::repeat_n(0u8, pad));
        for v in values {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b
    }

    #[test]
    fn padding_is_one_to_four_nuls() {
        let mut out = Vec::new();
        for nx in 1..6 {
            let map = HeightMap::from_rows(nx, 1, 1.0, 1.0, vec![1.0; nx]).unwrap();
            out.clear();
            write(&mut out, &map).unwrap();
            let hlen = out.iter().position(|&b| b == 0).unwrap();
            let start = out.len() - 4 * nx;
            assert_eq!(start % 4, 0);
            assert!((1..=4).contains(&(start - hlen)));
        }
    }

    #[test]
    fn reads_micrometre_units_and_offsets() {
        let h = "Gwyddion Simple Field 1.0\nXRes = 2\nYRes = 1\nXReal = 4\nYReal = 1\nXYUnits = um\nZUnits = um\nXOffset = 1000\n";
        let pad = 4 - h.len() % 4;
        let m = parse(&file(h, pad, &[1.5, f32::NAN])).unwrap();
        assert_eq!((m.nx, m.ny, m.dx_um, m.dy_um), (2, 1, 2.0, 1.0));
        assert_eq!(m.z_um[0], 1.5);
        assert!(m.z_um[1].is_nan());
        assert!((m.x0_mm - 1.0).abs() < 1e-12);
    }

    #[test]
    fn wrong_padding_and_size_give_byte_offsets() {
        let h = "Gwyddion Simple Field 1.0\nXRes = 2\nYRes = 2\n";
        let pad = 4 - h.len() % 4;
        let short = file(h, pad, &[1.0, 2.0, 3.0]);
        let e = parse(&short).unwrap_err();
        assert!(matches!(e.at, Location::Byte(_)), "{e}");
        assert!(e.message.contains("needs 16"), "{e}");
        let mut bad_pad = file(h, pad, &[1.0; 4]);
        bad_pad[h.len() + pad - 1] = b'x';
        if pad > 1 {
            let e = parse(&bad_pad).unwrap_err();
            assert_eq!(e.at, Location::Byte((h.len() + pad - 1) as u64), "{e}");
        }
    }

    #[test]
    fn missing_key_and_bad_value() {
        let h = "Gwyddion Simple Field 1.0\nXRes = 2\n";
        let e = parse(&file(h, 4 - h.len() % 4, &[1.0, 2.0])).unwrap_err();
        assert!(e.message.contains("YRes"), "{e}");
        let h = "Gwyddion Simple Field 1.0\nXRes = 2\nYRes = -1\n";
        let e = parse(&file(h, 4 - h.len() % 4, &[1.0, 2.0])).unwrap_err();
        assert_eq!(e.at, Location::Line { line: 3, field: 0 });
        let e = parse(b"Gwyddion Simple").unwrap_err();
        assert_eq!(e.at, Location::Byte(0));
    }

    #[test]
    fn rows_in_pieces_are_the_float32_values() {
        let (nx, ny) = (301, 40);
        let z: Vec<f64> = (0..nx * ny)
            .map(|k| {
                if k % 97 == 5 {
                    f64::NAN
                } else {
                    (k as f64 * 0.01).cos() * 2.5
                }
            })
            .collect();
        let map = HeightMap::from_rows(nx, ny, 0.5, 0.5, z).unwrap();
        let mut bytes = Vec::new();
        write(&mut bytes, &map).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.gsf");
        std::fs::write(&path, &bytes).unwrap();
        // `parse` widens each stored float32 value to f64 exactly: the oracle.
        let f = parse(&bytes).unwrap();
        let rows = GsfRows::open(std::fs::File::open(&path).unwrap(), &path)
            .ok()
            .unwrap();
        assert_eq!((rows.nx, rows.ny, rows.dx_um), (f.nx, f.ny, f.dx_um));
        for k in [1, 3, 7, ny, ny + 5] {
            let (mut all, mut firsts) = (Vec::new(), Vec::new());
            let r = rows.for_each_piece_of(0..ny, k, 1e6, |piece| {
                assert_eq!(piece.len() % nx, 0);
                firsts.push(all.len() / nx);
                all.extend_from_slice(piece);
            });
            assert!(r.is_ok());
            assert_eq!(firsts, (0..ny).step_by(k).collect::<Vec<_>>());
            assert_eq!(all.len(), f.z_um.len());
            assert!(
                all.iter()
                    .zip(&f.z_um)
                    .all(|(a, b)| f64::from(*a).to_bits() == b.to_bits())
            );
        }
        // Ranges of rows, read on the caller's thread: their values, in pieces of whole rows.
        for (range, k) in [(0..ny, 7), (5..17, 4), (39..40, 3), (30..ny + 3, 64)] {
            let mut got = Vec::new();
            let r = rows.for_each_piece_of(range.clone(), k, 1e6, |piece| {
                assert!(piece.len() % nx == 0 && piece.len() <= k * nx);
                got.extend_from_slice(piece);
            });
            assert!(r.is_ok());
            let want = &f.z_um[range.start * nx..range.end.min(ny) * nx];
            assert_eq!(got.len(), want.len());
            assert!(
                got.iter()
                    .zip(want)
                    .all(|(a, b)| f64::from(*a).to_bits() == b.to_bits())
            );
        }
        // A height beyond the limit stops the reading before its piece is handed on.
        let bad = f.z_um.iter().position(|v| v.abs() > 2.0).unwrap();
        match rows.for_each_piece_of(bad / nx..ny, 2, 2.0, |_| panic!("handed on")) {
            Err(PieceError::Beyond((k, _))) => assert_eq!(k, bad),
            _ => panic!("height beyond the limit accepted"),
        }
        let mut seen = 0;
        match rows.for_each_piece_of(0..ny, 3, 2.0, |piece| seen += piece.len()) {
            Err(PieceError::Beyond((k, v))) => {
                assert_eq!(k, bad);
                assert_eq!(f64::from(v).to_bits(), f.z_um[bad].to_bits());
            }
            _ => panic!("height beyond the limit accepted"),
        }
        assert!(seen <= bad / (3 * nx) * 3 * nx);
    }

    #[test]
    fn rows_of_a_large_map_hold_the_values_parse_widens_and_a_truncated_file_is_refused() {
        let (nx, ny) = (1500, 900); // several 4 MiB pieces
        let z: Vec<f64> = (0..nx * ny)
            .map(|k| {
                if k % 1001 == 5 {
                    f64::NAN
                } else {
                    (k as f64 * 0.001).sin() * 3.7
                }
            })
            .collect();
        let mut map = HeightMap::from_rows(nx, ny, 0.25, 0.5, z).unwrap();
        map.x0_mm = 1.5;
        let mut bytes = Vec::new();
        write(&mut bytes, &map).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.gsf");
        std::fs::write(&path, &bytes).unwrap();
        let rows = GsfRows::open(std::fs::File::open(&path).unwrap(), &path)
            .ok()
            .unwrap();
        let m = parse(&bytes).unwrap();
        assert_eq!(
            (rows.nx, rows.ny, rows.dx_um, rows.dy_um),
            (m.nx, m.ny, m.dx_um, m.dy_um)
        );
        assert_eq!((rows.x0_mm, rows.y0_mm), (m.x0_mm, m.y0_mm));
        let mut all = Vec::new();
        assert!(
            rows.for_each_piece_of(0..ny, 700, 1e6, |p| all.extend_from_slice(p))
                .is_ok()
        );
        assert_eq!(all.len(), m.z_um.len());
        for (a, b) in all.iter().zip(&m.z_um) {
            assert_eq!(f64::from(*a).to_bits(), b.to_bits());
        }
        let first = m.z_um.iter().position(|v| v.abs() > 3.0).unwrap();
        match rows.for_each_piece_of(0..ny, 700, 3.0, |_| {}) {
            Err(PieceError::Beyond((k, _))) => assert_eq!(k, first),
            _ => panic!("height beyond the limit accepted"),
        }
        // A truncated file is a format error at a byte offset, as with `parse`.
        std::fs::write(&path, &bytes[..bytes.len() - 2]).unwrap();
        match GsfRows::open(std::fs::File::open(&path).unwrap(), &path) {
            Err(ReadError::Format(e)) => assert!(matches!(e.at, Location::Byte(_)), "{e}"),
            _ => panic!("truncated file accepted"),
        }
    }
}
