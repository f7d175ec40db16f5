//! Participating teeth and the corrected feed mark spacing (002 Eqs 7-8, model.md §3.2),
//! crest heights (Eq 14), and the whole per-engagement analysis behind `crest tool`.
//!
//! Two rules decide which teeth leave marks on a plane at lead β:
//!
//! * [`Rule::Paper`] (default), Eq 8 as read in model.md: with the local radii
//!   r_j(z_c) at the generating height z_c, r_1 = max_j r_j, a tooth cuts when
//!   `r_j > r_1 − hc`, hc = Eq 14 at the nominal fz. Then zc = the count and
//!   fz_eff = fz·Z/zc (Eq 7). Ties count as cutting (a tolerance of 1e-12 mm).
//! * [`Rule::Exact`]: the lower envelope of the tooth profiles in the feed direction,
//!   each lowered by its normal deviation Δ_j and placed at (pitch_j/2π)·Z·fz + k·Z·fz
//!   (see [`super::section`]). A tooth cuts when it is on the envelope; the crest is the
//!   envelope's peak-to-valley height, and fz_eff = Z·fz/zc is the mean mark spacing.
//!
//! Normal deviation Δ_j: the run-out ρ_j moves the cutting point along the surface normal by
//! ρ_j sin κ_c (κ_c = the lead on a plane). For a ball, the per-tooth sphere-radius
//! deviation δ_j acts fully (the presetter measures the ball radius), so
//! Δ_j = (ρ_j − δ_j) sin κ_c + δ_j; for every other shape δ_j is radial like the rest. An
//! axial deviation ε_j (positive: the tooth lifted toward the shank) takes ε_j cos κ_c off
//! Δ_j; the paper rule takes it off the tooth's local radius (a tooth lifted by more than
//! the crest height leaves no mark).

use super::cutter::{Cutter, Shape};
use super::effective::effective_radius;
use super::section::{Envelope, envelope, feed_profile_for, nominal_crest_mm};
use std::f64::consts::{FRAC_PI_2, TAU};

/// Which teeth cut: the paper's threshold (002 Eq 8: r_j(z_c) > max r − hc(nominal fz)) or
/// the exact one-dimensional envelope. Written `"paper"` / `"exact"` in files and on the
/// command line (the one enum every config, study and option uses; the variants' lines are
/// the options' help).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Deserialize,
    serde::Serialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Rule {
    /// Marin et al. 2023, Eq 8: a tooth cuts when its radius at the generating height
    /// exceeds the largest one less the nominal crest height.
    Paper,
    /// Lower envelope of the teeth's feed-direction profiles (the default: a tooth cuts
    /// where its marks reach below the others').
    #[default]
    Exact,
}

impl Rule {
    /// The name used on the command line and in files (`paper`, `exact`).
    pub fn name(self) -> &'static str {
        match self {
            Rule::Paper => "paper",
            Rule::Exact => "exact",
        }
    }
}

/// A rule name that is neither `paper` nor `exact`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("unknown rule `{0}`, expected `paper` or `exact`")]
pub struct UnknownRule(pub String);

impl std::str::FromStr for Rule {
    type Err = UnknownRule;
    fn from_str(s: &str) -> Result<Rule, UnknownRule> {
        match s.trim().to_ascii_lowercase().as_str() {
            "paper" => Ok(Rule::Paper),
            "exact" => Ok(Rule::Exact),
            other => Err(UnknownRule(other.to_string())),
        }
    }
}

/// Why an engagement cannot be analysed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ToolError {
    /// The feed per tooth must be positive and finite.
    #[error("feed per tooth must be positive and finite, found {0} mm")]
    Feed(f64),
    /// The depth of cut must be non-negative and finite.
    #[error("depth of cut must be non-negative and finite, found {0} mm")]
    DepthOfCut(f64),
    /// The lead must lie within ±90°.
    #[error("lead angle must lie within ±90 degrees, found {0} degrees")]
    Lead(f64),
}

/// The paper rule on plain numbers: which of the `local_radii_mm` are within `hc_mm` of the
/// largest (ties and the largest itself cut).
pub fn paper_teeth(local_radii_mm: &[f64], hc_mm: f64) -> Vec<bool> {
    let r1 = local_radii_mm
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    local_radii_mm
        .iter()
        .map(|&r| r + 1e-12 > r1 - hc_mm)
        .collect()
}

/// Generating height z_c of the lowest point on a plane at lead β: c(1 − cos β) with c the
/// corner radius (R for a ball, 0 for a flat end, ri for a round insert); for a profile the
/// height of its point whose outward normal makes the angle β with the axis, mm.
pub fn generating_height_mm(cutter: &Cutter, lead_rad: f64) -> f64 {
    let b = lead_rad.abs().min(FRAC_PI_2);
    if let Shape::Profile(m) = &cutter.shape {
        return m.support(b.sin(), -b.cos())[1];
    }
    cutter.corner_radius_mm() * (1.0 - b.cos())
}

