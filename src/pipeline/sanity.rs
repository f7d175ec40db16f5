//! Loud sanity checks of a simulated patch (issue 33): heights beyond what any finishing
//! pass can leave, a patch narrower than one stepover or feed-mark period, a depth of cut
//! that clips the scallop, a tool that does not finish with its corner or ball, and
//! contradictory units in the file. Each finding is one plain sentence; `simulate` puts it
//! in its warnings and its failed checks (exit 1).
//!
//! The bounds are closed forms (model.md §4 and §7): the scallop of two circles of radius
//! R_eff a distance s apart, `scallop(s, R) = R − √(R² − s²/4)` (R when s ≥ 2R). R_eff is
//! the corner radius (R for a ball): a torus tilted by a lead has a larger effective radius
//! (R_eff = rc + Rd / sin λ), so the corner radius gives the larger scallop.

use crate::surface::ModelKind;
use crate::tool::Cutter;
use crate::toolpath::Program;

/// Safety factor on the larger closed-form scallop (curvature, a lead, run-out harmonics).
pub const SAFETY: f64 = 3.0;
/// Added to the height bound, µm (process effects, rasterisation).
pub const MARGIN_UM: f64 = 5.0;
/// A tool whose tool axis is within this angle of the patch plane finishes with its flank
/// (a wall), degrees: a flat end there is not warned of.
pub const WALL_DEG: f64 = 10.0;

/// The scallop of two circles of radius `radius_mm` whose centres are `step_mm` apart, mm:
/// R − √(R² − s²/4), and R when s ≥ 2R (the circles do not overlap).
pub fn scallop_mm(step_mm: f64, radius_mm: f64) -> f64 {
    let r = radius_mm;
    let q = r * r - 0.25 * step_mm * step_mm;
    if q <= 0.0 { r } else { r - q.sqrt() }
}

/// What the checks look at: the tool, the process and the simulated patch.
#[derive(Debug, Clone)]
pub struct Facts<'a> {
    /// The cutter simulated.
    pub cutter: &'a Cutter,
    /// The surface model (the swept ball leaves no feed marks).
    pub model: ModelKind,
    /// Feed per tooth, mm.
    pub fz_mm: f64,
    /// Chord tolerance of the meshes, µm.
    pub chord_tol_um: f64,
    /// Local stepover across the feed at the patch, mm (`None`: no neighbouring pass).
    pub stepover_mm: Option<f64>,
    /// Depth of cut, mm (nodes cut higher than this are not reached).
    pub ap_mm: f64,
    /// The heights, µm (NaN = not reached).
    pub heights_um: &'a [f64],
    /// A patch along the feed and across it, mm (`None` for a window or a map).
    pub patch_mm: Option<(f64, f64)>,
    /// |cos| of the angle between the tool axis and the surface normal at the patch
    /// (`None` when unknown).
    pub axis_normal_cos: Option<f64>,
}

/// The radius that generates the scallops, mm: the corner radius (R for a ball); 0 for a
/// tool without corner (flat end).
pub fn effective_radius_mm(cutter: &Cutter) -> f64 {
    cutter.corner_radius_mm()
}

/// How far the teeth's run-out can move a tooth from the nominal body, mm.
pub fn runout_spread_mm(cutter: &Cutter) -> f64 {
    let r = &cutter.runout;
    let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    r.offset_mm.abs()
        + r.tilt_rad.abs() * cutter.radius_mm
        + max_abs(&r.tooth_radius_dev_mm)
        + max_abs(&r.tooth_axial_dev_mm)
}

/// The feed-mark period along the feed, mm: fz, or one revolution (Z · fz) when run-out
/// makes the teeth differ; `None` for the swept model (no feed marks).
pub fn feed_period_mm(cutter: &Cutter, model: ModelKind, fz_mm: f64) -> Option<f64> {
    match model {
        ModelKind::Swept => None,
        _ if runout_spread_mm(cutter) > 0.0 => Some(fz_mm * cutter.teeth() as f64),
        _ => Some(fz_mm),
    }
}

/// The largest |height| a finishing pass can leave, µm:
/// `SAFETY · max(scallop(s, R_eff), scallop(p, R_eff)) + run-out + chord tolerance + MARGIN_UM`
/// with s the local stepover and p the feed-mark period. `None` without a corner radius or
/// a stepover.
pub fn height_bound_um(f: &Facts<'_>) -> Option<f64> {
    let r = effective_radius_mm(f.cutter);
    let s = f.stepover_mm?;
    if r <= 0.0 {
        return None;
    }
    let p = feed_period_mm(f.cutter, f.model, f.fz_mm).unwrap_or(0.0);
    let worst = scallop_mm(s, r).max(scallop_mm(p, r));
    Some(SAFETY * worst * 1e3 + runout_spread_mm(f.cutter) * 1e3 + f.chord_tol_um + MARGIN_UM)
}

