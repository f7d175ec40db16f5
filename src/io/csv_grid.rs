//! Grid CSV: one line per row (row 0 = y0, y ascending), one field per column (x ascending),
//! heights in µm. Separators `,` `;` tab or blanks (chosen from the first data line); lines
//! starting with `#` and blank lines are skipped; one all-text header line is tolerated.
//! The file carries no spacing: the caller supplies it.

use std::io::Write;

use super::{FormatError, fmt_value, parse_value};
use crate::surface::HeightMap;

/// Field separator of a line.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Sep {
    Char(char),
    Blank,
}

pub(crate) fn detect_sep(line: &str) -> Sep {
    for c in [',', ';', '\t'] {
        if line.contains(c) {
            return Sep::Char(c);
        }
    }
    Sep::Blank
}

pub(crate) fn split(line: &str, sep: Sep) -> Vec<&str> {
    match sep {
        Sep::Char(c) => line.split(c).collect(),
        Sep::Blank => line.split_whitespace().collect(),
    }
}

pub(crate) fn parse(text: &str, dx_um: f64, dy_um: f64) -> Result<HeightMap, FormatError> {
    let mut z = Vec::new();
    let mut nx = 0usize;
    let mut ny = 0usize;
    let mut sep = None;
    let mut header_seen = false;
    for (idx, raw) in text.lines().enumerate() {
        let line_no = idx + 1;
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let s = *sep.get_or_insert_with(|| detect_sep(line));
        let fields = split(line, s);
        if ny == 0 && !header_seen && fields.iter().all(|f| parse_value(f).is_none()) {
            header_seen = true;
            continue;
        }
        if ny == 0 {
            nx = fields.len();
        } else if fields.len() != nx {
            return Err(FormatError::line(
                line_no,
                0,
                format!(
                    "row has {} fields, the first row had {nx} (a grid CSV must be rectangular)",
                    fields.len()
                ),
            ));
        }
        for (k, f) in fields.iter().enumerate() {
            match parse_value(f) {
                Some(v) => z.push(v),
                None => {
                    return Err(FormatError::line(
                        line_no,
                        k + 1,
                        format!(
                            "expected a finite height in µm within ±1e6 (or NaN), found {:?}",
                            f.trim()
                        ),
                    ));
                }
            }
        }
        ny += 1;
    }
    if ny == 0 || nx == 0 {
        return Err(FormatError::file("no data rows found"));
    }
    HeightMap::from_rows(nx, ny, dx_um, dy_um, z)
        .ok_or_else(|| FormatError::file("internal: row count mismatch"))
}

/// The spacing and origin a grid CSV written by crest carries in its first comment line:
/// `# crest height map: dx_um=…, dy_um=…, x0_mm=…, y0_mm=…`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Meta {
    pub dx_um: f64,
    pub dy_um: f64,
    pub x0_mm: f64,
    pub y0_mm: f64,
}

/// Read the [`Meta`] comment, if the file has one (in its leading comment lines).
pub(crate) fn meta(text: &str) -> Option<Meta> {
    for line in text.lines() {
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        let c = t.strip_prefix('#')?;
        let Some(rest) = c.trim().strip_prefix("crest height map:") else {
            continue;
        };
        let get = |key: &str| {
            rest.split([',', ';'])
                .filter_map(|kv| kv.trim().split_once('='))
                .find(|(k, _)| k.trim() == key)
                .and_then(|(_, v)| v.trim().parse::<f64>().ok())
                .filter(|v| v.is_finite())
        };
        return Some(Meta {
            dx_um: get("dx_um").filter(|v| *v > 0.0)?,
            dy_um: get("dy_um").filter(|v| *v > 0.0)?,
            x0_mm: get("x0_mm").unwrap_or(0.0),
            y0_mm: get("y0_mm").unwrap_or(0.0),
        });
    }
    None
}

pub(crate) fn write(w: &mut dyn Write, map: &HeightMap) -> std::io::Result<()> {
    writeln!(
        w,
        "# crest height map: dx_um={}, dy_um={}, x0_mm={}, y0_mm={}; heights in µm, rows = y ascending, NaN = not reached",
        map.dx_um, map.dy_um, map.x0_mm, map.y0_mm
    )?;
    let mut csv = csv::WriterBuilder::new().has_headers(false).from_writer(w);
    for row in 0..map.ny {
        csv.write_record(map.row(row).iter().map(|v| fmt_value(*v)))?;
    }
    csv.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_rows_as_y_and_missing_as_nan() {
        let m = parse("# comment\n1, 2 ,3\n4,,NaN\n", 0.5, 0.25).unwrap();
        assert_eq!((m.nx, m.ny), (3, 2));
        assert_eq!(m.get(2, 0), 3.0);
        assert_eq!(m.get(0, 1), 4.0);
        assert!(m.get(1, 1).is_nan() && m.get(2, 1).is_nan());
        assert_eq!((m.dx_um, m.dy_um), (0.5, 0.25));
    }

    #[test]
    fn blank_separated_and_header() {
        let m = parse("a b\n1 2\n3   4\n", 1.0, 1.0).unwrap();
        assert_eq!(m.z_um, vec![1.0, 2.0, 3.0, 4.0]);
    }

    #[test]
    fn ragged_row_names_line() {
        let e = parse("1,2,3\n4,5\n", 1.0, 1.0).unwrap_err();
        assert_eq!(e.at, super::super::Location::Line { line: 2, field: 0 });
        assert!(e.message.contains("2 fields"), "{e}");
    }

    #[test]
    fn bad_number_names_line_and_field() {
        let e = parse("1,2\n3,4x\n", 1.0, 1.0).unwrap_err();
        assert_eq!(e.at, super::super::Location::Line { line: 2, field: 2 });
        assert!(e.message.contains("4x"), "{e}");
    }
}
