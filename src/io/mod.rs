//! File formats and safe writing: height-map readers and writers (CSV grid, x,y,z point
//! lists, Gwyddion `.gsf`, ISO 25178-71 / BCR `.sdf`, ISO 25178-72 `.x3p`), readers of the
//! instruments' own files (`.sur`, `.al3d`, `.gwy`, `.plu`, `.plux`, `.opd`, `.vk4`), and
//! [`write_atomic`], which never leaves a partial file.
//!
//! Every format maps onto [`HeightMap`]: row `i` is `y = y0 + i·dy` (ascending), column `j`
//! is `x = x0 + j·dx`, heights in µm, `NaN` for a node that was not measured or not reached.
//! Readers never panic: a malformed file gives a [`HeightMapError::Format`] naming the file,
//! the line (text formats) or byte offset (binary parts) and what was wrong.
//!
//! | extension | format | lateral | heights | missing nodes |
//! |---|---|---|---|---|
//! | `.csv` (grid) | one line per row, one column per x | `--dx-um`/`--dy-um` | µm | `NaN`, `nan`, `NA` or empty field |
//! | `.csv` with an `x,y,z` header, `.xyz` | one point per line, any order | from the coordinates, µm | µm | absent line or `NaN` |
//! | `.gsf` | Gwyddion Simple Field 1.0, float32 LE | `XReal`/`YReal` (pixels), metres | metres (`ZUnits`) | NaN |
//! | `.sdf` | ISO 25178-71 / BCR, text (`aBCR`/`aISO`) and binary reading; text writing | `Xscale`/`Yscale`, metres | value·`Zscale`, metres | `NaN` (text) |
//! | `.x3p` | ISO 25178-72 (OpenGPS) zip: `main.xml` + binary or listed heights, I/L/F/D read, D written, checksums verified | `CX`/`CY` `Increment`, `Offset`, metres | value·`CZ/Increment` + `Offset`, metres | validity mask, NaN or infinite |
//! | `.sur` | Digital Surf (MountainsMap), read: plain or zlib-compressed, 16/32-bit integer points, the first height layer of a multilayer file | `spacing_x`/`spacing_y`, `offset_x`/`offset_y` in `unit_step_x`/`_y` | (value·`spacing_z` + `offset_z`) in `unit_step_z` (m, mm, µm, nm) | `min_point − 2` when `non_measured_points` = 1 |
//! | `.al3d` | Alicona (focus variation), read: the float32 depth image | `PixelSizeXMeter`/`YMeter`, metres | metres | ≥ `InvalidPixelValue`, NaN, unrepeatable depths |
//! | `.gwy` | Gwyddion native (`GWYP`), read: the first channel with a length z unit, or `--channel TITLE` | `xreal/xres`, `xoff`, in `si_unit_xy` | `si_unit_z` | `/N/mask` non-zero |
//! | `.plu` | Sensofar binary, read: float32 heights at byte 500 (told by its extension only) | `mppx`/`mppy`, µm | µm | 1000001 |
//! | `.plux` | Sensofar zip, read: `index.xml` + `LAYER_0.raw` float32 | `FOV_X`/`FOV_Y`, µm | µm | NaN, 1000001 |
//! | `.opd` | Bruker/Veeco Vision, read: `RAW_DATA` (uint8, int16, float32) | `Pixel_size` mm, × `Aspect` along y | value·`Wavelength` nm / `Mult` | int16 32767, float32 ≥ 1e38 |
//! | `.vk4` | Keyence VK-X, read: the 16/32-bit height layer | `x_/y_length_per_pixel`, pm | value·`z_length_per_digit`, pm | none |
//! | `.datx` | Zygo (HDF5): **refused**, crest has no HDF5 reader; export `.x3p` or `.sdf` from Mx | | | |
//!
//! A format is told by its extension, and by its content where it has a magic (`.plu` has
//! none; a zip archive is a `.plux` when it names `index.xml` or `LAYER_0` and an `.x3p`
//! otherwise): a path without an extension is read as its content says, and so is a binary
//! map whose content carries another format's magic than its extension names (as surfalize
//! does); a path with an extension no format has is refused.

