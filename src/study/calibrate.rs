//! Calibration of process effects against a measured table: weighted least squares on the
//! case means (bounded Levenberg–Marquardt, finite-difference Jacobian), each fitted value
//! with its standard uncertainty, the correlation of the parameters, and leave-one-out
//! predictions (every case predicted by a refit without it).
//!
//! Weights are 1/σ² with σ a case's sample standard deviation, floored at half the pooled
//! standard deviation of that parameter over the table (two samples per case give a σ that
//! can be near zero by chance, and one such case would take the whole fit). Uncertainties are
//! the covariance (JᵀWJ)⁻¹ scaled by the reduced χ² (the scatter about the fit, not the
//! printed σ, sets them), with J by central differences of [`FD_STEP`] of each parameter's
//! scale: a simulated surface lives on a grid, so its Rz and Ra are step functions of h_min
//! on the scale of the chip thickness between neighbouring nodes, and a smaller difference
//! can land on one flat step (a zero column, a singular JᵀWJ). A parameter the data do not
//! determine gets a NaN uncertainty, never zero.
//!
//! Two references a physical model must beat, each with its own leave-one-out: the
//! geometric prediction plus a constant offset per parameter, and the geometric prediction
//! times a constant factor per parameter.

use super::measured::{MeasuredCase, Side};
use super::regression::{PredictError, Study, StudyCase, predict_case};
use crate::surface::{Process, Texture};
use crate::tool::Cutter;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::Serialize;

/// A parameter the calibration may fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum Free {
    /// `min_chip_um`: minimum uncut chip thickness, µm.
    MinChip,
    /// `recovery`: elastic recovery of the ploughed layer, 0..1.
    Recovery,
    /// `texture_sq_um`: Sq of the random texture, µm.
    TextureSq,
    /// `texture_corr_um`: its correlation length, µm.
    TextureCorr,
    /// `runout_offset_um`: run-out offset e0, µm.
    RunoutOffset,
    /// `runout_phase_deg`: direction of the offset, degrees.
    RunoutPhase,
    /// `tooth_deviation_um[j]`: radial deviation of tooth j (1-based, j ≥ 2), µm.
    ToothDeviation(usize),
}

/// Names `--free` accepts.
pub const FREE_NAMES: [&str; 7] = [
    "min_chip_um",
    "recovery",
    "texture_sq_um",
    "texture_corr_um",
    "runout_offset_um",
    "runout_phase_deg",
    "tooth_deviation_um",
];

/// Why a calibration cannot be made.
#[derive(Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CalibrateError {
    /// A name in the `free` list that is not a free parameter.
    #[error("unknown free parameter '{name}' (expected {})", FREE_NAMES.join(", "))]
    UnknownFree {
        /// The name given.
        name: String,
    },
    /// The `free` list names nothing.
    #[error("the free list names no parameter")]
    NoFree,
    /// A study case without measured rows.
    #[error("case {case} (lead {lead_deg}°, {side}) has no rows in the measured table")]
    Unmeasured {
        /// The case, 1-based.
        case: usize,
        /// Its lead angle, degrees.
        lead_deg: f64,
        /// Its side.
        side: String,
    },
    /// Fewer measured values than parameters (and one more).
    #[error("{values} measured values cannot fit {parameters} parameters")]
    TooFewValues {
        /// Measured values.
        values: usize,
        /// Free parameters.
        parameters: usize,
    },
    /// A case cannot be predicted.
    #[error(transparent)]
    Predict(#[from] PredictError),
}

