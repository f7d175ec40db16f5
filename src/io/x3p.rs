//! ISO 25178-72 / ISO 5436-2 XML surface files (`.x3p`, OpenGPS): the file MountainsMap,
//! Gwyddion and most confocal, white-light and focus-variation instruments export.
//!
//! An `.x3p` is a zip archive: `main.xml` (axes, sizes, metadata), `md5checksum.hex` (the
//! MD5 of `main.xml`), and, unless the heights are listed in the XML (`Record3/DataList`),
//! the binary heights (`Record3/DataLink/PointDataLink`, usually `bindata/data.bin`:
//! little-endian, x fastest) with, for integer data, a validity bit mask
//! (`ValidPointsLink`, one bit per point, least significant first, set = measured).
//!
//! Read: surfaces (`FeatureType` `SUR`) on a regular grid (`CX`, `CY` incremental), one layer,
//! the four point types `I` (int16), `L` (int32), `F` (float32) and `D` (float64); height =
//! stored value × `CZ/Increment` + `CZ/Offset` (metres), as the standard and surfalize read
//! it; not-measured points (mask bit clear, NaN or infinite) are NaN; `CX`/`CY` `Offset` is
//! the origin. Both checksums (of `main.xml`, and of the point data when the XML gives one)
//! are verified. Written: float64 (`D`) heights in metres, NaN for missing nodes, no mask.
//!
//! Every entry is read within a budget (the point data to exactly the size the XML gives),
//! so a zip bomb costs no more than a valid file of the node limit.

use std::io::{Cursor, Read, Write};

use md5::{Digest, Md5};

use super::FormatError;
use crate::surface::HeightMap;

/// The XML of an x3p, at most: a `DataList` of some 30 million heights.
const MAX_XML_BYTES: u64 = 1 << 30;
/// The name crest writes the point data under.
const POINT_DATA: &str = "bindata/data.bin";
const NAMESPACE: &str = "http://www.opengps.eu/2008/ISO5436_2";

/// The first bytes of a zip archive (an `.x3p`).
pub(crate) fn is_zip(head: &[u8]) -> bool {
    head.starts_with(b"PK\x03\x04")
}

/// Read an entry of the archive whole, refusing past `limit` bytes (decompressed).
pub(crate) fn entry(
    zip: &mut zip::ZipArchive<Cursor<&[u8]>>,
    name: &str,
    limit: u64,
) -> Result<Vec<u8>, FormatError> {
    let file = zip.by_name(name).map_err(|e| match e {
        zip::result::ZipError::FileNotFound => {
            FormatError::file(format!("the archive has no {name}"))
        }
        e => FormatError::file(format!("{name}: {e}")),
    })?;
    let mut out = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut out)
        .map_err(|e| FormatError::file(format!("{name}: cannot decompress ({e})")))?;
    if out.len() as u64 > limit {
        return Err(FormatError::file(format!(
            "{name} decompresses to more than {limit} bytes, more than its header allows"
        )));
    }
    Ok(out)
}

fn md5_hex(bytes: &[u8]) -> String {
    Md5::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The XML of `main.xml`, with the position of a node for messages.
struct Xml<'a> {
    doc: &'a roxmltree::Document<'a>,
}

impl<'a> Xml<'a> {
    fn at(&self, node: roxmltree::Node) -> String {
        let p = self.doc.text_pos_at(node.range().start);
        format!("main.xml line {}, column {}", p.row, p.col)
    }

    /// The element at `path` (`/`-separated local names) under `node`.
    fn find(&self, node: roxmltree::Node<'a, 'a>, path: &str) -> Option<roxmltree::Node<'a, 'a>> {
        let mut n = node;
        for name in path.split('/') {
            n = n
                .children()
                .find(|c| c.is_element() && c.tag_name().name() == name)?;
        }
        Some(n)
    }