mod al3d;
mod binary;
mod csv_grid;
mod gsf;
mod gwy;
mod opd;
mod plu;
mod plux;
mod sdf;
mod sur;
mod vk4;
mod x3p;
mod xyz;

pub mod atlas;
pub mod input;
pub mod measured;
pub mod mesh;
pub mod output;
pub mod profile_csv;
pub mod samples;
pub mod series;
pub mod table_error;
pub mod tables;
pub mod text;
pub mod toolpath;

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::surface::HeightMap;

pub use gsf::GsfRows;
pub use output::write_atomic;

/// Write a set of files into the folder `dir`, whole or not at all (see [`output::write_set`]).
pub fn write_files(dir: &Path, files: &[(String, Vec<u8>)]) -> std::io::Result<Vec<PathBuf>> {
    output::write_set(dir, files)
}

/// A height-map file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HeightMapFormat {
    /// Grid CSV: one line per row (y ascending), one column per x, µm.
    Csv,
    /// `x,y,z` point list on a regular grid, all µm.
    Xyz,
    /// Gwyddion Simple Field (`.gsf`).
    Gsf,
    /// ISO 25178-71 / BCR surface data file (`.sdf`).
    Sdf,
    /// ISO 25178-72 XML surface file (`.x3p`, OpenGPS).
    X3p,
    /// Digital Surf (MountainsMap) `.sur`, read only.
    Sur,
    /// Alicona `.al3d`, read only.
    Al3d,
    /// Gwyddion native `.gwy`, read only.
    Gwy,
    /// Sensofar binary `.plu`, read only.
    Plu,
    /// Sensofar zip `.plux`, read only.
    Plux,
    /// Bruker/Veeco Vision `.opd`, read only.
    Opd,
    /// Keyence `.vk4`, read only.
    Vk4,
    /// Zygo `.datx` (HDF5): recognised only to be refused with a clear message.
    Datx,
}

impl HeightMapFormat {
    /// The format named by a path's extension (case-insensitive): `.csv`, `.xyz`/`.txt`,
    /// `.gsf`, `.sdf`, `.x3p`, `.sur`, `.al3d`, `.gwy`, `.plu`, `.plux`, `.opd`, `.vk4`,
    /// `.datx`.
    pub fn from_path(path: &Path) -> Option<HeightMapFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "csv" => Some(HeightMapFormat::Csv),
            "xyz" | "txt" => Some(HeightMapFormat::Xyz),
            "gsf" => Some(HeightMapFormat::Gsf),
            "sdf" => Some(HeightMapFormat::Sdf),
            "x3p" => Some(HeightMapFormat::X3p),
            "sur" => Some(HeightMapFormat::Sur),
            "al3d" => Some(HeightMapFormat::Al3d),
            "gwy" => Some(HeightMapFormat::Gwy),
            "plu" => Some(HeightMapFormat::Plu),
            "plux" => Some(HeightMapFormat::Plux),
            "opd" => Some(HeightMapFormat::Opd),
            "vk4" => Some(HeightMapFormat::Vk4),
            "datx" => Some(HeightMapFormat::Datx),
            _ => None,
        }
    }

    /// The format's extension, for messages: `.csv`, `.sur`, ….
    pub fn extension(self) -> &'static str {
        match self {
            HeightMapFormat::Csv => ".csv",
            HeightMapFormat::Xyz => ".xyz",
            HeightMapFormat::Gsf => ".gsf",
            HeightMapFormat::Sdf => ".sdf",
            HeightMapFormat::X3p => ".x3p",
            HeightMapFormat::Sur => ".sur",
            HeightMapFormat::Al3d => ".al3d",
            HeightMapFormat::Gwy => ".gwy",
            HeightMapFormat::Plu => ".plu",
            HeightMapFormat::Plux => ".plux",
            HeightMapFormat::Opd => ".opd",
            HeightMapFormat::Vk4 => ".vk4",
            HeightMapFormat::Datx => ".datx",
        }
    }

    /// Whether the format has a magic of its own that [`HeightMapFormat::sniff`] tells
    /// (not text, not `.plu`).
    fn has_magic(self) -> bool {
        !matches!(
            self,
            HeightMapFormat::Csv | HeightMapFormat::Xyz | HeightMapFormat::Plu
        )
    }

    /// Whether crest writes this format (the instruments' own formats are only read).
    pub fn is_written(self) -> bool {
        matches!(
            self,
            HeightMapFormat::Csv
                | HeightMapFormat::Xyz
                | HeightMapFormat::Gsf
                | HeightMapFormat::Sdf
                | HeightMapFormat::X3p
        )
    }
}

