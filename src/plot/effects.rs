//! The designed experiment's figures: relative first-level effects per parameter (001 Fig
//! 11) and the effect of one factor at each of its levels (001 Fig 12), as line charts.

use crate::study::design::{Design, Effects};

/// The chart of 001 Fig 11: relative first-level effect EF_i1 (Eq 8, %) per parameter (x =
/// 1…n in [`Design::responses`] order), one series per factor with more than one level.
pub fn effects_chart(design: &Design, effects: &[Effects]) -> super::profile::LineChart {
    let factors = design.factors();
    let x: Vec<f64> = (1..=design.responses.len()).map(|k| k as f64).collect();
    let series = factors
        .iter()
        .enumerate()
        .filter(|(_, f)| f.levels.len() > 1)
        .map(|(i, f)| {
            let y: Vec<f64> = effects
                .iter()
                .map(|e| 100.0 * e.relative_first[i])
                .collect();
            super::profile::Series::new(format!("{} = {}", f.name, f.levels[0]), &x, &y)
        })
        .collect();
    let series: Vec<super::profile::Series> = series;
    let mut title = if design.title.is_empty() {
        "Relative first-level effects (001 Eq 8)".to_string()
    } else {
        format!("{}: relative first-level effects (Eq 8)", design.title)
    };
    // A single line gets no legend: name it in the title.
    if let [only] = series.as_slice() {
        title = format!("{title}, {}", only.label);
    }
    super::profile::LineChart {
        title,
        x_label: format!("parameter ({})", design.responses.join(", ")),
        y_label: "EF_i1 [%]".into(),
        series,
    }
}

/// The chart of 001 Fig 12: the relative effect `EF_ij/M` (%) of one factor at each of its
/// levels (x = the level), one series per response.
pub fn level_chart(
    design: &Design,
    effects: &[Effects],
    factor: usize,
) -> Option<super::profile::LineChart> {
    let f = design.factors().into_iter().nth(factor)?;
    let series = design
        .responses
        .iter()
        .zip(effects)
        .map(|(name, e)| {
            let y: Vec<f64> = e
                .effects
                .get(factor)
                .map(|row| {
                    row.iter()
                        .map(|v| {
                            if e.mean != 0.0 {
                                100.0 * v / e.mean
                            } else {
                                f64::NAN
                            }
                        })
                        .collect()
                })
                .unwrap_or_default();
            super::profile::Series::new(name.clone(), &f.levels, &y)
        })
        .collect();
    Some(super::profile::LineChart {
        title: if design.title.is_empty() {
            format!("Effect of {} (001 Eq 7 / M)", f.name)
        } else {
            format!("{}: effect of {} (Eq 7 / M)", design.title, f.name)
        },
        x_label: f.name.clone(),
        y_label: "EF_ij / M [%]".into(),
        series,
    })
}
