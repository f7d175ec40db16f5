//! Uncertain inputs and the bands of what they change: the standard uncertainties of a
//! study's `[uncertainty]` table, a cutter's run-out and calibrated parameters drawn from
//! them with a seeded generator, and the P5 / P50 / P95 of N samples run in parallel
//! (rayon; sample i draws from stream i of the seed, so the bands are the same for any
//! thread count). What a sample runs is [`super::montecarlo`]'s.

use crate::math::rng::Rng;
use crate::tool::Cutter;
use nalgebra::DMatrix;
use rayon::prelude::*;
use serde::Serialize;

/// Standard uncertainties of the inputs (a study's `[uncertainty]` table).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Uncertainty {
    /// Standard deviation of the run-out offset e0, µm (added as a random 2-D vector).
    pub runout_offset_um: f64,
    /// Standard deviation of every tooth's radial deviation, µm.
    pub tooth_deviation_um: f64,
    /// Draw the spindle phase at the start of every pass uniformly (one full turn).
    pub spindle_phase: bool,
    /// Scale of the calibrated parameters' standard uncertainties (1 = as fitted).
    pub parameter_scale: f64,
}

impl Default for Uncertainty {
    fn default() -> Self {
        Uncertainty {
            runout_offset_um: 0.0,
            tooth_deviation_um: 0.0,
            spindle_phase: true,
            parameter_scale: 1.0,
        }
    }
}

impl Uncertainty {
    /// Every standard uncertainty times `k` (the spindle phase stays as it is).
    pub fn scaled(&self, k: f64) -> Uncertainty {
        Uncertainty {
            runout_offset_um: self.runout_offset_um * k,
            tooth_deviation_um: self.tooth_deviation_um * k,
            spindle_phase: self.spindle_phase,
            parameter_scale: self.parameter_scale * k,
        }
    }
}

/// P5, P50 and P95 of one output.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Band {
    /// 5th percentile.
    pub p5: f64,
    /// Median.
    pub p50: f64,
    /// 95th percentile.
    pub p95: f64,
}

impl Band {
    /// A band of a run that failed or an output that was never finite.
    pub const NAN: Band = Band {
        p5: f64::NAN,
        p50: f64::NAN,
        p95: f64::NAN,
    };

    /// Whether `v` lies within [P5, P95] (with a relative slack of 1e-9 for rounding).
    pub fn contains(&self, v: f64) -> bool {
        let eps = 1e-9 * v.abs().max(1e-12);
        v >= self.p5 - eps && v <= self.p95 + eps
    }

    /// P95 − P5.
    pub fn width(&self) -> f64 {
        self.p95 - self.p5
    }
}

/// Percentile `q` (0..1) of sorted values, linear between order statistics.
fn percentile(sorted: &[f64], q: f64) -> f64 {
    let n = sorted.len();
    if n == 1 {
        return sorted[0];
    }
    let x = q * (n - 1) as f64;
    let i = (x.floor() as usize).min(n - 2);
    let f = x - i as f64;
    sorted[i] + (sorted[i + 1] - sorted[i]) * f
}

/// The band of `values` (NaN values are ignored; an empty set gives NaN).
pub fn band(values: &[f64]) -> Band {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return Band::NAN;
    }
    v.sort_by(f64::total_cmp);
    Band {
        p5: percentile(&v, 0.05),
        p50: percentile(&v, 0.5),
        p95: percentile(&v, 0.95),
    }
}

/// `cutter` with its run-out perturbed by `u`: a 2-D offset error of standard deviation
/// `runout_offset_um` per component added to the offset vector, and a normal error added
/// to every tooth's deviation (only when the uncertainty is positive).
pub fn perturb_cutter(cutter: &Cutter, u: &Uncertainty, rng: &mut Rng) -> Cutter {
    let mut c = cutter.clone();
    let (gx, gy) = (rng.normal(), rng.normal());
    if u.runout_offset_um > 0.0 {
        let r = &mut c.runout;
        let (s, co) = r.offset_phase_rad.sin_cos();
        let x = r.offset_mm * co + gx * u.runout_offset_um * 1e-3;
        let y = r.offset_mm * s + gy * u.runout_offset_um * 1e-3;
        r.offset_mm = x.hypot(y);
        r.offset_phase_rad = y.atan2(x).rem_euclid(std::f64::consts::TAU);
    }
    let teeth = c.teeth();
    let draws: Vec<f64> = (0..teeth).map(|_| rng.normal()).collect();
    if u.tooth_deviation_um > 0.0 {
        let r = &mut c.runout;
        if r.tooth_radius_dev_mm.len() != teeth {
            r.tooth_radius_dev_mm = vec![0.0; teeth];
        }
        for (d, g) in r.tooth_radius_dev_mm.iter_mut().zip(draws) {
            *d += g * u.tooth_deviation_um * 1e-3;
        }
    }
    c
}