/// Where in a file a problem is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// The whole file (e.g. a missing header key).
    File,
    /// 1-based line, and 1-based field (column) when known.
    Line {
        /// 1-based line.
        line: usize,
        /// 1-based field (column of the table), 0 when not known.
        field: usize,
    },
    /// 0-based byte offset (binary parts).
    Byte(u64),
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Location::File => Ok(()),
            Location::Line { line, field: 0 } => write!(f, ":{line}"),
            Location::Line { line, field } => write!(f, ":{line}: field {field}"),
            Location::Byte(b) => write!(f, ": byte {b}"),
        }
    }
}

/// A format problem found while parsing, without the file name (added by the caller).
#[derive(Debug, Clone, PartialEq)]
pub struct FormatError {
    /// Where the problem is.
    pub at: Location,
    /// What was wrong, lowercase, no trailing period.
    pub message: String,
}

impl FormatError {
    pub(crate) fn line(line: usize, field: usize, message: impl Into<String>) -> FormatError {
        FormatError {
            at: Location::Line { line, field },
            message: message.into(),
        }
    }
    pub(crate) fn byte(offset: u64, message: impl Into<String>) -> FormatError {
        FormatError {
            at: Location::Byte(offset),
            message: message.into(),
        }
    }
    pub(crate) fn file(message: impl Into<String>) -> FormatError {
        FormatError {
            at: Location::File,
            message: message.into(),
        }
    }
}

impl std::fmt::Display for FormatError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.at, self.message)
    }
}

/// Errors of the height-map readers.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum HeightMapError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file could not be read within its budget.
    #[error("{0}")]
    Input(Box<input::InputError>),
    /// The extension names no known format.
    #[error("{path}: unknown height-map extension (expected {})", READ_EXTENSIONS)]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The content is malformed.
    #[error("{path}{}: {}", .error.at, .error.message)]
    Format {
        /// The file.
        path: PathBuf,
        /// Where and what.
        error: FormatError,
    },
}

/// The extensions of the height maps crest reads, for messages.
pub const READ_EXTENSIONS: &str =
    ".csv, .xyz, .txt, .gsf, .sdf, .x3p, .sur, .al3d, .gwy, .plu, .plux, .opd or .vk4";

/// Options for reading height maps.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReadOptions {
    /// x spacing in µm; needed for grid CSV, checked against the file otherwise.
    pub dx_um: Option<f64>,
    /// y spacing in µm; defaults to `dx_um` for grid CSV.
    pub dy_um: Option<f64>,
    /// The channel of a `.gwy` to read, by its title (`--channel`); the first channel
    /// with heights in a length unit when `None`. Refused for other formats.
    pub channel: Option<String>,
}

