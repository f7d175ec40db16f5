//! Run-out what-if studies: how run-out offset, its phase, axis tilt, lead angle and feed per
//! tooth change the participating teeth, the effective feed mark spacing and the crest
//! height (002 Eqs 7-8 and 14, model.md §3), as a full factorial over the swept values.
//!
//! # Study file (`study.toml`)
//!
//! ```toml
//! tool = "../tools/ball-r5-z4.toml"  # the cutter, relative to the study file
//! ap_mm = 0.4                        # depth of cut along the normal, mm
//! rule = "paper"                     # "paper" (002 Eq 8, default) or "exact"
//! x = "offset_um"                    # optional: the run-out key on the plots' x axis
//! tool_heights_mm = [0.1, 0.4, 0.8, 1.5, 2.5, 4.0]  # optional: marked heights (Fig 14c)
//!
//! [sweep]                            # full factorial over every list
//! lead_deg = [5, 15, 25]             # required
//! fz_mm = [0.05]                     # required
//! offset_um = [0, 2, 4, 6, 8, 10]    # optional run-out keys: omitted = the tool's value
//! offset_phase_deg = [0, 45]
//! axis_tilt_deg = [0]
//! axis_tilt_phase_deg = [0]
//! ```
//!
//! Swept run-out values replace the tool's own `[runout]` values; its per-tooth radius
//! deviations are always kept. Cases are numbered in a fixed nested order (lead, fz,
//! offset, phase, tilt, tilt phase; the last varies fastest) and evaluated in parallel with
//! rayon; the result order does not depend on the thread count.
//!
//! The lateral run-out curve (cf. 002 Fig 14c) is computed for the tool's own run-out
//! (the measured state, like the presetter values in 002): for each lead and tool height,
//! the spread over the teeth of the normal deviation (how much deeper than nominal each
//! tooth's element at that height reaches along the surface normal).

use crate::plot::runout::{Chart, Panel, Series, render_png, render_svg};
use crate::tool::{Cutter, Rule, ToolError, analyse, line_column, normal_runout_spread_mm};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::io::Write;
use toml::Spanned;

/// Largest number of cases a study may expand to.
pub const MAX_CASES: usize = 200_000;

/// A swept run-out parameter (the plots' x axis).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunoutParam {
    /// e0, µm.
    OffsetUm,
    /// φ_e, degrees.
    OffsetPhaseDeg,
    /// τ, degrees.
    AxisTiltDeg,
    /// φ_τ, degrees.
    AxisTiltPhaseDeg,
}

impl RunoutParam {
    /// The key as written in files and CSV headers.
    pub fn key(self) -> &'static str {
        match self {
            RunoutParam::OffsetUm => "offset_um",
            RunoutParam::OffsetPhaseDeg => "offset_phase_deg",
            RunoutParam::AxisTiltDeg => "axis_tilt_deg",
            RunoutParam::AxisTiltPhaseDeg => "axis_tilt_phase_deg",
        }
    }

    /// Axis label with unit.
    pub fn label(self) -> &'static str {
        match self {
            RunoutParam::OffsetUm => "run-out offset e0 (µm)",
            RunoutParam::OffsetPhaseDeg => "run-out phase φe (°)",
            RunoutParam::AxisTiltDeg => "axis tilt τ (°)",
            RunoutParam::AxisTiltPhaseDeg => "axis tilt phase φτ (°)",
        }
    }

    /// The value of this parameter in a case.
    pub fn of(self, c: &RunoutCase) -> f64 {
        match self {
            RunoutParam::OffsetUm => c.offset_um,
            RunoutParam::OffsetPhaseDeg => c.offset_phase_deg,
            RunoutParam::AxisTiltDeg => c.axis_tilt_deg,
            RunoutParam::AxisTiltPhaseDeg => c.axis_tilt_phase_deg,
        }
    }
}

/// The `rule` key.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RuleName {
    /// 002 Eq 8.
    #[default]
    Paper,
    /// Exact 1-D envelope.
    Exact,
}

