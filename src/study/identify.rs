//! Run-out identified from measured feed-direction profiles: the mark grid, the level of
//! every tooth's marks, which teeth cut, the mark spacing and the pattern's period, and the
//! run-out that explains them (per-tooth deviations along the normal, and an offset and phase
//! when at least three teeth cut at a lead), with what the profiles cannot identify, and the
//! `[runout]` table of a `tool.toml` that reproduces them.
//!
//! Each profile is fitted on its own ([`super::identify_fit`]: least squares of the levels
//! for every trial of the mark grid's position, the teeth that do not cut found by a
//! likelihood-ratio test). Several profiles (a height map's lines along the feed) are put on
//! the same tooth labels and averaged: a tooth cuts when it cuts in most of them, its level
//! is the mean of theirs weighted by the samples it owns, and the level of a tooth that does
//! not cut is its bound under the averaged envelope.
//!
//! Conventions (those of `tool.toml`, model.md §3.1): tooth 1 is the deepest tooth (for an
//! even pitch; with an uneven pitch the teeth keep the tool's order, found from the spacing
//! of the marks, tooth 1 the deepest of the teeth the pitch pattern cannot tell from the
//! tool's tooth 1), the others follow in cutting order; the phase is `offset_phase_deg`'s
//! (ρ_j = e0·cos(ψ_j − φ_e), ψ_j = −pitch_j − helix lag at the generating height). A
//! profile is taken in the feed direction: read backwards, the cutting order reverses.

use super::identify_fit::{Marks, ProfileFit, bounds, fit_profile};
use crate::tool::{
    Cutter, FeedProfile, Shape, feed_profile_for, generating_height_mm, mark_positions_mm,
    normal_deviation_mm,
};
use serde::Serialize;
use std::f64::consts::TAU;

/// What the profile can and cannot identify.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Identifiable {
    /// The mark period (always, given two periods of profile).
    pub period: bool,
    /// Which teeth cut.
    pub teeth_cutting: bool,
    /// Offset and phase (only with ≥ 3 cutting teeth at a lead angle, the offset resolved
    /// above the levels' uncertainty).
    pub offset_phase: bool,
    /// Per tooth: its deviation is identified (it cuts) or only bounded (it does not).
    pub tooth_deviation: Vec<bool>,
    /// Plain statements of the limits.
    pub notes: Vec<String>,
}

/// The `[runout]` table written by `--write-tool`, in `tool.toml`'s keys and units.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunoutTable {
    /// `offset_um` (absent when the offset is not identifiable).
    pub offset_um: Option<f64>,
    /// `offset_phase_deg`, from tooth 1 (absent with the offset).
    pub offset_phase_deg: Option<f64>,
    /// `tooth_radius_deviation_um`, one per tooth: what the offset leaves of each tooth's
    /// level; a tooth that leaves no mark is set back beyond its bound, so that it stays out.
    pub tooth_radius_deviation_um: Vec<f64>,
}

/// The identified run-out.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Identification {
    /// Period of the mark pattern, mm: the smallest shift that maps the marks onto
    /// themselves (one revolution's feed Z·fz whenever the teeth cut unlike each other).
    pub period_mm: f64,
    /// Mean distance between the marks the profile shows, mm: Z·fz / the teeth that cut
    /// (fz when every tooth cuts).
    pub mark_spacing_mm: f64,
    /// One revolution's feed Z·fz, mm.
    pub revolution_mm: f64,
    /// Teeth that cut (1-based; tooth 1 = the deepest, then in cutting order).
    pub teeth_cutting: Vec<usize>,
    /// Run-out offset e0, µm (None when not identifiable).
    pub offset_um: Option<f64>,
    /// Its phase φ_e from tooth 1, degrees in [0, 360), `offset_phase_deg`'s convention
    /// (None when not identifiable).
    pub phase_deg: Option<f64>,
    /// Per-tooth deviation along the surface normal relative to tooth 1, µm (≤ 0; for teeth
    /// that do not cut, the smallest setback consistent with the profile).
    pub tooth_deviation_um: Vec<f64>,
    /// RMS of profile − model, µm.
    pub residual_um: f64,
    /// Position of tooth 1's first mark on the (first) profile, mm.
    pub first_mark_mm: f64,
    /// Profiles fitted.
    pub profiles: usize,
    /// The `[runout]` table that reproduces the profile (`--write-tool`).
    pub runout: RunoutTable,
    /// What is identified.
    pub identifiable: Identifiable,
}

