//! Triangle meshes of the design surface: binary and ASCII STL, Wavefront OBJ and PLY
//! (ASCII, binary little- and big-endian) read into a [`Mesh`] in mm; binary STL written for
//! the known surfaces of `crest synth`; PLY point clouds with normals and heights written for
//! part maps.
//!
//! Readers never trust a count: a binary STL whose triangle count disagrees with its size,
//! a PLY whose element counts overrun the file, a vertex index out of range or a value that
//! is not a finite number are errors naming the file and the line (text) or the triangle and
//! byte offset (binary). [`read_part`] also checks the mesh ([`Mesh::checked`]): duplicate
//! triangles and inconsistent winding are errors at the offending triangle's line;
//! degenerate triangles are dropped with a warning naming them.

use crate::math::{Point3, Vec3};
use crate::parse::Span;
use crate::part::{Mesh, MeshError, Part};
use crate::surface::MapPoint;
use std::io::Write;
use std::path::Path;

/// Why a mesh file cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error, miette::Diagnostic)]
#[error("{file}:{at}: {message}")]
pub struct MeshFileError {
    /// File name as given.
    pub file: String,
    /// Where: a line (and column) of a text mesh, or a place in a binary one.
    pub at: MeshPlace,
    /// What is wrong.
    pub message: String,
}

/// Where in a mesh file a problem is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MeshPlace {
    /// A line (and column, when known) of a text mesh, shown `LINE` or `LINE:COLUMN`; the
    /// whole file is line 1.
    Line(Span),
    /// A place in a binary mesh, in words (`triangle N (byte B)`, `byte B`).
    Binary(String),
}

impl MeshPlace {
    /// The whole file (shown as line 1).
    fn file() -> MeshPlace {
        at_line(1)
    }
}

impl std::fmt::Display for MeshPlace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MeshPlace::Line(s) if s.column == 0 => write!(f, "{}", s.line),
            MeshPlace::Line(s) => write!(f, "{}:{}", s.line, s.column),
            MeshPlace::Binary(w) => f.write_str(w),
        }
    }
}

/// A mesh file's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// STL, binary or ASCII (by content).
    Stl,
    /// Wavefront OBJ.
    Obj,
    /// Stanford PLY (ASCII or binary).
    Ply,
}

impl MeshFormat {
    /// The format by extension (`.stl`, `.obj`, `.ply`, any case).
    pub fn from_path(path: &Path) -> Option<MeshFormat> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "stl" => Some(MeshFormat::Stl),
            "obj" => Some(MeshFormat::Obj),
            "ply" => Some(MeshFormat::Ply),
            _ => None,
        }
    }
}

/// Where each triangle of a parsed mesh came from, to name it in errors.
#[derive(Debug, Clone, Default)]
struct Origins {
    /// Per triangle: the 1-based line (text formats) or byte offset (binary), and whether it
    /// is a byte offset.
    at: Vec<(u64, bool)>,
}

impl Origins {
    fn push_line(&mut self, line: usize) {
        self.at.push((line as u64, false));
    }
    fn push_byte(&mut self, byte: usize) {
        self.at.push((byte as u64, true));
    }
    fn describe(&self, triangle: usize) -> MeshPlace {
        match self.at.get(triangle) {
            Some(&(l, false)) => MeshPlace::Line(Span::line_u64(l)),
            Some(&(b, true)) => MeshPlace::Binary(format!("triangle {} (byte {b})", triangle + 1)),
            None => MeshPlace::Binary(format!("triangle {}", triangle + 1)),
        }
    }
}

/// A parsed mesh with the origin of each triangle.
struct Parsed {
    mesh: Mesh,
    origins: Origins,
}

/// A design surface read and checked: the part, and warnings (dropped degenerate triangles).
#[derive(Debug)]
pub struct PartFile {
    /// The indexed part.
    pub part: Part,
    /// Non-fatal findings, each naming the file and where.
    pub warnings: Vec<String>,
    /// Triangles kept.
    pub triangles: usize,
}

/// Read, check and index a design surface (STL, OBJ or PLY by extension).
pub fn read_part(path: &Path) -> Result<PartFile, MeshFileError> {
    let file = path.display().to_string();
    let err = |at: MeshPlace, message: String| MeshFileError {
        file: file.clone(),
        at,
        message,
    };
    let format = MeshFormat::from_path(path).ok_or_else(|| {
        err(
            MeshPlace::file(),
            "unknown mesh format (expected .stl, .obj or .ply)".into(),
        )
    })?;
    let bytes = super::input::read_staged(path, "mesh", |head| mesh_stage(format, head))
        .map_err(|e| err(MeshPlace::file(), e.detail()))?;
    part_from_bytes(&bytes, format, &file)
}