impl From<RuleName> for Rule {
    fn from(r: RuleName) -> Rule {
        match r {
            RuleName::Paper => Rule::Paper,
            RuleName::Exact => Rule::Exact,
        }
    }
}

/// The `[sweep]` table.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepConfig {
    /// Lead angles, degrees.
    pub lead_deg: Spanned<Vec<f64>>,
    /// Feeds per tooth, mm.
    pub fz_mm: Spanned<Vec<f64>>,
    /// Run-out offsets e0, µm.
    #[serde(default)]
    pub offset_um: Option<Spanned<Vec<f64>>>,
    /// Offset phases φ_e, degrees.
    #[serde(default)]
    pub offset_phase_deg: Option<Spanned<Vec<f64>>>,
    /// Axis tilts τ, degrees.
    #[serde(default)]
    pub axis_tilt_deg: Option<Spanned<Vec<f64>>>,
    /// Tilt phases φ_τ, degrees.
    #[serde(default)]
    pub axis_tilt_phase_deg: Option<Spanned<Vec<f64>>>,
}

/// A `study.toml` document.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyConfig {
    /// Path of the `tool.toml`, relative to the study file.
    pub tool: String,
    /// Depth of cut, mm.
    pub ap_mm: Spanned<f64>,
    /// Participating-teeth rule.
    #[serde(default)]
    pub rule: RuleName,
    /// The run-out parameter on the x axis of the plots.
    #[serde(default)]
    pub x: Option<RunoutParam>,
    /// Tool heights marked on the lateral run-out plot, mm.
    #[serde(default)]
    pub tool_heights_mm: Option<Spanned<Vec<f64>>>,
    /// The swept values.
    pub sweep: SweepConfig,
}

/// Why a study file was rejected (1-based line and column, key named in the message).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("line {line}, column {column}: {message}")]
pub struct StudyError {
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
    /// Byte range of the offending text, when known.
    pub span: Option<std::ops::Range<usize>>,
    /// What is wrong.
    pub message: String,
}

/// One case of a study.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RunoutCase {
    /// 0-based case number.
    pub case: usize,
    /// Lead, degrees.
    pub lead_deg: f64,
    /// Feed per tooth, mm.
    pub fz_mm: f64,
    /// e0, µm.
    pub offset_um: f64,
    /// φ_e, degrees.
    pub offset_phase_deg: f64,
    /// τ, degrees.
    pub axis_tilt_deg: f64,
    /// φ_τ, degrees.
    pub axis_tilt_phase_deg: f64,
}

/// One row of `runout.csv`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunoutRow {
    /// The case.
    pub case: RunoutCase,
    /// Rule used.
    pub rule: &'static str,
    /// Participating teeth under the rule.
    pub zc: usize,
    /// zc of the paper rule.
    pub zc_paper: usize,
    /// zc of the exact rule.
    pub zc_exact: usize,
    /// 1-based indices of the participating teeth, `;`-separated.
    pub participating_teeth: String,
    /// fz·Z/zc, mm.
    pub fz_effective_mm: f64,
    /// Eq 14 at the nominal fz, µm.
    pub crest_height_um: f64,
    /// Crest corrected for run-out under the rule, µm.
    pub crest_height_corrected_um: f64,
    /// Exact 1-D envelope crest, µm.
    pub crest_height_exact_um: f64,
    /// R_ef,max, mm.
    pub effective_radius_mm: f64,
    /// R_ef,max / R.
    pub cutting_speed_ratio: f64,
    /// Spread of the teeth's normal deviation at the generating height, µm.
    pub normal_runout_spread_um: f64,
}

