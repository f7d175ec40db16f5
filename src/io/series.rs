//! Series read back for plots: a two-column numeric table (x, y), and the planned feed that
//! `crest feed -o POSES.csv` writes, so that one command's output is the next one's input.

use super::table_error::TableError;
use crate::parse::Span;
use std::collections::HashMap;
use std::path::Path;

/// A table that could not be read: the message names the file (and the line and the column).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SeriesError {
    /// The file could not be read as text (the message names it).
    #[error("{0}")]
    Read(String),
    /// The table as a whole (no data rows).
    #[error("{file}: {message}")]
    Table {
        /// File name as given.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// A line of the table, or a field of a line.
    #[error(transparent)]
    At(#[from] TableError),
}

impl SeriesError {
    fn table(file: &str, message: &str) -> SeriesError {
        SeriesError::Table {
            file: file.to_string(),
            message: message.to_string(),
        }
    }

    fn line(file: &str, line: u64, message: String) -> SeriesError {
        TableError::line(file, line, message).into()
    }

    fn field(file: &str, line: u64, column: usize, message: String) -> SeriesError {
        let at = Span::line_column(
            u32::try_from(line).unwrap_or(u32::MAX),
            u32::try_from(column).unwrap_or(u32::MAX),
        );
        TableError::field(file, at, message).into()
    }
}

fn read_text(path: &Path) -> Result<String, SeriesError> {
    // `text::read_text` records the path as an input.
    super::text::read_text(path, "table", super::input::TABLE)
        .map_err(|e| SeriesError::Read(e.to_string()))
}

/// A two-column numeric table: optional header line, `#` comments, fields separated by
/// commas, semicolons, tabs or blanks; columns past the second are ignored.
pub fn read_two_columns(path: &Path) -> Result<(Vec<f64>, Vec<f64>), SeriesError> {
    let text = read_text(path)?;
    two_columns(&text, &path.display().to_string())
}

pub(crate) fn two_columns(text: &str, name: &str) -> Result<(Vec<f64>, Vec<f64>), SeriesError> {
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line
            .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
            .filter(|f| !f.is_empty())
            .collect();
        let parsed: Vec<Option<f64>> = fields.iter().map(|f| f.parse::<f64>().ok()).collect();
        if xs.is_empty() && parsed.iter().all(|v| v.is_none()) {
            continue; // header
        }
        if fields.len() < 2 {
            return Err(SeriesError::line(
                name,
                i as u64 + 1,
                format!("expected two numbers, found {}", fields.len()),
            ));
        }
        for (k, v) in parsed.iter().take(2).enumerate() {
            if v.is_none() {
                let col = line.find(fields[k]).unwrap_or(0) + 1;
                return Err(SeriesError::field(
                    name,
                    i as u64 + 1,
                    col,
                    format!("expected a number, found '{}'", fields[k]),
                ));
            }
        }
        xs.push(parsed[0].unwrap_or(f64::NAN));
        ys.push(parsed[1].unwrap_or(f64::NAN));
    }
    if xs.is_empty() {
        return Err(SeriesError::table(name, "no data rows"));
    }
    Ok((xs, ys))
}

/// Planned feeds by tool path name and source line, mm/min.
pub type PlannedFeeds = HashMap<(String, u32), f64>;

/// The planned feed of `crest feed -o POSES.csv`, by tool path name and source line
/// (mm/min). `None` when the file is not such a table (no `path`, `line` and
/// `feed_mm_min` columns in its header).
pub fn read_planned_feed(path: &Path) -> Result<Option<PlannedFeeds>, SeriesError> {
    let text = read_text(path)?;
    planned_feed(&text, &path.display().to_string())
}

fn planned_feed(text: &str, name: &str) -> Result<Option<PlannedFeeds>, SeriesError> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(false)
        .from_reader(text.as_bytes());
    let headers = match reader.headers() {
        Ok(h) => h.clone(),
        Err(_) => return Ok(None),
    };
    let col = |key: &str| headers.iter().position(|h| h.trim() == key);
    let (Some(cp), Some(cl), Some(cf)) = (col("path"), col("line"), col("feed_mm_min")) else {
        return Ok(None);
    };
    let mut out = HashMap::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map(|p| p.line()).unwrap_or(0);
            SeriesError::line(name, line, e.to_string())
        })?;
        let line_no = record.position().map(|p| p.line()).unwrap_or(0);
        let field = |k: usize, what: &str| -> Result<&str, SeriesError> {
            record.get(k).ok_or_else(|| {
                SeriesError::line(name, line_no, format!("missing the {what} column"))
            })
        };
        let column_of = |k: usize| -> usize {
            // 1-based character column of field k in the raw line.
            record
                .iter()
                .take(k)
                .map(|f| f.chars().count() + 1)
                .sum::<usize>()
                + 1
        };
        let line: u32 = field(cl, "line")?.trim().parse().map_err(|_| {
            SeriesError::field(
                name,
                line_no,
                column_of(cl),
                format!(
                    "expected a source line number, found '{}'",
                    record.get(cl).unwrap_or("")
                ),
            )
        })?;
        let raw = field(cf, "feed_mm_min")?.trim();
        let feed: f64 = raw.parse().map_err(|_| {
            SeriesError::field(
                name,
                line_no,
                column_of(cf),
                format!("expected a feed in mm/min, found '{raw}'"),
            )
        })?;
        out.insert((field(cp, "path")?.to_string(), line), feed);
    }
    if out.is_empty() {
        return Err(SeriesError::table(name, "no data rows"));
    }
    Ok(Some(out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_columns_with_header_and_errors() {
        let (x, y) = two_columns("s,f\n0,100\n1;200\n# c\n2 300 9\n", "t.csv").unwrap();
        assert_eq!(x, vec![0.0, 1.0, 2.0]);
        assert_eq!(y, vec![100.0, 200.0, 300.0]);
        let e = two_columns("0,1\n2,x\n", "t.csv").unwrap_err();
        assert_eq!(e.to_string(), "t.csv:2:3: expected a number, found 'x'");
        assert!(two_columns("a,b\n", "t.csv").is_err());
        let e = two_columns("0,1\n2\n", "t.csv").unwrap_err();
        assert_eq!(e.to_string(), "t.csv:2: expected two numbers, found 1");
        let e = two_columns("a,b\n", "t.csv").unwrap_err();
        assert_eq!(e.to_string(), "t.csv: no data rows");
    }

    #[test]
    fn planned_feed_by_path_and_line() {
        let text = "path,index,line,t_s,feed_mm_min,path_speed_mm_min\nP1,0,12,0,0,0\nP1,1,13,0.1,950.5,950.5\n";
        let m = planned_feed(text, "p.csv").unwrap().unwrap();
        assert_eq!(m[&("P1".to_string(), 13)], 950.5);
        assert_eq!(m.len(), 2);
        assert!(planned_feed("s,f\n0,1\n", "p.csv").unwrap().is_none());
        let e = planned_feed("path,line,feed_mm_min\nP1,7,fast\n", "p.csv").unwrap_err();
        assert_eq!(
            e.to_string(),
            "p.csv:2:6: expected a feed in mm/min, found 'fast'"
        );
    }
}