/// The budget of a mesh from its first bytes: a binary STL its header's size, an OBJ or
/// ASCII STL text within [`super::input::MESH`], a PLY (ASCII or binary) that budget after
/// its `ply` line; nothing more of a file that starts as none of them.
fn mesh_stage(format: MeshFormat, head: &[u8]) -> super::input::Stage {
    use super::input::{MESH, Stage, text_stage};
    match format {
        MeshFormat::Stl => {
            let text_start = head
                .iter()
                .position(|b| !b.is_ascii_whitespace())
                .is_some_and(|i| head[i..].starts_with(b"solid"));
            if text_start && looks_like_ascii_stl(head) {
                return text_stage(head, MESH);
            }
            let n = u64::from(u32::from_le_bytes([head[80], head[81], head[82], head[83]]));
            match 84 + 50 * n {
                len if len <= MESH.bytes => Stage::Budget(super::input::Budget {
                    bytes: len,
                    line: None,
                    why: "84 bytes and 50 per triangle of the binary STL's count",
                }),
                _ => Stage::Budget(MESH),
            }
        }
        MeshFormat::Obj => text_stage(head, MESH),
        MeshFormat::Ply if head.starts_with(b"ply") => Stage::Budget(MESH),
        MeshFormat::Ply => Stage::Stop,
    }
}

/// [`read_part`] on the bytes of a file named `file` in `format`.
pub fn part_from_bytes(
    bytes: &[u8],
    format: MeshFormat,
    file: &str,
) -> Result<PartFile, MeshFileError> {
    let err = |at: MeshPlace, message: String| MeshFileError {
        file: file.to_string(),
        at,
        message,
    };
    let parsed = match format {
        MeshFormat::Stl => parse_stl(bytes),
        MeshFormat::Obj => parse_obj(bytes),
        MeshFormat::Ply => parse_ply(bytes),
    }
    .map_err(|(at, message)| err(at, message))?;
    let Parsed { mesh, origins } = parsed;
    let (mesh, check) = mesh.checked().map_err(|e| {
        let (t, message) = match &e {
            MeshError::Empty => (None, e.to_string()),
            MeshError::NotFinite { triangle, .. }
            | MeshError::BadIndex { triangle, .. }
            | MeshError::NonManifold { triangle } => (Some(*triangle), e.to_string()),
            MeshError::Duplicate { triangle, first } => (
                Some(*triangle),
                format!(
                    "triangle {} repeats triangle {} (at {})",
                    triangle + 1,
                    first + 1,
                    origins.describe(*first)
                ),
            ),
            MeshError::Winding {
                triangle,
                neighbour,
            } => (
                Some(*triangle),
                format!(
                    "triangle {} is wound against its neighbour, triangle {} (at {}): their shared edge runs the same way in both",
                    triangle + 1,
                    neighbour + 1,
                    origins.describe(*neighbour)
                ),
            ),
        };
        let at = t.map_or_else(MeshPlace::file, |t| origins.describe(t));
        err(at, message)
    })?;
    let warnings = check
        .degenerate
        .iter()
        .map(|&t| {
            format!(
                "{file}:{}: degenerate triangle {} (zero area) skipped",
                origins.describe(t),
                t + 1
            )
        })
        .collect();
    let triangles = mesh.triangles.len();
    Ok(PartFile {
        part: Part::from_checked(mesh),
        warnings,
        triangles,
    })
}

type ParseResult = Result<Parsed, (MeshPlace, String)>;

fn at_line(line: usize) -> MeshPlace {
    MeshPlace::Line(Span::line(u32::try_from(line).unwrap_or(u32::MAX)))
}

fn number(tok: Option<&str>, line: usize, what: &str) -> Result<f64, (MeshPlace, String)> {
    let t = tok.ok_or_else(|| {
        (
            at_line(line),
            format!("expected {what}, found the end of the line"),
        )
    })?;
    let v: f64 = t.parse().map_err(|_| {
        (
            at_line(line),
            format!("expected {what}, found `{}`", short(t)),
        )
    })?;
    if !v.is_finite() {
        return Err((
            at_line(line),
            format!("{what} `{}` is not finite", short(t)),
        ));
    }
    Ok(v)
}

/// A vertex coordinate of a text mesh: a finite number within ±100 m
/// ([`crate::math::limits::coordinates`]).
fn coordinate(tok: Option<&str>, line: usize) -> Result<f64, (MeshPlace, String)> {
    let v = number(tok, line, "a coordinate")?;
    crate::math::limits::coordinates(&[v]).map_err(|m| (at_line(line), m.to_string()))?;
    Ok(v)
}