/// Normal deviation Δ_j of tooth `j` at height z for the lead β (see the module doc), mm:
/// how much deeper than nominal the tooth's element at height z reaches along the surface
/// normal when it passes its lowest point.
pub fn normal_deviation_mm(cutter: &Cutter, j: usize, z_mm: f64, lead_rad: f64) -> f64 {
    let b = lead_rad.abs().min(FRAC_PI_2);
    let rho = cutter.runout_mm(j, z_mm);
    let d = match cutter.shape {
        Shape::Ball => {
            let delta = cutter.tooth_dev_mm(j);
            (rho - delta) * b.sin() + delta * (cutter.kappa_at(z_mm) - b).cos()
        }
        _ => rho * b.sin(),
    };
    let eps = cutter.tooth_axial_dev_mm(j);
    if eps != 0.0 { d - eps * b.cos() } else { d }
}

/// Positions of the teeth's marks within one revolution's feed Z·fz, mm.
pub fn mark_positions_mm(cutter: &Cutter, fz_mm: f64) -> Vec<f64> {
    let period = cutter.teeth() as f64 * fz_mm;
    cutter
        .pitch_rad
        .iter()
        .map(|p| p.rem_euclid(TAU) / TAU * period)
        .collect()
}

/// One tooth in an [`Analysis`].
#[derive(Debug, Clone, PartialEq)]
pub struct ToothAnalysis {
    /// 1-based index in cutting order.
    pub index: usize,
    /// Tooth radius R + ρ_j(z_c), mm (the presetter radius when there is no offset or tilt).
    pub radius_mm: f64,
    /// Local radius r_j(z_c) at the generating height, less the axial deviation ε_j (what
    /// the paper rule compares), mm.
    pub local_radius_mm: f64,
    /// Radial run-out ρ_j(z_c), mm.
    pub runout_mm: f64,
    /// Axial deviation ε_j, mm (positive: lifted toward the shank).
    pub axial_deviation_mm: f64,
    /// Normal deviation Δ_j at the generating point, mm.
    pub normal_deviation_mm: f64,
    /// Cuts under the chosen rule.
    pub participates: bool,
    /// Cuts under the paper rule.
    pub participates_paper: bool,
    /// Cuts under the exact rule.
    pub participates_exact: bool,
    /// R_ef,max of a body of this tooth's radius, mm (002 Table 3 rows z1-z4).
    pub effective_radius_mm: f64,
    /// 100 (R_ef(R) − R_ef(R_t)) / R_ef(R), % (002 Table 3 "error").
    pub effective_radius_error_pct: f64,
}

/// Everything `crest tool` reports for one engagement.
#[derive(Debug, Clone, PartialEq)]
pub struct Analysis {
    /// The rule used for `participates`, `zc`, `fz_effective_mm` and the corrected crest.
    pub rule: Rule,
    /// Lead β, rad.
    pub lead_rad: f64,
    /// Depth of cut, mm.
    pub ap_mm: f64,
    /// Nominal feed per tooth, mm.
    pub fz_mm: f64,
    /// R_ef,max of the nominal tool, mm.
    pub effective_radius_mm: f64,
    /// R_ef,max / R.
    pub cutting_speed_ratio: f64,
    /// Radius of the generating (lowest) point, mm.
    pub contact_radius_mm: f64,
    /// Generating height z_c, mm.
    pub generating_height_mm: f64,
    /// Crest height at the nominal fz (Eq 14 for a ball), mm.
    pub crest_height_mm: f64,
    /// Per-tooth results.
    pub teeth: Vec<ToothAnalysis>,
    /// Number of participating teeth under the chosen rule.
    pub zc: usize,
    /// Corrected mark spacing fz·Z/zc, mm.
    pub fz_effective_mm: f64,
    /// Crest height corrected for run-out: paper rule, Eq 14 at fz_eff; exact rule, the
    /// envelope's crest, mm.
    pub crest_height_corrected_mm: f64,
    /// The exact envelope crest whatever the rule, mm.
    pub crest_height_exact_mm: f64,
    /// zc of the paper rule.
    pub zc_paper: usize,
    /// zc of the exact rule.
    pub zc_exact: usize,
}