/// A checked study: the cases to run and the plot settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Study {
    /// Tool path as written (relative to the study file).
    pub tool: String,
    /// Depth of cut, mm.
    pub ap_mm: f64,
    /// Rule.
    pub rule: Rule,
    /// The x axis of the plots.
    pub x: RunoutParam,
    /// Swept leads, degrees (in file order).
    pub leads_deg: Vec<f64>,
    /// Marked tool heights, mm (empty = six heights spread over the end).
    pub tool_heights_mm: Vec<f64>,
    /// Which keys were swept with more than one value (for series labels).
    pub swept: Vec<&'static str>,
    sweep: SweepValues,
}

#[derive(Debug, Clone, PartialEq)]
struct SweepValues {
    lead: Vec<f64>,
    fz: Vec<f64>,
    offset: Option<Vec<f64>>,
    phase: Option<Vec<f64>>,
    tilt: Option<Vec<f64>>,
    tilt_phase: Option<Vec<f64>>,
}

fn at(text: &str, span: std::ops::Range<usize>, message: String) -> StudyError {
    let (line, column) = line_column(text, span.start);
    StudyError {
        line,
        column,
        span: Some(span),
        message,
    }
}

fn list(
    text: &str,
    key: &str,
    v: &Spanned<Vec<f64>>,
    ok: impl Fn(f64) -> bool,
    what: &str,
) -> Result<Vec<f64>, StudyError> {
    if v.get_ref().is_empty() {
        return Err(at(text, v.span(), format!("`{key}` must not be empty")));
    }
    if let Some(bad) = v.get_ref().iter().find(|x| !(x.is_finite() && ok(**x))) {
        return Err(at(
            text,
            v.span(),
            format!("`{key}` values must be {what}, found {bad}"),
        ));
    }
    Ok(v.get_ref().clone())
}

/// Parse and check a study file.
pub fn parse_study(text: &str) -> Result<Study, StudyError> {
    let cfg: StudyConfig = toml::from_str(text).map_err(|e| {
        let span = e.span();
        let (line, column) = span.as_ref().map_or((1, 1), |s| line_column(text, s.start));
        StudyError {
            line,
            column,
            span,
            message: e.message().trim().to_string(),
        }
    })?;
    let ap = *cfg.ap_mm.get_ref();
    if !(ap.is_finite() && ap >= 0.0) {
        return Err(at(
            text,
            cfg.ap_mm.span(),
            format!("`ap_mm` must be non-negative, found {ap}"),
        ));
    }
    let s = &cfg.sweep;
    let any = |_: f64| true;
    let opt = |key: &str, v: &Option<Spanned<Vec<f64>>>, ok: &dyn Fn(f64) -> bool, what: &str| {
        v.as_ref().map(|v| list(text, key, v, ok, what)).transpose()
    };
    let values = SweepValues {
        lead: list(
            text,
            "sweep.lead_deg",
            &s.lead_deg,
            |x| x.abs() <= 90.0,
            "within ±90 degrees",
        )?,
        fz: list(text, "sweep.fz_mm", &s.fz_mm, |x| x > 0.0, "positive")?,
        offset: opt("sweep.offset_um", &s.offset_um, &any, "finite")?,
        phase: opt(
            "sweep.offset_phase_deg",
            &s.offset_phase_deg,
            &any,
            "finite",
        )?,
        tilt: opt(
            "sweep.axis_tilt_deg",
            &s.axis_tilt_deg,
            &|x: f64| x.abs() < 45.0,
            "within ±45 degrees",
        )?,
        tilt_phase: opt(
            "sweep.axis_tilt_phase_deg",
            &s.axis_tilt_phase_deg,
            &any,
            "finite",
        )?,
    };
    let heights = match &cfg.tool_heights_mm {
        Some(h) => list(text, "tool_heights_mm", h, |x| x >= 0.0, "non-negative")?,
        None => Vec::new(),
    };
    let len = |v: &Option<Vec<f64>>| v.as_ref().map_or(1, Vec::len);
    let n = values.lead.len()
        * values.fz.len()
        * len(&values.offset)
        * len(&values.phase)
        * len(&values.tilt)
        * len(&values.tilt_phase);
    if n > MAX_CASES {
        return Err(at(
            text,
            s.lead_deg.span(),
            format!("the sweep expands to {n} cases, more than {MAX_CASES}"),
        ));
    }
    let many = |v: &Option<Vec<f64>>| len(v) > 1;
    let mut swept = Vec::new();
    if values.lead.len() > 1 {
        swept.push("lead_deg");
    }
    if values.fz.len() > 1 {
        swept.push("fz_mm");
    }
    for (key, v) in [
        ("offset_um", &values.offset),
        ("offset_phase_deg", &values.phase),
        ("axis_tilt_deg", &values.tilt),
        ("axis_tilt_phase_deg", &values.tilt_phase),
    ] {
        if many(v) {
            swept.push(key);
        }
    }
    let x = cfg.x.unwrap_or(if many(&values.offset) {
        RunoutParam::OffsetUm
    } else if many(&values.tilt) {
        RunoutParam::AxisTiltDeg
    } else if many(&values.phase) {
        RunoutParam::OffsetPhaseDeg
    } else if many(&values.tilt_phase) {
        RunoutParam::AxisTiltPhaseDeg
    } else {
        RunoutParam::OffsetUm
    });
    Ok(Study {
        tool: cfg.tool,
        ap_mm: ap,
        rule: cfg.rule.into(),
        x,
        leads_deg: values.lead.clone(),
        tool_heights_mm: heights,
        swept,
        sweep: values,
    })
}

