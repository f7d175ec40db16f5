//! The regression study file of `crest report` (the cases of a measured table and how to
//! predict them): its schema and checks, read into a [`Study`].
//!
//! ```toml
//! title = "002 Table 2"
//! tool = "../tools/ball-r5-z4-presetter.toml"   # relative to the study file
//! model = "crest"                               # or "simulate"
//! fz_mm = 0.05
//! rule = "paper"                                # or "exact" (the default)
//! ap_mm = 0.4
//! stepover_mm = 0.3                             # optional: for Sa/Sz and stepover Ra/Rz columns
//! [runout]                                      # optional: replaces the tool's [runout]
//! tooth_radius_deviation_um = [-10, -15, -24, -25]
//! [simulate]                                    # optional: settings of model = "simulate"
//! surface_model = "ice"
//! grid_um = 1.0
//! dtheta_deg = 0.5
//! [process]                                     # optional: process effects (docs/process-effects.md)
//! min_chip_um = 2.0                             # also recovery, texture_sq_um, texture_corr_um, texture_seed
//! [uncertainty]                                 # optional: inputs of --monte-carlo (standard uncertainties)
//! runout_offset_um = 1.0                        # 2-D error of the offset vector, per component
//! tooth_deviation_um = 1.0                      # error of every tooth's radial deviation
//! spindle_phase = true                          # draw the spindle phase of every pass (default)
//! parameter_scale = 1.0                         # times the calibrated parameters' uncertainties
//! [[case]]
//! lead_deg = 15
//! side = "convex"
//! surface_radius_mm = 20                        # optional
//! ```

