//! The calibration and Monte Carlo parts of a regression report (Markdown, HTML, the JSON
//! and CSV of `crest calibrate`): fitted values with uncertainties, geometric / calibrated /
//! leave-one-out columns, the constant-offset reference and what the data can tell apart.

use crate::math::trim_decimals;
use crate::study::calibrate::Calibration;
use crate::study::compare::Regression;
use std::fmt::Write;

fn pct(v: f64, m: f64) -> f64 {
    100.0 * (v - m) / m
}

/// The JSON object of `crest calibrate --json`.
pub fn calibration_json(cal: &Calibration) -> serde_json::Value {
    let mut params = serde_json::Map::new();
    let mut sigma = serde_json::Map::new();
    for (n, v, s) in &cal.parameters {
        params.insert(n.clone(), serde_json::json!(v));
        sigma.insert(n.clone(), serde_json::json!(s));
    }
    serde_json::json!({
        "parameters": params,
        "parameters_sigma": sigma,
        "correlation": cal.correlation,
        "cases": cal.cases,
        "loo_rms_pct": cal.loo_rms_pct,
        "fit_rms_pct": cal.fit_rms_pct,
        "constant_loo_rms_pct": cal.constant_loo_rms_pct,
        "factor_loo_rms_pct": cal.factor_loo_rms_pct,
        "factors": cal.factors.iter().map(|(n, v)| (n.clone(), serde_json::json!(v))).collect::<serde_json::Map<_, _>>(),
        "geometric_constant": cal.geometric_constant,
        "chi2": cal.chi2,
        "dof": cal.dof,
    })
}

/// `calibration.csv`: one row per case and parameter, written through the csv crate (a
/// side label with a comma, a quote or a line break is quoted).
pub fn calibration_csv(cal: &Calibration) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let head = [
        "lead_deg",
        "side",
        "parameter",
        "measured_um",
        "sigma_um",
        "geometric_um",
        "calibrated_um",
        "loo_um",
        "constant_loo_um",
        "factor_loo_um",
    ];
    // Writing into a Vec cannot fail.
    let _ = w.write_record(head);
    for c in &cal.cases {
        let mut row = vec![
            c.lead_deg.to_string(),
            c.side.name().to_string(),
            c.parameter.to_string(),
        ];
        for v in [
            c.measured_um,
            c.sigma_um,
            c.geometric_um,
            c.calibrated_um,
            c.loo_um,
            c.constant_loo_um,
            c.factor_loo_um,
        ] {
            row.push(format!("{v:.4}"));
        }
        let _ = w.write_record(&row);
    }
    let bytes = w.into_inner().unwrap_or_default();
    String::from_utf8(bytes).unwrap_or_default()
}