/// At most 40 characters of a token, for messages.
fn short(t: &str) -> String {
    if t.chars().count() > 40 {
        format!("{}…", t.chars().take(40).collect::<String>())
    } else {
        t.to_string()
    }
}

/// STL: binary when the size matches the header's count, ASCII when it starts with `solid`
/// and does not, a truncated or lying binary file otherwise.
fn parse_stl(bytes: &[u8]) -> ParseResult {
    let binary_count = (bytes.len() >= 84)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64);
    let fits = binary_count.is_some_and(|n| bytes.len() as u64 == 84 + 50 * n);
    let text_start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .is_some_and(|i| bytes[i..].starts_with(b"solid"));
    if fits && !(text_start && looks_like_ascii_stl(bytes)) {
        return parse_binary_stl(bytes);
    }
    if text_start {
        return parse_ascii_stl(bytes);
    }
    match binary_count {
        None => Err((
            MeshPlace::file(),
            format!(
                "truncated STL: {} bytes, less than the 84-byte header",
                bytes.len()
            ),
        )),
        Some(n) => Err((
            MeshPlace::file(),
            format!(
                "binary STL whose header says {n} triangles ({} bytes) but the file has {} bytes",
                84 + 50 * n,
                bytes.len()
            ),
        )),
    }
}

fn looks_like_ascii_stl(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(512)];
    head.windows(5).any(|w| w == b"facet") || head.windows(8).any(|w| w == b"endsolid")
}

fn parse_binary_stl(bytes: &[u8]) -> ParseResult {
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    let mut corners = Vec::with_capacity(n);
    let mut origins = Origins::default();
    let f =
        |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]) as f64;
    for t in 0..n {
        let o = 84 + 50 * t;
        let normal = Vec3::new(f(o), f(o + 4), f(o + 8));
        let mut tri = [Point3::origin(); 3];
        for (k, p) in tri.iter_mut().enumerate() {
            let b = o + 12 + 12 * k;
            *p = Point3::new(f(b), f(b + 4), f(b + 8));
            if !p.coords.iter().all(|c| c.is_finite()) {
                return Err((
                    MeshPlace::Binary(format!("triangle {} (byte {b})", t + 1)),
                    format!("vertex {} is not finite", k + 1),
                ));
            }
            crate::math::limits::coordinates(p.coords.as_slice()).map_err(|m| {
                (
                    MeshPlace::Binary(format!("triangle {} (byte {b})", t + 1)),
                    format!("vertex {}: {m}", k + 1),
                )
            })?;
        }
        check_stored_normal(&normal, &tri).map_err(|m| {
            (
                MeshPlace::Binary(format!("triangle {} (byte {o})", t + 1)),
                m.to_string(),
            )
        })?;
        corners.push(tri);
        origins.push_byte(o);
    }
    Ok(Parsed {
        mesh: Mesh::from_corners(&corners),
        origins,
    })
}

/// A stored facet normal against the winding of its triangle's vertices.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error(
    "the facet normal points against the winding of its vertices (counter-clockwise seen from outside)"
)]
struct NormalAgainstWinding;

/// A stored facet normal that points against the winding's normal means the winding (or
/// the normal) is wrong.
fn check_stored_normal(stored: &Vec3, tri: &[Point3; 3]) -> Result<(), NormalAgainstWinding> {
    if !stored.iter().all(|c| c.is_finite()) || stored.norm() < 1e-6 {
        return Ok(()); // many exporters write zero normals
    }
    let n = (tri[1] - tri[0]).cross(&(tri[2] - tri[0]));
    if n.norm() > 0.0 && n.dot(stored) < 0.0 {
        return Err(NormalAgainstWinding);
    }
    Ok(())
}