/// Analyse `cutter` cutting a plane at lead `lead_deg` (degrees), depth `ap_mm` and feed per
/// tooth `fz_mm` under `rule`.
pub fn analyse(
    cutter: &Cutter,
    lead_deg: f64,
    ap_mm: f64,
    fz_mm: f64,
    rule: Rule,
) -> Result<Analysis, ToolError> {
    if !(fz_mm.is_finite() && fz_mm > 0.0) {
        return Err(ToolError::Feed(fz_mm));
    }
    if !(ap_mm.is_finite() && ap_mm >= 0.0) {
        return Err(ToolError::DepthOfCut(ap_mm));
    }
    if !(lead_deg.is_finite() && lead_deg.abs() <= 90.0) {
        return Err(ToolError::Lead(lead_deg));
    }
    let lead = lead_deg.to_radians();
    let z_teeth = cutter.teeth();
    let nominal = effective_radius(cutter, lead, ap_mm);
    let zc_height = generating_height_mm(cutter, lead);
    let profile = feed_profile_for(cutter, lead);
    let hc = nominal_crest_mm(&profile, fz_mm);

    let local: Vec<f64> = (0..z_teeth)
        .map(|j| {
            let r = cutter.tooth_radius(j, zc_height);
            let eps = cutter.tooth_axial_dev_mm(j);
            if eps != 0.0 { r - eps } else { r }
        })
        .collect();
    let paper = paper_teeth(&local, hc);
    let deviations: Vec<f64> = (0..z_teeth)
        .map(|j| normal_deviation_mm(cutter, j, zc_height, lead))
        .collect();
    let Envelope {
        participates: exact,
        crest_mm: exact_crest,
        ..
    } = envelope(
        &profile,
        &mark_positions_mm(cutter, fz_mm),
        &deviations,
        z_teeth as f64 * fz_mm,
    );
    let zc_paper = paper.iter().filter(|&&p| p).count().max(1);
    let zc_exact = exact.iter().filter(|&&p| p).count().max(1);
    let (chosen, zc) = match rule {
        Rule::Paper => (&paper, zc_paper),
        Rule::Exact => (&exact, zc_exact),
    };
    let fz_eff = fz_mm * z_teeth as f64 / zc as f64;
    let corrected = match rule {
        Rule::Paper => nominal_crest_mm(&profile, fz_eff),
        Rule::Exact => exact_crest,
    };
    let teeth = (0..z_teeth)
        .map(|j| {
            let rho = cutter.runout_mm(j, zc_height);
            let radius = cutter.radius_mm + rho;
            let eff = if radius > 0.0 {
                effective_radius(&cutter.with_radius(radius), lead, ap_mm).max_mm
            } else {
                0.0
            };
            ToothAnalysis {
                index: j + 1,
                radius_mm: radius,
                local_radius_mm: local[j],
                runout_mm: rho,
                axial_deviation_mm: cutter.tooth_axial_dev_mm(j),
                normal_deviation_mm: deviations[j],
                participates: chosen[j],
                participates_paper: paper[j],
                participates_exact: exact[j],
                effective_radius_mm: eff,
                effective_radius_error_pct: if nominal.max_mm > 0.0 {
                    100.0 * (nominal.max_mm - eff) / nominal.max_mm
                } else {
                    0.0
                },
            }
        })
        .collect();
    Ok(Analysis {
        rule,
        lead_rad: lead,
        ap_mm,
        fz_mm,
        effective_radius_mm: nominal.max_mm,
        cutting_speed_ratio: nominal.max_mm / cutter.radius_mm,
        contact_radius_mm: nominal.contact_mm,
        generating_height_mm: zc_height,
        crest_height_mm: hc,
        teeth,
        zc,
        fz_effective_mm: fz_eff,
        crest_height_corrected_mm: corrected,
        crest_height_exact_mm: exact_crest,
        zc_paper,
        zc_exact,
    })
}

/// Spread (max − min over the teeth) of the normal deviation at height `z_mm` and lead
/// `lead_rad`, mm: the run-out the surface sees from the elements at that tool height
/// (the quantity plotted against tool height, cf. 002 Fig 14c).
pub fn normal_runout_spread_mm(cutter: &Cutter, z_mm: f64, lead_rad: f64) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for j in 0..cutter.teeth() {
        let d = normal_deviation_mm(cutter, j, z_mm, lead_rad);
        lo = lo.min(d);
        hi = hi.max(d);
    }
    if hi >= lo { hi - lo } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn zero_runout_all_teeth_cut_and_spacing_is_fz() {
        let c = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        for rule in [Rule::Paper, Rule::Exact] {
            let a = analyse(&c, 15.0, 0.4, 0.05, rule).unwrap();
            assert_eq!(a.zc, 4);
            assert_relative_eq!(a.fz_effective_mm, 0.05, epsilon = 1e-15);
            assert_relative_eq!(a.crest_height_corrected_mm * 1e3, 0.0625004, epsilon = 1e-6);
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let c = Cutter::new(Shape::Ball, 5.0, 4, 0.0);
        assert_eq!(
            analyse(&c, 15.0, 0.4, 0.0, Rule::Paper),
            Err(ToolError::Feed(0.0))
        );
        assert!(analyse(&c, 95.0, 0.4, 0.05, Rule::Paper).is_err());
        assert!(analyse(&c, 15.0, f64::NAN, 0.05, Rule::Paper).is_err());
    }

    #[test]
    fn rule_names_round_trip() {
        for r in [Rule::Paper, Rule::Exact] {
            assert_eq!(r.name().parse::<Rule>().unwrap(), r);
        }
        assert!("both".parse::<Rule>().is_err());
    }
}
