//! A regression's verdict: every case of a study predicted and held against the measured
//! table (mean ± σ, pass or fail within a tolerance in percent of the measured mean), and the
//! [`Regression`] the writers ([`crate::report::regression`], [`crate::plot::regression`])
//! render. The predictions are [`super::regression`]'s; a calibration
//! ([`super::calibrate`]) replaces them by leave-one-out values ([`judge_by_loo`]).

use super::measured::{MeasuredCase, MeasuredTable, Param, Side, Stat, summarize};
use super::regression::{CrestPrediction, Model, Study, ZmapPrediction, predict_case};
use crate::math::trim_decimals;
use crate::surface::Process;
use crate::tool::Cutter;
use serde::Serialize;

/// The default tolerance of `crest report`, percent of the measured mean.
pub const DEFAULT_TOLERANCE_PCT: f64 = 20.0;

/// Why a regression cannot be made: the study and the table do not match, or a case cannot
/// be predicted.
#[derive(Debug, Clone, PartialEq, thiserror::Error, miette::Diagnostic)]
#[error("{file}: {message}")]
pub struct RegressionError {
    /// The study file, as given.
    pub file: String,
    /// What is wrong.
    pub message: String,
}

/// One parameter of one case held against its measurement.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// Parameter name (`Rz` or `Ra`).
    pub parameter: String,
    /// Measured statistics, µm.
    pub measured: Stat,
    /// Simulated value, µm.
    pub simulated_um: f64,
    /// simulated / measured mean.
    pub ratio: f64,
    /// 100·(simulated − mean)/mean.
    pub deviation_pct: f64,
    /// Whether the simulated value lies within mean ± σ.
    pub within_sigma: bool,
    /// |deviation| ≤ tolerance.
    pub pass: bool,
}

impl Comparison {
    fn new(parameter: &str, measured: Stat, simulated_um: f64, tolerance_pct: f64) -> Self {
        let ratio = simulated_um / measured.mean;
        let deviation_pct = 100.0 * (simulated_um - measured.mean) / measured.mean;
        let within_sigma = measured
            .sd
            .is_some_and(|sd| (simulated_um - measured.mean).abs() <= sd);
        // A zero mean gives an infinite or NaN deviation, which fails.
        let pass = deviation_pct.abs() <= tolerance_pct;
        Comparison {
            parameter: parameter.to_string(),
            measured,
            simulated_um,
            ratio,
            deviation_pct,
            within_sigma,
            pass,
        }
    }
}

/// The result of one case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseResult {
    /// Lead angle, degrees.
    pub lead_deg: f64,
    /// Curvature side.
    pub side: Side,
    /// Local surface radius, mm (None = plane).
    pub surface_radius_mm: Option<f64>,
    /// Model used.
    pub model: Model,
    /// Programmed feed per tooth, mm.
    pub fz_mm: f64,
    /// The measurements.
    pub measured: MeasuredCase,
    /// The crest model's prediction (always computed, also for reference).
    pub prediction: CrestPrediction,
    /// The z-map prediction, for `model = "simulate"`.
    pub zmap: Option<ZmapPrediction>,
    /// Comparisons (Rz first, then Ra, for the columns the table has).
    pub comparisons: Vec<Comparison>,
    /// Every comparison passes.
    pub pass: bool,
}

/// A whole regression: what the writers render and `--json` prints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Regression {
    /// Study title.
    pub title: String,
    /// Source of the measurements.
    pub source: Option<String>,
    /// Notes from the study.
    pub notes: Option<String>,
    /// Measured table file, as given.
    pub measured_file: String,
    /// Study file, as given.
    pub study_file: String,
    /// Tool file, as written in the study.
    pub tool_file: String,
    /// Tool description (one line).
    pub tool: String,
    /// Run-out description (one line).
    pub runout: String,
    /// Depth of cut, mm.
    pub ap_mm: f64,
    /// Nominal cutting speed, m/min.
    pub cutting_speed_m_min: Option<f64>,
    /// Stepover of the study, mm (for the areal and stepover-direction columns).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stepover_mm: Option<f64>,
    /// Tolerance, percent of the measured mean.
    pub tolerance_pct: f64,
    /// The command that made the report.
    pub command: String,
    /// crest version.
    pub version: String,
    /// Per case.
    pub cases: Vec<CaseResult>,
    /// Every case passes.
    pub pass: bool,
    /// Process effects of the study (what the simulated columns include).
    pub process: Process,
    /// The calibration (`--free`); then a case passes on its leave-one-out prediction.
    pub calibration: Option<super::calibrate::Calibration>,
    /// Monte Carlo bands per case (`--monte-carlo`).
    pub monte_carlo: Option<Vec<super::montecarlo::CaseBands>>,
}