impl Study {
    /// The cases in their fixed order, with the tool's run-out filling unswept keys.
    pub fn cases(&self, cutter: &Cutter) -> Vec<RunoutCase> {
        let r = &cutter.runout;
        let or = |v: &Option<Vec<f64>>, base: f64| v.clone().unwrap_or_else(|| vec![base]);
        let offsets = or(&self.sweep.offset, r.offset_mm * 1e3);
        let phases = or(&self.sweep.phase, r.offset_phase_rad.to_degrees());
        let tilts = or(&self.sweep.tilt, r.tilt_rad.to_degrees());
        let tilt_phases = or(&self.sweep.tilt_phase, r.tilt_phase_rad.to_degrees());
        let mut out = Vec::new();
        for &lead_deg in &self.sweep.lead {
            for &fz_mm in &self.sweep.fz {
                for &offset_um in &offsets {
                    for &offset_phase_deg in &phases {
                        for &axis_tilt_deg in &tilts {
                            for &axis_tilt_phase_deg in &tilt_phases {
                                out.push(RunoutCase {
                                    case: out.len(),
                                    lead_deg,
                                    fz_mm,
                                    offset_um,
                                    offset_phase_deg,
                                    axis_tilt_deg,
                                    axis_tilt_phase_deg,
                                });
                            }
                        }
                    }
                }
            }
        }
        out
    }

    /// The six default tool heights (or the configured ones), mm: evenly spaced in the
    /// polar angle from 10° to 85° on the corner arc (the end face for a flat end).
    pub fn marked_heights_mm(&self, cutter: &Cutter) -> Vec<f64> {
        if !self.tool_heights_mm.is_empty() {
            return self.tool_heights_mm.clone();
        }
        default_marked_heights_mm(cutter)
    }

    /// A label for the series a case belongs to: every swept key except the x axis (and,
    /// with `skip_lead`, the lead).
    pub fn series_label(&self, c: &RunoutCase, skip_lead: bool) -> String {
        let mut parts = Vec::new();
        for key in &self.swept {
            if *key == self.x.key() || (skip_lead && *key == "lead_deg") {
                continue;
            }
            parts.push(match *key {
                "lead_deg" => format!("lead {}°", c.lead_deg),
                "fz_mm" => format!("fz {} mm", c.fz_mm),
                "offset_um" => format!("e0 {} µm", c.offset_um),
                "offset_phase_deg" => format!("φe {}°", c.offset_phase_deg),
                "axis_tilt_deg" => format!("τ {}°", c.axis_tilt_deg),
                _ => format!("φτ {}°", c.axis_tilt_phase_deg),
            });
        }
        parts.join(", ")
    }
}

