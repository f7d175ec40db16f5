//! `crest tool`: the analysis of a cutter at one engagement (effective radius, crest
//! height, participating teeth) as the JSON object the command line and the Python
//! package print.

use crate::tool::{Analysis, Cutter, Rule};

/// The object of `crest tool --json` for `cutter` (read from `tool`) at
/// `(lead_deg, ap_mm, fz_mm)` under `rule`, analysed as `a`.
pub fn analysis_json(
    cutter: &Cutter,
    tool: &str,
    (lead_deg, ap_mm, fz_mm): (f64, f64, f64),
    rule: Rule,
    a: &Analysis,
) -> serde_json::Value {
    let r = cutter.radius_mm;
    let teeth: Vec<serde_json::Value> = a
        .teeth
        .iter()
        .map(|t| {
            serde_json::json!({
                "index": t.index,
                "radius_mm": t.radius_mm,
                "local_radius_mm": t.local_radius_mm,
                "runout_um": t.runout_mm * 1e3,
                "axial_deviation_um": t.axial_deviation_mm * 1e3,
                "normal_deviation_um": t.normal_deviation_mm * 1e3,
                "participates": t.participates,
                "participates_paper": t.participates_paper,
                "participates_exact": t.participates_exact,
                "effective_radius_mm": t.effective_radius_mm,
                "cutting_speed_ratio": t.effective_radius_mm / r,
                "effective_radius_error_pct": t.effective_radius_error_pct,
            })
        })
        .collect();
    serde_json::json!({
        "tool": tool,
        "shape": cutter.shape.name(),
        "description": cutter.describe(),
        "radius_mm": r,
        "corner_radius_mm": cutter.corner_radius_mm(),
        "teeth_count": cutter.teeth(),
        "helix_deg": cutter.helix_rad.to_degrees(),
        "lead_deg": lead_deg,
        "ap_mm": ap_mm,
        "fz_mm": fz_mm,
        "rule": rule.name(),
        "effective_radius_mm": a.effective_radius_mm,
        "cutting_speed_ratio": a.cutting_speed_ratio,
        "cutting_speed_pct": 100.0 * a.cutting_speed_ratio,
        "contact_radius_mm": a.contact_radius_mm,
        "generating_height_mm": a.generating_height_mm,
        "crest_height_um": a.crest_height_mm * 1e3,
        "crest_height_corrected_um": a.crest_height_corrected_mm * 1e3,
        "crest_height_exact_um": a.crest_height_exact_mm * 1e3,
        "zc": a.zc,
        "zc_paper": a.zc_paper,
        "zc_exact": a.zc_exact,
        "fz_effective_mm": a.fz_effective_mm,
        "participating_teeth": a.teeth.iter().filter(|t| t.participates).map(|t| t.index).collect::<Vec<_>>(),
        "teeth": teeth,
    })
}