fn parse_ascii_stl(bytes: &[u8]) -> ParseResult {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        let before = String::from_utf8_lossy(&bytes[..at]);
        (
            MeshPlace::Line(Span::of(&before, at..at + 1)),
            "not UTF-8 text".to_string(),
        )
    })?;
    let mut corners = Vec::new();
    let mut origins = Origins::default();
    let mut normal = Vec3::zeros();
    let mut verts: Vec<Point3> = Vec::new();
    let mut facet_line = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut toks = raw.split_whitespace();
        let Some(kw) = toks.next() else { continue };
        match kw {
            "solid" | "endsolid" | "outer" | "endloop" => {}
            "facet" => {
                facet_line = line;
                verts.clear();
                if toks.next() == Some("normal") {
                    normal = Vec3::new(
                        number(toks.next(), line, "a normal component")?,
                        number(toks.next(), line, "a normal component")?,
                        number(toks.next(), line, "a normal component")?,
                    );
                }
            }
            "vertex" => {
                if verts.len() == 3 {
                    return Err((at_line(line), "a facet with more than 3 vertices".into()));
                }
                verts.push(Point3::new(
                    coordinate(toks.next(), line)?,
                    coordinate(toks.next(), line)?,
                    coordinate(toks.next(), line)?,
                ));
            }
            "endfacet" => {
                let tri: [Point3; 3] = verts.as_slice().try_into().map_err(|_| {
                    (
                        at_line(facet_line),
                        format!("a facet with {} vertices (3 expected)", verts.len()),
                    )
                })?;
                check_stored_normal(&normal, &tri)
                    .map_err(|m| (at_line(facet_line), m.to_string()))?;
                corners.push(tri);
                origins.push_line(facet_line);
                verts.clear();
                normal = Vec3::zeros();
            }
            other => {
                return Err((
                    MeshPlace::Line(Span::line_column(
                        u32::try_from(line).unwrap_or(u32::MAX),
                        u32::try_from(raw.len() - raw.trim_start().len() + 1).unwrap_or(u32::MAX),
                    )),
                    format!("expected an STL keyword, found `{}`", short(other)),
                ));
            }
        }
    }
    if !verts.is_empty() {
        return Err((
            at_line(facet_line),
            "the last facet is not closed (endfacet missing)".into(),
        ));
    }
    Ok(Parsed {
        mesh: Mesh::from_corners(&corners),
        origins,
    })
}

/// Resolve an OBJ vertex reference (`i`, `i/t`, `i//n`, `i/t/n`; negative = from the end).
fn obj_index(tok: &str, count: usize, line: usize) -> Result<u32, (MeshPlace, String)> {
    let head = tok.split('/').next().unwrap_or("");
    let i: i64 = head.parse().map_err(|_| {
        (
            at_line(line),
            format!("expected a vertex index, found `{}`", short(tok)),
        )
    })?;
    let idx = if i > 0 {
        i - 1
    } else if i < 0 {
        count as i64 + i
    } else {
        -1
    };
    if idx < 0 || idx >= count as i64 {
        return Err((
            at_line(line),
            format!("vertex index {i} is out of range ({count} vertices so far)"),
        ));
    }
    Ok(idx as u32)
}

fn parse_obj(bytes: &[u8]) -> ParseResult {
    let text = String::from_utf8_lossy(bytes);
    let mut mesh = Mesh::default();
    let mut origins = Origins::default();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let raw = raw.split('#').next().unwrap_or("");
        let mut toks = raw.split_whitespace();
        match toks.next() {
            Some("v") => mesh.vertices.push(Point3::new(
                coordinate(toks.next(), line)?,
                coordinate(toks.next(), line)?,
                coordinate(toks.next(), line)?,
            )),
            Some("f") => {
                let idx: Vec<u32> = toks
                    .map(|t| obj_index(t, mesh.vertices.len(), line))
                    .collect::<Result<_, _>>()?;
                if idx.len() < 3 {
                    return Err((at_line(line), format!("a face with {} vertices", idx.len())));
                }
                for k in 1..idx.len() - 1 {
                    mesh.triangles.push([idx[0], idx[k], idx[k + 1]]);
                    origins.push_line(line);
                }
            }
            _ => {} // normals, texture coordinates, groups, materials: not needed
        }
    }
    Ok(Parsed { mesh, origins })
}

/// A PLY scalar type.
#[derive(Debug, Clone, Copy, PartialEq)]
enum PlyType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl PlyType {
    fn parse(s: &str) -> Option<PlyType> {
        Some(match s {
            "char" | "int8" => PlyType::I8,
            "uchar" | "uint8" => PlyType::U8,
            "short" | "int16" => PlyType::I16,
            "ushort" | "uint16" => PlyType::U16,
            "int" | "int32" => PlyType::I32,
            "uint" | "uint32" => PlyType::U32,
            "float" | "float32" => PlyType::F32,
            "double" | "float64" => PlyType::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            PlyType::I8 | PlyType::U8 => 1,
            PlyType::I16 | PlyType::U16 => 2,
            PlyType::I32 | PlyType::U32 | PlyType::F32 => 4,
            PlyType::F64 => 8,
        }
    }
    fn read(self, b: &[u8], big: bool) -> f64 {
        macro_rules! get {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                (if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            }};
        }
        match self {
            PlyType::I8 => b[0] as i8 as f64,
            PlyType::U8 => b[0] as f64,
            PlyType::I16 => get!(i16, 2),
            PlyType::U16 => get!(u16, 2),
            PlyType::I32 => get!(i32, 4),
            PlyType::U32 => get!(u32, 4),
            PlyType::F32 => get!(f32, 4),
            PlyType::F64 => get!(f64, 8),
        }
    }
}