    /// The text of the element at `path`, which must exist.
    fn text(
        &self,
        node: roxmltree::Node<'a, 'a>,
        base: &str,
        path: &str,
    ) -> Result<(&'a str, roxmltree::Node<'a, 'a>), FormatError> {
        let n = self.find(node, path).ok_or_else(|| {
            FormatError::file(format!(
                "main.xml has no {base}/{path} (at {})",
                self.at(node)
            ))
        })?;
        Ok((n.text().unwrap_or("").trim(), n))
    }

    fn number(
        &self,
        node: roxmltree::Node<'a, 'a>,
        base: &str,
        path: &str,
    ) -> Result<f64, FormatError> {
        let (t, n) = self.text(node, base, path)?;
        t.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                FormatError::file(format!(
                    "{base}/{path} at {} is {t:?}, not a finite number",
                    self.at(n)
                ))
            })
    }

    fn size(&self, node: roxmltree::Node<'a, 'a>, path: &str) -> Result<usize, FormatError> {
        let (t, n) = self.text(node, "Record3", path)?;
        t.parse::<usize>().ok().filter(|&v| v > 0).ok_or_else(|| {
            FormatError::file(format!(
                "Record3/{path} at {} is {t:?}, not a positive whole number",
                self.at(n)
            ))
        })
    }
}

/// The stored point type of `CZ/DataType`.
#[derive(Clone, Copy)]
enum PointType {
    I16,
    I32,
    F32,
    F64,
}