/// Read a height map, the format chosen by the extension (see the module table).
///
/// Grid CSV needs `opts.dx_um` (and `dy_um`, default = `dx_um`). For the other formats the
/// spacing comes from the file; a spacing given in `opts` that disagrees by more than 1e-6
/// relative is an error.
///
/// The file is read once, within the budget of its format ([`input::read_staged`]: a
/// `.gsf` or binary `.sdf` to the size its header gives, a text map to the node limit); a
/// path without an extension (`-` for standard input, a pipe) is told by its content
/// ([`HeightMapFormat::sniff`]).
pub fn read_heightmap(path: &Path, opts: &ReadOptions) -> Result<HeightMap, HeightMapError> {
    let by_name = HeightMapFormat::from_path(path);
    if by_name.is_none() && path.extension().is_some() {
        return Err(HeightMapError::UnknownFormat {
            path: path.to_path_buf(),
        });
    }
    let mut sniffed = None;
    let bytes = input::read_staged(path, "height map", |head| {
        let format = by_name.unwrap_or_else(|| HeightMapFormat::sniff(head));
        sniffed = Some(format);
        budget_of(format, head)
    })
    .map_err(|e| HeightMapError::Input(Box::new(e)))?;
    let mut format = by_name
        .or(sniffed)
        .unwrap_or_else(|| HeightMapFormat::sniff(&bytes));
    // A binary map whose content is plainly another format than its extension says (the
    // other format's magic) is read as what it is, that format named in any error.
    let seen = HeightMapFormat::sniff(&bytes);
    let renamed = seen != format
        && seen.has_magic()
        && !matches!(format, HeightMapFormat::Csv | HeightMapFormat::Xyz);
    if renamed {
        format = seen;
    }
    parse_heightmap(&bytes, format, opts).map_err(|mut error| {
        if renamed {
            error.message = format!(
                "{} (the content is a {} file, whatever the extension says)",
                error.message,
                format.extension()
            );
        }
        HeightMapError::Format {
            path: path.to_path_buf(),
            error,
        }
    })
}

/// The budget of a height map of `format` from its first bytes `head` ([`input::Stage`]).
fn budget_of(format: HeightMapFormat, head: &[u8]) -> input::Stage {
    use input::Stage;
    match format {
        HeightMapFormat::Gsf => match gsf::stored_len(head) {
            Some(len) if len <= input::GSF_MAX.bytes => Stage::Budget(input::Budget {
                bytes: len,
                line: None,
                why: "XRes × YRes float32 values after the header",
            }),
            // Past the node limit: read no further than the limit allows.
            Some(_) => Stage::Budget(input::GSF_MAX),
            // No valid header in the first bytes: the parser says what is wrong with them.
            None => Stage::Stop,
        },
        HeightMapFormat::Sdf => match head.first() {
            Some(b'a') => input::text_stage(head, input::MAP_TEXT),
            Some(b'b') => Stage::Budget(input::SDF_BINARY),
            _ => Stage::Stop,
        },
        HeightMapFormat::X3p | HeightMapFormat::Plux => Stage::Budget(input::X3P),
        HeightMapFormat::Sur
        | HeightMapFormat::Al3d
        | HeightMapFormat::Gwy
        | HeightMapFormat::Plu
        | HeightMapFormat::Opd
        | HeightMapFormat::Vk4 => Stage::Budget(input::INSTRUMENT_MAP),
        // Refused on its first bytes.
        HeightMapFormat::Datx => Stage::Stop,
        HeightMapFormat::Csv => input::text_stage(head, input::MAP_TEXT),
        HeightMapFormat::Xyz => input::text_stage(head, input::MAP_XYZ),
    }
}

impl HeightMapFormat {
    /// The format the first bytes of a file show: `.gsf` and `.sdf` by their first line,
    /// the instruments' binary files by their magic, a zip archive as `.plux` or `.x3p`,
    /// else CSV (a grid, or a point list with an `x,y,z` header). A `.plu` has no magic.
    pub fn sniff(head: &[u8]) -> HeightMapFormat {
        if sur::is_sur(head) {
            HeightMapFormat::Sur
        } else if head.starts_with(al3d::MAGIC) {
            HeightMapFormat::Al3d
        } else if head.starts_with(gwy::MAGIC) {
            HeightMapFormat::Gwy
        } else if head.starts_with(opd::MAGIC) {
            HeightMapFormat::Opd
        } else if head.starts_with(vk4::MAGIC) {
            HeightMapFormat::Vk4
        } else if head.starts_with(b"\x89HDF\r\n\x1a\n") {
            HeightMapFormat::Datx
        } else if plux::looks_like(head) {
            HeightMapFormat::Plux
        } else if head.starts_with(b"Gwyddion Simple Field") {
            HeightMapFormat::Gsf
        } else if [b"aBCR", b"aISO", b"bBCR", b"bISO"]
            .iter()
            .any(|m| head.starts_with(*m))
        {
            HeightMapFormat::Sdf
        } else if x3p::is_zip(head) {
            HeightMapFormat::X3p
        } else {
            HeightMapFormat::Csv
        }
    }
}

