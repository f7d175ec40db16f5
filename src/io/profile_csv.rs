//! Measured profiles as CSV: one point per line, `x` in mm and `z` in µm (`x_mm,z_um`),
//! spacing regular or not (digitised profiles from papers are irregular); `#` comments and a
//! header line are skipped.

use std::path::Path;

/// Read a profile CSV; errors name the file and line.
pub fn read_profile_csv(path: &Path) -> miette::Result<(Vec<f64>, Vec<f64>)> {
    let text = super::text::read_text(path, "profile")?;
    parse_profile_csv(&text, &path.display().to_string())
}

/// Parse profile CSV text that came from `file`.
pub fn parse_profile_csv(text: &str, file: &str) -> miette::Result<(Vec<f64>, Vec<f64>)> {
    let (mut xs, mut zs) = (Vec::new(), Vec::new());
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let cols: Vec<&str> = t
            .split([',', ';', '\t', ' '])
            .filter(|c| !c.is_empty())
            .collect();
        let nums: Option<Vec<f64>> = cols.iter().take(2).map(|c| c.parse::<f64>().ok()).collect();
        match nums {
            Some(v) if v.len() == 2 && v.iter().all(|x| x.is_finite()) => {
                xs.push(v[0]);
                zs.push(v[1]);
            }
            _ if xs.is_empty() && i == 0 => continue, // header
            _ => {
                return Err(miette::miette!(
                    "{file}:{}:1: expected two numbers `x_mm,z_um`, found `{t}`",
                    i + 1
                ));
            }
        }
    }
    if xs.len() < 2 {
        return Err(miette::miette!(
            "{file}: the profile has fewer than two points"
        ));
    }
    Ok((xs, zs))
}