use super::ConfigError;
use crate::study::measured::Side;
use crate::study::regression::{Model, SimulateSpec, Study, StudyCase};
use crate::surface::ModelKind;
use crate::tool::{Rule, Runout};
use serde::Deserialize;
use toml::Spanned;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RunoutFile {
    #[serde(default)]
    offset_um: f64,
    #[serde(default)]
    offset_phase_deg: f64,
    #[serde(default)]
    axis_tilt_deg: f64,
    #[serde(default)]
    axis_tilt_phase_deg: f64,
    #[serde(default)]
    tooth_radius_deviation_um: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SimulateFile {
    #[serde(default)]
    surface_model: ModelKind,
    grid_um: Option<Spanned<f64>>,
    dtheta_deg: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CaseFile {
    lead_deg: Spanned<f64>,
    side: Side,
    #[serde(default)]
    surface_radius_mm: Option<Spanned<f64>>,
    #[serde(default)]
    fz_mm: Option<Spanned<f64>>,
    #[serde(default)]
    model: Option<Model>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyFile {
    title: String,
    #[serde(default)]
    source: Option<String>,
    tool: String,
    #[serde(default)]
    model: Model,
    fz_mm: Spanned<f64>,
    #[serde(default)]
    rule: Rule,
    ap_mm: Spanned<f64>,
    #[serde(default)]
    cutting_speed_m_min: Option<f64>,
    #[serde(default)]
    stepover_mm: Option<Spanned<f64>>,
    #[serde(default)]
    runout: Option<Spanned<RunoutFile>>,
    #[serde(default)]
    simulate: Option<SimulateFile>,
    #[serde(default)]
    notes: Option<String>,
    #[serde(default)]
    process: Option<super::process::EffectsFile>,
    #[serde(default)]
    uncertainty: Option<super::uncertainty::UncertaintyFile>,
    #[serde(rename = "case", default)]
    cases: Vec<Spanned<CaseFile>>,
}

/// Parse a study from TOML text; `file` names the file in error messages. Unknown keys,
/// missing keys and impossible values are errors at their line and column.
pub fn parse_study(text: &str, file: &str) -> Result<Study, ConfigError> {
    let s: StudyFile = super::from_toml(text, file)?;
    let at = |pos: usize, message: String| ConfigError::at(file, text, pos, message);
    let fz = *s.fz_mm.get_ref();
    let (fz_lo, fz_hi) = crate::math::limits::FZ_MM;
    if !(fz.is_finite() && (fz_lo..=fz_hi).contains(&fz)) {
        return Err(at(
            s.fz_mm.span().start,
            format!("fz_mm must lie between {fz_lo} and {fz_hi} mm, found {fz}"),
        ));
    }
    let ap = *s.ap_mm.get_ref();
    if !(ap.is_finite() && ap >= 0.0) {
        return Err(at(
            s.ap_mm.span().start,
            format!("ap_mm must be a non-negative number, found {ap}"),
        ));
    }
    let stepover_mm = match &s.stepover_mm {
        None => None,
        Some(v) => {
            let ae = *v.get_ref();
            if !(ae.is_finite() && ae > 0.0) {
                return Err(at(
                    v.span().start,
                    format!("stepover_mm must be a positive number, found {ae}"),
                ));
            }
            Some(ae)
        }
    };
    let simulate = match &s.simulate {
        None => None,
        Some(sim) => {
            let mut spec = SimulateSpec {
                surface_model: sim.surface_model,
                ..SimulateSpec::default()
            };
            if let Some(g) = &sim.grid_um {
                let v = *g.get_ref();
                if !(v.is_finite() && (0.1..=50.0).contains(&v)) {
                    return Err(at(
                        g.span().start,
                        format!("[simulate] grid_um must lie in [0.1, 50], found {v}"),
                    ));
                }
                spec.grid_um = v;
            }
            if let Some(d) = &sim.dtheta_deg {
                let v = *d.get_ref();
                let lo = crate::math::limits::MIN_DTHETA_DEG;
                if !(v.is_finite() && v >= lo && v <= 10.0) {
                    return Err(at(
                        d.span().start,
                        format!("[simulate] dtheta_deg must lie in [{lo}, 10], found {v}"),
                    ));
                }
                spec.dtheta_deg = v;
            }
            Some(spec)
        }
    };
    let runout = match &s.runout {
        None => None,
        Some(r) => {
            let v = r.get_ref();
            let all = [
                v.offset_um,
                v.offset_phase_deg,
                v.axis_tilt_deg,
                v.axis_tilt_phase_deg,
            ];
            if all
                .iter()
                .chain(v.tooth_radius_deviation_um.iter())
                .any(|x| !x.is_finite())
            {
                return Err(at(r.span().start, "[runout] values must be finite".into()));
            }
            Some(Runout {
                offset_mm: v.offset_um * 1e-3,
                offset_phase_rad: v.offset_phase_deg.to_radians(),
                tilt_rad: v.axis_tilt_deg.to_radians(),
                tilt_phase_rad: v.axis_tilt_phase_deg.to_radians(),
                tooth_radius_dev_mm: v
                    .tooth_radius_deviation_um
                    .iter()
                    .map(|d| d * 1e-3)
                    .collect(),
                ..Default::default()
            })
        }
    };
    if s.cases.is_empty() {
        return Err(ConfigError::whole(file, "the study has no [[case]]"));
    }
    let mut cases: Vec<StudyCase> = Vec::with_capacity(s.cases.len());
    for (i, c) in s.cases.iter().enumerate() {
        let n = i + 1;
        let cs = c.get_ref();
        let lead = *cs.lead_deg.get_ref();
        if !(lead.is_finite() && (0.0..90.0).contains(&lead)) {
            return Err(at(
                cs.lead_deg.span().start,
                format!("case {n}: lead_deg must lie in [0, 90), found {lead}"),
            ));
        }
        let fz_mm = match &cs.fz_mm {
            Some(f) if !(f.get_ref().is_finite() && (fz_lo..=fz_hi).contains(f.get_ref())) => {
                return Err(at(
                    f.span().start,
                    format!(
                        "case {n}: fz_mm must lie between {fz_lo} and {fz_hi} mm, found {}",
                        f.get_ref()
                    ),
                ));
            }
            f => f.as_ref().map(|f| *f.get_ref()),
        };
        let surface_radius_mm = match &cs.surface_radius_mm {
            Some(r) => {
                let rs = *r.get_ref();
                if !(rs.is_finite() && rs > 0.0) {
                    return Err(at(
                        r.span().start,
                        format!("case {n}: surface_radius_mm must be positive, found {rs}"),
                    ));
                }
                if cs.side == Side::Plane {
                    return Err(at(
                        r.span().start,
                        format!("case {n}: surface_radius_mm is given but side is plane"),
                    ));
                }
                if !cs.side.is_curved() {
                    return Err(at(
                        r.span().start,
                        format!(
                            "case {n}: surface_radius_mm is given but side `{}` is a plain label; the curvature correction needs side = \"concave\" or \"convex\"",
                            cs.side.name()
                        ),
                    ));
                }
                Some(rs)
            }
            None => None,
        };
        if let Some(j) = cases
            .iter()
            .position(|d| d.lead_deg == lead && d.side == cs.side)
        {
            return Err(at(
                c.span().start,
                format!(
                    "case {n} repeats case {} (lead {}°, {})",
                    j + 1,
                    lead,
                    cs.side.name()
                ),
            ));
        }
        cases.push(StudyCase {
            lead_deg: lead,
            side: cs.side.clone(),
            surface_radius_mm,
            fz_mm,
            model: cs.model,
        });
    }
    let process = match &s.process {
        Some(p) => p.to_process(text, file, None)?,
        None => crate::surface::Process::default(),
    };
    let uncertainty = match &s.uncertainty {
        Some(u) => u.to_uncertainty(text, file)?,
        None => crate::study::uncertainty::Uncertainty::default(),
    };
    Ok(Study {
        process,
        uncertainty,
        title: s.title,
        source: s.source,
        tool: s.tool,
        model: s.model,
        fz_mm: fz,
        rule: s.rule,
        ap_mm: ap,
        cutting_speed_m_min: s.cutting_speed_m_min,
        stepover_mm,
        runout,
        simulate,
        notes: s.notes,
        cases,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = "title = \"t\"\ntool = \"t.toml\"\nfz_mm = 0.05\nap_mm = 0.4\n";

    #[test]
    fn rule_errors_name_their_line() {
        let e = parse_study(
            &format!("{BASE}[[case]]\nlead_deg = 15\nside = \"convex\"\n[[case]]\nlead_deg = 95\nside = \"plane\"\n"),
            "s.toml",
        )
        .unwrap_err();
        assert_eq!((e.0.span.line, e.0.span.column), (9, 12), "{e}");
        assert!(e.message().contains("lead_deg"), "{e}");
        let e = parse_study(&BASE.replace("fz_mm = 0.05", "fz_mm = -0.05"), "s.toml").unwrap_err();
        assert_eq!((e.0.span.line, e.0.span.column), (3, 9), "{e}");
        let e = parse_study(
            &format!("{BASE}rule = \"papr\"\n[[case]]\nlead_deg = 5\nside = \"plane\"\n"),
            "s.toml",
        )
        .unwrap_err();
        assert_eq!(e.0.span.line, 5, "{e}");
        let e = parse_study(BASE, "s.toml").unwrap_err();
        assert!(e.message().contains("no [[case]]"), "{e}");
    }
}
