//! Gaussian profile and areal filters (ISO 16610-21 / -61).
//!
//! Weighting function `s(x) = exp(−π (x/(α λ))²)/(α λ)`, `α = sqrt(ln 2/π)`, i.e. a Gaussian
//! of standard deviation `σ = λ·sqrt(ln 2 / 2)/π` (50 % amplitude transmission at the nesting
//! index λ). The areal filter is the product of the x and y kernels, applied separably with
//! each axis' own step. The kernel is truncated at `round(4σ)` samples (as
//! `scipy.ndimage.gaussian_filter`) and renormalised.
//!
//! End effects: the data are extended by symmetric reflection (`d c b a | a b c d | d c b a`,
//! scipy's `reflect`), so every node gets a value ([`EndEffects::Reflect`], what surfalize
//! does). [`EndEffects::Trim`] additionally discards the end zones, λc/2 at each border, as
//! ISO 4288 practice does for profiles; the caller crops (see `params::preprocess_*`).
//! Missing nodes: normalised convolution (weights of valid nodes only); a missing node stays
//! missing.

use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

use crate::surface::HeightMap;

/// How the borders of a filtered field are treated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EndEffects {
    /// Symmetric reflection at the borders, no trimming (surfalize 0.19.2).
    #[default]
    Reflect,
    /// Reflection, then discard half the largest nesting index at each border (ISO 4288).
    Trim,
}

impl EndEffects {
    /// A sentence for the output.
    pub fn describe(self) -> &'static str {
        match self {
            EndEffects::Reflect => {
                "symmetric reflection at the borders, no trimming (as surfalize/scipy 'reflect')"
            }
            EndEffects::Trim => {
                "symmetric reflection, then lambda/2 of the largest nesting index discarded at each border (ISO 4288)"
            }
        }
    }
}

/// Standard deviation of the ISO 16610-21 Gaussian weighting function for nesting index
/// `cutoff` (same unit).
pub fn gaussian_sigma(cutoff: f64) -> f64 {
    cutoff / std::f64::consts::PI * (std::f64::consts::LN_2 / 2.0).sqrt()
}

fn kernel(sigma_px: f64) -> Vec<f64> {
    let radius = (4.0 * sigma_px + 0.5) as usize;
    let mut w: Vec<f64> = (0..=2 * radius)
        .map(|k| {
            let t = k as f64 - radius as f64;
            (-0.5 * (t / sigma_px) * (t / sigma_px)).exp()
        })
        .collect();
    let s: f64 = w.iter().sum();
    for v in &mut w {
        *v /= s;
    }
    w
}

/// Index of the symmetric (half-sample) reflection of `i` into `0..n`.
#[inline]
fn reflect(i: isize, n: usize) -> usize {
    let p = 2 * n as isize;
    let m = i.rem_euclid(p) as usize;
    if m < n { m } else { 2 * n - 1 - m }
}

/// Kernels longer than this use FFT convolution.
const DIRECT_MAX_RADIUS: usize = 48;

/// FFT plans (forward, inverse), the kernel's spectrum and the transform length.
type FftConv = (Arc<dyn Fft<f64>>, Arc<dyn Fft<f64>>, Vec<Complex64>, usize);

/// A line filter reusable over many lines of one length.
struct LineFilter {
    w: Vec<f64>,
    radius: usize,
    fft: Option<FftConv>,
}

impl LineFilter {
    fn new(n: usize, sigma_px: f64) -> LineFilter {
        let w = kernel(sigma_px);
        let radius = w.len() / 2;
        let fft = (radius > DIRECT_MAX_RADIUS).then(|| {
            let len = (n + 4 * radius + 1).next_power_of_two();
            let mut planner = FftPlanner::<f64>::new();
            let fwd = planner.plan_fft_forward(len);
            let inv = planner.plan_fft_inverse(len);
            let mut kf = vec![Complex64::default(); len];
            for (k, &v) in w.iter().enumerate() {
                kf[k] = Complex64::new(v, 0.0);
            }
            fwd.process(&mut kf);
            (fwd, inv, kf, len)
        });
        LineFilter { w, radius, fft }
    }