impl Free {
    /// Read a comma-separated list; `tooth_deviation_um` stands for teeth 2..Z (tooth 1 is
    /// the reference: a common deviation of every tooth is a change of radius).
    pub fn parse_list(list: &str, teeth: usize) -> Result<Vec<Free>, CalibrateError> {
        let mut out = Vec::new();
        for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let f = match name {
                "min_chip_um" => vec![Free::MinChip],
                "recovery" => vec![Free::Recovery],
                "texture_sq_um" => vec![Free::TextureSq],
                "texture_corr_um" => vec![Free::TextureCorr],
                "runout_offset_um" => vec![Free::RunoutOffset],
                "runout_phase_deg" => vec![Free::RunoutPhase],
                "tooth_deviation_um" => (2..=teeth).map(Free::ToothDeviation).collect(),
                _ => {
                    return Err(CalibrateError::UnknownFree {
                        name: name.to_string(),
                    });
                }
            };
            for x in f {
                if !out.contains(&x) {
                    out.push(x);
                }
            }
        }
        if out.is_empty() {
            return Err(CalibrateError::NoFree);
        }
        Ok(out)
    }

    /// The name in outputs.
    pub fn name(&self) -> String {
        match self {
            Free::MinChip => "min_chip_um".into(),
            Free::Recovery => "recovery".into(),
            Free::TextureSq => "texture_sq_um".into(),
            Free::TextureCorr => "texture_corr_um".into(),
            Free::RunoutOffset => "runout_offset_um".into(),
            Free::RunoutPhase => "runout_phase_deg".into(),
            Free::ToothDeviation(j) => format!("tooth_deviation_um[{j}]"),
        }
    }

    /// Bounds of the fit.
    pub fn bounds(&self) -> (f64, f64) {
        match self {
            Free::MinChip => (0.0, 20.0),
            Free::Recovery => (0.0, 1.0),
            Free::TextureSq => (0.0, 5.0),
            Free::TextureCorr => (1.0, 500.0),
            Free::RunoutOffset => (0.0, 50.0),
            Free::RunoutPhase => (-720.0, 720.0),
            Free::ToothDeviation(_) => (-50.0, 50.0),
        }
    }

    /// The value in `process` and `cutter` (a start away from zero where zero has no
    /// gradient).
    fn start(&self, process: &Process, cutter: &Cutter) -> f64 {
        match self {
            Free::MinChip => (process.min_chip_mm * 1e3).max(1.0),
            Free::Recovery => process.recovery,
            Free::TextureSq => process.texture.map_or(0.1, |t| t.sq_mm * 1e3).max(0.05),
            Free::TextureCorr => process.texture.map_or(20.0, |t| t.corr_mm * 1e3),
            Free::RunoutOffset => (cutter.runout.offset_mm * 1e3).max(1.0),
            Free::RunoutPhase => cutter.runout.offset_phase_rad.to_degrees(),
            Free::ToothDeviation(j) => {
                let d = &cutter.runout.tooth_radius_dev_mm;
                (d.get(j - 1).copied().unwrap_or(0.0) - d.first().copied().unwrap_or(0.0)) * 1e3
            }
        }
    }
}

/// `process` and `cutter` with the free parameters set to `x`.
pub fn apply(free: &[Free], x: &[f64], process: &Process, cutter: &Cutter) -> (Process, Cutter) {
    let mut p = *process;
    let mut c = cutter.clone();
    for (f, &v) in free.iter().zip(x) {
        match f {
            Free::MinChip => p.min_chip_mm = v * 1e-3,
            Free::Recovery => p.recovery = v,
            Free::TextureSq | Free::TextureCorr => {
                let mut t = p.texture.unwrap_or(Texture {
                    sq_mm: 0.0,
                    corr_mm: 0.02,
                    seed: 1,
                });
                if *f == Free::TextureSq {
                    t.sq_mm = v * 1e-3;
                } else {
                    t.corr_mm = v * 1e-3;
                }
                p.texture = Some(t);
            }
            Free::RunoutOffset => c.runout.offset_mm = v * 1e-3,
            Free::RunoutPhase => c.runout.offset_phase_rad = v.to_radians(),
            Free::ToothDeviation(j) => {
                let n = c.teeth();
                if c.runout.tooth_radius_dev_mm.len() != n {
                    c.runout.tooth_radius_dev_mm = vec![0.0; n];
                }
                let d0 = c.runout.tooth_radius_dev_mm[0];
                if let Some(d) = c.runout.tooth_radius_dev_mm.get_mut(j - 1) {
                    *d = d0 + v * 1e-3;
                }
            }
        }
    }
    (p, c)
}