/// Why a profile cannot identify the run-out.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IdentifyError {
    /// The feed per tooth is not positive.
    #[error("fz_mm must be positive, got {0}")]
    Feed(f64),
    /// The lead is not finite or beyond ±90°.
    #[error("lead_deg must lie within ±90 degrees, got {0}")]
    Lead(f64),
    /// The profile spans less than two turns' feed or has fewer than 8 points.
    #[error(
        "the profile spans {length_mm:.4} mm; identification needs at least two turns' feed ({needed_mm:.4} mm) and 8 points"
    )]
    Short {
        /// Length of the profile, mm.
        length_mm: f64,
        /// Two turns' feed, mm.
        needed_mm: f64,
    },
    /// No profile was given.
    #[error("no profile to identify from")]
    NoProfile,
}

/// Identify the run-out of `cutter` (its shape, radius, teeth and pitch; its run-out is
/// ignored) from the profile `x_mm`, `z_um` (any order, irregular spacing) cut with feed per
/// tooth `fz_mm` at lead `lead_deg`.
pub fn identify(
    x_mm: &[f64],
    z_um: &[f64],
    cutter: &Cutter,
    fz_mm: f64,
    lead_deg: f64,
) -> Result<Identification, IdentifyError> {
    identify_profiles(&[(x_mm, z_um)], cutter, fz_mm, lead_deg, true)
}

/// Most samples fitted per profile: a longer profile is thinned evenly (every k-th point),
/// which keeps the fit's cost bounded whatever the instrument's sampling.
pub const MAX_SAMPLES: usize = 50_000;

/// The points of a profile that can be fitted: finite, sorted by x, heights in mm, at most
/// [`MAX_SAMPLES`].
fn prepared(x_mm: &[f64], z_um: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let mut pts: Vec<(f64, f64)> = x_mm
        .iter()
        .zip(z_um)
        .filter(|(x, z)| x.is_finite() && z.is_finite())
        .map(|(x, z)| (*x, z * 1e-3))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let k = pts.len().div_ceil(MAX_SAMPLES).max(1);
    pts.into_iter().step_by(k).unzip()
}

/// Whether the pitch is even (teeth every 2π/Z).
fn even_pitch(cutter: &Cutter) -> bool {
    let nt = cutter.teeth() as f64;
    cutter
        .pitch_rad
        .iter()
        .enumerate()
        .all(|(j, p)| (p.rem_euclid(TAU) - TAU * j as f64 / nt).abs() < 1e-9)
}

/// The shifts r of the teeth's labels (tooth k + r called tooth k) that leave the pitch
/// pattern as it is: every r for an even pitch, 0 alone for most uneven ones. The profile
/// cannot tell such labellings apart; tooth 1 is the deepest of them.
fn symmetries(cutter: &Cutter) -> Vec<usize> {
    let nt = cutter.teeth();
    let p = &cutter.pitch_rad;
    (0..nt)
        .filter(|&r| {
            (0..nt).all(|k| {
                let d = (p[(r + k) % nt] - p[r] - p[k]).rem_euclid(TAU);
                d.min(TAU - d) < 1e-9
            })
        })
        .collect()
}

