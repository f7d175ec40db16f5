//! Measured profiles as CSV: one point per line, `x` in mm and `z` in µm (`x_mm,z_um`),
//! spacing regular or not (digitised profiles from papers are irregular); `#` comments and a
//! header line are skipped.

use std::path::Path;

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