/// One measured value the fit holds the model to.
#[derive(Debug, Clone, PartialEq)]
struct Target {
    case: usize,
    rz: bool,
    mean: f64,
    sigma: f64,
}

/// One case and parameter of a calibration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CalibratedCase {
    /// Lead angle, degrees.
    pub lead_deg: f64,
    /// Curvature side.
    pub side: Side,
    /// `Rz` or `Ra`.
    pub parameter: String,
    /// Measured mean, µm.
    pub measured_um: f64,
    /// Measured sample standard deviation, µm (the weight uses it floored, see the module).
    pub sigma_um: f64,
    /// The model without process effects, µm.
    pub geometric_um: f64,
    /// The model with the fitted parameters, µm.
    pub calibrated_um: f64,
    /// The model refitted without this case, µm.
    pub loo_um: f64,
    /// Geometric plus the constant offset refitted without this case, µm.
    pub constant_loo_um: f64,
    /// Geometric times the constant factor refitted without this case, µm.
    pub factor_loo_um: f64,
}

/// A calibration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Calibration {
    /// Fitted parameters in `--free` order: (name, value, standard uncertainty).
    pub parameters: Vec<(String, f64, f64)>,
    /// Correlation matrix of the fitted parameters.
    pub correlation: Vec<Vec<f64>>,
    /// Covariance matrix of the fitted parameters.
    pub covariance: Vec<Vec<f64>>,
    /// Bounds of the fit per parameter.
    pub bounds: Vec<(f64, f64)>,
    /// Per case and parameter.
    pub cases: Vec<CalibratedCase>,
    /// χ² of the fit (weighted residuals).
    pub chi2: f64,
    /// Degrees of freedom (values − parameters).
    pub dof: usize,
    /// RMS of the leave-one-out deviations, percent of the measured means.
    pub loo_rms_pct: f64,
    /// RMS of the in-sample deviations, percent.
    pub fit_rms_pct: f64,
    /// The same for the constant-offset reference (geometric + one offset per parameter).
    pub constant_loo_rms_pct: f64,
    /// The same for the constant-factor reference (geometric × one factor per parameter).
    pub factor_loo_rms_pct: f64,
    /// The constant factor per parameter (`Rz`, `Ra`) fitted on every case: measured ≈
    /// factor × geometric (weighted least squares).
    pub factors: Vec<(String, f64)>,
    /// Whether the geometric prediction is the same for every case (within 0.5 %).
    pub geometric_constant: bool,
}

/// The study's predictions (Rz, Ra per case) with `process` and `cutter`, in parallel.
fn predict_all(
    study: &Study,
    cutter: &Cutter,
    process: &Process,
) -> Result<Vec<(f64, f64)>, PredictError> {
    study
        .cases
        .par_iter()
        .map(|c: &StudyCase| {
            predict_case(study, cutter, c, process, 0.0).map(|p| (p.rz_um, p.ra_um))
        })
        .collect()
}

fn values(targets: &[Target], preds: &[(f64, f64)]) -> Vec<f64> {
    targets
        .iter()
        .map(|t| {
            let p = preds[t.case];
            if t.rz { p.0 } else { p.1 }
        })
        .collect()
}

/// The inverse of `a` (LU with partial pivoting), NaN everywhere when `a` is singular.
fn invert(a: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = a.len();
    let inv = DMatrix::from_fn(n, n, |i, j| a[i][j])
        .lu()
        .try_inverse()
        .unwrap_or_else(|| DMatrix::from_element(n, n, f64::NAN));
    (0..n)
        .map(|i| (0..n).map(|j| inv[(i, j)]).collect())
        .collect()
}

/// The model's values at the target cases for a parameter vector.
type ModelFn<'a> = dyn Fn(&[f64]) -> Result<Vec<f64>, PredictError> + 'a;

/// Finite-difference step, as a fraction of a parameter's scale (its value, at least 5 % of
/// its range up to 10).
pub const FD_STEP: f64 = 0.05;

