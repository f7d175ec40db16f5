//! Measured profiles as CSV: one point per line, `x` in mm and `z` in µm (`x_mm,z_um`),
//! spacing regular or not (digitised profiles from papers are irregular); `#` comments and a
//! header line are skipped.

use std::path::Path;

/// Whether the first line of `head` that is neither blank nor a `#` comment is the header
/// of a measured profile: two columns, `x_mm` and `z_um` (any case, commas, semicolons,
/// tabs or blanks between them).
pub fn is_profile_header(head: &[u8]) -> bool {
    let text = String::from_utf8_lossy(&head[..head.len().min(4096)]);
    let Some(line) = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
    else {
        return false;
    };
    let fields: Vec<String> = line
        .trim_start_matches('\u{feff}')
        .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
        .filter(|f| !f.is_empty())
        .map(|f| f.trim_matches('"').to_ascii_lowercase())
        .collect();
    fields == ["x_mm", "z_um"]
}

/// The points of `path` when it is a `.csv` whose header names the two columns `x_mm` and
/// `z_um` (a measured profile, as `runout identify` and `plot profile --measured` read it),
/// else `None` (a height map); only the first bytes are read to tell.
pub fn read_if_profile(path: &Path) -> miette::Result<Option<(Vec<f64>, Vec<f64>)>> {
    let csv = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if !csv || !super::input::is_regular(path) {
        return Ok(None);
    }
    let head = super::input::read_staged(path, "profile", |_| super::input::Stage::Stop)
        .map_err(|e| miette::miette!("{e}"))?;
    if !is_profile_header(&head) {
        return Ok(None);
    }
    read_profile_csv(path).map(Some)
}

/// Read a profile CSV; errors name the file and line.
pub fn read_profile_csv(path: &Path) -> miette::Result<(Vec<f64>, Vec<f64>)> {
    let text = super::text::read_text(path, "profile", super::input::TABLE)?;
    parse_profile_csv(&text, &path.display().to_string())
}

/// Parse profile CSV text that came from `file` (the two-column table of
/// [`super::series`]; a profile needs at least two points).
pub fn parse_profile_csv(text: &str, file: &str) -> miette::Result<(Vec<f64>, Vec<f64>)> {
    let (xs, zs) = super::series::two_columns(text, file).map_err(|e| miette::miette!("{e}"))?;
    if xs.len() < 2 {
        return Err(miette::miette!(
            "{file}: the profile has fewer than two points"
        ));
    }
    Ok((xs, zs))
}