/// What the fit does and does not establish, in plain sentences.
pub fn statement(cal: &Calibration, tolerance_pct: f64) -> Vec<String> {
    let mut out = Vec::new();
    let names: Vec<String> = cal.parameters.iter().map(|p| p.0.clone()).collect();
    out.push(format!(
        "The fit chooses {} so that the model's Rz and Ra match the measured case means (weights 1/σ², σ floored at half the pooled σ). In-sample it is within {:.1} % RMS; that says nothing about prediction, because the parameters were chosen on the same cases.",
        names.join(", "),
        cal.fit_rms_pct
    ));
    let n_loo = cal.cases.len();
    let within = cal
        .cases
        .iter()
        .filter(|c| pct(c.loo_um, c.measured_um).abs() <= tolerance_pct)
        .count();
    out.push(format!(
        "Leave-one-out (each case predicted by a refit without it): {within} of {n_loo} values within ±{}% of the measured mean, RMS {:.1} %. This is the only column the verdict counts.",
        trim_decimals(tolerance_pct, 2),
        cal.loo_rms_pct
    ));
    if cal.geometric_constant {
        out.push(format!(
            "The geometric prediction is the same for every case, so any model that adds a lead-independent effect to it is fitted by a constant just as well: a constant offset per parameter on the geometric model predicts the left-out cases with RMS {:.1} %. A good fit here therefore does not show that ploughing (or any named mechanism) is the cause; it shows only that the gap between geometry and measurement is roughly constant across the cases.",
            cal.constant_loo_rms_pct
        ));
    } else {
        out.push(format!(
            "The geometric prediction differs between cases, so the fitted effects act on case-to-case differences too. For reference, a constant offset per parameter on the geometric model predicts the left-out cases with RMS {:.1} %, a constant factor per parameter with RMS {:.1} % (the calibrated model: {:.1} %).",
            cal.constant_loo_rms_pct, cal.factor_loo_rms_pct, cal.loo_rms_pct
        ));
    }
    let n = cal.parameters.len();
    for i in 0..n {
        for j in i + 1..n {
            let r = cal.correlation[i][j];
            if !r.is_finite() {
                out.push(format!(
                    "The correlation of {} and {} is not determined: the model's values do not change with at least one of them near the fit.",
                    cal.parameters[i].0, cal.parameters[j].0
                ));
            } else if r.abs() > 0.9 {
                out.push(format!(
                    "{} and {} are correlated at {r:+.2}: the data cannot tell them apart; only a combination of the two is determined.",
                    cal.parameters[i].0, cal.parameters[j].0
                ));
            } else {
                out.push(format!(
                    "{} and {} are correlated at {r:+.2}: the data separate them.",
                    cal.parameters[i].0, cal.parameters[j].0
                ));
            }
        }
    }
    for (name, v, s) in &cal.parameters {
        if !(s.is_finite()) || *s > v.abs() {
            out.push(format!(
                "{name} = {v:.3} ± {s:.3}: the uncertainty exceeds the value; the data do not determine it."
            ));
        }
    }
    out
}

/// The Markdown section (empty without a calibration or bands).
pub fn markdown(r: &Regression) -> String {
    let mut s = String::new();
    if let Some(cal) = &r.calibration {
        let _ = writeln!(s, "## Calibration\n");
        let _ = writeln!(s, "| parameter | fitted | standard uncertainty | bounds |");
        let _ = writeln!(s, "|---|---|---|---|");
        for ((n, v, sd), b) in cal.parameters.iter().zip(&cal.bounds) {
            let _ = writeln!(
                s,
                "| {n} | {v:.4} | {sd:.4} | {} … {} |",
                trim_decimals(b.0, 3),
                trim_decimals(b.1, 3)
            );
        }
        let _ = writeln!(
            s,
            "\nχ² = {:.3} with {} degrees of freedom.\n",
            cal.chi2, cal.dof
        );
        let _ = writeln!(
            s,
            "| lead (°) | side | param | measured mean ± σ (µm) | geometric (µm) | calibrated (µm) | leave-one-out (µm) | LOO deviation (%) | constant-offset LOO (µm) | constant-factor LOO (µm) | result (LOO) |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|");
        for c in &cal.cases {
            let d = pct(c.loo_um, c.measured_um);
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.4} ± {:.4} | {:.4} | {:.4} | {:.4} | {:+.1} | {:.4} | {:.4} | {} |",
                trim_decimals(c.lead_deg, 3),
                super::md_cell(c.side.name()),
                c.parameter,
                c.measured_um,
                c.sigma_um,
                c.geometric_um,
                c.calibrated_um,
                c.loo_um,
                d,
                c.constant_loo_um,
                c.factor_loo_um,
                if d.abs() <= r.tolerance_pct {
                    "pass"
                } else {
                    "FAIL"
                }
            );
        }
        let _ = writeln!(s, "\n### What the fit does and does not establish\n");
        for line in statement(cal, r.tolerance_pct) {
            let _ = writeln!(s, "- {line}");
        }
        let _ = writeln!(s);
    }
    if let Some(b) = &r.monte_carlo {
        let _ = writeln!(s, "## Monte Carlo bands\n");
        let _ = writeln!(
            s,
            "| lead (°) | side | Rz P5 / P50 / P95 (µm) | Rz deterministic | Ra P5 / P50 / P95 (µm) | Ra deterministic |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|");
        for c in b {
            let _ = writeln!(
                s,
                "| {} | {} | {:.4} / {:.4} / {:.4} | {:.4} | {:.4} / {:.4} / {:.4} | {:.4} |",
                trim_decimals(c.lead_deg, 3),
                super::md_cell(c.side.name()),
                c.rz.p5,
                c.rz.p50,
                c.rz.p95,
                c.deterministic_um.0,
                c.ra.p5,
                c.ra.p50,
                c.ra.p95,
                c.deterministic_um.1
            );
        }
        let _ = writeln!(s);
    }
    s
}