/// The cutter of one case: the tool with the case's run-out (tooth deviations kept).
pub fn case_cutter(cutter: &Cutter, c: &RunoutCase) -> Cutter {
    let mut out = cutter.clone();
    out.runout.offset_mm = c.offset_um * 1e-3;
    out.runout.offset_phase_rad = c.offset_phase_deg.to_radians();
    out.runout.tilt_rad = c.axis_tilt_deg.to_radians();
    out.runout.tilt_phase_rad = c.axis_tilt_phase_deg.to_radians();
    out
}

/// Evaluate one case.
pub fn run_case(cutter: &Cutter, study: &Study, c: &RunoutCase) -> Result<RunoutRow, ToolError> {
    let cc = case_cutter(cutter, c);
    let a = analyse(&cc, c.lead_deg, study.ap_mm, c.fz_mm, study.rule)?;
    Ok(RunoutRow {
        case: *c,
        rule: study.rule.name(),
        zc: a.zc,
        zc_paper: a.zc_paper,
        zc_exact: a.zc_exact,
        participating_teeth: a
            .teeth
            .iter()
            .filter(|t| t.participates)
            .map(|t| t.index.to_string())
            .collect::<Vec<_>>()
            .join(";"),
        fz_effective_mm: a.fz_effective_mm,
        crest_height_um: a.crest_height_mm * 1e3,
        crest_height_corrected_um: a.crest_height_corrected_mm * 1e3,
        crest_height_exact_um: a.crest_height_exact_mm * 1e3,
        effective_radius_mm: a.effective_radius_mm,
        cutting_speed_ratio: a.cutting_speed_ratio,
        normal_runout_spread_um: normal_runout_spread_mm(&cc, a.generating_height_mm, a.lead_rad)
            * 1e3,
    })
}

/// Run every case in parallel; rows come back in case order.
pub fn run_study(cutter: &Cutter, study: &Study) -> Result<Vec<RunoutRow>, ToolError> {
    study
        .cases(cutter)
        .par_iter()
        .map(|c| run_case(cutter, study, c))
        .collect()
}

/// Lateral run-out against tool height for one lead (cf. 002 Fig 14c).
#[derive(Debug, Clone, PartialEq)]
pub struct LateralCurve {
    /// Lead, degrees.
    pub lead_deg: f64,
    /// (tool height mm, spread µm) along the end, densely.
    pub curve: Vec<(f64, f64)>,
    /// (tool height mm, spread µm) at the marked heights.
    pub marks: Vec<(f64, f64)>,
}

/// Six tool heights spread over the end, mm: where the corner's normal is 10°, 25°, …, 85°
/// from the axis.
pub fn default_marked_heights_mm(cutter: &Cutter) -> Vec<f64> {
    let c = cutter.corner_radius_mm();
    (0..6)
        .map(|i| c * (1.0 - (10.0 + 15.0 * i as f64).to_radians().cos()))
        .collect()
}

/// The lateral run-out curves of the tool's own run-out for each lead of the study.
pub fn lateral_curves(cutter: &Cutter, study: &Study) -> Vec<LateralCurve> {
    lateral_curves_for(cutter, &study.leads_deg, &study.marked_heights_mm(cutter))
}

/// The lateral run-out curves of the tool's own run-out for the given leads (degrees), with
/// markers at the given tool heights (mm): the spread over the teeth of the deviation along
/// the surface normal, densely from the tip to the top of the corner radius.
pub fn lateral_curves_for(
    cutter: &Cutter,
    leads_deg: &[f64],
    marks_mm: &[f64],
) -> Vec<LateralCurve> {
    let top = cutter.corner_radius_mm().max(0.05 * cutter.radius_mm);
    let spread = |z: f64, lead: f64| normal_runout_spread_mm(cutter, z, lead.to_radians()) * 1e3;
    leads_deg
        .iter()
        .map(|&lead| LateralCurve {
            lead_deg: lead,
            curve: (0..=200)
                .map(|i| {
                    let z = top * i as f64 / 200.0;
                    (z, spread(z, lead))
                })
                .collect(),
            marks: marks_mm.iter().map(|&z| (z, spread(z, lead))).collect(),
        })
        .collect()
}

