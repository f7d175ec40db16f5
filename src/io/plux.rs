//! Sensofar `.plux` files (SensoVIEW, S neox): a zip archive of an XML index and binary
//! layers; the height layer is read.
//!
//! `index.xml` gives `GENERAL/IMAGE_SIZE_X`, `IMAGE_SIZE_Y` (nodes) and `FOV_X`, `FOV_Y`
//! (the spacing between nodes, µm, as surfalize reads them); `LAYER_0.raw` holds the
//! heights, `IMAGE_SIZE_X × IMAGE_SIZE_Y` float32 µm (little-endian, x fastest, row 0
//! first; more bytes may follow). A NaN, or 1000001 as in `.plu` (1 m: no surface height;
//! surfalize keeps it as a height), is a point not measured.
//! Each entry is decompressed within a budget (the layer to the size the index gives).

use std::io::Cursor;

use super::FormatError;
use super::binary;
use crate::surface::HeightMap;

const INDEX: &str = "index.xml";
const LAYER: &str = "LAYER_0.raw";

/// Whether the first bytes of a zip archive name a `.plux` entry (an `.x3p` starts with
/// `main.xml`).
pub(crate) fn looks_like(head: &[u8]) -> bool {
    super::x3p::is_zip(head)
        && [INDEX.as_bytes(), b"LAYER_0"]
            .iter()
            .any(|n| memchr::memmem::find(&head[..head.len().min(4096)], n).is_some())
}

pub(crate) fn parse(bytes: &[u8]) -> Result<HeightMap, FormatError> {
    let mut zip = zip::ZipArchive::new(Cursor::new(bytes)).map_err(|e| {
        FormatError::file(format!(
            "not a readable .plux (a .plux is a zip archive): {e}"
        ))
    })?;
    let xml = super::x3p::entry(&mut zip, INDEX, 64 << 20)?;
    let text = std::str::from_utf8(&xml)
        .map(str::to_string)
        .unwrap_or_else(|_| binary::latin1(&xml));
    let doc = roxmltree::Document::parse_with_options(
        &text,
        roxmltree::ParsingOptions {
            allow_dtd: false,
            ..Default::default()
        },
    )
    .map_err(|e| FormatError::file(format!("{INDEX}: {e}")))?;
    let general = doc
        .root_element()
        .children()
        .find(|c| c.has_tag_name("GENERAL"))
        .ok_or_else(|| FormatError::file(format!("{INDEX} has no GENERAL element")))?;
    let value = |name: &str| -> Result<f64, FormatError> {
        let node = general
            .children()
            .find(|c| c.has_tag_name(name))
            .ok_or_else(|| FormatError::file(format!("{INDEX} has no GENERAL/{name}")))?;
        let t = node.text().unwrap_or("").trim();
        t.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                let p = doc.text_pos_at(node.range().start);
                FormatError::file(format!(
                    "{INDEX} line {}: GENERAL/{name} is {t:?}, not a number",
                    p.row
                ))
            })
    };
    let whole = |name: &str| -> Result<i64, FormatError> {
        let v = value(name)?;
        if v.fract() != 0.0 || v.abs() > 1e12 {
            return Err(FormatError::file(format!(
                "{INDEX}: GENERAL/{name} is {v}, not a whole number"
            )));
        }
        Ok(v as i64)
    };
    let (nx, ny) = (whole("IMAGE_SIZE_X")?, whole("IMAGE_SIZE_Y")?);
    let stored = zip
        .by_name(LAYER)
        .map(|f| f.size())
        .map_err(|_| FormatError::file(format!("the archive has no {LAYER}")))?;
    let n = binary::nodes(
        nx,
        ny,
        4,
        usize::try_from(stored).unwrap_or(usize::MAX),
        &format!("{LAYER}: IMAGE_SIZE_X × IMAGE_SIZE_Y"),
    )?;
    let raw = super::x3p::entry(&mut zip, LAYER, 4 * n as u64)?;
    if raw.len() < 4 * n {
        return Err(FormatError::file(format!(
            "{LAYER} holds {} bytes, fewer than the {} of IMAGE_SIZE_X × IMAGE_SIZE_Y float32 heights",
            raw.len(),
            4 * n
        )));
    }
    let z = raw
        .chunks_exact(4)
        .take(n)
        .map(|b| match f32::from_le_bytes([b[0], b[1], b[2], b[3]]) {
            1_000_001.0 => f64::NAN,
            v => f64::from(v),
        })
        .collect();
    let dx = binary::spacing(value("FOV_X")?, "GENERAL/FOV_X")?;
    let dy = binary::spacing(value("FOV_Y")?, "GENERAL/FOV_Y")?;
    binary::finish(nx as usize, ny as usize, (dx, dy), (0.0, 0.0), z)
}