/// The mapping of an error in opening a `.gsf` to [`HeightMapError`].
fn gsf_error(path: &Path) -> impl Fn(gsf::ReadError) -> HeightMapError + '_ {
    move |e| match e {
        gsf::ReadError::Io(source) => HeightMapError::Io {
            path: path.to_path_buf(),
            source,
        },
        gsf::ReadError::Format(error) => HeightMapError::Format {
            path: path.to_path_buf(),
            error,
        },
    }
}

/// Open a Gwyddion `.gsf` for reading its heights in pieces of rows ([`GsfRows::read_row_range`]),
/// in a few rows of memory: the header is read and checked (spacing against `opts`) now,
/// the heights (the stored float32 values in µm, which [`read_heightmap`] widens to `f64`
/// exactly) as they are handed on.
///
/// Only a regular file is read this way ([`input::is_regular`]); standard input, a pipe or
/// a device is refused here (read it with [`read_heightmap`]).
pub fn open_gsf_rows(path: &Path, opts: &ReadOptions) -> Result<GsfRows, HeightMapError> {
    let err = gsf_error(path);
    if !input::is_regular(path) {
        return Err(err(gsf::ReadError::Io(std::io::Error::other(
            "not a regular file: read it whole",
        ))));
    }
    output::register_input(path);
    let file = std::fs::File::open(path).map_err(|e| err(gsf::ReadError::Io(e)))?;
    let rows = GsfRows::open(file, path).map_err(&err)?;
    check_against(opts.dx_um, rows.dx_um, "dx").map_err(|e| err(e.into()))?;
    check_against(opts.dy_um, rows.dy_um, "dy").map_err(|e| err(e.into()))?;
    Ok(rows)
}

impl GsfRows {
    /// Hand the heights of the rows `rows` (those of the map: rows past its end are not
    /// there) to `each` in pieces of `piece` whole rows (the last may be shorter), in
    /// order, read on the caller's thread, so that several threads can each read their own
    /// rows at once; may be called again for another pass. A finite height beyond ±1 m is an
    /// error (as in [`read_heightmap`]), raised before its piece is handed on.
    pub fn read_row_range(
        &self,
        rows: std::ops::Range<usize>,
        piece: usize,
        each: impl FnMut(&[f32]),
    ) -> Result<(), HeightMapError> {
        self.for_each_piece_of(rows, piece, MAX_HEIGHT_UM, each)
            .map_err(|e| self.piece_error(e))
    }

    fn piece_error(&self, e: gsf::PieceError) -> HeightMapError {
        match e {
            gsf::PieceError::Io(source) => HeightMapError::Io {
                path: self.path().to_path_buf(),
                source,
            },
            gsf::PieceError::Beyond((k, v)) => HeightMapError::Format {
                path: self.path().to_path_buf(),
                error: beyond(k, v, self.nx),
            },
        }
    }
}

/// The error of a height beyond ±1 m at index `k` of a map `nx` wide.
fn beyond(k: usize, v: f32, nx: usize) -> FormatError {
    FormatError::file(format!(
        "the height at row {}, column {} is {} µm, beyond ±{MAX_HEIGHT_UM} µm (1 m): not a surface height",
        k / nx.max(1),
        k % nx.max(1),
        f64::from(v)
    ))
}