/// The HTML section: the Markdown section's tables as HTML.
pub fn html(r: &Regression) -> String {
    let md = markdown(r);
    let mut s = String::new();
    let mut in_table = false;
    let mut in_list = false;
    for line in md.lines() {
        let t = line.trim();
        let esc = |x: &str| {
            x.replace("\\|", "|")
                .replace('&', "&amp;")
                .replace('<', "&lt;")
                .replace('>', "&gt;")
        };
        if t.starts_with('|') {
            if t.starts_with("|---") {
                continue;
            }
            let cells: Vec<String> = t
                .trim_matches('|')
                .split(" | ")
                .map(|c| esc(c.trim()))
                .collect();
            if !in_table {
                s.push_str("<table>\n<tr>");
                for c in &cells {
                    let _ = write!(s, "<th>{c}</th>");
                }
                s.push_str("</tr>\n");
                in_table = true;
            } else {
                s.push_str("<tr>");
                for c in &cells {
                    let cls = if c == "FAIL" { " class=\"fail\"" } else { "" };
                    let _ = write!(s, "<td{cls}>{c}</td>");
                }
                s.push_str("</tr>\n");
            }
            continue;
        }
        if in_table {
            s.push_str("</table>\n");
            in_table = false;
        }
        if let Some(item) = t.strip_prefix("- ") {
            if !in_list {
                s.push_str("<ul>\n");
                in_list = true;
            }
            let _ = writeln!(s, "<li>{}</li>", esc(item));
            continue;
        }
        if in_list {
            s.push_str("</ul>\n");
            in_list = false;
        }
        if let Some(h) = t.strip_prefix("### ") {
            let _ = writeln!(s, "<h3>{}</h3>", esc(h));
        } else if let Some(h) = t.strip_prefix("## ") {
            let _ = writeln!(s, "<h2>{}</h2>", esc(h));
        } else if !t.is_empty() {
            let _ = writeln!(s, "<p>{}</p>", esc(t));
        }
    }
    if in_table {
        s.push_str("</table>\n");
    }
    if in_list {
        s.push_str("</ul>\n");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::calibrate::CalibratedCase;
    use crate::study::measured::Side;

    #[test]
    fn a_side_label_with_comma_quote_and_bar_stays_one_field_and_one_cell() {
        let label = "a,b \"q\" p|q";
        let case = CalibratedCase {
            lead_deg: 15.0,
            side: Side::Other(label.to_string()),
            parameter: "Rz".to_string(),
            measured_um: 1.0,
            sigma_um: 0.1,
            geometric_um: 1.0,
            calibrated_um: 1.0,
            loo_um: 1.0,
            constant_loo_um: 1.0,
            factor_loo_um: 1.0,
        };
        let cal = Calibration {
            parameters: Vec::new(),
            correlation: Vec::new(),
            covariance: Vec::new(),
            bounds: Vec::new(),
            cases: vec![case],
            chi2: 0.0,
            dof: 0,
            loo_rms_pct: 0.0,
            fit_rms_pct: 0.0,
            constant_loo_rms_pct: 0.0,
            factor_loo_rms_pct: 0.0,
            factors: Vec::new(),
            geometric_constant: true,
        };
        let text = calibration_csv(&cal);
        let mut rows = csv::Reader::from_reader(text.as_bytes());
        let head = rows.headers().unwrap().len();
        let recs: Vec<csv::StringRecord> = rows.records().map(|r| r.unwrap()).collect();
        assert_eq!(recs.len(), 1);
        assert_eq!(recs[0].len(), head, "{text}");
        assert_eq!(&recs[0][1], label);
        // One Markdown cell: the bar escaped, the HTML shows it back.
        let cell = crate::report::md_cell(label);
        assert_eq!(cell, "a,b \"q\" p\\|q");
        let row = format!("| x | {cell} | y |");
        assert_eq!(row.split(" | ").count(), 3);
    }
}