impl PointType {
    fn bytes(self) -> usize {
        match self {
            PointType::I16 => 2,
            PointType::I32 | PointType::F32 => 4,
            PointType::F64 => 8,
        }
    }
    fn value(self, b: &[u8]) -> f64 {
        match self {
            PointType::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            PointType::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            PointType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            PointType::F64 => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    }
}

pub(crate) fn parse(bytes: &[u8]) -> Result<HeightMap, FormatError> {
    let mut zip = zip::ZipArchive::new(Cursor::new(bytes)).map_err(|e| {
        FormatError::file(format!("not a readable x3p (an x3p is a zip archive): {e}"))
    })?;
    let xml_bytes = entry(&mut zip, "main.xml", MAX_XML_BYTES)?;
    let sum = entry(&mut zip, "md5checksum.hex", 4096)?;
    let stated = String::from_utf8_lossy(&sum)
        .split_whitespace()
        .next()
        .unwrap_or("")
        .to_ascii_lowercase();
    let actual = md5_hex(&xml_bytes);
    if stated != actual {
        return Err(FormatError::file(format!(
            "md5checksum.hex gives {stated:?} but main.xml's MD5 is {actual}: the file is damaged"
        )));
    }
    let text = std::str::from_utf8(&xml_bytes).map_err(|e| {
        FormatError::file(format!(
            "main.xml is not UTF-8 text (byte {})",
            e.valid_up_to()
        ))
    })?;
    let doc = roxmltree::Document::parse_with_options(
        text,
        roxmltree::ParsingOptions {
            allow_dtd: false,
            ..Default::default()
        },
    )
    .map_err(|e| FormatError::file(format!("main.xml: {e}")))?;
    let x = Xml { doc: &doc };
    let root = doc.root_element();
    if root.tag_name().name() != "ISO5436_2" {
        return Err(FormatError::file(format!(
            "main.xml's root element is <{}>, not <ISO5436_2>",
            root.tag_name().name()
        )));
    }
    let r1 = x
        .find(root, "Record1")
        .ok_or_else(|| FormatError::file("main.xml has no Record1 (the axes)"))?;
    let r3 = x
        .find(root, "Record3")
        .ok_or_else(|| FormatError::file("main.xml has no Record3 (the sizes and the data)"))?;
    let (feature, n) = x.text(r1, "Record1", "FeatureType")?;
    if feature != "SUR" {
        return Err(FormatError::file(format!(
            "Record1/FeatureType at {} is {feature:?}: crest reads surfaces (SUR), not profiles (PRF) or point clouds (PCL)",
            x.at(n)
        )));
    }
    let mut step = [0.0; 2];
    let mut offset = [0.0; 2];
    for (k, axis) in ["CX", "CY"].into_iter().enumerate() {
        let base = format!("Record1/Axes/{axis}");
        let a = x
            .find(r1, &format!("Axes/{axis}"))
            .ok_or_else(|| FormatError::file(format!("main.xml has no {base}")))?;
        let (kind, n) = x.text(a, &base, "AxisType")?;
        if kind != "I" {
            return Err(FormatError::file(format!(
                "{base}/AxisType at {} is {kind:?}: only incremental (I) x and y axes, a regular grid, are read",
                x.at(n)
            )));
        }
        step[k] = x.number(a, &base, "Increment")?;
        if step[k] <= 0.0 {
            return Err(FormatError::file(format!(
                "{base}/Increment is {} m: the spacing must be positive",
                step[k]
            )));
        }
        offset[k] = match x.find(a, "Offset") {
            Some(_) => x.number(a, &base, "Offset")?,
            None => 0.0,
        };
    }
    let cz = x
        .find(r1, "Axes/CZ")
        .ok_or_else(|| FormatError::file("main.xml has no Record1/Axes/CZ"))?;
    let (dt, n) = x.text(cz, "Record1/Axes/CZ", "DataType")?;
    let ty = match dt {
        "I" => PointType::I16,
        "L" => PointType::I32,
        "F" => PointType::F32,
        "D" => PointType::F64,
        _ => {
            return Err(FormatError::file(format!(
                "Record1/Axes/CZ/DataType at {} is {dt:?}, not I, L, F or D",
                x.at(n)
            )));
        }
    };
    let z_inc = match x.find(cz, "Increment") {
        Some(_) => x.number(cz, "Record1/Axes/CZ", "Increment")?,
        None => 1.0,
    };
    let z_off = match x.find(cz, "Offset") {
        Some(_) => x.number(cz, "Record1/Axes/CZ", "Offset")?,
        None => 0.0,
    };
    let nx = x.size(r3, "MatrixDimension/SizeX")?;
    let ny = x.size(r3, "MatrixDimension/SizeY")?;
    let nz = x.size(r3, "MatrixDimension/SizeZ")?;
    if nz != 1 {
        return Err(FormatError::file(format!(
            "Record3/MatrixDimension/SizeZ is {nz}: crest reads one layer of heights"
        )));
    }
    let nodes = nx
        .checked_mul(ny)
        .filter(|&n| n <= crate::math::limits::MAX_NODES)
        .ok_or_else(|| {
            FormatError::file(format!(
                "Record3/MatrixDimension gives {nx} × {ny} points, more than the {} nodes crest reads",
                crate::math::limits::MAX_NODES
            ))
        })?;
    let raw: Vec<f64> = if let Some(link) = x.find(r3, "DataLink") {
        let (name, _) = x.text(link, "Record3/DataLink", "PointDataLink")?;
        let want = (nodes * ty.bytes()) as u64;
        let data = entry(&mut zip, name, want)?;
        if data.len() as u64 != want {
            return Err(FormatError::file(format!(
                "{name} holds {} bytes, but SizeX × SizeY = {nx} × {ny} points of {} bytes are {want}",
                data.len(),
                ty.bytes()
            )));
        }
        if let Some(sum) = x.find(link, "MD5ChecksumPointData") {
            let stated = sum.text().unwrap_or("").trim().to_ascii_lowercase();
            let actual = md5_hex(&data);
            if !stated.is_empty() && stated != actual {
                return Err(FormatError::file(format!(
                    "Record3/DataLink/MD5ChecksumPointData at {} gives {stated:?} but {name}'s MD5 is {actual}: the file is damaged",
                    x.at(sum)
                )));
            }
        }
        let mut raw: Vec<f64> = data.chunks_exact(ty.bytes()).map(|b| ty.value(b)).collect();
        if let Some(v) = x.find(link, "ValidPointsLink") {
            let vname = v.text().unwrap_or("").trim();
            let bits = entry(&mut zip, vname, nodes.div_ceil(8) as u64)?;
            if bits.len() < nodes.div_ceil(8) {
                return Err(FormatError::file(format!(
                    "{vname} holds {} bytes, fewer than the {} bits of {nx} × {ny} points",
                    bits.len(),
                    nodes
                )));
            }
            for (k, r) in raw.iter_mut().enumerate() {
                if bits[k / 8] >> (k % 8) & 1 == 0 {
                    *r = f64::NAN;
                }
            }
        }
        raw
    } else if let Some(list) = x.find(r3, "DataList") {
        let mut raw = Vec::with_capacity(nodes);
        for d in list
            .children()
            .filter(|c| c.is_element() && c.tag_name().name() == "Datum")
        {
            if raw.len() == nodes {
                return Err(FormatError::file(format!(
                    "Record3/DataList has more than SizeX × SizeY = {nodes} Datum elements (at {})",
                    x.at(d)
                )));
            }
            let t = d.text().unwrap_or("").trim();
            // With incremental x and y only z is stored; a Datum "x;y;z" gives its last value.
            let z = t.rsplit(';').next().unwrap_or("").trim();
            raw.push(if z.is_empty() {
                f64::NAN
            } else {
                z.parse::<f64>().map_err(|_| {
                    FormatError::file(format!(
                        "Record3/DataList/Datum {} at {} is {t:?}, not a number",
                        raw.len() + 1,
                        x.at(d)
                    ))
                })?
            });
        }
        if raw.len() != nodes {
            return Err(FormatError::file(format!(
                "Record3/DataList has {} Datum elements, but SizeX × SizeY = {nx} × {ny} = {nodes}",
                raw.len()
            )));
        }
        raw
    } else {
        return Err(FormatError::file(
            "Record3 has neither a DataLink (binary heights) nor a DataList",
        ));
    };
    let z_um: Vec<f64> = raw
        .into_iter()
        .map(|r| {
            let z = (r * z_inc + z_off) * 1e6;
            if z.is_finite() { z } else { f64::NAN }
        })
        .collect();
    if z_um.iter().all(|z| z.is_nan()) {
        return Err(FormatError::file(format!(
            "every one of the {nx} × {ny} points is marked not measured"
        )));
    }
    Ok(HeightMap {
        nx,
        ny,
        dx_um: step[0] * 1e6,
        dy_um: step[1] * 1e6,
        x0_mm: offset[0] * 1e3,
        y0_mm: offset[1] * 1e3,
        z_um,
    })
}

/// Shortest round-trip text of a number, as `xsd:double` takes it.
fn num(v: f64) -> String {
    format!("{v:?}")
}

/// The date crest writes (ISO 8601, UTC): `SOURCE_DATE_EPOCH` when set (reproducible
/// outputs), else now.
fn date() -> String {
    let secs = std::env::var("SOURCE_DATE_EPOCH")
        .ok()
        .and_then(|s| s.trim().parse::<i64>().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs() as i64)
        });
    civil(secs)
}

