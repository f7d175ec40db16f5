//! Run-out identified from a measured feed-direction profile: the mark grid (its phase within
//! fz), the depth of every tooth's marks, which teeth cut, the pattern's period and the
//! run-out that explains it (per-tooth deviations along the normal, and an offset and phase
//! when at least three teeth cut at a lead), with what the profile cannot identify.
//!
//! Model: the profile is the lower envelope of the tool's feed profile (arcs of radius R for
//! a ball end) centred every fz at x0 + m·fz, mark m made by tooth m mod Z and lowered by that
//! tooth's depth d_j. For a trial x0 every d_j is the least depth that keeps the tooth's arcs
//! on or above the profile (for a tooth that cuts, its own depth; for one that leaves no mark,
//! the bound of its setback); x0 is chosen by the least residual.

use crate::tool::{Cutter, FeedProfile, feed_profile};
use serde::Serialize;

/// What the profile can and cannot identify.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Identifiable {
    /// The mark period (always, given two periods of profile).
    pub period: bool,
    /// Which teeth cut.
    pub teeth_cutting: bool,
    /// Offset and phase (only with ≥ 3 cutting teeth at a lead angle).
    pub offset_phase: bool,
    /// Per tooth: its deviation is identified (it cuts) or only bounded (it does not).
    pub tooth_deviation: Vec<bool>,
    /// Plain statements of the limits.
    pub notes: Vec<String>,
}

/// The identified run-out.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Identification {
    /// Period of the mark pattern, mm.
    pub period_mm: f64,
    /// Teeth that cut (1-based; tooth 1 = the deepest, then in cutting order).
    pub teeth_cutting: Vec<usize>,
    /// Run-out offset, µm (None when not identifiable).
    pub offset_um: Option<f64>,
    /// Phase of the offset from tooth 1, degrees (None when not identifiable).
    pub phase_deg: Option<f64>,
    /// Per-tooth radial deviation relative to tooth 1, µm (≤ 0; for teeth that do not cut,
    /// the smallest setback consistent with the profile).
    pub tooth_deviation_um: Vec<f64>,
    /// RMS of profile − model, µm.
    pub residual_um: f64,
    /// Position of tooth 1's first mark, mm.
    pub first_mark_mm: f64,
    /// What is identified.
    pub identifiable: Identifiable,
}

/// Linear interpolation of sorted samples at `x` (clamped).
fn interp(xs: &[f64], zs: &[f64], x: f64) -> f64 {
    let i = xs.partition_point(|v| *v < x);
    if i == 0 {
        return zs[0];
    }
    if i >= xs.len() {
        return zs[xs.len() - 1];
    }
    let (x0, x1) = (xs[i - 1], xs[i]);
    if x1 <= x0 {
        return zs[i];
    }
    zs[i - 1] + (zs[i] - zs[i - 1]) * (x - x0) / (x1 - x0)
}

