//! The run-out study's figures: participating teeth and crest height against the swept
//! run-out key (faceted by the other swept keys, one series per lead), and the lateral
//! run-out against tool height (cf. 002 Fig 14c), as [`Chart`]s.

use super::chart::{Chart, Panel, Series};
pub use super::chart::{render_png, render_svg};
use crate::study::runout::{LateralCurve, RunoutRow, Study};
use crate::tool::Rule;

/// Cases grouped for plotting: facets (every swept key except the x axis and the lead),
/// each with one series per lead, sorted by x.
type Facets<'a> = Vec<(String, Vec<(usize, f64, Vec<&'a RunoutRow>)>)>;

/// Most facets drawn side by side; beyond this every group goes into one panel.
const MAX_FACETS: usize = 4;

fn facets<'a>(rows: &'a [RunoutRow], study: &Study) -> Facets<'a> {
    let split = {
        let mut labels: Vec<String> = rows
            .iter()
            .map(|r| study.series_label(&r.case, true))
            .collect();
        labels.dedup();
        labels.sort();
        labels.dedup();
        labels.len() <= MAX_FACETS
    };
    let mut out: Facets = Vec::new();
    for r in rows {
        let (facet, series) = if split {
            (
                study.series_label(&r.case, true),
                format!("lead {}°", r.case.lead_deg),
            )
        } else {
            (String::new(), study.series_label(&r.case, false))
        };
        let _ = series;
        let lead_idx = study
            .leads_deg
            .iter()
            .position(|&l| l == r.case.lead_deg)
            .unwrap_or(0);
        let key = if split {
            lead_idx
        } else {
            // One colour per combined group, in first-seen order.
            usize::MAX
        };
        let entry = match out.iter_mut().position(|(f, _)| *f == facet) {
            Some(i) => &mut out[i].1,
            None => {
                out.push((facet, Vec::new()));
                &mut out.last_mut().expect("just pushed").1
            }
        };
        let label_of = |row: &RunoutRow| study.series_label(&row.case, false);
        let pos = if key == usize::MAX {
            let l = label_of(r);
            entry
                .iter()
                .position(|(_, _, v)| v.first().is_some_and(|x| label_of(x) == l))
        } else {
            entry.iter().position(|(k, _, _)| *k == key)
        };
        match pos {
            Some(i) => entry[i].2.push(r),
            None => {
                let color = if key == usize::MAX { entry.len() } else { key };
                entry.push((color, r.case.lead_deg, vec![r]));
            }
        }
    }
    for (_, series) in &mut out {
        for (_, _, v) in series.iter_mut() {
            v.sort_by(|a, b| study.x.of(&a.case).total_cmp(&study.x.of(&b.case)));
        }
    }
    out
}

fn series_name(study: &Study, first: &RunoutRow, split: bool, tool_name: &str) -> String {
    let l = if split {
        if study.leads_deg.len() > 1 || study.swept.is_empty() {
            format!("lead {}°", first.case.lead_deg)
        } else {
            String::new()
        }
    } else {
        study.series_label(&first.case, false)
    };
    if l.is_empty() {
        format!("{tool_name}, lead {}°", first.case.lead_deg)
    } else {
        l
    }
}

fn line(label: String, points: Vec<(f64, f64)>, color: usize, dashed: bool) -> Series {
    let markers = points.len() <= 80;
    Series {
        label,
        points,
        color,
        dashed,
        markers: markers && !dashed,
        line: true,
    }
}

fn caption(facet: &str) -> String {
    facet.to_string()
}

fn size(columns: usize, rows: usize) -> (u32, u32) {
    let cols = columns.max(1) as u32;
    let rows = rows.max(1) as u32;
    ((560 * cols + 120).max(1000), (400 * rows + 60).max(640))
}

/// What the two participating-tooth rules say, in the words under the charts.
fn rule_notes(study: &Study) -> Vec<String> {
    vec![
        format!(
            "Which teeth cut ({} rule here). Exact rule (default): a tooth cuts where its feed marks reach below the other teeth's",
            study.rule.name()
        ),
        "envelope along the feed. Paper rule (Marin et al. 2023, Eq 8; rule = \"paper\"): a tooth cuts while its radius is within".into(),
        "the nominal crest height of the largest one, so it drops teeth, and predicts a large crest, at much smaller run-out.".into(),
    ]
}

fn with_notes((w, h): (u32, u32), notes: &[String]) -> (u32, u32) {
    (w, h + 21 * notes.len() as u32 + 12)
}