/// Parameters drawn from N(`mean`, `scale²`·`cov`) (Cholesky; a singular direction gets no
/// spread), each clamped to its `bounds`.
pub fn draw_parameters(
    mean: &[f64],
    cov: &[Vec<f64>],
    scale: f64,
    bounds: &[(f64, f64)],
    rng: &mut Rng,
) -> Vec<f64> {
    let n = mean.len();
    let l = cholesky(cov);
    let g: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
    (0..n)
        .map(|i| {
            let d: f64 = (0..n).map(|k| l[i][k] * g[k]).sum();
            let v = mean[i] + scale * d;
            let (lo, hi) = bounds.get(i).copied().unwrap_or((f64::MIN, f64::MAX));
            v.clamp(lo, hi)
        })
        .collect()
}

/// A factor `L` with `L Lᵀ = a` of a symmetric positive semi-definite matrix: the lower
/// Cholesky factor (nalgebra) when `a` is positive definite, else `V √max(Λ, 0)` of its
/// symmetric eigen-decomposition, so that a singular direction gets no spread (zero when
/// `a` holds a non-finite value).
pub fn cholesky(a: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = a.len();
    let m = DMatrix::from_fn(n, n, |i, j| a[i][j]);
    let factor = match m.clone().cholesky() {
        Some(c) => c.l(),
        None if m.iter().all(|v| v.is_finite()) => match m.try_symmetric_eigen(1e-15, 10_000) {
            Some(e) => {
                let root = e.eigenvalues.map(|l| l.max(0.0).sqrt());
                e.eigenvectors * DMatrix::from_diagonal(&root)
            }
            None => DMatrix::zeros(n, n),
        },
        None => DMatrix::zeros(n, n),
    };
    (0..n)
        .map(|i| (0..n).map(|j| factor[(i, j)]).collect())
        .collect()
}

/// Largest number of Monte Carlo samples (`--monte-carlo N`): the outputs of every sample
/// are kept until their percentiles are taken.
pub const MAX_SAMPLES: usize = 100_000;

/// A number of Monte Carlo samples (the request's `monte_carlo`) out of 1..=[`MAX_SAMPLES`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SamplesError {
    /// No sample.
    #[error("‹monte_carlo› needs at least one sample")]
    None,
    /// More than [`MAX_SAMPLES`].
    #[error("‹monte_carlo› takes at most {MAX_SAMPLES} samples, got {0}")]
    TooMany(usize),
}

/// Check a number of Monte Carlo samples: at least one, at most [`MAX_SAMPLES`].
pub fn check_samples(n: usize) -> Result<(), SamplesError> {
    if n == 0 {
        return Err(SamplesError::None);
    }
    if n > MAX_SAMPLES {
        return Err(SamplesError::TooMany(n));
    }
    Ok(())
}

/// Run `f` for samples 0..`n` (each with its own stream of `seed`) in parallel and return
/// the band of every output (`f` returns the same number of outputs every time).
pub fn bands<F, E>(n: usize, seed: u64, f: F) -> Result<Vec<Band>, E>
where
    F: Fn(&mut Rng) -> Result<Vec<f64>, E> + Sync,
    E: From<SamplesError> + Send,
{
    check_samples(n)?;
    let outs: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .with_min_len(1)
        .map(|i| f(&mut Rng::stream(seed, i as u64)))
        .collect::<Result<_, _>>()?;
    let m = outs[0].len();
    Ok((0..m)
        .map(|k| band(&outs.iter().map(|o| o[k]).collect::<Vec<_>>()))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_of_a_ramp_and_cholesky_of_a_2x2() {
        let v: Vec<f64> = (0..=100).map(f64::from).collect();
        let b = band(&v);
        assert_eq!((b.p5, b.p50, b.p95), (5.0, 50.0, 95.0));
        let l = cholesky(&[vec![4.0, 2.0], vec![2.0, 5.0]]);
        assert_eq!(l, vec![vec![2.0, 0.0], vec![1.0, 2.0]]);
        let a = bands::<_, SamplesError>(50, 3, |r| Ok(vec![r.normal()])).unwrap();
        let b = bands::<_, SamplesError>(50, 3, |r| Ok(vec![r.normal()])).unwrap();
        assert_eq!(a, b);
    }
}