/// The findings of the checks on a simulated grid, one sentence each (empty: all pass).
pub fn check(f: &Facts<'_>) -> Vec<String> {
    let mut out = Vec::new();
    let r_eff = effective_radius_mm(f.cutter);
    // 1. Heights beyond the bound.
    if let Some(bound) = height_bound_um(f) {
        let (lo, hi) = f
            .heights_um
            .iter()
            .filter(|h| h.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &h| {
                (lo.min(h), hi.max(h))
            });
        let worst = if lo.abs() > hi.abs() { lo } else { hi };
        if worst.is_finite() && worst.abs() > bound {
            out.push(format!(
                "height {worst:.1} µm found, beyond the {bound:.1} µm that a finishing pass can leave ({SAFETY} × the larger scallop of a ball of R_eff {r_eff} mm over the stepover {:.4} mm or the feed-mark period {:.4} mm, + run-out {:.1} µm + chord tolerance {} µm + {MARGIN_UM} µm): the reference surface or the path is wrong here; do not trust this patch",
                f.stepover_mm.unwrap_or(f64::NAN),
                feed_period_mm(f.cutter, f.model, f.fz_mm).unwrap_or(0.0),
                runout_spread_mm(f.cutter) * 1e3,
                f.chord_tol_um
            ));
        }
    }
    // 2. A patch narrower than one period.
    if let Some((length, width)) = f.patch_mm {
        if let Some(s) = f.stepover_mm
            && width < s
        {
            out.push(format!(
                "the patch is {width} mm wide across the feed, narrower than the local stepover {s:.4} mm: its areal parameters (Sa, Sq, Sz) do not cover one scallop period; widen ‹patch_mm› to at least {s:.3} mm across"
            ));
        }
        if let Some(p) = feed_period_mm(f.cutter, f.model, f.fz_mm)
            && length < p
        {
            out.push(format!(
                "the patch is {length} mm long along the feed, shorter than the feed-mark period {p:.4} mm: its areal parameters (Sa, Sq, Sz) do not cover one period; lengthen ‹patch_mm› to at least {p:.4} mm along"
            ));
        }
    }
    // 3. A depth of cut that clips the scallop.
    let unreached = f.heights_um.iter().filter(|h| !h.is_finite()).count();
    if unreached > 0
        && r_eff > 0.0
        && let Some(s) = f.stepover_mm
    {
        let scallop = scallop_mm(s, r_eff);
        if scallop > f.ap_mm {
            out.push(format!(
                "{unreached} of {} nodes ({:.1} %) are not reached: the scallop of the stepover {s:.4} mm with R_eff {r_eff} mm is {:.1} µm, more than the depth of cut ‹ap_mm› {} mm, so the crests above it are clipped; raise ‹ap_mm› above {:.3} mm",
                f.heights_um.len(),
                100.0 * unreached as f64 / f.heights_um.len().max(1) as f64,
                scallop * 1e3,
                f.ap_mm,
                scallop
            ));
        }
    }
    // 4. A tool that does not finish with its corner or ball: a flat end face and no
    // corner (a cone or an engraver has no end face: its tip finishes).
    if r_eff <= 0.0 && f.cutter.flat_end_radius_mm() > 0.0 {
        let wall = f
            .axis_normal_cos
            .is_some_and(|c| c < WALL_DEG.to_radians().sin());
        if !wall {
            out.push(format!(
                "the {} tool (diameter {} mm) has no corner radius: on a floor its flat end face cuts, and the map shows the end face's marks, not a finishing roughness (use a ball or bull-nose tool, or ‹tool› with its corner radius)",
                f.cutter.shape.name(),
                2.0 * f.cutter.radius_mm
            ));
        }
    }
    out
}

/// The lowering's warnings about contradictory units (see
/// [`crate::toolpath::CONTRADICTORY_UNITS`]), with their line and column.
pub fn unit_findings(program: &Program) -> Vec<String> {
    program
        .warnings
        .iter()
        .filter(|w| w.message.starts_with(crate::toolpath::CONTRADICTORY_UNITS))
        .map(|w| format!("line {}, column {}: {}", w.at.line, w.at.column, w.message))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::Shape;

    #[test]
    fn scallop_is_the_two_circle_sag() {
        // R 3, s 0.5: 3 − √(9 − 0.0625).
        assert!((scallop_mm(0.5, 3.0) - (3.0 - 8.9375f64.sqrt())).abs() < 1e-15);
        assert_eq!(scallop_mm(7.0, 3.0), 3.0);
        // The NURBS export: ball D30, stepover 14.6 mm, about 1.9 mm.
        assert!((scallop_mm(14.6, 15.0) - 1.896).abs() < 1e-3);
    }

    #[test]
    fn each_check_fires_and_stays_quiet() {
        let ball = Cutter::new(Shape::Ball, 3.0, 2, 0.5);
        let ok = vec![1.0, 5.0, 10.0];
        let mut f = Facts {
            cutter: &ball,
            model: ModelKind::Dome,
            fz_mm: 0.1,
            chord_tol_um: 1.0,
            stepover_mm: Some(0.5),
            ap_mm: 0.5,
            heights_um: &ok,
            patch_mm: Some((1.0, 1.0)),
            axis_normal_cos: Some(1.0),
        };
        assert!(check(&f).is_empty(), "{:?}", check(&f));
        let bound = height_bound_um(&f).unwrap_or(0.0);
        let expect = 3.0 * 1e3 * (3.0 - 8.9375f64.sqrt()) + 1.0 + 5.0;
        assert!((bound - expect).abs() < 1e-9);
        let bad = vec![1.0, -(bound + 0.1)];
        f.heights_um = &bad;
        assert_eq!(check(&f).len(), 1);
        f.heights_um = &ok;
        f.patch_mm = Some((0.05, 0.4));
        assert_eq!(check(&f).len(), 2);
        f.patch_mm = None;
        let clipped = vec![1.0, f64::NAN];
        f.heights_um = &clipped;
        f.stepover_mm = Some(2.0);
        f.ap_mm = 0.1;
        assert_eq!(check(&f).len(), 1);
        let flat = Cutter::new(Shape::Flat, 3.0, 2, 0.5);
        f.cutter = &flat;
        f.heights_um = &ok;
        assert_eq!(check(&f).len(), 1);
        f.axis_normal_cos = Some(0.0);
        assert!(check(&f).is_empty());
    }
}