/// Attach a calibration to `reg` and judge every case by its leave-one-out prediction alone
/// (never by the in-sample fit): a case passes when each parameter's leave-one-out value is
/// within the tolerance of the measured mean.
/// The comparisons then hold the leave-one-out values, so the table, the plots and the
/// verdict all show what is judged.
pub fn judge_by_loo(reg: &mut Regression, cal: super::calibrate::Calibration) {
    let tol = reg.tolerance_pct;
    for c in &mut reg.cases {
        let mut pass = true;
        for k in &mut c.comparisons {
            let loo = cal.cases.iter().find(|x| {
                x.lead_deg == c.lead_deg && x.side == c.side && x.parameter == k.parameter
            });
            let loo_um = loo.map_or(f64::NAN, |x| x.loo_um);
            *k = Comparison::new(&k.parameter, k.measured, loo_um, tol);
            pass &= k.pass;
        }
        c.pass = pass;
    }
    reg.pass = reg.cases.iter().all(|c| c.pass);
    reg.calibration = Some(cal);
}

/// Inputs of [`regress`] besides the parsed files.
#[derive(Debug, Clone)]
pub struct Provenance {
    /// Measured table file, as given.
    pub measured_file: String,
    /// Study file, as given.
    pub study_file: String,
    /// The command line that made the report.
    pub command: String,
}