    /// Plain convolution of the reflected extension of `x` (no missing values).
    fn convolve(&self, x: &[f64], out: &mut [f64]) {
        let n = x.len();
        let r = self.radius as isize;
        match &self.fft {
            None => {
                // Extend once by reflection, then plain dot products (no index arithmetic
                // in the inner loop).
                let ext: Vec<f64> = (0..n + 2 * self.radius)
                    .map(|k| x[reflect(k as isize - r, n)])
                    .collect();
                for (i, o) in out.iter_mut().enumerate() {
                    *o = self
                        .w
                        .iter()
                        .zip(&ext[i..i + self.w.len()])
                        .map(|(a, b)| a * b)
                        .sum();
                }
            }
            Some((fwd, inv, kf, len)) => {
                let ext = n + 2 * self.radius;
                let mut buf = vec![Complex64::default(); *len];
                for (k, b) in buf.iter_mut().take(ext).enumerate() {
                    *b = Complex64::new(x[reflect(k as isize - r, n)], 0.0);
                }
                fwd.process(&mut buf);
                for (b, k) in buf.iter_mut().zip(kf) {
                    *b *= k;
                }
                inv.process(&mut buf);
                let scale = 1.0 / *len as f64;
                // Full convolution index i + 2r is the output centred at sample i.
                for (i, o) in out.iter_mut().enumerate() {
                    *o = buf[i + 2 * self.radius].re * scale;
                }
            }
        }
    }

    /// Normalised convolution: missing values are skipped, missing stays missing.
    fn apply(&self, x: &[f64], out: &mut [f64]) {
        if x.iter().all(|v| v.is_finite()) {
            self.convolve(x, out);
            return;
        }
        let n = x.len();
        let vals: Vec<f64> = x
            .iter()
            .map(|&v| if v.is_finite() { v } else { 0.0 })
            .collect();
        let mask: Vec<f64> = x
            .iter()
            .map(|&v| if v.is_finite() { 1.0 } else { 0.0 })
            .collect();
        let mut num = vec![0.0; n];
        let mut den = vec![0.0; n];
        self.convolve(&vals, &mut num);
        self.convolve(&mask, &mut den);
        for i in 0..n {
            out[i] = if x[i].is_finite() && den[i] > 1e-9 {
                num[i] / den[i]
            } else {
                f64::NAN
            };
        }
    }
}

/// Gaussian low-pass of one line sampled at `step` (nesting index `cutoff`, same unit).
pub fn gaussian_lowpass_line(x: &[f64], cutoff: f64, step: f64) -> Vec<f64> {
    let mut out = vec![0.0; x.len()];
    if x.is_empty() {
        return out;
    }
    let f = LineFilter::new(x.len(), gaussian_sigma(cutoff) / step);
    f.apply(x, &mut out);
    out
}

/// Areal Gaussian low-pass of a height map (nesting index `cutoff_um`), separable along x
/// then y; an axis with a single node is left alone.
pub fn gaussian_filter_map(map: &HeightMap, cutoff_um: f64) -> HeightMap {
    let (nx, ny) = (map.nx, map.ny);
    let mut out = map.clone();
    let sigma = gaussian_sigma(cutoff_um);
    if nx > 1 {
        let f = LineFilter::new(nx, sigma / map.dx_um);
        let mut line = vec![0.0; nx];
        for r in 0..ny {
            f.apply(&map.z_um[r * nx..(r + 1) * nx], &mut line);
            out.z_um[r * nx..(r + 1) * nx].copy_from_slice(&line);
        }
    }
    if ny > 1 {
        let f = LineFilter::new(ny, sigma / map.dy_um);
        let mut col = vec![0.0; ny];
        let mut res = vec![0.0; ny];
        for c in 0..nx {
            for (r, v) in col.iter_mut().enumerate() {
                *v = out.z_um[r * nx + c];
            }
            f.apply(&col, &mut res);
            for (r, v) in res.iter().enumerate() {
                out.z_um[r * nx + c] = *v;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigma_constant() {
        assert!((gaussian_sigma(1.0) - 0.187390).abs() < 1e-6);
    }

    #[test]
    fn reflect_is_half_sample_symmetric() {
        let n = 4;
        let got: Vec<usize> = (-5..9).map(|i| reflect(i, n)).collect();
        assert_eq!(got, vec![3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0]);
    }

    #[test]
    fn fft_and_direct_agree() {
        let x: Vec<f64> = (0..300).map(|k| ((k * k) % 17) as f64 * 0.1).collect();
        let small = LineFilter::new(300, 20.0);
        assert!(small.fft.is_some());
        let mut a = vec![0.0; 300];
        small.convolve(&x, &mut a);
        let mut b = vec![0.0; 300];
        for (i, o) in b.iter_mut().enumerate() {
            let r = small.radius as isize;
            *o = small
                .w
                .iter()
                .enumerate()
                .map(|(k, wk)| wk * x[reflect(i as isize + k as isize - r, 300)])
                .sum();
        }
        for (p, q) in a.iter().zip(&b) {
            assert!((p - q).abs() < 1e-12);
        }
    }

    #[test]
    fn missing_stays_missing_and_constant_passes() {
        let mut x = vec![2.0; 50];
        x[10] = f64::NAN;
        let y = gaussian_lowpass_line(&x, 5.0, 0.5);
        assert!(y[10].is_nan());
        assert!(
            y.iter()
                .filter(|v| v.is_finite())
                .all(|v| (v - 2.0).abs() < 1e-12)
        );
    }
}
