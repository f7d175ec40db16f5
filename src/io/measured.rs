//! The measured-table reader: CSV with one row per case and sample (`lead_deg,side,sample,
//! Ra_um,Rz_um`, like 002 Table 2; optionally `Sa_um`, `Sz_um`, `Sq_um`, `Sdq`,
//! `Ra_stepover_um`, `Rz_stepover_um`, and `measured_file`, a height map to measure), every
//! bad cell named by file, line and column.

use super::table_error::TableError;
use crate::parse::Span;
use crate::study::measured::{Columns, MeasuredRow, MeasuredTable, Param, Side};
use std::collections::BTreeMap;

/// Why a measured table was rejected.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
pub enum MeasuredError {
    /// A malformed line, or a value (or a header's column name) that could not be read,
    /// its message starting with the column's name (`column `Ra_um`: …`).
    #[error(transparent)]
    At(#[from] TableError),
    /// The header lacks required columns.
    #[error(
        "{file}:{}: missing column(s) {missing}; the header must name lead_deg, side, sample and measured_file or at least one of Ra_um, Rz_um, Sa_um, Sz_um, Sq_um, Sdq, Ra_stepover_um, Rz_stepover_um",
        at.line
    )]
    MissingColumns {
        /// File name as given.
        file: String,
        /// The header's line.
        at: Span,
        /// The missing column names, comma separated.
        missing: String,
    },
}

const KNOWN_COLUMNS: [&str; 12] = [
    "lead_deg",
    "side",
    "sample",
    "Ra_um",
    "Rz_um",
    "Sa_um",
    "Sz_um",
    "Sq_um",
    "Sdq",
    "Ra_stepover_um",
    "Rz_stepover_um",
    "measured_file",
];

/// The 1-based line where a record starts: the csv crate may place a record that follows
/// blank or comment lines at the first of them, so skip those from its byte offset.
fn line_of_record(text: &str, pos: &csv::Position) -> u64 {
    let bytes = text.as_bytes();
    let mut at = usize::try_from(pos.byte())
        .unwrap_or(usize::MAX)
        .min(bytes.len());
    // Skip blank and comment lines (the record's offset may point at them).
    while at < bytes.len() {
        match bytes[at] {
            b'\n' | b'\r' => at += 1,
            b'#' => {
                at = bytes[at..]
                    .iter()
                    .position(|b| *b == b'\n')
                    .map_or(bytes.len(), |p| at + p + 1);
            }
            _ => break,
        }
    }
    1 + bytes[..at].iter().filter(|b| **b == b'\n').count() as u64
}

/// A value (or a header's column name) of column `name` at `at` that could not be read.
fn bad_cell(file: &str, at: Span, name: &str, message: impl std::fmt::Display) -> MeasuredError {
    TableError::field(file, at, format!("column `{name}`: {message}")).into()
}

/// Where field `index` of the raw CSV line `raw` (line `line`) starts (just after the
/// line's end when it has fewer fields).
fn field_span(raw: &str, line: u64, index: usize) -> Span {
    let line = u32::try_from(line).unwrap_or(u32::MAX);
    let mut field = 0;
    let mut in_quotes = false;
    for (at, ch) in raw.char_indices() {
        if field == index {
            return Span::in_line(line, raw, at..at);
        }
        match ch {
            '"' => in_quotes = !in_quotes,
            ',' if !in_quotes => field += 1,
            _ => {}
        }
    }
    Span::in_line(line, raw, raw.len()..raw.len())
}