/// Seconds since 1970-01-01T00:00:00Z as an ISO 8601 UTC date and time.
fn civil(secs: i64) -> String {
    let [y, m, d, hh, mm, ss] = super::civil_utc(secs);
    format!("{y:04}-{m:02}-{d:02}T{hh:02}:{mm:02}:{ss:02}Z")
}

fn main_xml(map: &HeightMap, data_md5: &str) -> String {
    let date = date();
    let axis = |name: &str, step_um: f64, origin_mm: f64| {
        format!(
            "      <{name}>\n        <AxisType>I</AxisType>\n        <DataType>D</DataType>\n        <Increment>{}</Increment>\n        <Offset>{}</Offset>\n      </{name}>\n",
            num(step_um * 1e-6),
            num(origin_mm * 1e-3)
        )
    };
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n\
<p:ISO5436_2 xmlns:p=\"{NAMESPACE}\" xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" xsi:schemaLocation=\"{NAMESPACE} {NAMESPACE}/ISO5436_2.xsd\">\n\
  <Record1>\n    <Revision>ISO5436 - 2000</Revision>\n    <FeatureType>SUR</FeatureType>\n    <Axes>\n\
{}{}      <CZ>\n        <AxisType>A</AxisType>\n        <DataType>D</DataType>\n        <Increment>1</Increment>\n        <Offset>0</Offset>\n      </CZ>\n    </Axes>\n  </Record1>\n\
  <Record2>\n    <Date>{date}</Date>\n    <Creator>crest</Creator>\n    <Instrument>\n      <Manufacturer>crest</Manufacturer>\n      <Model>simulation</Model>\n      <Serial>not available</Serial>\n      <Version>{}</Version>\n    </Instrument>\n    <CalibrationDate>{date}</CalibrationDate>\n    <ProbingSystem>\n      <Type>Software</Type>\n      <Identification>crest</Identification>\n    </ProbingSystem>\n    <Comment>Written by crest {}; heights in metres, NaN where no node was reached</Comment>\n  </Record2>\n\
  <Record3>\n    <MatrixDimension>\n      <SizeX>{}</SizeX>\n      <SizeY>{}</SizeY>\n      <SizeZ>1</SizeZ>\n    </MatrixDimension>\n    <DataLink>\n      <PointDataLink>{POINT_DATA}</PointDataLink>\n      <MD5ChecksumPointData>{}</MD5ChecksumPointData>\n    </DataLink>\n  </Record3>\n\
  <Record4>\n    <ChecksumFile>md5checksum.hex</ChecksumFile>\n  </Record4>\n</p:ISO5436_2>\n",
        axis("CX", map.dx_um, map.x0_mm),
        axis("CY", map.dy_um, map.y0_mm),
        env!("CARGO_PKG_VERSION"),
        env!("CARGO_PKG_VERSION"),
        map.nx,
        map.ny,
        data_md5.to_ascii_uppercase()
    )
}