/// Parse a height map from memory (see [`read_heightmap`]). A `.csv` whose first line is
/// an `x,y,z` header is read as a point list.
pub fn parse_heightmap(
    bytes: &[u8],
    format: HeightMapFormat,
    opts: &ReadOptions,
) -> Result<HeightMap, FormatError> {
    if let (Some(name), false) = (&opts.channel, format == HeightMapFormat::Gwy) {
        return Err(FormatError::file(format!(
            "‹channel› {name:?} names a channel of a Gwyddion .gwy file; this is a {} file, which has one height layer",
            format.extension()
        )));
    }
    let map = match format {
        HeightMapFormat::Csv => {
            let text = as_text(bytes)?;
            if xyz::has_xyz_header(text) {
                xyz::parse(text)?
            } else {
                // The spacing from the options, else from the comment crest writes.
                let meta = csv_grid::meta(text);
                let dx = opts.dx_um.or(meta.map(|m| m.dx_um)).ok_or_else(|| {
                    FormatError::file("a grid CSV carries no spacing: give ‹dx_um› (and ‹dy_um›)")
                })?;
                let dy = opts.dy_um.or(meta.map(|m| m.dy_um)).unwrap_or(dx);
                check_spacing_value("dx", dx)?;
                check_spacing_value("dy", dy)?;
                if let Some(m) = meta {
                    check_against(opts.dx_um, m.dx_um, "dx")?;
                    check_against(opts.dy_um, m.dy_um, "dy")?;
                }
                let mut map = csv_grid::parse(text, dx, dy)?;
                if let Some(m) = meta {
                    map.x0_mm = m.x0_mm;
                    map.y0_mm = m.y0_mm;
                }
                check_heights(&map)?;
                return Ok(map);
            }
        }
        HeightMapFormat::Xyz => xyz::parse(as_text(bytes)?)?,
        HeightMapFormat::Gsf => gsf::parse(bytes)?,
        HeightMapFormat::Sdf => sdf::parse(bytes)?,
        HeightMapFormat::X3p => x3p::parse(bytes)?,
        HeightMapFormat::Sur => sur::parse(bytes)?,
        HeightMapFormat::Al3d => al3d::parse(bytes)?,
        HeightMapFormat::Gwy => gwy::parse(bytes, opts.channel.as_deref())?,
        HeightMapFormat::Plu => plu::parse(bytes)?,
        HeightMapFormat::Plux => plux::parse(bytes)?,
        HeightMapFormat::Opd => opd::parse(bytes)?,
        HeightMapFormat::Vk4 => vk4::parse(bytes)?,
        HeightMapFormat::Datx => return Err(FormatError::file(DATX_REFUSED)),
    };
    check_heights(&map)?;
    check_against(opts.dx_um, map.dx_um, "dx")?;
    check_against(opts.dy_um, map.dy_um, "dy")?;
    Ok(map)
}

fn check_spacing_value(name: &str, v: f64) -> Result<(), FormatError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(FormatError::file(format!(
            "{name} must be a positive number of µm, got {}",
            crate::math::limits::shown(v)
        )))
    }
}

fn check_against(given: Option<f64>, file: f64, name: &str) -> Result<(), FormatError> {
    match given {
        Some(g) if (g - file).abs() > 1e-6 * file.abs().max(g.abs()) => Err(FormatError::file(
            format!("the file gives {name} = {file} µm but --{name}-um says {g}"),
        )),
        _ => Ok(()),
    }
}

fn as_text(bytes: &[u8]) -> Result<&str, FormatError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let off = e.valid_up_to();
        let line = bytes[..off].iter().filter(|&&b| b == b'\n').count() + 1;
        FormatError::line(line, 0, format!("not UTF-8 text (byte {off})"))
    })
}

/// Why a Zygo `.datx` is refused.
pub const DATX_REFUSED: &str =
    "Zygo .datx is HDF5, which crest cannot read; export .x3p or .sdf from Mx";