/// Hold every case of `study` against `table`. `cutter` is the study's tool with the run-out
/// already applied. Every measured case must have a study case and vice versa.
pub fn regress(
    table: &MeasuredTable,
    study: &Study,
    cutter: &Cutter,
    tolerance_pct: f64,
    provenance: Provenance,
) -> Result<Regression, RegressionError> {
    let err = |message: String| RegressionError {
        file: provenance.study_file.clone(),
        message,
    };
    let measured = summarize(table);
    for m in &measured {
        if !study
            .cases
            .iter()
            .any(|c| c.lead_deg == m.lead_deg && c.side == m.side)
        {
            return Err(err(format!(
                "the measured table ({}) has lead {}°, {} but the study has no such [[case]]",
                provenance.measured_file,
                m.lead_deg,
                m.side.name()
            )));
        }
    }
    let mut cases = Vec::new();
    for (i, c) in study.cases.iter().enumerate() {
        let Some(m) = measured
            .iter()
            .find(|m| m.lead_deg == c.lead_deg && m.side == c.side)
        else {
            return Err(err(format!(
                "case {} (lead {}°, {}) has no rows in the measured table {}",
                i + 1,
                c.lead_deg,
                c.side.name(),
                provenance.measured_file
            )));
        };
        let fz = c.fz_mm.unwrap_or(study.fz_mm);
        let model = c.model.unwrap_or(study.model);
        let p = predict_case(study, cutter, c, &study.process, 0.0)
            .map_err(|e| err(format!("case {}: {e}", i + 1)))?;
        let (sim_rz, sim_ra) = (p.rz_um, p.ra_um);
        let mut comparisons = Vec::new();
        if let Some(rz) = m.rz {
            comparisons.push(Comparison::new("Rz", rz, sim_rz, tolerance_pct));
        }
        if let Some(ra) = m.ra {
            comparisons.push(Comparison::new("Ra", ra, sim_ra, tolerance_pct));
        }
        // Areal and stepover-direction columns, when the table has them.
        let extra: Vec<(Param, Stat)> = Param::ALL
            .into_iter()
            .filter(|p| p.is_extra())
            .filter_map(|p| m.stat(p).map(|s| (p, s)))
            .collect();
        if !extra.is_empty() {
            let Some(ae) = study.stepover_mm else {
                return Err(err(format!(
                    "the measured table ({}) has {} but the study gives no stepover_mm (the distance between passes) to predict it",
                    provenance.measured_file,
                    extra
                        .iter()
                        .map(|(p, _)| p.column())
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            };
            let across = super::stepover::predict(cutter, ae, &p.profile_um, p.profile_step_mm)
                .map_err(|e| err(format!("case {}: {e}", i + 1)))?;
            for (param, stat) in extra {
                comparisons.push(Comparison::new(
                    param.label(),
                    stat,
                    across.value(param),
                    tolerance_pct,
                ));
            }
        }
        let (prediction, zmap) = (p.crest, p.zmap);
        let pass = comparisons.iter().all(|c| c.pass);
        cases.push(CaseResult {
            lead_deg: c.lead_deg,
            side: c.side.clone(),
            surface_radius_mm: c.surface_radius_mm,
            model,
            fz_mm: fz,
            measured: m.clone(),
            prediction,
            zmap,
            comparisons,
            pass,
        });
    }
    let pass = cases.iter().all(|c| c.pass);
    Ok(Regression {
        title: study.title.clone(),
        source: study.source.clone(),
        notes: study.notes.clone(),
        measured_file: provenance.measured_file,
        study_file: provenance.study_file,
        tool_file: study.tool.clone(),
        tool: describe_tool(cutter),
        runout: describe_runout(cutter),
        ap_mm: study.ap_mm,
        cutting_speed_m_min: study.cutting_speed_m_min,
        stepover_mm: study.stepover_mm,
        tolerance_pct,
        command: provenance.command,
        version: env!("CARGO_PKG_VERSION").to_string(),
        cases,
        pass,
        process: study.process,
        calibration: None,
        monte_carlo: None,
    })
}

fn describe_tool(c: &Cutter) -> String {
    let shape = match c.shape {
        crate::tool::Shape::Ball => "ball end".to_string(),
        crate::tool::Shape::Torus { corner_radius_mm } => {
            format!("torus, corner radius {corner_radius_mm} mm")
        }
        crate::tool::Shape::Flat => "flat end".to_string(),
        _ => c.describe(),
    };
    format!(
        "{shape}, R = {} mm, {} teeth, helix {}°",
        c.radius_mm,
        c.teeth(),
        trim_decimals(c.helix_rad.to_degrees(), 4)
    )
}

fn describe_runout(c: &Cutter) -> String {
    let r = &c.runout;
    let mut parts = Vec::new();
    if r.offset_mm != 0.0 {
        parts.push(format!(
            "offset e0 = {} µm at {}°",
            trim_decimals(r.offset_mm * 1e3, 4),
            trim_decimals(r.offset_phase_rad.to_degrees(), 4)
        ));
    }
    if r.tilt_rad != 0.0 {
        parts.push(format!(
            "axis tilt {}° at {}°",
            trim_decimals(r.tilt_rad.to_degrees(), 4),
            trim_decimals(r.tilt_phase_rad.to_degrees(), 4)
        ));
    }
    if r.tooth_radius_dev_mm.iter().any(|d| *d != 0.0) {
        let devs: Vec<String> = r
            .tooth_radius_dev_mm
            .iter()
            .map(|d| trim_decimals(d * 1e3, 4))
            .collect();
        let radii: Vec<String> = r
            .tooth_radius_dev_mm
            .iter()
            .map(|d| format!("{:.3}", c.radius_mm + d))
            .collect();
        parts.push(format!(
            "tooth radius deviations {} µm (tooth radii {} mm)",
            devs.join(" / "),
            radii.join(" / ")
        ));
    }
    if parts.is_empty() {
        "none".to_string()
    } else {
        parts.join("; ")
    }
}