#[derive(Debug, Clone)]
enum PlyProp {
    Scalar(String, PlyType),
    List(String, PlyType, PlyType),
}

#[derive(Debug, Clone)]
struct PlyElement {
    name: String,
    count: usize,
    props: Vec<PlyProp>,
}

fn parse_ply(bytes: &[u8]) -> ParseResult {
    // Header: text lines up to `end_header`.
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or_else(|| {
            (
                MeshPlace::file(),
                "not a PLY file: no end_header".to_string(),
            )
        })?;
    let body_start = bytes[end..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |p| end + p + 1);
    let header = String::from_utf8_lossy(&bytes[..end]);
    let mut lines = header.lines().enumerate();
    if lines.next().map(|(_, l)| l.trim()) != Some("ply") {
        return Err((
            MeshPlace::file(),
            "not a PLY file: the first line is not `ply`".into(),
        ));
    }
    let mut format = None;
    let mut elements: Vec<PlyElement> = Vec::new();
    for (i, l) in lines {
        let line = i + 1;
        let t: Vec<&str> = l.split_whitespace().collect();
        match t.as_slice() {
            ["format", f, _] => format = Some(f.to_string()),
            ["element", name, n] => elements.push(PlyElement {
                name: name.to_string(),
                count: n
                    .parse()
                    .map_err(|_| (at_line(line), format!("bad element count `{}`", short(n))))?,
                props: Vec::new(),
            }),
            ["property", "list", ct, it, name] => {
                let (Some(c), Some(i)) = (PlyType::parse(ct), PlyType::parse(it)) else {
                    return Err((at_line(line), format!("unknown list types `{ct} {it}`")));
                };
                let e = elements
                    .last_mut()
                    .ok_or_else(|| (at_line(line), "a property before any element".to_string()))?;
                e.props.push(PlyProp::List(name.to_string(), c, i));
            }
            ["property", ty, name] => {
                let ty = PlyType::parse(ty).ok_or_else(|| {
                    (
                        at_line(line),
                        format!("unknown property type `{}`", short(ty)),
                    )
                })?;
                let e = elements
                    .last_mut()
                    .ok_or_else(|| (at_line(line), "a property before any element".to_string()))?;
                e.props.push(PlyProp::Scalar(name.to_string(), ty));
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            _ => {
                return Err((
                    at_line(line),
                    format!("unexpected PLY header line `{}`", short(l)),
                ));
            }
        }
    }
    let header_lines = header.lines().count() + 1;
    let big = match format.as_deref() {
        Some("ascii") => None,
        Some("binary_little_endian") => Some(false),
        Some("binary_big_endian") => Some(true),
        other => {
            return Err((MeshPlace::file(), format!("unknown PLY format {other:?}")));
        }
    };
    let body = &bytes[body_start..];
    let mut mesh = Mesh::default();
    let mut origins = Origins::default();
    match big {
        None => {
            let text = String::from_utf8_lossy(body);
            let mut rows = text
                .lines()
                .enumerate()
                .filter(|(_, l)| !l.trim().is_empty());
            for e in &elements {
                for _ in 0..e.count {
                    let Some((i, row)) = rows.next() else {
                        return Err((
                            at_line(header_lines + 1),
                            format!("the file ends before its {} {} elements", e.count, e.name),
                        ));
                    };
                    let line = header_lines + i + 1;
                    let mut toks = row.split_whitespace();
                    let mut xyz = [f64::NAN; 3];
                    let mut face: Vec<u32> = Vec::new();
                    for p in &e.props {
                        match p {
                            PlyProp::Scalar(name, _) => {
                                let v = number(toks.next(), line, name)?;
                                if let Some(k) = ["x", "y", "z"].iter().position(|c| c == name) {
                                    xyz[k] = v;
                                }
                            }
                            PlyProp::List(name, _, _) => {
                                let n = number(toks.next(), line, "a list length")?;
                                if !(0.0..=1e6).contains(&n) {
                                    return Err((at_line(line), format!("list length {n}")));
                                }
                                for _ in 0..n as usize {
                                    let v = number(toks.next(), line, "a vertex index")?;
                                    if name.starts_with("vertex_ind") {
                                        face.push(ply_index(v, line)?);
                                    }
                                }
                            }
                        }
                    }
                    ply_item(e, xyz, &face, &mut mesh, &mut origins, line, false)?;
                }
            }
        }
        Some(big) => {
            let mut o = 0usize;
            let take =
                |o: &mut usize, n: usize, what: &str| -> Result<usize, (MeshPlace, String)> {
                    if *o + n > body.len() {
                        return Err((
                            MeshPlace::Binary(format!("byte {}", body_start + *o)),
                            format!("the file ends inside {what}"),
                        ));
                    }
                    let at = *o;
                    *o += n;
                    Ok(at)
                };
            for e in &elements {
                for k in 0..e.count {
                    let start = body_start + o;
                    let mut xyz = [f64::NAN; 3];
                    let mut face: Vec<u32> = Vec::new();
                    for p in &e.props {
                        match p {
                            PlyProp::Scalar(name, ty) => {
                                let at = take(&mut o, ty.size(), &e.name)?;
                                let v = ty.read(&body[at..], big);
                                if let Some(c) = ["x", "y", "z"].iter().position(|c| c == name) {
                                    xyz[c] = v;
                                }
                            }
                            PlyProp::List(name, ct, it) => {
                                let at = take(&mut o, ct.size(), &e.name)?;
                                let n = ct.read(&body[at..], big);
                                if !(0.0..=1e6).contains(&n) {
                                    return Err((
                                        MeshPlace::Binary(format!("byte {start}")),
                                        format!("list length {n}"),
                                    ));
                                }
                                for _ in 0..n as usize {
                                    let at = take(&mut o, it.size(), &e.name)?;
                                    if name.starts_with("vertex_ind") {
                                        let v = it.read(&body[at..], big);
                                        face.push(ply_index(v, 0).map_err(|(_, m)| {
                                            (
                                                MeshPlace::Binary(format!(
                                                    "{} {} (byte {start})",
                                                    e.name,
                                                    k + 1
                                                )),
                                                m,
                                            )
                                        })?);
                                    }
                                }
                            }
                        }
                    }
                    ply_item(e, xyz, &face, &mut mesh, &mut origins, start, true)?;
                }
            }
        }
    }
    Ok(Parsed { mesh, origins })
}

fn ply_index(v: f64, at: usize) -> Result<u32, (MeshPlace, String)> {
    if v >= 0.0 && v < u32::MAX as f64 && v.fract() == 0.0 {
        Ok(v as u32)
    } else {
        Err((at_line(at), format!("bad vertex index {v}")))
    }
}

fn ply_item(
    e: &PlyElement,
    xyz: [f64; 3],
    face: &[u32],
    mesh: &mut Mesh,
    origins: &mut Origins,
    at: usize,
    binary: bool,
) -> Result<(), (MeshPlace, String)> {
    let place = |at: usize| {
        if binary {
            MeshPlace::Binary(format!("byte {at}"))
        } else {
            at_line(at)
        }
    };
    match e.name.as_str() {
        "vertex" => {
            if !xyz.iter().all(|v| v.is_finite()) {
                return Err((place(at), "a vertex without finite x, y, z".into()));
            }
            crate::math::limits::coordinates(&xyz).map_err(|m| (place(at), m.to_string()))?;
            mesh.vertices.push(Point3::new(xyz[0], xyz[1], xyz[2]));
        }
        "face" => {
            if face.len() < 3 {
                return Err((place(at), format!("a face with {} vertices", face.len())));
            }
            for k in 1..face.len() - 1 {
                mesh.triangles.push([face[0], face[k], face[k + 1]]);
                if binary {
                    origins.push_byte(at);
                } else {
                    origins.push_line(at);
                }
            }
        }
        _ => {}
    }
    Ok(())
}

/// Write `mesh` as binary STL (f32 coordinates, facet normals from the winding).
pub fn write_stl(mesh: &Mesh, out: &mut dyn Write) -> std::io::Result<()> {
    let mut header = [0u8; 80];
    let title = b"crest design surface, mm";
    header[..title.len()].copy_from_slice(title);
    out.write_all(&header)?;
    out.write_all(&(mesh.triangles.len() as u32).to_le_bytes())?;
    for t in 0..mesh.triangles.len() {
        let n = mesh.face_normal(t);
        for v in [n.x, n.y, n.z] {
            out.write_all(&(v as f32).to_le_bytes())?;
        }
        for &i in &mesh.triangles[t] {
            let p = mesh.vertices[i as usize];
            for v in [p.x, p.y, p.z] {
                out.write_all(&(v as f32).to_le_bytes())?;
            }
        }
        out.write_all(&[0, 0])?;
    }
    Ok(())
}

/// Write a part map as an ASCII PLY point cloud: `x y z nx ny nz height_um` per point (NaN
/// written as `nan` for nodes no tooth reached).
pub fn write_map_ply(points: &[MapPoint], out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "ply")?;
    writeln!(out, "format ascii 1.0")?;
    writeln!(
        out,
        "comment crest part map: heights along the normal, µm; nan = not reached"
    )?;
    writeln!(out, "element vertex {}", points.len())?;
    for p in ["x", "y", "z", "nx", "ny", "nz", "height_um"] {
        writeln!(out, "property float {p}")?;
    }
    writeln!(out, "end_header")?;
    for m in points {
        let h = if m.height_um.is_finite() {
            format!("{:.4}", m.height_um)
        } else {
            "nan".to_string()
        };
        writeln!(
            out,
            "{:.6} {:.6} {:.6} {:.6} {:.6} {:.6} {h}",
            m.point.x, m.point.y, m.point.z, m.normal.x, m.normal.y, m.normal.z
        )?;
    }
    Ok(())
}