/// Identify from several profiles along the feed (each `(x mm, z µm)`), averaged. With
/// `strict`, a profile too short is an error; otherwise it is left out (an error only when
/// none is left).
pub fn identify_profiles(
    profiles: &[(&[f64], &[f64])],
    cutter: &Cutter,
    fz_mm: f64,
    lead_deg: f64,
    strict: bool,
) -> Result<Identification, IdentifyError> {
    let nt = cutter.teeth();
    if !(fz_mm.is_finite() && fz_mm > 0.0) {
        return Err(IdentifyError::Feed(fz_mm));
    }
    if !(lead_deg.is_finite() && lead_deg.abs() <= 90.0) {
        return Err(IdentifyError::Lead(lead_deg));
    }
    let lead = lead_deg.to_radians();
    let period = nt as f64 * fz_mm;
    let even = even_pitch(cutter);
    let sym = symmetries(cutter);
    let marks = Marks {
        profile: match cutter.shape {
            Shape::Ball => FeedProfile::Circle {
                radius_mm: cutter.radius_mm,
            },
            _ => feed_profile_for(cutter, lead),
        },
        pos_mm: mark_positions_mm(cutter, fz_mm),
        period_mm: period,
        span_mm: if even { fz_mm } else { period },
    };
    let mut fits: Vec<(ProfileFit, f64)> = Vec::new();
    let mut short = None;
    for (x_mm, z_um) in profiles {
        let (xs, zs) = prepared(x_mm, z_um);
        let len = xs.last().copied().unwrap_or(0.0) - xs.first().copied().unwrap_or(0.0);
        if xs.len() < 8 || len < 2.0 * period {
            short = Some(IdentifyError::Short {
                length_mm: len,
                needed_mm: 2.0 * period,
            });
            if strict {
                break;
            }
            continue;
        }
        fits.push((fit_profile(&marks, &xs, &zs), xs[0]));
    }
    if let (true, Some(e)) = (strict, short.clone()) {
        return Err(e);
    }
    if fits.is_empty() {
        return Err(short.unwrap_or(IdentifyError::NoProfile));
    }
    // Labels: tooth 0 the deepest of the labellings the pitch allows (the cutting teeth
    // first), every fit rotated onto the first's.
    let deepest = |levels: &[f64], cuts: &[bool]| {
        sym.iter()
            .copied()
            .min_by(|&p, &q| {
                (!cuts[p], levels[p])
                    .partial_cmp(&(!cuts[q], levels[q]))
                    .unwrap_or(std::cmp::Ordering::Equal)
            })
            .unwrap_or(0)
    };
    let rotated = |f: &ProfileFit, r: usize| -> (Vec<f64>, Vec<bool>, Vec<usize>) {
        let base = f.levels_mm[r];
        (
            (0..nt).map(|k| f.levels_mm[(r + k) % nt] - base).collect(),
            (0..nt).map(|k| f.cuts[(r + k) % nt]).collect(),
            (0..nt).map(|k| f.owned[(r + k) % nt]).collect(),
        )
    };
    let first_rot = deepest(&fits[0].0.levels_mm, &fits[0].0.cuts);
    let reference = rotated(&fits[0].0, first_rot);
    let mut aligned = vec![reference.clone()];
    for (f, _) in &fits[1..] {
        let cost = |r: usize| {
            let (l, c, _) = rotated(f, r);
            (0..nt)
                .map(|k| {
                    let mismatch = if c[k] != reference.1[k] { 1.0 } else { 0.0 };
                    mismatch + ((l[k] - reference.0[k]) * 1e3).powi(2).min(1.0)
                })
                .sum::<f64>()
        };
        let r = sym
            .iter()
            .copied()
            .min_by(|&p, &q| cost(p).total_cmp(&cost(q)))
            .unwrap_or(0);
        aligned.push(rotated(f, r));
    }
    // Averaged: a tooth cuts in most profiles; its level is the owned-weighted mean.
    let votes: Vec<usize> = (0..nt)
        .map(|k| aligned.iter().filter(|a| a.1[k]).count())
        .collect();
    let mut cuts: Vec<bool> = votes.iter().map(|v| 2 * v > aligned.len()).collect();
    if !cuts.iter().any(|c| *c) {
        cuts[0] = true;
    }
    let mut levels = vec![0.0; nt];
    let mut owned = vec![0usize; nt];
    for k in (0..nt).filter(|&k| cuts[k]) {
        let (mut s, mut w) = (0.0, 0.0);
        for a in aligned.iter().filter(|a| a.1[k]) {
            let wk = a.2[k].max(1) as f64;
            s += wk * a.0[k];
            w += wk;
            owned[k] += a.2[k];
        }
        levels[k] = s / w;
    }
    let levels = bounds(&marks, &levels, &cuts);
    // Relabel so that tooth 0 is the deepest of the averaged levels.
    let r = deepest(&levels, &cuts);
    let levels: Vec<f64> = (0..nt).map(|k| levels[(r + k) % nt] - levels[r]).collect();
    let cuts: Vec<bool> = (0..nt).map(|k| cuts[(r + k) % nt]).collect();
    let owned: Vec<usize> = (0..nt).map(|k| owned[(r + k) % nt]).collect();
    let rss: f64 = fits.iter().map(|f| f.0.rss_mm2).sum();
    let samples: usize = fits.iter().map(|f| f.0.samples).sum();
    let sigma = (fits.iter().map(|f| f.0.variance_mm2()).sum::<f64>() / fits.len() as f64).sqrt();
    // Standard error of a tooth's level, mm.
    let se = |k: usize| sigma / (owned[k].max(1) as f64).sqrt();
    // Normal deviation Δ relative to tooth 1 (≥ 0 deeper), mm.
    let dev: Vec<f64> = levels.iter().map(|l| -l).collect();
    let cutting: Vec<usize> = (0..nt).filter(|&k| cuts[k]).map(|k| k + 1).collect();
    // Period: the smallest shift k (dividing Z) that maps the pattern onto itself.
    let k_period = (1..=nt)
        .filter(|k| *k == nt || (nt.is_multiple_of(*k) && sym.contains(k)))
        .find(|&k| {
            (0..nt).all(|i| {
                let q = (i + k) % nt;
                cuts[i] == cuts[q]
                    && (!cuts[i] || (dev[i] - dev[q]).abs() <= 4.0 * se(i).hypot(se(q)) + 1e-6)
            })
        })
        .unwrap_or(nt);
    let zc = generating_height_mm(cutter, lead);
    let (sl, mut notes) = (
        lead.abs().min(std::f64::consts::FRAC_PI_2).sin(),
        Vec::new(),
    );
    let offset = fit_offset(cutter, &dev, &cuts, sl, &se, nt);
    match offset {
        Some(_) => {}
        None if cutting.len() < 3 => notes.push(format!(
            "{} of {nt} teeth cut: an offset and its phase cannot be separated from per-tooth deviations; the deviations are given instead.",
            cutting.len()
        )),
        None if sl <= 0.05 => notes.push(
            "At a lead near 0° the contact is at the tip, where a radial offset does not move the surface: the offset is not identifiable."
                .to_string(),
        ),
        None => notes.push(
            "The teeth's levels differ by less than the profile resolves: the offset is not identifiable."
                .to_string(),
        ),
    }
    let silent: Vec<String> = (0..nt)
        .filter(|k| !cuts[*k])
        .map(|k| format!("tooth {} ≥ {:.3} µm", k + 1, -dev[k] * 1e3))
        .collect();
    if !silent.is_empty() {
        notes.push(format!(
            "Teeth that leave no mark are only bounded: each is set back at least as far as given (setbacks {}); any larger setback gives the same profile, and the tool written sets them back further so that they stay out.",
            silent.join(", ")
        ));
    }
    if !even {
        notes.push(
            "Uneven pitch: the teeth keep the tool's order, placed by the spacing of the marks (tooth 1 = the tool's tooth 1, or the deepest of the teeth the pitch cannot tell from it)."
                .to_string(),
        );
    }
    // The [runout] table that reproduces the profile.
    let phase_shift = cutter.helix_lag(zc);
    let k_delta = delta_coefficient(cutter, zc, lead);
    let (pos_cut, dev_cut): (Vec<f64>, Vec<f64>) = (0..nt)
        .filter(|&k| cuts[k])
        .map(|k| (marks.pos_mm[(r + k) % nt], dev[k]))
        .unzip();
    let crest = crate::tool::envelope(&marks.profile, &pos_cut, &dev_cut, period).crest_mm;
    let margin = (0.25 * crest).max(1e-5);
    let model = |k: usize| -> f64 {
        offset.map_or(0.0, |(e, psi, c)| {
            c + sl * e * (cutter.pitch_rad[k] + psi).cos()
        })
    };
    let written: Vec<f64> = (0..nt)
        .map(|k| {
            let target = match (cuts[k], offset) {
                (true, _) => dev[k],
                (false, Some(_)) => (dev[k] - margin).min(model(k)),
                (false, None) => dev[k] - margin,
            };
            if k_delta.abs() < 1e-3 {
                0.0
            } else {
                (target - model(k)) / k_delta * 1e3
            }
        })
        .collect();
    let (offset_um, phase_deg) = match offset {
        Some((e, psi, _)) => (
            Some(e * 1e3),
            Some((psi - phase_shift).to_degrees().rem_euclid(360.0) % 360.0),
        ),
        None => (None, None),
    };
    let (fit0, a0) = (&fits[0].0, fits[0].1);
    let tooth1 = (first_rot + r) % nt;
    let x1 = fit0.x0_mm + marks.pos_mm[tooth1];
    let first_mark_mm = x1 + ((a0 - x1) / period).ceil() * period;
    Ok(Identification {
        period_mm: if k_period == nt {
            period
        } else {
            cutter.pitch_rad[k_period].rem_euclid(TAU) / TAU * period
        },
        mark_spacing_mm: period / cutting.len().max(1) as f64,
        revolution_mm: period,
        teeth_cutting: cutting,
        offset_um,
        phase_deg,
        tooth_deviation_um: dev.iter().map(|d| d * 1e3).collect(),
        residual_um: (rss / samples.max(1) as f64).sqrt() * 1e3,
        first_mark_mm,
        profiles: fits.len(),
        runout: RunoutTable {
            offset_um,
            offset_phase_deg: phase_deg,
            tooth_radius_deviation_um: written,
        },
        identifiable: Identifiable {
            period: true,
            teeth_cutting: true,
            offset_phase: offset.is_some(),
            tooth_deviation: cuts,
            notes,
        },
    })
}