/// Participating teeth and effective fz against run-out: one row per quantity, one column
/// per facet (e.g. per phase), one coloured series per lead.
pub fn teeth_chart(rows: &[RunoutRow], study: &Study, teeth: usize, tool_name: &str) -> Chart {
    let f = facets(rows, study);
    let split = f.len() > 1 || f.first().is_some_and(|(l, _)| !l.is_empty());
    let split = split
        || study
            .swept
            .iter()
            .all(|k| *k == "lead_deg" || *k == study.x.key());
    let x = study.x;
    let cols = f.len().max(1);
    let mut panels = Vec::new();
    for quantity in 0..2 {
        for (facet, series) in &f {
            panels.push(Panel {
                caption: if quantity == 0 {
                    caption(facet)
                } else {
                    String::new()
                },
                y_label: if quantity == 0 {
                    "participating teeth zc".into()
                } else {
                    "effective fz (mm/tooth)".into()
                },
                // From zero to the tooth count, with head room for the legend above it.
                y_range: if quantity == 0 {
                    Some((0.0, teeth as f64 * 1.9 + 0.5))
                } else {
                    None
                },
                y_integer: quantity == 0,
                series: series
                    .iter()
                    .flat_map(|(color, _, v)| {
                        let name = series_name(study, v[0], split, tool_name);
                        let mut out = vec![line(
                            if quantity == 0 {
                                format!("{name}, {} rule", study.rule.name())
                            } else {
                                name.clone()
                            },
                            v.iter()
                                .map(|r| {
                                    let y = if quantity == 0 {
                                        r.zc as f64
                                    } else {
                                        r.fz_effective_mm
                                    };
                                    (x.of(&r.case), y)
                                })
                                .collect(),
                            *color,
                            false,
                        )];
                        if quantity == 0 {
                            // The other rule, dashed, on the same axes.
                            let (other, pick): (&str, fn(&RunoutRow) -> usize) =
                                if study.rule == Rule::Paper {
                                    ("exact", |r| r.zc_exact)
                                } else {
                                    ("paper", |r| r.zc_paper)
                                };
                            out.push(line(
                                format!("{name}, {other} rule"),
                                v.iter().map(|r| (x.of(&r.case), pick(r) as f64)).collect(),
                                *color,
                                true,
                            ));
                        }
                        out
                    })
                    .collect(),
            });
        }
    }
    let notes = rule_notes(study);
    Chart {
        title: format!(
            "Participating teeth and effective feed per tooth against run-out ({} rule)",
            study.rule.name()
        ),
        x_label: x.label().to_string(),
        panels,
        size: with_notes(size(cols, 2), &notes),
        columns: cols,
        notes,
        x_integer: false,
    }
}

/// Crest height against run-out for each lead: the corrected crest under the study's rule
/// (solid) and the crest of the exact 1-D envelope (dashed), one column per facet.
pub fn crest_chart(rows: &[RunoutRow], study: &Study, tool_name: &str) -> Chart {
    let f = facets(rows, study);
    let split = f.len() > 1 || f.first().is_some_and(|(l, _)| !l.is_empty());
    let split = split
        || study
            .swept
            .iter()
            .all(|k| *k == "lead_deg" || *k == study.x.key());
    let x = study.x;
    let cols = f.len().max(1);
    let panels = f
        .iter()
        .map(|(facet, series)| {
            let mut out = Vec::new();
            for (color, _, v) in series {
                let name = series_name(study, v[0], split, tool_name);
                out.push(line(
                    format!("{name}, at fz_eff of the {} rule", study.rule.name()),
                    v.iter()
                        .map(|r| (x.of(&r.case), r.crest_height_corrected_um))
                        .collect(),
                    *color,
                    false,
                ));
                out.push(line(
                    format!("{name}, envelope of the marks"),
                    v.iter()
                        .map(|r| (x.of(&r.case), r.crest_height_exact_um))
                        .collect(),
                    *color,
                    true,
                ));
            }
            Panel {
                caption: caption(facet),
                y_label: "crest height hc (µm)".into(),
                y_range: None,
                y_integer: false,
                series: out,
            }
        })
        .collect();
    let mut notes = vec![
        "Solid: the crest R − √(R² − fz_eff²/4) at the effective feed per tooth of the rule; dashed: the crest of the lower".into(),
        "envelope of every tooth's marks along the feed (the exact 1-D profile).".into(),
    ];
    notes.extend(rule_notes(study));
    Chart {
        title: format!(
            "Feed-direction crest height against run-out ({} rule)",
            study.rule.name()
        ),
        x_label: x.label().to_string(),
        panels,
        size: with_notes(size(cols, 1), &notes),
        columns: cols,
        notes,
        x_integer: false,
    }
}

/// Lateral run-out against tool height for each lead (cf. 002 Fig 14c).
pub fn lateral_chart(curves: &[LateralCurve], tool_name: &str) -> Chart {
    let mut series = Vec::new();
    for (i, c) in curves.iter().enumerate() {
        series.push(Series {
            label: format!("lead {}°", c.lead_deg),
            points: c.curve.clone(),
            color: i,
            dashed: false,
            markers: false,
            line: true,
        });
        series.push(Series {
            label: String::new(),
            points: c.marks.clone(),
            color: i,
            dashed: false,
            markers: true,
            line: false,
        });
    }
    Chart {
        title: format!("Lateral run-out against tool height, {tool_name}"),
        x_label: "tool height z above the tip (mm)".into(),
        columns: 1,
        panels: vec![Panel {
            caption: String::new(),
            y_label: "run-out along the normal, max − min over teeth (µm)".into(),
            y_range: None,
            y_integer: false,
            series,
        }],
        size: (1000, 640),
        notes: Vec::new(),
        x_integer: false,
    }
}

/// The study's three figures, each as SVG and PNG: `(file name, bytes)` in the order
/// `runout-teeth`, `runout-crest`, `runout-lateral`.
pub fn figures(
    rows: &[RunoutRow],
    study: &Study,
    teeth: usize,
    lateral: &[LateralCurve],
    tool_name: &str,
) -> std::io::Result<Vec<(String, Vec<u8>)>> {
    let charts = [
        ("runout-teeth", teeth_chart(rows, study, teeth, tool_name)),
        ("runout-crest", crest_chart(rows, study, tool_name)),
        ("runout-lateral", lateral_chart(lateral, tool_name)),
    ];
    let mut out = Vec::new();
    for (stem, chart) in charts {
        out.push((format!("{stem}.svg"), render_svg(&chart)?.into_bytes()));
        out.push((format!("{stem}.png"), render_png(&chart)?));
    }
    Ok(out)
}