/// Columns of `runout.csv`.
pub const CSV_HEADER: [&str; 20] = [
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
pub fn write_csv(rows: &[RunoutRow], teeth: usize, w: &mut dyn Write) -> std::io::Result<()> {
    let mut csv = csv::Writer::from_writer(w);
    csv.write_record(CSV_HEADER)?;
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
                y_range: if quantity == 0 {
                    Some((0.0, teeth as f64 + 0.5))
                } else {
                    None
                },
                y_integer: quantity == 0,
                series: series
                    .iter()
                    .map(|(color, _, v)| {
                        line(
                            series_name(study, v[0], split, tool_name),
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
                        )
                    })
                    .collect(),
            });
        }
    }
    Chart {
        title: format!(
            "Participating teeth and effective feed per tooth against run-out ({} rule)",
            study.rule.name()
        ),
        x_label: x.label().to_string(),
        panels,
        size: size(cols, 2),
        columns: cols,
    }
}

/// Crest height against run-out for each lead: the corrected crest under the study's rule
/// (solid) and, under the paper rule, the exact 1-D crest (dashed), one column per facet.
pub fn crest_chart(rows: &[RunoutRow], study: &Study, tool_name: &str) -> Chart {
    let f = facets(rows, study);
    let split = f.len() > 1 || f.first().is_some_and(|(l, _)| !l.is_empty());
    let split = split
        || study
            .swept
            .iter()
            .all(|k| *k == "lead_deg" || *k == study.x.key());
    let x = study.x;
    let paper = study.rule == Rule::Paper;
    let cols = f.len().max(1);
    let panels = f
        .iter()
        .map(|(facet, series)| {
            let mut out = Vec::new();
            for (color, _, v) in series {
                let name = series_name(study, v[0], split, tool_name);
                out.push(line(
                    if paper {
                        format!("{name}, Eq 14 at fz_eff")
                    } else {
                        name.clone()
                    },
                    v.iter()
                        .map(|r| (x.of(&r.case), r.crest_height_corrected_um))
                        .collect(),
                    *color,
                    false,
                ));
                if paper {
                    out.push(line(
                        format!("{name}, exact 1-D"),
                        v.iter()
                            .map(|r| (x.of(&r.case), r.crest_height_exact_um))
                            .collect(),
                        *color,
                        true,
                    ));
                }
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
    Chart {
        title: format!(
            "Feed-direction crest height against run-out ({} rule)",
            study.rule.name()
        ),
        x_label: x.label().to_string(),
        panels,
        size: size(cols, 1),
        columns: cols,
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
    }
}

/// Names of the files [`write_outputs`] writes into the output folder.
pub const OUTPUT_FILES: [&str; 7] = [
    "runout.csv",
    "runout-teeth.svg",
    "runout-teeth.png",
    "runout-crest.svg",
    "runout-crest.png",
    "runout-lateral.svg",
    "runout-lateral.png",
];

/// Write `runout.csv` and the three charts (SVG and PNG) into `dir` (which must exist),
/// each file atomically. Returns the paths written.
pub fn write_outputs(
    dir: &std::path::Path,
    cutter: &Cutter,
    study: &Study,
    rows: &[RunoutRow],
    tool_name: &str,
) -> std::io::Result<Vec<std::path::PathBuf>> {
    use crate::io::write_atomic;
    let mut written = Vec::new();
    let csv_path = dir.join(OUTPUT_FILES[0]);
    write_atomic(&csv_path, |w| write_csv(rows, cutter.teeth(), w))?;
    written.push(csv_path);
    let charts = [
        (
            "runout-teeth",
            teeth_chart(rows, study, cutter.teeth(), tool_name),
        ),
        ("runout-crest", crest_chart(rows, study, tool_name)),
        (
            "runout-lateral",
            lateral_chart(&lateral_curves(cutter, study), tool_name),
        ),
    ];
    for (stem, chart) in charts {
        let svg = render_svg(&chart)?;
        let svg_path = dir.join(format!("{stem}.svg"));
        write_atomic(&svg_path, |w| w.write_all(svg.as_bytes()))?;
        written.push(svg_path);
        let png = render_png(&chart)?;
        let png_path = dir.join(format!("{stem}.png"));
        write_atomic(&png_path, |w| w.write_all(&png))?;
        written.push(png_path);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::Shape;

    const SAMPLE: &str = include_str!("../../samples/studies/runout.toml");

    #[test]
    fn sample_study_parses_and_expands_in_order() {
        let study = parse_study(SAMPLE).unwrap();
        let cutter = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        let cases = study.cases(&cutter);
        assert!(cases.len() > 10);
        for (i, c) in cases.iter().enumerate() {
            assert_eq!(c.case, i);
        }
        // The last key varies fastest, the lead slowest.
        assert_eq!(cases[0].lead_deg, study.leads_deg[0]);
        assert_eq!(
            cases.last().unwrap().lead_deg,
            *study.leads_deg.last().unwrap()
        );
    }

    #[test]
    fn study_errors_name_key_and_line() {
        let e = parse_study(
            "tool = \"t.toml\"\nap_mm = 0.4\n[sweep]\nlead_deg = [5]\nfz_mm = [0.05, -1]\n",
        )
        .unwrap_err();
        assert_eq!(e.line, 5);
        assert!(e.message.contains("fz_mm"), "{e}");
        let e = parse_study("tool = \"t.toml\"\nap_mm = 0.4\n[sweep]\nlead_deg = [5]\nfz_mm = [0.05]\nrunout = [1]\n")
            .unwrap_err();
        assert_eq!(e.line, 6);
        assert!(e.message.contains("runout"), "{e}");
    }

    #[test]
    fn parallel_result_is_deterministic_and_matches_serial() {
        let study = parse_study(SAMPLE).unwrap();
        let mut cutter = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        cutter.runout.tooth_radius_dev_mm = vec![-0.010, -0.015, -0.024, -0.025];
        let rows = run_study(&cutter, &study).unwrap();
        let serial: Vec<RunoutRow> = study
            .cases(&cutter)
            .iter()
            .map(|c| run_case(&cutter, &study, c).unwrap())
            .collect();
        assert_eq!(rows, serial);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| run_study(&cutter, &study).unwrap());
        assert_eq!(rows, one);
        let mut buf = Vec::new();
        write_csv(&rows, 4, &mut buf).unwrap();
        let text = String::from_utf8(buf).unwrap();
        assert_eq!(text.lines().count(), rows.len() + 1);
        assert!(text.starts_with("case,lead_deg,fz_mm,offset_um"));
    }

    #[test]
    fn zero_offset_with_presetter_radii_keeps_only_tooth_one() {
        let study = parse_study(
            "tool = \"t\"\nap_mm = 0.4\n[sweep]\nlead_deg = [15]\nfz_mm = [0.05]\noffset_um = [0]\n",
        )
        .unwrap();
        let mut cutter = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        cutter.runout.tooth_radius_dev_mm = vec![-0.010, -0.015, -0.024, -0.025];
        let rows = run_study(&cutter, &study).unwrap();
        assert_eq!(rows.len(), 1);
        assert_eq!(rows[0].participating_teeth, "1");
        assert!((rows[0].fz_effective_mm - 0.2).abs() < 1e-12);
        // Spread of δ at z_c (κ = β): 25 − 10 = 15 µm.
        assert!((rows[0].normal_runout_spread_um - 15.0).abs() < 1e-9);
    }
}