/// How much a tooth radius deviation δ moves the surface along the normal at this lead:
/// fully for a ball (a presetter's sphere radius), `sin lead` for every other shape.
fn delta_coefficient(cutter: &Cutter, zc: f64, lead: f64) -> f64 {
    let mut probe = cutter.clone();
    probe.runout = Default::default();
    probe.runout.tooth_radius_dev_mm = vec![1e-3; cutter.teeth()];
    normal_deviation_mm(&probe, 0, zc, lead) / 1e-3
}

/// The offset e, the angle ψ = lag + φ (rad; φ is `offset_phase_deg`, lag the helix lag at
/// the generating height) and the common level c from the cutting teeth's normal deviations
/// Δ_k = c + sin L·e·cos(pitch_k + ψ), when at least three teeth cut at a lead and e·sin L
/// stands above four standard errors of the levels.
fn fit_offset(
    cutter: &Cutter,
    dev: &[f64],
    cuts: &[bool],
    sl: f64,
    se: &dyn Fn(usize) -> f64,
    nt: usize,
) -> Option<(f64, f64, f64)> {
    let cutting: Vec<usize> = (0..nt).filter(|&k| cuts[k]).collect();
    if cutting.len() < 3 || sl <= 0.05 {
        return None;
    }
    // Least squares for (c, A, B) in Δ = c + sl (A cos p + B sin p).
    let mut m = [[0.0; 3]; 3];
    let mut v = [0.0; 3];
    for &k in &cutting {
        let p = cutter.pitch_rad[k];
        let f = [1.0, sl * p.cos(), sl * p.sin()];
        for a in 0..3 {
            for b in 0..3 {
                m[a][b] += f[a] * f[b];
            }
            v[a] += f[a] * dev[k];
        }
    }
    let mm = nalgebra::Matrix3::from_fn(|a, b| m[a][b]);
    let sol = mm.lu().solve(&nalgebra::Vector3::from(v))?;
    let (c, a, b) = (sol[0], sol[1], sol[2]);
    let e = a.hypot(b);
    let worst = cutting.iter().map(|&k| se(k)).fold(0.0, f64::max);
    if !(e.is_finite() && e * sl > 4.0 * worst) {
        return None;
    }
    // cos(p + λ + φ) = cos p cos(λ + φ) − sin p sin(λ + φ): A = e cos(λ + φ), B = −e sin(λ + φ).
    Some((e, (-b).atan2(a), c))
}