/// Write `map` as an x3p: float64 heights in metres (NaN for missing nodes), deflated.
pub(crate) fn write(w: &mut dyn Write, map: &HeightMap) -> std::io::Result<()> {
    let mut data = Vec::with_capacity(map.z_um.len() * 8);
    for z in &map.z_um {
        data.extend_from_slice(&(z * 1e-6).to_le_bytes());
    }
    let xml = main_xml(map, &md5_hex(&data));
    let sum = format!("{} *main.xml\n", md5_hex(xml.as_bytes()));
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .last_modified_time(zip::DateTime::default());
    let io = |e: zip::result::ZipError| std::io::Error::other(e.to_string());
    zip.start_file("main.xml", opts).map_err(io)?;
    zip.write_all(xml.as_bytes())?;
    zip.start_file(POINT_DATA, opts).map_err(io)?;
    zip.write_all(&data)?;
    zip.start_file("md5checksum.hex", opts).map_err(io)?;
    zip.write_all(sum.as_bytes())?;
    let bytes = zip.finish().map_err(io)?.into_inner();
    w.write_all(&bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_are_civil() {
        // Python's datetime.fromtimestamp(s, timezone.utc) for each.
        assert_eq!(civil(0), "1970-01-01T00:00:00Z");
        assert_eq!(civil(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(civil(1_796_512_345), "2026-12-05T23:12:25Z");
        assert_eq!(civil(-86_400), "1969-12-31T00:00:00Z");
    }

    #[test]
    fn written_maps_read_back_bit_for_bit() {
        let map = HeightMap {
            nx: 3,
            ny: 2,
            dx_um: 0.5,
            dy_um: 0.25,
            x0_mm: 1.5,
            y0_mm: -2.0,
            z_um: vec![0.1, -2.5, f64::NAN, 3.0e-3, 1234.5678, 0.0],
        };
        let mut bytes = Vec::new();
        write(&mut bytes, &map).unwrap();
        assert!(is_zip(&bytes));
        let back = parse(&bytes).unwrap();
        assert_eq!((back.nx, back.ny), (3, 2));
        assert_eq!((back.dx_um, back.dy_um), (0.5, 0.25));
        assert_eq!((back.x0_mm, back.y0_mm), (1.5, -2.0));
        for (a, b) in map.z_um.iter().zip(&back.z_um) {
            // µm → m → µm: within one rounding of each multiplication.
            assert!(
                a.is_nan() && b.is_nan() || (a - b).abs() <= 2e-16 * a.abs(),
                "{a} {b}"
            );
        }
    }
}
