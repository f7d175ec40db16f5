//! Height profiles: a simulated profile against position and, optionally, a measured one, as
//! a one-panel [`Chart`].

use super::PlotError;
use super::chart::{Chart, Series, write};
use std::path::Path;

/// Plot height profiles against position: a simulated profile and, optionally, a measured
/// one (x in mm, heights in µm).
pub fn plot_profiles(
    title: &str,
    simulated: (&[f64], &[f64]),
    measured: Option<(&[f64], &[f64])>,
    path: &Path,
) -> Result<(), PlotError> {
    let mut series = vec![Series::line("simulated", simulated.0, simulated.1, 0)];
    if let Some((x, z)) = measured {
        series.push(Series::line("measured", x, z, 1));
    }
    write(
        &Chart::lines(
            title,
            "position along the profile [mm]",
            "height [µm]",
            series,
        ),
        path,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_svg_has_title_labels_and_legend() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("p.svg");
        let x: Vec<f64> = (0..200).map(|i| i as f64 * 0.01).collect();
        let z: Vec<f64> = x.iter().map(|x| (x * 20.0).sin()).collect();
        let m: Vec<f64> = x.iter().map(|x| 1.1 * (x * 20.0).sin()).collect();
        plot_profiles("Profile test 3", (&x, &z), Some((&x, &m)), &out).unwrap();
        let svg = std::fs::read_to_string(&out).unwrap();
        for text in [
            "Profile test 3",
            "height [µm]",
            "[mm]",
            "simulated",
            "measured",
        ] {
            assert!(svg.contains(text), "missing {text}");
        }
        assert!(matches!(
            plot_profiles("x", (&x, &z), None, &dir.path().join("p.pdf")),
            Err(PlotError::Format(_))
        ));
        let nan = [f64::NAN];
        assert!(matches!(
            plot_profiles("x", (&nan, &nan), None, &out),
            Err(PlotError::Empty(_))
        ));
    }
}
