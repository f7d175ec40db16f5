//! Run-out what-if studies: how run-out offset, its phase, axis tilt, lead angle and feed per
//! tooth change the participating teeth, the effective feed mark spacing and the crest
//! height (002 Eqs 7-8 and 14, model.md §3), as a full factorial over the swept values.
//!
//! The study file (`study.toml`) is read by [`crate::config::runout`]:
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

use crate::tool::{Cutter, Rule, ToolError, analyse, normal_runout_spread_mm};
use rayon::prelude::*;
use serde::Serialize;

/// Largest number of cases a study may expand to.
pub const MAX_CASES: usize = 200_000;

/// A swept run-out parameter (the plots' x axis).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, Serialize)]
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
    /// The swept values.
    pub sweep: SweepValues,
}

/// The swept values of a run-out study (file order).
#[derive(Debug, Clone, PartialEq)]
pub struct SweepValues {
    /// Leads, degrees.
    pub lead: Vec<f64>,
    /// Feeds per tooth, mm.
    pub fz: Vec<f64>,
    /// Offsets e0, µm (None = the tool's).
    pub offset: Option<Vec<f64>>,
    /// Offset phases φe, degrees.
    pub phase: Option<Vec<f64>>,
    /// Axis tilts τ, degrees.
    pub tilt: Option<Vec<f64>>,
    /// Tilt phases φτ, degrees.
    pub tilt_phase: Option<Vec<f64>>,
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
    run_cases(cutter, study, &study.cases(cutter))
}

/// Run the given cases (some of [`Study::cases`]) in parallel; rows come back in their order.
pub fn run_cases(
    cutter: &Cutter,
    study: &Study,
    cases: &[RunoutCase],
) -> Result<Vec<RunoutRow>, ToolError> {
    cases
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
    let c = cutter.end_height_mm();
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
    let top = cutter.end_height_mm().max(0.05 * cutter.radius_mm);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::runout::parse_study;
    use crate::io::tables::write_runout_csv as write_csv;
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
        assert_eq!(e.at.line, 5);
        assert!(e.message.contains("fz_mm"), "{e}");
        let e = parse_study("tool = \"t.toml\"\nap_mm = 0.4\n[sweep]\nlead_deg = [5]\nfz_mm = [0.05]\nrunout = [1]\n")
            .unwrap_err();
        assert_eq!(e.at.line, 6);
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