/// The finite-difference step of parameter `i` at `x`.
fn fd_step(x: f64, (lo, hi): (f64, f64)) -> f64 {
    FD_STEP * x.abs().max(0.05 * (hi - lo).min(10.0))
}

/// A weighted least-squares fit of `model(x)` to `targets` (those with `use_[k]`).
struct Fit {
    x: Vec<f64>,
    chi2: f64,
    m: usize,
}

fn fit(
    model: &ModelFn,
    targets: &[Target],
    keep: &[bool],
    x0: &[f64],
    bounds: &[(f64, f64)],
) -> Result<Fit, PredictError> {
    let resid = |v: &[f64]| -> Vec<f64> {
        targets
            .iter()
            .zip(v)
            .zip(keep)
            .filter(|(_, k)| **k)
            .map(|((t, p), _)| (p - t.mean) / t.sigma)
            .collect()
    };
    let chi2 = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let n = x0.len();
    let mut x = x0.to_vec();
    let mut r = resid(&model(&x)?);
    let mut c2 = chi2(&r);
    let mut lambda = 1e-2;
    let mut jtj = vec![vec![0.0; n]; n];
    for _ in 0..40 {
        // Forward differences, away from the upper bound.
        let mut jac = vec![vec![0.0; r.len()]; n];
        for i in 0..n {
            let (lo, hi) = bounds[i];
            let mut h = fd_step(x[i], (lo, hi));
            if x[i] + h > hi {
                h = -h;
            }
            let mut xp = x.clone();
            xp[i] = (x[i] + h).clamp(lo, hi);
            let rp = resid(&model(&xp)?);
            for (k, v) in rp.iter().enumerate() {
                jac[i][k] = (v - r[k]) / (xp[i] - x[i]);
            }
        }
        for a in 0..n {
            for b in 0..n {
                jtj[a][b] = jac[a].iter().zip(&jac[b]).map(|(p, q)| p * q).sum();
            }
        }
        let g: Vec<f64> = (0..n)
            .map(|a| -jac[a].iter().zip(&r).map(|(p, q)| p * q).sum::<f64>())
            .collect();
        let mut improved = false;
        for _ in 0..8 {
            let a = DMatrix::from_fn(n, n, |i, j| {
                let damping = if i == j {
                    lambda * jtj[i][i].max(1e-12)
                } else {
                    0.0
                };
                jtj[i][j] + damping
            });
            let Some(d) = a.lu().solve(&DVector::from_column_slice(&g)) else {
                lambda *= 10.0;
                continue;
            };
            let xn: Vec<f64> = (0..n)
                .map(|i| (x[i] + d[i]).clamp(bounds[i].0, bounds[i].1))
                .collect();
            let rn = resid(&model(&xn)?);
            let cn = chi2(&rn);
            if cn < c2 {
                let gain = (c2 - cn) / c2.max(1e-300);
                x = xn;
                r = rn;
                c2 = cn;
                lambda = (lambda / 3.0).max(1e-9);
                improved = gain > 1e-7;
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    Ok(Fit {
        x,
        chi2: c2,
        m: r.len(),
    })
}

/// Calibrate the `free` parameters of `study` (process effects from the study's
/// `[process]`, `cutter` with its run-out) against `measured`.
pub fn calibrate(
    measured: &[MeasuredCase],
    study: &Study,
    cutter: &Cutter,
    free: &[Free],
) -> Result<Calibration, CalibrateError> {
    // Measured values in study-case order.
    let mut targets = Vec::new();
    let pooled = |rz: bool| {
        let sds: Vec<f64> = measured
            .iter()
            .filter_map(|m| if rz { m.rz } else { m.ra })
            .filter_map(|s| s.sd)
            .collect();
        if sds.is_empty() {
            f64::NAN
        } else {
            (sds.iter().map(|s| s * s).sum::<f64>() / sds.len() as f64).sqrt()
        }
    };
    let (pool_rz, pool_ra) = (pooled(true), pooled(false));
    for (i, c) in study.cases.iter().enumerate() {
        let m = measured
            .iter()
            .find(|m| m.lead_deg == c.lead_deg && m.side == c.side)
            .ok_or_else(|| CalibrateError::Unmeasured {
                case: i + 1,
                lead_deg: c.lead_deg,
                side: c.side.name().to_string(),
            })?;
        for (rz, stat, pool) in [(true, m.rz, pool_rz), (false, m.ra, pool_ra)] {
            if let Some(s) = stat {
                let floor = if pool.is_finite() { 0.5 * pool } else { 0.0 };
                let sigma = s.sd.unwrap_or(f64::NAN).max(floor);
                let sigma = if sigma.is_finite() && sigma > 0.0 {
                    sigma
                } else {
                    (0.1 * s.mean).abs().max(1e-6)
                };
                targets.push(Target {
                    case: i,
                    rz,
                    mean: s.mean,
                    sigma,
                });
            }
        }
    }
    let n = free.len();
    if targets.len() <= n {
        return Err(CalibrateError::TooFewValues {
            values: targets.len(),
            parameters: n,
        });
    }
    let bounds: Vec<(f64, f64)> = free.iter().map(Free::bounds).collect();
    let x0: Vec<f64> = free
        .iter()
        .zip(&bounds)
        .map(|(f, b)| f.start(&study.process, cutter).clamp(b.0, b.1))
        .collect();
    let model = |x: &[f64]| -> Result<Vec<f64>, PredictError> {
        let (p, c) = apply(free, x, &study.process, cutter);
        Ok(values(&targets, &predict_all(study, &c, &p)?))
    };
    let geometric = values(&targets, &predict_all(study, cutter, &Process::default())?);
    let all = vec![true; targets.len()];
    let full = fit(&model, &targets, &all, &x0, &bounds)?;
    let calibrated = model(&full.x)?;
    let dof = full.m - n;
    let scale = if dof > 0 { full.chi2 / dof as f64 } else { 1.0 };
    // JᵀWJ at the fit by central differences (one-sided at a bound).
    let mut jac = vec![vec![0.0; targets.len()]; n];
    for i in 0..n {
        let h = fd_step(full.x[i], bounds[i]);
        let (mut xp, mut xm) = (full.x.clone(), full.x.clone());
        xp[i] = (full.x[i] + h).min(bounds[i].1);
        xm[i] = (full.x[i] - h).max(bounds[i].0);
        let (vp, vm) = (model(&xp)?, model(&xm)?);
        for (k, t) in targets.iter().enumerate() {
            jac[i][k] = (vp[k] - vm[k]) / (xp[i] - xm[i]) / t.sigma;
        }
    }
    let jtj: Vec<Vec<f64>> = (0..n)
        .map(|a| {
            (0..n)
                .map(|b| jac[a].iter().zip(&jac[b]).map(|(p, q)| p * q).sum())
                .collect()
        })
        .collect();
    let cov: Vec<Vec<f64>> = invert(&jtj)
        .into_iter()
        .map(|row| row.into_iter().map(|v| v * scale).collect())
        .collect();
    let sd: Vec<f64> = (0..n)
        .map(|i| {
            let v = cov[i][i];
            if v.is_finite() && v >= 0.0 {
                v.sqrt()
            } else {
                f64::NAN
            }
        })
        .collect();
    let correlation = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| cov[i][j] / (sd[i] * sd[j]).max(1e-300))
                .collect()
        })
        .collect();
    // Leave one case out: refit from the full fit, predict the case left out.
    let ncases = study.cases.len();
    let mut loo = vec![f64::NAN; targets.len()];
    for c in 0..ncases {
        let keep: Vec<bool> = targets.iter().map(|t| t.case != c).collect();
        if keep.iter().filter(|k| **k).count() <= n {
            continue;
        }
        let f = fit(&model, &targets, &keep, &full.x, &bounds)?;
        let v = model(&f.x)?;
        for (k, t) in targets.iter().enumerate() {
            if t.case == c {
                loo[k] = v[k];
            }
        }
    }
    // The constant-offset reference: geometric + weighted mean offset per parameter.
    let offset = |keep: &dyn Fn(&Target) -> bool, rz: bool| {
        let (mut sw, mut s) = (0.0, 0.0);
        for (t, g) in targets.iter().zip(&geometric) {
            if t.rz == rz && keep(t) {
                let w = 1.0 / (t.sigma * t.sigma);
                sw += w;
                s += w * (t.mean - g);
            }
        }
        s / sw
    };
    let constant_loo: Vec<f64> = targets
        .iter()
        .zip(&geometric)
        .map(|(t, g)| g + offset(&|u: &Target| u.case != t.case, t.rz))
        .collect();
    // The constant-factor reference: geometric × the weighted least-squares factor
    // Σ w·m·g / Σ w·g² per parameter.
    let factor = |keep: &dyn Fn(&Target) -> bool, rz: bool| {
        let (mut sgg, mut smg) = (0.0, 0.0);
        for (t, g) in targets.iter().zip(&geometric) {
            if t.rz == rz && keep(t) {
                let w = 1.0 / (t.sigma * t.sigma);
                sgg += w * g * g;
                smg += w * t.mean * g;
            }
        }
        smg / sgg
    };
    let factor_loo: Vec<f64> = targets
        .iter()
        .zip(&geometric)
        .map(|(t, g)| g * factor(&|u: &Target| u.case != t.case, t.rz))
        .collect();
    let rms = |v: &[f64]| {
        let d: Vec<f64> = targets
            .iter()
            .zip(v)
            .filter(|(_, p)| p.is_finite())
            .map(|(t, p)| 100.0 * (p - t.mean) / t.mean)
            .collect();
        (d.iter().map(|x| x * x).sum::<f64>() / d.len().max(1) as f64).sqrt()
    };
    let spread = |rz: bool| {
        let g: Vec<f64> = targets
            .iter()
            .zip(&geometric)
            .filter(|(t, _)| t.rz == rz)
            .map(|(_, g)| *g)
            .collect();
        let lo = g.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = g.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        g.is_empty() || (hi - lo) <= 0.005 * hi.abs()
    };
    let cases = targets
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let c = &study.cases[t.case];
            let m = measured
                .iter()
                .find(|m| m.lead_deg == c.lead_deg && m.side == c.side);
            let sd = m
                .and_then(|m| if t.rz { m.rz } else { m.ra })
                .and_then(|s| s.sd)
                .unwrap_or(f64::NAN);
            CalibratedCase {
                lead_deg: c.lead_deg,
                side: c.side.clone(),
                parameter: if t.rz { "Rz" } else { "Ra" }.to_string(),
                measured_um: t.mean,
                sigma_um: sd,
                geometric_um: geometric[k],
                calibrated_um: calibrated[k],
                loo_um: loo[k],
                constant_loo_um: constant_loo[k],
                factor_loo_um: factor_loo[k],
            }
        })
        .collect();
    Ok(Calibration {
        parameters: free
            .iter()
            .zip(&full.x)
            .zip(&sd)
            .map(|((f, v), s)| (f.name(), *v, *s))
            .collect(),
        correlation,
        covariance: cov,
        bounds,
        cases,
        chi2: full.chi2,
        dof,
        loo_rms_pct: rms(&loo),
        fit_rms_pct: rms(&calibrated),
        constant_loo_rms_pct: rms(&constant_loo),
        factor_loo_rms_pct: rms(&factor_loo),
        factors: [(true, "Rz"), (false, "Ra")]
            .into_iter()
            .filter(|(rz, _)| targets.iter().any(|t| t.rz == *rz))
            .map(|(rz, name)| (name.to_string(), factor(&|_: &Target| true, rz)))
            .collect(),
        geometric_constant: spread(true) && spread(false),
    })
}

impl Calibration {
    /// The fitted values in `--free` order.
    pub fn values(&self) -> Vec<f64> {
        self.parameters.iter().map(|p| p.1).collect()
    }
}
