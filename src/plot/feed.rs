//! Quantities along the tool path: the feed (programmed, predicted, measured) and the
//! crest heights it leaves, against the arc length of the path.

use super::PlotError;
use super::chart::{Chart, Series, write};
use std::path::Path;

/// Plot feeds (mm/min) against path length `s_mm` (mm), one line per `(label, feed)`.
pub fn plot_feed(
    title: &str,
    s_mm: &[f64],
    feeds: &[(&str, &[f64])],
    path: &Path,
) -> Result<(), PlotError> {
    along_path(title, "feed [mm/min]", s_mm, feeds, path)
}

/// Plot crest heights (µm) against path length `s_mm` (mm), one line per `(label, crest)`.
pub fn plot_crest_along_path(
    title: &str,
    s_mm: &[f64],
    crests_um: &[(&str, &[f64])],
    path: &Path,
) -> Result<(), PlotError> {
    along_path(title, "crest height [µm]", s_mm, crests_um, path)
}

fn along_path(
    title: &str,
    y_label: &str,
    s_mm: &[f64],
    lines: &[(&str, &[f64])],
    path: &Path,
) -> Result<(), PlotError> {
    if let Some((label, y)) = lines.iter().find(|(_, y)| y.len() != s_mm.len()) {
        return Err(PlotError::Invalid(format!(
            "'{label}' has {} values for {} path positions",
            y.len(),
            s_mm.len()
        )));
    }
    let series = lines
        .iter()
        .enumerate()
        .map(|(i, (label, y))| Series::line(*label, s_mm, y, i))
        .collect();
    write(
        &Chart::lines(title, "path length [mm]", y_label, series),
        path,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feed_svg_has_title_axes_and_legend() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("f.svg");
        let s: Vec<f64> = (0..=100).map(|i| i as f64).collect();
        let prog = vec![4000.0; 101];
        let act: Vec<f64> = s.iter().map(|s| 4000.0 - 35.0 * s).collect();
        plot_feed(
            "Feed along the pass",
            &s,
            &[("programmed", &prog), ("actual", &act)],
            &out,
        )
        .unwrap();
        let svg = std::fs::read_to_string(&out).unwrap();
        for t in [
            "Feed along the pass",
            "feed [mm/min]",
            "path length [mm]",
            "programmed",
            "actual",
        ] {
            assert!(svg.contains(t), "missing {t}");
        }
        let short = [1.0];
        assert!(matches!(
            plot_crest_along_path("c", &s, &[("a", &short)], &out),
            Err(PlotError::Invalid(_))
        ));
    }
}