/// Parse a measured table from CSV text. `file` names the file in error messages.
///
/// Lines starting with `#` are comments. The header must hold `lead_deg`, `side`,
/// `sample` and at least one of `Ra_um`, `Rz_um` (feed-direction profile), `Sa_um`, `Sz_um`,
/// `Sq_um`, `Sdq` (areal), `Ra_stepover_um`, `Rz_stepover_um` (stepover-direction profile)
/// or `measured_file` (a height map, relative to the table, measured by the pipeline), in
/// any order; other columns are errors (a misspelt unit must not be ignored). A row that
/// names a measured file may leave its numbers empty (the file gives them). `side` is `concave`, `convex` or `plane` (these
/// carry curvature) or any other non-empty label (a plain grouping label).
/// Roughness values must be finite and non-negative; each (lead, side, sample) appears once.
pub fn parse_measured(text: &str, file: &str) -> Result<MeasuredTable, MeasuredError> {
    let raw_lines: Vec<&str> = text.lines().collect();
    let raw_line = |line: u64| -> &str {
        usize::try_from(line)
            .ok()
            .and_then(|l| raw_lines.get(l.saturating_sub(1)))
            .copied()
            .unwrap_or("")
    };
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(text.as_bytes());
    let csv_err = |e: csv::Error| -> MeasuredError {
        let line = e.position().map(|p| p.line()).unwrap_or(0);
        TableError::line(file, line, format!("not valid CSV: {e}")).into()
    };
    let headers = reader.headers().map_err(csv_err)?.clone();
    let header_line = headers
        .position()
        .map(|p| line_of_record(text, p))
        .unwrap_or(1);
    if headers.is_empty() || headers.iter().all(|h| h.is_empty()) {
        return Err(MeasuredError::MissingColumns {
            file: file.to_string(),
            at: Span::line_u64(header_line),
            missing: "lead_deg, side, sample, Ra_um, Rz_um".to_string(),
        });
    }
    let mut index: BTreeMap<&str, usize> = BTreeMap::new();
    for (i, h) in headers.iter().enumerate() {
        let Some(known) = KNOWN_COLUMNS.iter().find(|k| **k == h) else {
            return Err(bad_cell(
                file,
                field_span(raw_line(header_line), header_line, i),
                h,
                format!(
                    "unknown column; expected one of {} (units in the name)",
                    KNOWN_COLUMNS.join(", ")
                ),
            ));
        };
        if index.insert(known, i).is_some() {
            return Err(bad_cell(
                file,
                field_span(raw_line(header_line), header_line, i),
                h,
                "column given twice",
            ));
        }
    }
    let mut missing: Vec<&str> = ["lead_deg", "side", "sample"]
        .into_iter()
        .filter(|c| !index.contains_key(c))
        .collect();
    let columns = Columns {
        ra: index.contains_key("Ra_um"),
        rz: index.contains_key("Rz_um"),
        extra: Param::EXTRA.map(|p| index.contains_key(p.column())),
        file: index.contains_key("measured_file"),
    };
    if !columns.file && !Param::ALL.into_iter().any(|p| columns.has(p)) {
        missing.push("Ra_um or Rz_um (or measured_file)");
    }
    if !missing.is_empty() {
        return Err(MeasuredError::MissingColumns {
            file: file.to_string(),
            at: Span::line_u64(header_line),
            missing: missing.join(", "),
        });
    }

    let mut rows: Vec<MeasuredRow> = Vec::new();
    for record in reader.records() {
        let record = record.map_err(csv_err)?;
        let line = record
            .position()
            .map(|p| line_of_record(text, p))
            .unwrap_or(0);
        if record.iter().all(|f| f.is_empty()) {
            continue;
        }
        if record.len() != headers.len() {
            return Err(MeasuredError::At(TableError::line(
                file,
                line,
                format!(
                    "{} field(s) where the header has {}",
                    record.len(),
                    headers.len()
                ),
            )));
        }
        let cell = |name: &str| -> (usize, &str) {
            let i = index[name];
            (i, record.get(i).unwrap_or(""))
        };
        let bad = |name: &str, i: usize, message: String| {
            bad_cell(file, field_span(raw_line(line), line, i), name, message)
        };
        let measured_file = if columns.file {
            let (_, f) = cell("measured_file");
            (!f.is_empty()).then(|| f.to_string())
        } else {
            None
        };
        let number = |name: &str, nonneg: bool| -> Result<f64, MeasuredError> {
            let (i, s) = cell(name);
            let v: f64 = s
                .parse()
                .map_err(|_| bad(name, i, format!("expected a number, found `{s}`")))?;
            if !v.is_finite() || (nonneg && v < 0.0) {
                return Err(bad(
                    name,
                    i,
                    format!("expected a finite non-negative number, found `{s}`"),
                ));
            }
            // A roughness beyond a millimetre is not a measurement of a finished surface.
            if nonneg && v > 1e3 {
                return Err(bad(
                    name,
                    i,
                    format!("expected a roughness in µm up to 1000, found `{s}`"),
                ));
            }
            Ok(v)
        };
        let lead_deg = number("lead_deg", false)?;
        if !(-90.0..=90.0).contains(&lead_deg) {
            let (i, s) = cell("lead_deg");
            return Err(bad(
                "lead_deg",
                i,
                format!("lead angle must lie in [-90, 90] degrees, found `{s}`"),
            ));
        }
        let (si, s) = cell("side");
        // concave, convex and plane carry curvature; any other label only groups rows.
        let side = Side::parse(s).ok_or_else(|| {
            bad(
                "side",
                si,
                "empty side label (concave, convex, plane or any other label)".to_string(),
            )
        })?;
        let (pi, sample) = cell("sample");
        if sample.is_empty() {
            return Err(bad("sample", pi, "empty sample label".to_string()));
        }
        // A roughness cell: required unless the row names a measured file (which gives the
        // value when the cell is empty).
        let value = |p: Param| -> Result<Option<f64>, MeasuredError> {
            if !columns.has(p) || (measured_file.is_some() && cell(p.column()).1.is_empty()) {
                return Ok(None);
            }
            number(p.column(), true).map(Some)
        };
        let ra_um = value(Param::Ra)?;
        let rz_um = value(Param::Rz)?;
        let mut extra_um = [None; 6];
        for (v, p) in extra_um.iter_mut().zip(Param::EXTRA) {
            *v = value(p)?;
        }
        if let Some(prev) = rows
            .iter()
            .find(|r| r.lead_deg == lead_deg && r.side == side && r.sample == sample)
        {
            return Err(bad(
                "sample",
                pi,
                format!(
                    "sample `{sample}` of lead {lead_deg}°, {} given twice (first on line {})",
                    side.name(),
                    prev.line
                ),
            ));
        }
        rows.push(MeasuredRow {
            lead_deg,
            side,
            sample: sample.to_string(),
            ra_um,
            rz_um,
            extra_um,
            measured_file,
            line,
        });
    }
    if rows.is_empty() {
        return Err(
            TableError::line(file, header_line, "the table has a header but no data rows").into(),
        );
    }
    Ok(MeasuredTable { columns, rows })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_columns_count_characters() {
        assert_eq!(field_span("5,concave,S1,x,2", 4, 0).column, 1);
        assert_eq!(field_span("5,concave,S1,x,2", 4, 3).column, 14);
        assert_eq!(field_span("5,\"a,b\",S1", 4, 2).column, 9);
        assert_eq!(field_span("µ,x", 4, 1), Span::in_line(4, "µ,x", 3..3));
        assert_eq!(field_span("a", 4, 3).column, 2);
    }
}
