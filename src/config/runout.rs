//! The run-out study file (`study.toml` of `crest runout`): its schema and checks, read into
//! a [`crate::study::runout::Study`].
//!
//! ```toml
//! tool = "../tools/ball-r5-z4.toml"  # the cutter, relative to the study file
//! ap_mm = 0.4                        # depth of cut along the normal, mm
//! rule = "exact"                     # "exact" (default) or "paper" (Marin et al. 2023, Eq 8)
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

use crate::parse::Span;
use crate::study::runout::{MAX_CASES, RunoutParam, Study, SweepValues};
use crate::tool::Rule;
use serde::Deserialize;
use toml::Spanned;

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
    pub rule: Rule,
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
#[error("line {}, column {}: {message}", at.line, at.column)]
pub struct StudyError {
    /// Where (line 1, column 1 when the TOML reader gives no place).
    pub at: Span,
    /// What is wrong.
    pub message: String,
}

fn at(text: &str, span: std::ops::Range<usize>, message: String) -> StudyError {
    StudyError {
        at: Span::of(text, span),
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
    let cfg: StudyConfig = toml::from_str(text).map_err(|e| StudyError {
        at: super::toml_span(text, &e),
        message: e.message().trim().to_string(),
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
        rule: cfg.rule,
        x,
        leads_deg: values.lead.clone(),
        tool_heights_mm: heights,
        swept,
        sweep: values,
    })
}
