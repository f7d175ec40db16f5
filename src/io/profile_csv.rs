//! Measured profiles as CSV: one point per line, `x` in mm and `z` in µm (`x_mm,z_um`),
//! spacing regular or not (digitised profiles from papers are irregular); `#` comments and a
//! header line are skipped.

use std::path::Path;

/// Why a measured profile could not be read: each message names the file.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
pub enum ProfileError {
    /// The file's first bytes could not be read within its budget (shown as one line).
    #[error("{0}")]
    Head(super::input::InputError),
    /// The file could not be read as text.
    #[error(transparent)]
    #[diagnostic(transparent)]
    Text(#[from] super::text::TextError),
    /// The two-column table is not one (shown as one line).
    #[error("{0}")]
    Table(super::series::SeriesError),
    /// The table has fewer than two points.
    #[error("{file}: the profile has fewer than two points")]
    TooShort {
        /// File name as given.
        file: String,
    },
}

/// The points of a profile: x in mm, z in µm.
pub type Points = (Vec<f64>, Vec<f64>);

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
pub fn read_if_profile(path: &Path) -> Result<Option<Points>, ProfileError> {
    let csv = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if !csv || !super::input::is_regular(path) {
        return Ok(None);
    }
    let head = super::input::read_staged(path, "profile", |_| super::input::Stage::Stop)
        .map_err(ProfileError::Head)?;
    if !is_profile_header(&head) {
        return Ok(None);
    }
    read_profile_csv(path).map(Some)
}

/// Read a profile CSV; errors name the file and line.
pub fn read_profile_csv(path: &Path) -> Result<Points, ProfileError> {
    let text = super::text::read_text(path, "profile", super::input::TABLE)?;
    parse_profile_csv(&text, &path.display().to_string())
}

/// Parse profile CSV text that came from `file` (the two-column table of
/// [`super::series`]; a profile needs at least two points).
pub fn parse_profile_csv(text: &str, file: &str) -> Result<Points, ProfileError> {
    let (xs, zs) = super::series::two_columns(text, file).map_err(ProfileError::Table)?;
    if xs.len() < 2 {
        return Err(ProfileError::TooShort {
            file: file.to_string(),
        });
    }
    Ok((xs, zs))
}