/// Why a profile cannot identify the run-out.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IdentifyError {
    /// The feed per tooth is not positive.
    #[error("fz_mm must be positive, got {0}")]
    Feed(f64),
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
    let nt = cutter.teeth();
    if !(fz_mm.is_finite() && fz_mm > 0.0) {
        return Err(IdentifyError::Feed(fz_mm));
    }
    let mut pts: Vec<(f64, f64)> = x_mm
        .iter()
        .zip(z_um)
        .filter(|(x, z)| x.is_finite() && z.is_finite())
        .map(|(x, z)| (*x, z * 1e-3))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (xs, zs): (Vec<f64>, Vec<f64>) = pts.into_iter().unzip();
    let len = xs.last().copied().unwrap_or(0.0) - xs.first().copied().unwrap_or(0.0);
    let period = nt as f64 * fz_mm;
    if xs.len() < 8 || len < 2.0 * period {
        return Err(IdentifyError::Short {
            length_mm: len,
            needed_mm: 2.0 * period,
        });
    }
    let lead = lead_deg.to_radians();
    let profile = match cutter.shape {
        crate::tool::Shape::Ball => FeedProfile::Circle {
            radius_mm: cutter.radius_mm,
        },
        _ => feed_profile(cutter.radius_mm, cutter.corner_radius_mm(), lead),
    };
    let (a, b) = (xs[0], xs[xs.len() - 1]);
    let steps = 200usize;
    let dx = (fz_mm / steps as f64).max(len / 400_000.0);
    let grid: Vec<f64> = (0..=((b - a) / dx) as usize)
        .map(|i| a + i as f64 * dx)
        .collect();
    let zg: Vec<f64> = grid.iter().map(|&x| interp(&xs, &zs, x)).collect();
    // Marks m from before the start to after the end.
    let m0 = (a / fz_mm).floor() as i64 - 2 * nt as i64 - 1;
    let m1 = (b / fz_mm).ceil() as i64 + 2 * nt as i64 + 1;
    let class = |m: i64| m.rem_euclid(nt as i64) as usize;
    // d_j: the least depth that keeps every mark of tooth j on or above the profile (for a
    // tooth that cuts, its own depth; for one that does not, the bound of its setback).
    let reach = (nt as f64 + 1.0) * fz_mm;
    let depths = |x0: f64| -> Vec<f64> {
        let mut d = vec![f64::NEG_INFINITY; nt];
        for m in m0..=m1 {
            let c = x0 + m as f64 * fz_mm;
            if c < a || c > b {
                continue;
            }
            let j = class(m);
            let i0 = grid.partition_point(|x| *x < c - reach);
            let i1 = grid.partition_point(|x| *x <= c + reach);
            for i in i0..i1 {
                let h = profile.height(grid[i] - c);
                if h.is_finite() {
                    d[j] = d[j].max(zg[i] - h);
                }
            }
        }
        let top = zs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        d.iter()
            .map(|v| if v.is_finite() { *v } else { top })
            .collect()
    };
    let envelope = |x0: f64, d: &[f64], x: f64| -> (f64, usize) {
        let lo = ((x - reach - x0) / fz_mm).floor() as i64;
        let hi = ((x + reach - x0) / fz_mm).ceil() as i64;
        let mut best = (f64::INFINITY, 0);
        for m in lo..=hi {
            let j = class(m);
            let v = profile.height(x - x0 - m as f64 * fz_mm) + d[j];
            if v < best.0 {
                best = (v, j);
            }
        }
        best
    };
    let residual = |x0: f64, d: &[f64]| -> f64 {
        let s: f64 = grid
            .iter()
            .zip(&zg)
            .map(|(&x, z)| (envelope(x0, d, x).0 - z).powi(2))
            .sum();
        (s / grid.len() as f64).sqrt()
    };
    let mut best = (f64::INFINITY, 0.0);
    for i in 0..steps {
        let x0 = i as f64 * fz_mm / steps as f64;
        let r = residual(x0, &depths(x0));
        if r < best.0 {
            best = (r, x0);
        }
    }
    // Refine x0 by golden-section search around the best trial.
    let (mut lo, mut hi) = (best.1 - fz_mm / steps as f64, best.1 + fz_mm / steps as f64);
    for _ in 0..30 {
        let m1 = lo + 0.382 * (hi - lo);
        let m2 = lo + 0.618 * (hi - lo);
        if residual(m1, &depths(m1)) < residual(m2, &depths(m2)) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    let x0 = 0.5 * (lo + hi);
    let d = depths(x0);
    let res = residual(x0, &d);
    // A class cuts where its mark is the envelope, lower than every other mark by more than
    // the fit's residual (and 1 nm).
    let margin = (2.0 * res).max(1e-6);
    let mut cuts = vec![false; nt];
    for &x in &grid {
        let lo = ((x - reach - x0) / fz_mm).floor() as i64;
        let hi = ((x + reach - x0) / fz_mm).ceil() as i64;
        let (mut b1, mut b2, mut j1) = (f64::INFINITY, f64::INFINITY, 0);
        for m in lo..=hi {
            let v = profile.height(x - x0 - m as f64 * fz_mm) + d[class(m)];
            if v < b1 {
                if class(m) != j1 {
                    b2 = b1;
                }
                b1 = v;
                j1 = class(m);
            } else if v < b2 && class(m) != j1 {
                b2 = v;
            }
        }
        if b2 - b1 > margin {
            cuts[j1] = true;
        }
    }
    // Tooth 1 = the deepest class; the others in cutting order after it.
    let j1 = (0..nt).min_by(|&p, &q| d[p].total_cmp(&d[q])).unwrap_or(0);
    let order: Vec<usize> = (0..nt).map(|k| (j1 + k) % nt).collect();
    let dev_um: Vec<f64> = order.iter().map(|&j| -(d[j] - d[j1]) * 1e3).collect();
    let cutting: Vec<usize> = order
        .iter()
        .enumerate()
        .filter(|(_, j)| cuts[**j])
        .map(|(k, _)| k + 1)
        .collect();
    // Period: the smallest shift k (dividing Z) that maps the pattern onto itself.
    let dtol = 0.02 + 0.2 * res * 1e3;
    let k = (1..=nt)
        .filter(|k| nt.is_multiple_of(*k))
        .find(|&k| {
            (0..nt).all(|i| {
                let (p, q) = (order[i], order[(i + k) % nt]);
                cuts[p] == cuts[q] && (!cuts[p] || ((d[p] - d[q]) * 1e3).abs() <= dtol)
            })
        })
        .unwrap_or(nt);
    // Offset and phase from the cutting teeth: d_j = c − sin L·e·cos(φ − θ_j).
    let (sl, mut notes) = (lead.sin(), Vec::new());
    let mut offset = None;
    if cutting.len() >= 3 && sl.abs() > 0.05 {
        let rows: Vec<(f64, f64, f64)> = cutting
            .iter()
            .map(|&t| {
                let th = cutter.pitch_rad[t - 1];
                (th.cos(), th.sin(), -dev_um[t - 1])
            })
            .collect();
        // Least squares for (c, A, B) in z = c − sl (A cos θ + B sin θ).
        let mut m = [[0.0; 3]; 3];
        let mut v = [0.0; 3];
        for (cth, sth, z) in &rows {
            let f = [1.0, -sl * cth, -sl * sth];
            for p in 0..3 {
                for q in 0..3 {
                    m[p][q] += f[p] * f[q];
                }
                v[p] += f[p] * z;
            }
        }
        let mm = nalgebra::Matrix3::from_fn(|p, q| m[p][q]);
        if let Some(sol) = mm.lu().solve(&nalgebra::Vector3::from(v)) {
            offset = Some((sol[1].hypot(sol[2]), sol[2].atan2(sol[1]).to_degrees()));
        }
    } else {
        notes.push(if cutting.len() < 3 {
            format!(
                "{} of {nt} teeth cut: an offset and its phase cannot be separated from per-tooth deviations; the deviations are given instead.",
                cutting.len()
            )
        } else {
            "At a lead near 0° the contact is at the tip, where a radial offset does not move the surface: the offset is not identifiable.".to_string()
        });
    }
    let silent: Vec<String> = (0..nt)
        .filter(|k| !cuts[order[*k]])
        .map(|k| format!("tooth {} ≥ {:.3} µm", k + 1, -dev_um[k]))
        .collect();
    if !silent.is_empty() {
        notes.push(format!(
            "Teeth that leave no mark are only bounded: each is set back at least as far as given (setbacks {}); any larger setback gives the same profile.",
            silent.join(", ")
        ));
    }
    Ok(Identification {
        period_mm: k as f64 * fz_mm,
        teeth_cutting: cutting,
        offset_um: offset.map(|o| o.0 * 1.0),
        phase_deg: offset.map(|o| o.1.rem_euclid(360.0)),
        tooth_deviation_um: dev_um,
        residual_um: res * 1e3,
        first_mark_mm: x0 + (((a - x0) / fz_mm).ceil()) * fz_mm,
        identifiable: Identifiable {
            period: true,
            teeth_cutting: true,
            offset_phase: offset.is_some(),
            tooth_deviation: order.iter().map(|&j| cuts[j]).collect(),
            notes,
        },
    })
}