/// Write a height map, the format chosen by the extension: `.csv` (rows = y ascending,
/// µm), `.xyz`/`.txt` (x,y,z point list, µm), `.gsf` (Gwyddion Simple Field, metres,
/// float32), `.sdf` (ISO 25178-71 / BCR text, metres, float64 values) or `.x3p` (ISO
/// 25178-72, metres, float64).
pub fn write_heightmap(path: &Path, map: &HeightMap) -> std::io::Result<()> {
    let mut set = output::Outputs::new();
    stage_heightmap(&mut set, path, map)?;
    set.land().map(drop)
}

/// Stage a height map as [`write_heightmap`] writes it, into a set of outputs that lands
/// together ([`output::Outputs`]).
pub fn stage_heightmap(
    set: &mut output::Outputs,
    path: &Path,
    map: &HeightMap,
) -> std::io::Result<()> {
    let format = HeightMapFormat::from_path(path)
        .filter(|f| f.is_written())
        .ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "{}: unknown height-map extension for writing (expected .csv, .xyz, .txt, .gsf, .sdf or .x3p)",
                path.display()
            ),
        )
    })?;
    if map.z_um.len() != map.nx * map.ny {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "height map has {} heights for {}×{} nodes",
                map.z_um.len(),
                map.nx,
                map.ny
            ),
        ));
    }
    set.file(path, |w| write_heightmap_to(w, format, map))
}

/// Write a height map in `format` to any writer (see [`write_heightmap`]).
pub fn write_heightmap_to(
    w: &mut dyn Write,
    format: HeightMapFormat,
    map: &HeightMap,
) -> std::io::Result<()> {
    match format {
        HeightMapFormat::Csv => csv_grid::write(w, map),
        HeightMapFormat::Xyz => xyz::write(w, map),
        HeightMapFormat::Gsf => gsf::write(w, map),
        HeightMapFormat::Sdf => sdf::write(w, map),
        HeightMapFormat::X3p => x3p::write(w, map),
        f => Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "crest reads {} files but does not write them (write .x3p, .sdf, .gsf, .csv or .xyz)",
                f.extension()
            ),
        )),
    }
}

/// Why a map could not be taken through its stored form.
#[derive(Debug, thiserror::Error)]
pub enum StoredError {
    /// The format cannot be written.
    #[error("{0}")]
    Write(#[from] std::io::Error),
    /// What was written did not read back.
    #[error("{0}")]
    Read(FormatError),
}

/// The map as a file of `format` stores it (written and parsed back in memory): what a later
/// `crest metrics FILE` reads, e.g. float32 heights for GSF.
pub fn as_stored(map: &HeightMap, format: HeightMapFormat) -> Result<HeightMap, StoredError> {
    let mut bytes = Vec::new();
    write_heightmap_to(&mut bytes, format, map)?;
    let opts = ReadOptions {
        dx_um: Some(map.dx_um),
        dy_um: Some(map.dy_um),
        channel: None,
    };
    parse_heightmap(&bytes, format, &opts).map_err(StoredError::Read)
}

/// Seconds since 1970-01-01T00:00:00Z as (year, month, day, hour, minute, second), UTC, in
/// the proleptic Gregorian calendar (days to a civil date by H. Hinnant's
/// `civil_from_days`): the dates the `.sdf` and `.x3p` writers stamp.
pub(crate) fn civil_utc(secs: i64) -> [i64; 6] {
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    [y, m, d, rem / 3600, rem / 60 % 60, rem % 60]
}

/// Parse one number of a text format; `NaN`, `nan`, `NA`, `N/A` and empty mean missing.
pub(crate) fn parse_value(s: &str) -> Option<f64> {
    let t = s.trim();
    if t.is_empty()
        || t.eq_ignore_ascii_case("nan")
        || t.eq_ignore_ascii_case("na")
        || t.eq_ignore_ascii_case("n/a")
    {
        return Some(f64::NAN);
    }
    // `inf` and values that overflow to it (1e400) are not heights, nor is anything beyond
    // a metre: refused rather than taken as missing.
    t.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && v.abs() <= MAX_HEIGHT_UM)
}

