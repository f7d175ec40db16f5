//! Result tables as CSV, written with the `csv` crate: `runout.csv` of a run-out study,
//! `runs.csv` and `effects.csv` of a designed experiment.

use crate::study::design::{Design, Effects, RunResult};
use crate::study::runout::RunoutRow;
use std::io::Write;

/// Columns of `runout.csv`.
pub const RUNOUT_CSV_HEADER: [&str; 20] = [
    "case",
    "lead_deg",
    "fz_mm",
    "offset_um",
    "offset_phase_deg",
    "axis_tilt_deg",
    "axis_tilt_phase_deg",
    "rule",
    "zc",
    "zc_paper",
    "zc_exact",
    "participating_teeth",
    "fz_effective_mm",
    "crest_height_um",
    "crest_height_corrected_um",
    "crest_height_exact_um",
    "effective_radius_mm",
    "cutting_speed_ratio",
    "normal_runout_spread_um",
    "teeth",
];

/// Write the rows as CSV (one row per case, header first). `teeth` is the number of teeth Z.
pub fn write_runout_csv(
    rows: &[RunoutRow],
    teeth: usize,
    w: &mut dyn Write,
) -> std::io::Result<()> {
    let mut csv = csv::Writer::from_writer(w);
    csv.write_record(RUNOUT_CSV_HEADER)?;
    for r in rows {
        let c = &r.case;
        let num = |x: f64| format!("{x}");
        csv.write_record([
            c.case.to_string(),
            num(c.lead_deg),
            num(c.fz_mm),
            num(c.offset_um),
            num(c.offset_phase_deg),
            num(c.axis_tilt_deg),
            num(c.axis_tilt_phase_deg),
            r.rule.to_string(),
            r.zc.to_string(),
            r.zc_paper.to_string(),
            r.zc_exact.to_string(),
            r.participating_teeth.clone(),
            num(r.fz_effective_mm),
            num(r.crest_height_um),
            num(r.crest_height_corrected_um),
            num(r.crest_height_exact_um),
            num(r.effective_radius_mm),
            num(r.cutting_speed_ratio),
            num(r.normal_runout_spread_um),
            teeth.to_string(),
        ])?;
    }
    csv.flush()
}

/// A number of a JSON result: the number when finite, else `null` (JSON has no NaN or
/// infinity). Every JSON output of crest writes its floats through this one rule.
pub fn json_number(v: f64) -> serde_json::Value {
    serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

/// A value of a results table: six decimals, empty when not finite (a failed run).
fn fmt_value(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6}")
    } else {
        String::new()
    }
}

/// `runs.csv`: one row per run, `run`, the factor values, `fz_mm`, `step_mm`, the responses
/// and `error` (why the run failed, empty otherwise). With Monte Carlo bands (any run has
/// them: `crest study --monte-carlo`), each response column `X` is followed by `X_p5`,
/// `X_p50` and `X_p95`, its 5th, 50th and 95th percentiles over the samples.
pub fn write_runs_csv(
    design: &Design,
    results: &[RunResult],
    w: &mut dyn Write,
) -> std::io::Result<()> {
    let banded = results.iter().any(|r| r.bands.is_some());
    let mut csv = csv::Writer::from_writer(w);
    let mut head = vec!["run".to_string()];
    head.extend(design.factors().into_iter().map(|f| f.name));
    head.push("fz_mm".into());
    head.push("step_mm".into());
    // Response columns are named by their symbol only: units follow iso25178.md.
    for name in &design.responses {
        head.push(name.clone());
        if banded {
            head.extend(["p5", "p50", "p95"].map(|q| format!("{name}_{q}")));
        }
    }
    head.push("error".into());
    csv.write_record(&head)?;
    for r in results {
        let mut row = vec![r.point.run.to_string()];
        row.extend(r.point.values.iter().map(|v| format!("{v}")));
        row.push(fmt_value(r.fz_mm));
        row.push(fmt_value(r.stepover_mm));
        for (k, v) in r.responses.iter().enumerate() {
            row.push(fmt_value(*v));
            if banded {
                let b = r
                    .bands
                    .as_ref()
                    .and_then(|b| b.get(k))
                    .copied()
                    .unwrap_or(crate::study::uncertainty::Band::NAN);
                row.extend([b.p5, b.p50, b.p95].map(fmt_value));
            }
        }
        row.push(r.error.clone().unwrap_or_default());
        csv.write_record(&row)?;
    }
    csv.flush()
}

/// `effects.csv`: one row per response, factor and level: `response,factor,level,mean,
/// effect` (001 Eq 7, M_ij − M) and `relative_first` (Eq 8, filled on the first level only).
pub fn write_effects_csv(
    design: &Design,
    effects: &[Effects],
    w: &mut dyn Write,
) -> std::io::Result<()> {
    let mut csv = csv::Writer::from_writer(w);
    csv.write_record([
        "response",
        "factor",
        "level",
        "mean",
        "effect",
        "relative_first",
    ])?;
    let factors = design.factors();
    for (resp, e) in design.responses.iter().zip(effects) {
        for (i, f) in factors.iter().enumerate() {
            for (j, level) in f.levels.iter().enumerate() {
                let rel = if j == 0 {
                    fmt_value(e.relative_first[i])
                } else {
                    String::new()
                };
                csv.write_record([
                    resp.clone(),
                    f.name.clone(),
                    format!("{level}"),
                    fmt_value(e.mean),
                    fmt_value(e.effects[i][j]),
                    rel,
                ])?;
            }
        }
    }
    csv.flush()
}