/// Read a part map written by [`write_map_ply`] (or any PLY point cloud with x, y, z and
/// `height_um`; normals optional).
pub fn read_map_ply(path: &Path) -> Result<Vec<MapPoint>, MeshFileError> {
    read_map_ply_column(path, "height_um")
}

/// [`read_map_ply`] with the value of each point taken from property `column` (any float
/// property of the cloud, e.g. `Sa_um` of `crest atlas`'s cloud) instead of `height_um`.
pub fn read_map_ply_column(path: &Path, column: &str) -> Result<Vec<MapPoint>, MeshFileError> {
    let file = path.display().to_string();
    let bytes = super::input::read_staged(path, "part map", |head| {
        super::input::text_stage(head, super::input::MESH)
    })
    .map_err(|e| MeshFileError {
        file: file.clone(),
        at: MeshPlace::file(),
        message: e.detail(),
    })?;
    let text = String::from_utf8(bytes).map_err(|e| MeshFileError {
        file: file.clone(),
        at: MeshPlace::file(),
        message: format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
    })?;
    let err = |line: usize, message: String| MeshFileError {
        file: file.clone(),
        at: at_line(line),
        message,
    };
    let mut lines = text.lines().enumerate();
    let mut props: Vec<String> = Vec::new();
    let mut count = 0usize;
    let mut ascii = false;
    for (i, l) in lines.by_ref() {
        let t: Vec<&str> = l.split_whitespace().collect();
        match t.as_slice() {
            ["format", "ascii", _] => ascii = true,
            ["element", "vertex", n] => {
                count = n
                    .parse()
                    .map_err(|_| err(i + 1, format!("bad count `{n}`")))?
            }
            ["property", _, name] => props.push(name.to_string()),
            ["end_header"] => break,
            _ => {}
        }
    }
    if !ascii {
        return Err(err(1, "only ASCII PLY part maps are read".into()));
    }
    let col = |n: &str| props.iter().position(|p| p == n);
    let (Some(x), Some(y), Some(z), Some(h)) = (col("x"), col("y"), col("z"), col(column)) else {
        return Err(err(
            1,
            format!(
                "a point cloud needs x, y, z and {column} properties (it has {})",
                props.join(", ")
            ),
        ));
    };
    let normal = (col("nx"), col("ny"), col("nz"));
    let mut out = Vec::new();
    for (i, l) in lines {
        if out.len() == count {
            break;
        }
        let v: Vec<f64> = l
            .split_whitespace()
            .map(|t| t.parse::<f64>().unwrap_or(f64::NAN))
            .collect();
        if v.len() < props.len() {
            return Err(err(
                i + 1,
                format!("{} values for {} properties", v.len(), props.len()),
            ));
        }
        let n = match normal {
            (Some(a), Some(b), Some(c)) => Vec3::new(v[a], v[b], v[c]),
            _ => Vec3::zeros(),
        };
        out.push(MapPoint {
            point: Point3::new(v[x], v[y], v[z]),
            normal: n,
            height_um: v[h],
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str, bytes: &[u8]) -> (tempfile::TempDir, std::path::PathBuf) {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        (d, p)
    }

    fn quad() -> Mesh {
        Mesh {
            vertices: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(1.0, 1.0, 0.0),
                Point3::new(0.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn binary_stl_round_trips_and_a_lying_count_is_refused() {
        let mut buf = Vec::new();
        write_stl(&quad(), &mut buf).unwrap();
        assert_eq!(buf.len(), 84 + 100);
        let (_d, p) = tmp("q.stl", &buf);
        let f = read_part(&p).unwrap();
        assert_eq!(f.triangles, 2);
        assert_eq!(f.part.mesh().vertices.len(), 4);
        // Truncated: the header still says 2.
        let (_d, p) = tmp("t.stl", &buf[..150]);
        let e = read_part(&p).unwrap_err().to_string();
        assert!(
            e.contains("t.stl:1:") && e.contains("says 2 triangles"),
            "{e}"
        );
        // A count that lies.
        let mut lie = buf.clone();
        lie[80] = 7;
        let (_d, p) = tmp("l.stl", &lie);
        assert!(
            read_part(&p)
                .unwrap_err()
                .to_string()
                .contains("says 7 triangles")
        );
        // A NaN vertex.
        let mut nan = buf.clone();
        nan[84 + 50 + 12..84 + 50 + 16].copy_from_slice(&f32::NAN.to_le_bytes());
        let (_d, p) = tmp("n.stl", &nan);
        let e = read_part(&p).unwrap_err().to_string();
        assert!(
            e.contains("triangle 2 (byte 146)") && e.contains("not finite"),
            "{e}"
        );
    }

    #[test]
    fn ascii_stl_errors_name_the_line() {
        let good = "solid q\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\n\
                    facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid q\n";
        let (_d, p) = tmp("a.stl", good.as_bytes());
        assert_eq!(read_part(&p).unwrap().triangles, 2);
        let (_d, p) = tmp(
            "a.stl",
            good.replace("vertex 1 1 0\nendloop", "vertex 1 x 0\nendloop")
                .as_bytes(),
        );
        let e = read_part(&p).unwrap_err().to_string();
        assert!(e.contains("a.stl:6:") && e.contains("`x`"), "{e}");
        // The second facet wound the other way (its stored normal agrees with the flip).
        let flipped = good.replace(
            "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\nvertex 0 1 0",
            "facet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\nvertex 1 1 0",
        );
        let (_d, p) = tmp("w.stl", flipped.as_bytes());
        let e = read_part(&p).unwrap_err().to_string();
        assert!(e.contains("w.stl:9:") && e.contains("wound against"), "{e}");
        // A stored normal against the winding.
        let (_d, p) = tmp(
            "s.stl",
            good.replacen("facet normal 0 0 1", "facet normal 0 0 -1", 1)
                .as_bytes(),
        );
        let e = read_part(&p).unwrap_err().to_string();
        assert!(
            e.contains("s.stl:2:") && e.contains("against the winding"),
            "{e}"
        );
        // Duplicate facet.
        let dup = good.replace("endsolid q\n", "facet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 0 0\nendloop\nendfacet\nendsolid q\n");
        let (_d, p) = tmp("d.stl", dup.as_bytes());
        let e = read_part(&p).unwrap_err().to_string();
        assert!(
            e.contains("d.stl:16:") && e.contains("repeats triangle 1"),
            "{e}"
        );
        let (_d, p) = tmp("e.stl", b"solid empty\nendsolid empty\n");
        assert!(
            read_part(&p)
                .unwrap_err()
                .to_string()
                .contains("no triangle")
        );
    }

    #[test]
    fn obj_and_ply_read_with_degenerate_warnings() {
        let obj = "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3 4\nf 1 2/1 5//1\n";
        let (_d, p) = tmp("q.obj", obj.as_bytes());
        let f = read_part(&p).unwrap();
        assert_eq!(f.triangles, 2);
        assert_eq!(f.warnings.len(), 1);
        assert!(
            f.warnings[0].contains("q.obj:8:") && f.warnings[0].contains("degenerate"),
            "{:?}",
            f.warnings
        );
        let (_d, p) = tmp("b.obj", b"v 0 0 0\nv 1 0 0\nf 1 2 9\n");
        assert!(read_part(&p).unwrap_err().to_string().contains("b.obj:3:"));
        let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                   element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let (_d, p) = tmp("q.ply", ply.as_bytes());
        assert_eq!(read_part(&p).unwrap().triangles, 2);
        // Binary little endian, the same quad; then cut short.
        let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
        for v in [
            [0.0f32, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ] {
            for c in v {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        bin.push(4);
        for i in [0i32, 1, 2, 3] {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        let (_d, p) = tmp("b.ply", &bin);
        assert_eq!(read_part(&p).unwrap().triangles, 2);
        let (_d, p) = tmp("c.ply", &bin[..bin.len() - 3]);
        assert!(
            read_part(&p)
                .unwrap_err()
                .to_string()
                .contains("ends inside face")
        );
    }

    #[test]
    fn part_maps_round_trip() {
        let pts = vec![
            MapPoint {
                point: Point3::new(1.0, 2.0, 3.0),
                normal: Vec3::z(),
                height_um: 1.25,
            },
            MapPoint {
                point: Point3::new(1.0, 2.1, 3.0),
                normal: Vec3::z(),
                height_um: f64::NAN,
            },
        ];
        let mut buf = Vec::new();
        write_map_ply(&pts, &mut buf).unwrap();
        let (_d, p) = tmp("m.ply", &buf);
        let back = read_map_ply(&p).unwrap();
        assert_eq!(back.len(), 2);
        assert_eq!(back[0].height_um, 1.25);
        assert!(back[1].height_um.is_nan());
    }
}