/// A length read from a file's metres or ratios, rounded to 12 significant digits: the
/// binary round trip of `2e-5` m × 1e6 gives 19.999999999999996 µm, which is 20 µm.
pub(crate) fn tidy(v: f64) -> f64 {
    if v.is_finite() && v != 0.0 {
        format!("{v:.11e}").parse().unwrap_or(v)
    } else {
        v
    }
}

/// Largest magnitude of a height (and of a text map's coordinate) that is read, µm (1 m).
pub const MAX_HEIGHT_UM: f64 = 1e6;

/// Refuse a map whose finite heights exceed [`MAX_HEIGHT_UM`] (binary formats), naming
/// the first offending node.
fn check_heights(map: &HeightMap) -> Result<(), FormatError> {
    if let Some(k) = map.z_um.iter().position(|v| v.abs() > MAX_HEIGHT_UM) {
        return Err(FormatError::file(format!(
            "the height at row {}, column {} is {} µm, beyond ±{MAX_HEIGHT_UM} µm (1 m): not a surface height",
            k / map.nx.max(1),
            k % map.nx.max(1),
            map.z_um[k]
        )));
    }
    Ok(())
}

/// Shortest round-trip text of a height; `NaN` for missing.
pub(crate) fn fmt_value(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        "NaN".to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.csv");
        let r = write_atomic(&out, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        write_atomic(&out, |w| w.write_all(b"ok")).unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"ok");
        #[cfg(unix)]
        {
            // Readable by others (not tempfile's 0600), whatever the umask leaves of 0666.
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&out).unwrap().permissions().mode();
            assert_eq!(mode & 0o044, 0o044, "mode {mode:o}");
        }
    }

    #[test]
    fn format_from_extension() {
        assert_eq!(
            HeightMapFormat::from_path(Path::new("a/b.GSF")),
            Some(HeightMapFormat::Gsf)
        );
        assert_eq!(
            HeightMapFormat::from_path(Path::new("b.sdf")),
            Some(HeightMapFormat::Sdf)
        );
        assert_eq!(HeightMapFormat::from_path(Path::new("b.png")), None);
    }

    #[test]
    fn spacing_and_origin_survive_every_format() {
        let mut map =
            HeightMap::from_rows(3, 2, 20.0, 10.0, vec![0.5, -1.25, 2.0, 3.0, f64::NAN, 4.5])
                .unwrap();
        map.x0_mm = -12.5;
        map.y0_mm = 3.02;
        for format in [
            HeightMapFormat::Csv,
            HeightMapFormat::Xyz,
            HeightMapFormat::Gsf,
            HeightMapFormat::Sdf,
        ] {
            let mut bytes = Vec::new();
            write_heightmap_to(&mut bytes, format, &map).unwrap();
            let back = parse_heightmap(&bytes, format, &ReadOptions::default())
                .unwrap_or_else(|e| panic!("{format:?}: {e}"));
            assert_eq!((back.nx, back.ny), (3, 2), "{format:?}");
            assert_eq!((back.dx_um, back.dy_um), (20.0, 10.0), "{format:?}");
            assert_eq!((back.x0_mm, back.y0_mm), (-12.5, 3.02), "{format:?}");
            assert_eq!(back.z_um[1], -1.25, "{format:?}");
            assert!(back.z_um[4].is_nan(), "{format:?}");
        }
    }

    #[test]
    fn csv_needs_spacing() {
        let e = parse_heightmap(b"1,2\n3,4\n", HeightMapFormat::Csv, &ReadOptions::default())
            .unwrap_err();
        assert!(e.message.contains("‹dx_um›"), "{e}");
    }

    #[test]
    fn spacing_mismatch_is_an_error() {
        let text = b"x,y,z\n0,0,1\n2,0,1\n0,2,1\n2,2,1\n";
        let opts = ReadOptions {
            dx_um: Some(1.0),
            ..Default::default()
        };
        let e = parse_heightmap(text, HeightMapFormat::Xyz, &opts).unwrap_err();
        assert!(e.message.contains("dx = 2"), "{e}");
    }
}
