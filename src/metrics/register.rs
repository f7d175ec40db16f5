//! Registration of a predicted height map onto a measured one: the feed direction from the
//! 2-D spectrum, the rigid placement (rotation about the centres, then a shift), the shift by
//! FFT cross-correlation, and the 1-D spectra and profiles along and across the feed.
//!
//! Angles are degrees counter-clockwise from +x in the map's own frame (y = row·dy,
//! ascending). The feed direction is the lay of the dominant periodic texture (the scallops
//! run along the feed): perpendicular to the frequency vector of the strongest spectral peak,
//! in [0, 180).

use rustfft::FftDirection;
use rustfft::num_complex::Complex64;

use super::fft::Fft2;
use crate::surface::HeightMap;

/// Lowest frequency searched for a spectral peak, in cycles per extent of the data.
const MIN_CYCLES: f64 = 1.5;

/// Largest padded correlation field (nodes) refined on its Fourier series; larger ones are
/// refined by a parabola through whole lags (each evaluation of the series costs the field).
const FOURIER_REFINE_MAX: usize = 1 << 21;

/// Zero-padding factor of the 1-D spectra.
const PAD_1D: usize = 8;

/// Maps of more nodes than this are searched on block means (the spectral peak, the
/// whole-lag correlation peak) before the correlation is refined at full resolution: 724 ×
/// 724 nodes, whose padded correlation field is [`FOURIER_REFINE_MAX`].
const COARSE_NODES: usize = FOURIER_REFINE_MAX / 4;

/// Lines of a 1-D spectrum transformed in parallel before they are summed (in order).
const LINES_AT_ONCE: usize = 64;

/// The block size that brings a map within [`COARSE_NODES`] (1 when it is).
fn decimation(map: &HeightMap) -> usize {
    let n = map.nx * map.ny;
    if n <= COARSE_NODES {
        1
    } else {
        ((n as f64 / COARSE_NODES as f64).sqrt().ceil() as usize).max(2)
    }
}

/// Block means of `d × d` nodes (missing nodes left out; a block without a valid node is
/// missing), spacing `d` times the map's; the last blocks may be partial.
fn block_means(map: &HeightMap, d: usize) -> HeightMap {
    let (cx, cy) = (map.nx.div_ceil(d), map.ny.div_ceil(d));
    let mut z = vec![f64::NAN; cx * cy];
    for (j, out) in z.chunks_exact_mut(cx).enumerate() {
        let mut sum = vec![(0.0, 0usize); cx];
        for r in j * d..((j + 1) * d).min(map.ny) {
            for (c, v) in map.z_um[r * map.nx..(r + 1) * map.nx].iter().enumerate() {
                if v.is_finite() {
                    let s = &mut sum[c / d];
                    s.0 += v;
                    s.1 += 1;
                }
            }
        }
        for (o, (s, n)) in out.iter_mut().zip(sum) {
            if n > 0 {
                *o = s / n as f64;
            }
        }
    }
    let mut m = HeightMap::new_nan(cx, cy, map.dx_um * d as f64, map.dy_um * d as f64);
    m.z_um = z;
    m
}

fn hann(i: usize, n: usize) -> f64 {
    if n <= 1 {
        1.0
    } else {
        0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / (n - 1) as f64).cos()
    }
}

/// Mean of the finite values (`NaN` when there is none).
fn finite_mean(z: &[f64]) -> f64 {
    let (s, n) = z
        .iter()
        .filter(|v| v.is_finite())
        .fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 { f64::NAN } else { s / n as f64 }
}

/// Mean-removed heights with missing nodes as 0, times a 2-D Hann window when `window`.
fn centred(map: &HeightMap, window: bool) -> Vec<f64> {
    let m = finite_mean(&map.z_um);
    let mut out = Vec::with_capacity(map.z_um.len());
    for r in 0..map.ny {
        let wy = if window { hann(r, map.ny) } else { 1.0 };
        for c in 0..map.nx {
            let v = map.z_um[r * map.nx + c];
            let wx = if window { hann(c, map.nx) } else { 1.0 };
            out.push(if v.is_finite() {
                (v - m) * wx * wy
            } else {
                0.0
            });
        }
    }
    out
}

/// The 2-D FFT of `w` (`ny × nx`) zero-padded to `(py, px)` (the padding rows are zero
/// and stay so: only the field's rows are transformed along).
fn fft2_padded(w: &[f64], nx: usize, ny: usize, px: usize, py: usize) -> Vec<Complex64> {
    super::fft::padded_forward(nx, ny, px, py, |k| Complex64::new(w[k], 0.0))
}

/// `ln |DTFT|²` of the windowed field at the frequency (fx, fy), cycles/µm.
fn dtft_log_power(w: &[f64], map: &HeightMap, fx: f64, fy: f64) -> f64 {
    let tau = 2.0 * std::f64::consts::PI;
    let ex: Vec<Complex64> = (0..map.nx)
        .map(|j| Complex64::from_polar(1.0, -tau * fx * j as f64 * map.dx_um))
        .collect();
    let mut acc = Complex64::default();
    for (i, row) in w.chunks_exact(map.nx).enumerate() {
        let s: Complex64 = row.iter().zip(&ex).map(|(v, e)| e * v).sum();
        acc += s * Complex64::from_polar(1.0, -tau * fy * i as f64 * map.dy_um);
    }
    (acc.norm_sqr() + 1e-300).ln()
}

/// One parabolic step towards the maximum of `f` around `x` with step `h`.
fn parabolic_step(f: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
    let (fm, f0, fp) = (f(x - h), f(x), f(x + h));
    let den = fm - 2.0 * f0 + fp;
    if den < 0.0 {
        x + (0.5 * (fm - fp) / den).clamp(-1.0, 1.0) * h
    } else if fp > f0 && fp >= fm {
        x + h
    } else if fm > f0 {
        x - h
    } else {
        x
    }
}

/// The offset of a parabola's vertex through three equally spaced values (in steps, within ±½).
fn vertex(fm: f64, f0: f64, fp: f64) -> f64 {
    let den = fm - 2.0 * f0 + fp;
    if den < 0.0 {
        (0.5 * (fm - fp) / den).clamp(-0.5, 0.5)
    } else {
        0.0
    }
}

/// The frequency (fx, fy) of the strongest spectral peak of a map, cycles/µm, refined to a
/// small fraction of a bin on the continuous spectrum of the Hann-windowed heights.
///
/// A map of more than [`COARSE_NODES`] nodes is searched on its block means (the same
/// extent, so the same frequency resolution; a texture of fewer than 2 blocks per period is
/// then out of reach).
pub fn spectral_peak(map: &HeightMap) -> Option<(f64, f64)> {
    if map.nx < 8 || map.ny < 8 {
        return None;
    }
    let d = decimation(map);
    if d > 1 {
        return spectral_peak(&block_means(map, d));
    }
    let w = centred(map, true);
    let (px, py) = (2 * map.nx, 2 * map.ny);
    let f = fft2_padded(&w, map.nx, map.ny, px, py);
    let (bx, by) = (1.0 / (px as f64 * map.dx_um), 1.0 / (py as f64 * map.dy_um));
    let (lx, ly) = (map.nx as f64 * map.dx_um, map.ny as f64 * map.dy_um);
    let mut best: Option<(f64, f64, f64)> = None;
    for ky in 0..=py / 2 {
        for c in 0..px {
            let kx = if c <= px / 2 {
                c as f64
            } else {
                c as f64 - px as f64
            };
            let (fx, fy) = (kx * bx, ky as f64 * by);
            if (fx * lx).powi(2) + (fy * ly).powi(2) < MIN_CYCLES * MIN_CYCLES {
                continue;
            }
            let p = f[ky * px + c].norm_sqr();
            if best.is_none_or(|b| p > b.0) {
                best = Some((p, fx, fy));
            }
        }
    }
    let (_, mut fx, mut fy) = best?;
    let (mut hx, mut hy) = (0.5 * bx, 0.5 * by);
    for _ in 0..14 {
        fx = parabolic_step(|t| dtft_log_power(&w, map, t, fy), fx, hx);
        fy = parabolic_step(|t| dtft_log_power(&w, map, fx, t), fy, hy);
        hx *= 0.5;
        hy *= 0.5;
    }
    Some((fx, fy))
}

/// The feed direction of a map, degrees in [0, 180): perpendicular to its strongest
/// spectral peak's frequency vector.
pub fn feed_direction_deg(map: &HeightMap) -> Option<f64> {
    let (fx, fy) = spectral_peak(map)?;
    let d = (fy.atan2(fx).to_degrees() + 90.0).rem_euclid(180.0);
    d.is_finite().then(|| {
        if (1e-9..=180.0 - 1e-9).contains(&d) {
            d
        } else {
            0.0
        }
    })
}

/// A rigid placement of a prediction on a measurement: the prediction is rotated by
/// `rotation_deg` (counter-clockwise) about its centre, put on the measurement's centre, then
/// moved by `shift_um`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Placement {
    /// Rotation, degrees counter-clockwise.
    pub rotation_deg: f64,
    /// Shift (x, y), µm.
    pub shift_um: [f64; 2],
}

/// `t` put on the nearest whole number when within 1e-9 of it. For 0 ≤ t < 2⁵² from the
/// truncation, whose remainder is exact (as is `t − round(t)` within that range), so the
/// same values as `round` without its call into libm (the SSE2 target has no rounding
/// instruction); other values through `round`.
fn snap_node(t: f64) -> f64 {
    const EXACT: f64 = (1u64 << 52) as f64;
    if (0.0..EXACT).contains(&t) {
        let f = t as u64 as f64;
        let frac = t - f;
        if frac == 0.0 {
            t
        } else if frac < 1e-9 {
            f
        } else if 1.0 - frac < 1e-9 {
            f + 1.0
        } else {
            t
        }
    } else if (t - t.round()).abs() < 1e-9 {
        t.round()
    } else {
        t
    }
}

/// Bilinear value of `map` at fractional node (col `j`, row `i`); `NaN` outside the map or
/// where a node with weight is missing.
pub fn bilinear(map: &HeightMap, j: f64, i: f64) -> f64 {
    let (j, i) = (snap_node(j), snap_node(i));
    if !(j >= 0.0 && i >= 0.0 && j <= (map.nx - 1) as f64 && i <= (map.ny - 1) as f64) {
        return f64::NAN;
    }
    // Truncation is the floor of these non-negative values (no call into libm).
    let (j0, i0) = (j as usize, i as usize);
    let (tx, ty) = (j - j0 as f64, i - i0 as f64);
    let mut s = 0.0;
    for (di, wy) in [(0, 1.0 - ty), (1, ty)] {
        for (dj, wx) in [(0, 1.0 - tx), (1, tx)] {
            let w = wx * wy;
            if w == 0.0 {
                continue;
            }
            s += w * map.z_um[(i0 + di) * map.nx + j0 + dj];
        }
    }
    s
}

/// The prediction `pred` placed on the grid of `grid` (its spacing, size and origin),
/// bilinearly resampled; nodes it does not cover are `NaN`.
pub fn place(pred: &HeightMap, grid: &HeightMap, pl: &Placement) -> HeightMap {
    let mut out = HeightMap::new_nan(grid.nx, grid.ny, grid.dx_um, grid.dy_um);
    out.x0_mm = grid.x0_mm;
    out.y0_mm = grid.y0_mm;
    let (s, c) = pl.rotation_deg.to_radians().sin_cos();
    let (gcx, gcy) = (
        (grid.nx - 1) as f64 * grid.dx_um / 2.0,
        (grid.ny - 1) as f64 * grid.dy_um / 2.0,
    );
    let (pcx, pcy) = (
        (pred.nx - 1) as f64 * pred.dx_um / 2.0,
        (pred.ny - 1) as f64 * pred.dy_um / 2.0,
    );
    use rayon::prelude::*;
    out.z_um
        .par_chunks_exact_mut(grid.nx)
        .enumerate()
        .for_each(|(r, row)| {
            for (col, z) in row.iter_mut().enumerate() {
                let mx = col as f64 * grid.dx_um - gcx - pl.shift_um[0];
                let my = r as f64 * grid.dy_um - gcy - pl.shift_um[1];
                // Rotate back by −rotation.
                let (px, py) = (c * mx + s * my, -s * mx + c * my);
                *z = bilinear(pred, (px + pcx) / pred.dx_um, (py + pcy) / pred.dy_um);
            }
        });
    out
}

/// The shift (µm) that best lays `placed` onto `measured` (the same grid): the peak of their
/// linear cross-correlation, refined by a parabola through its neighbours in each axis; and
/// the peak's normalised height (1 for identical maps): for maps over [`COARSE_NODES`] the
/// correlation coefficient over the common nodes at the best whole lag
/// ([`shift_peak_is_coefficient`]), for smaller ones the biased correlation over the norms
/// of both whole maps.
pub fn correlation_shift(measured: &HeightMap, placed: &HeightMap) -> Option<([f64; 2], f64)> {
    let (nx, ny) = (measured.nx, measured.ny);
    if placed.nx != nx || placed.ny != ny || nx < 2 || ny < 2 {
        return None;
    }
    if nx * ny > COARSE_NODES {
        return coarse_to_fine(measured, placed);
    }
    let a = centred(measured, false);
    let b = centred(placed, false);
    let norm = (a.iter().map(|v| v * v).sum::<f64>() * b.iter().map(|v| v * v).sum::<f64>()).sqrt();
    if norm.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let (px, py) = (2 * nx, 2 * ny);
    let fa = fft2_padded(&a, nx, ny, px, py);
    let mut fb = fft2_padded(&b, nx, ny, px, py);
    for (x, y) in fb.iter_mut().zip(&fa) {
        *x = y * x.conj();
    }
    let cross = fb.clone();
    // The spectrum of the count of overlapping valid nodes, to refine on the unbiased
    // correlation (the biased one, whose peak is searched, leans towards zero lag).
    let valid = |m: &HeightMap| -> Vec<f64> {
        m.z_um
            .iter()
            .map(|v| if v.is_finite() { 1.0 } else { 0.0 })
            .collect()
    };
    let ma = fft2_padded(&valid(measured), nx, ny, px, py);
    let mut overlap = fft2_padded(&valid(placed), nx, ny, px, py);
    for (x, y) in overlap.iter_mut().zip(&ma) {
        *x = y * x.conj();
    }
    let unbiased = |tx: f64, ty: f64| {
        correlation_at(&cross, px, py, tx, ty) / correlation_at(&overlap, px, py, tx, ty).max(1.0)
    };
    let mut f = Fft2::new(py, px, FftDirection::Inverse);
    f.rows(&mut fb);
    f.columns(&mut fb);
    let scale = (px * py) as f64;
    let r: Vec<f64> = fb.iter().map(|v| v.re / scale).collect();
    let (k, peak) =
        r.iter().enumerate().fold(
            (0, f64::NEG_INFINITY),
            |b, (k, &v)| if v > b.1 { (k, v) } else { b },
        );
    let (ky, kx) = (k / px, k % px);
    let at = |y: usize, x: usize| r[(y % py) * px + (x % px)];
    let ox = vertex(at(ky, kx + px - 1), peak, at(ky, kx + 1));
    let oy = vertex(at(ky + py - 1, kx), peak, at(ky + 1, kx));
    let lag = |k: usize, n: usize| {
        if k < n / 2 {
            k as f64
        } else {
            k as f64 - n as f64
        }
    };
    let (mut tx, mut ty) = (lag(kx, px) + ox, lag(ky, py) + oy);
    // Refine on the band-limited interpolation of the unbiased correlation (its Fourier
    // series); larger maps go through `coarse_to_fine`.
    let mut h = 0.25;
    for _ in 0..10 {
        tx = parabolic_step(|t| unbiased(t, ty), tx, h);
        ty = parabolic_step(|t| unbiased(tx, t), ty, h);
        h *= 0.5;
    }
    let snap = |t: f64| if t.abs() < 1e-6 { 0.0 } else { t };
    Some((
        [snap(tx) * measured.dx_um, snap(ty) * measured.dy_um],
        peak / norm,
    ))
}

/// Whether [`correlation_shift`] on maps of `measured`'s grid returns the correlation
/// coefficient over the common nodes (maps over [`COARSE_NODES`], registered coarse to fine),
/// which ranks two placements as their correlation over the common nodes does; a smaller
/// map's normalised peak leans with the size of the overlap.
pub fn shift_peak_is_coefficient(measured: &HeightMap) -> bool {
    measured.nx * measured.ny > COARSE_NODES
}

/// The whole lag (columns, rows) of the peak of the linear cross-correlation
/// `Σ a[n + t]·b[n]` of two maps on one grid (mean removed, missing nodes as 0).
fn whole_lag(measured: &HeightMap, placed: &HeightMap) -> Option<(i64, i64)> {
    let (nx, ny) = (measured.nx, measured.ny);
    let a = centred(measured, false);
    let b = centred(placed, false);
    let (px, py) = (super::fft::fast_len(2 * nx), super::fft::fast_len(2 * ny));
    let fa = fft2_padded(&a, nx, ny, px, py);
    let mut fb = fft2_padded(&b, nx, ny, px, py);
    for (x, y) in fb.iter_mut().zip(&fa) {
        *x = y * x.conj();
    }
    let mut f = Fft2::new(py, px, FftDirection::Inverse);
    f.rows(&mut fb);
    f.columns(&mut fb);
    let (k, peak) = fb
        .iter()
        .enumerate()
        .fold((0, f64::NEG_INFINITY), |b, (k, v)| {
            if v.re > b.1 { (k, v.re) } else { b }
        });
    if !(peak.is_finite() && peak > 0.0) {
        return None;
    }
    let lag = |k: usize, n: usize| {
        if k < n / 2 {
            k as i64
        } else {
            k as i64 - n as i64
        }
    };
    Some((lag(k % px, px), lag(k / px, py)))
}

/// The sums of one row pair, `w` nodes from `ka` in `a` and `kb` in `b`:
/// [Σ a·b, Σ a·vb, Σ b·va, Σ a²·vb, Σ b²·va, Σ va·vb].
#[inline]
fn row_sums(
    (a, va): (&[f64], &[f64]),
    (b, vb): (&[f64], &[f64]),
    ka: usize,
    kb: usize,
    w: usize,
) -> [f64; 6] {
    let mut t = [0.0; 6];
    for l in 0..w {
        let (x, y, p, q) = (a[ka + l], b[kb + l], va[ka + l], vb[kb + l]);
        t[0] += x * y;
        t[1] += x * q;
        t[2] += y * p;
        t[3] += x * x * q;
        t[4] += y * y * p;
        t[5] += p * q;
    }
    t
}

/// [`lagged_sums`] of the lags (tx, ty) for each tx of `txs`, in one pass over the row pairs
/// of `ty` (each row of the four fields read once for all of them, where a pass per lag read
/// it once per lag): every lag's rows are summed in the same order, so the same bits.
fn lagged_sums_row(
    (a, va): (&[f64], &[f64]),
    (b, vb): (&[f64], &[f64]),
    (nx, ny): (usize, usize),
    ty: i64,
    txs: &[i64],
) -> Vec<[f64; 6]> {
    let mut out = vec![[0.0; 6]; txs.len()];
    let ay = ty.unsigned_abs() as usize;
    if ay >= ny {
        return out;
    }
    let (ra0, rb0) = if ty >= 0 { (ay, 0) } else { (0, ay) };
    for i in 0..ny - ay {
        let (ra, rb) = ((ra0 + i) * nx, (rb0 + i) * nx);
        for (s, &tx) in out.iter_mut().zip(txs) {
            let ax = tx.unsigned_abs() as usize;
            if ax >= nx {
                continue;
            }
            let w = nx - ax;
            let (ca, cb) = if tx >= 0 { (ax, 0) } else { (0, ax) };
            let (ka, kb) = (ra + ca, rb + cb);
            let t = row_sums((a, va), (b, vb), ka, kb, w);
            for (s, t) in s.iter_mut().zip(t) {
                *s += t;
            }
        }
    }
    out
}

/// The sums of a whole lag t = (tx, ty) over the nodes valid in both maps (`a`, `b`
/// mean-removed with missing nodes as 0, `va`, `vb` 1 where valid), `a` taken at n + t:
/// [Σ a·b, Σ a, Σ b, Σ a², Σ b², count].
#[cfg(test)]
fn lagged_sums(
    (a, va): (&[f64], &[f64]),
    (b, vb): (&[f64], &[f64]),
    (nx, ny): (usize, usize),
    (tx, ty): (i64, i64),
) -> [f64; 6] {
    let (ax, ay) = (tx.unsigned_abs() as usize, ty.unsigned_abs() as usize);
    if ax >= nx || ay >= ny {
        return [0.0; 6];
    }
    let w = nx - ax;
    let (ca, cb) = if tx >= 0 { (ax, 0) } else { (0, ax) };
    let mut s = [0.0; 6];
    let (ra0, rb0) = if ty >= 0 { (ay, 0) } else { (0, ay) };
    for i in 0..ny - ay {
        let (ka, kb) = ((ra0 + i) * nx + ca, (rb0 + i) * nx + cb);
        let t = row_sums((a, va), (b, vb), ka, kb, w);
        for (s, t) in s.iter_mut().zip(t) {
            *s += t;
        }
    }
    s
}

/// The correlation coefficient of the two maps over their common valid nodes at a lag,
/// from its sums ([`lagged_sums_row`]; `NaN` below 64 nodes).
fn zncc(s: [f64; 6]) -> f64 {
    let n = s[5];
    if n < 64.0 {
        return f64::NAN;
    }
    let cov = s[0] - s[1] * s[2] / n;
    let (va, vb) = (s[3] - s[1] * s[1] / n, s[4] - s[2] * s[2] / n);
    cov / (va * vb).sqrt()
}

/// [`correlation_shift`] of maps over [`COARSE_NODES`]: the whole-lag peak of the
/// correlation of their block means, then the full-resolution correlation coefficient over
/// the nodes both maps cover (zero-mean normalised, so neither the size of the overlap nor
/// its local mean leans it) climbed from it to its highest whole lag, and refined by a
/// parabola through its neighbours in each axis; the peak returned is that coefficient.
fn coarse_to_fine(measured: &HeightMap, placed: &HeightMap) -> Option<([f64; 2], f64)> {
    use rayon::prelude::*;
    let (nx, ny) = (measured.nx, measured.ny);
    let d = decimation(measured);
    let (lx, ly) = whole_lag(&block_means(measured, d), &block_means(placed, d))?;
    let a = centred(measured, false);
    let b = centred(placed, false);
    let norm = (a.iter().map(|v| v * v).sum::<f64>() * b.iter().map(|v| v * v).sum::<f64>()).sqrt();
    if norm.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let valid = |m: &HeightMap| -> Vec<f64> {
        m.z_um
            .iter()
            .map(|v| if v.is_finite() { 1.0 } else { 0.0 })
            .collect()
    };
    let (va, vb) = (valid(measured), valid(placed));
    // The lags of one row of lags (one ty) in one pass over its row pairs.
    let at_row = |ty: i64, txs: &[i64]| lagged_sums_row((&a, &va), (&b, &vb), (nx, ny), ty, txs);
    // Climb the unbiased correlation (sum over count) from the coarse peak, a 3 × 3
    // neighbourhood at a time (in parallel), until its centre is the highest.
    let mut seen: std::collections::BTreeMap<(i64, i64), f64> = Default::default();
    let (mut tx, mut ty) = (lx * d as i64, ly * d as i64);
    for _ in 0..4 * d + 8 {
        let around: Vec<(i64, i64)> = (ty - 1..=ty + 1)
            .flat_map(|y| (tx - 1..=tx + 1).map(move |x| (x, y)))
            .filter(|t| !seen.contains_key(t))
            .collect();
        let mut rows: Vec<(i64, Vec<i64>)> = Vec::new();
        for &(x, y) in &around {
            match rows.last_mut() {
                Some((ry, xs)) if *ry == y => xs.push(x),
                _ => rows.push((y, vec![x])),
            }
        }
        let r: Vec<Vec<f64>> = rows
            .par_iter()
            .map(|(y, xs)| at_row(*y, xs).into_iter().map(zncc).collect())
            .collect();
        seen.extend(around.into_iter().zip(r.into_iter().flatten()));
        let best = (ty - 1..=ty + 1)
            .flat_map(|y| (tx - 1..=tx + 1).map(move |x| (x, y)))
            .fold(((tx, ty), f64::NEG_INFINITY), |b, t| {
                let v = seen[&t];
                if v > b.1 { (t, v) } else { b }
            });
        if best.0 == (tx, ty) {
            break;
        }
        (tx, ty) = best.0;
    }
    let u = |t: (i64, i64)| seen.get(&t).copied().unwrap_or(f64::NAN);
    let peak = u((tx, ty));
    if !peak.is_finite() {
        return None;
    }
    let ox = vertex(u((tx - 1, ty)), peak, u((tx + 1, ty)));
    let oy = vertex(u((tx, ty - 1)), peak, u((tx, ty + 1)));
    let snap = |t: f64| if t.abs() < 1e-6 { 0.0 } else { t };
    Some((
        [
            snap(tx as f64 + ox) * measured.dx_um,
            snap(ty as f64 + oy) * measured.dy_um,
        ],
        peak,
    ))
}

/// The cross-correlation at a fractional lag (tx, ty) nodes from its spectrum `cross`
/// (`py × px`), by its Fourier series (the Nyquist terms taken as cosines).
fn correlation_at(cross: &[Complex64], px: usize, py: usize, tx: f64, ty: f64) -> f64 {
    let tau = 2.0 * std::f64::consts::PI;
    let signed = |k: usize, n: usize| {
        if 2 * k == n {
            0.0
        } else if k < n / 2 {
            k as f64
        } else {
            k as f64 - n as f64
        }
    };
    let ex: Vec<Complex64> = (0..px)
        .map(|k| Complex64::from_polar(1.0, tau * signed(k, px) * tx / px as f64))
        .collect();
    let mut acc = Complex64::default();
    for (ky, row) in cross.chunks_exact(px).enumerate() {
        let s: Complex64 = row.iter().zip(&ex).map(|(a, e)| a * e).sum();
        acc += s * Complex64::from_polar(1.0, tau * signed(ky, py) * ty / py as f64);
    }
    acc.re
}

/// The averaged power spectrum of lines and the period of its strongest peak.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LineSpectrum {
    /// Frequencies, cycles/µm.
    pub freq_per_um: Vec<f64>,
    /// Mean power of the Hann-windowed lines, µm².
    pub power: Vec<f64>,
    /// Period of the strongest peak above 1.5 cycles per line, µm (`NaN` when none).
    pub peak_period_um: f64,
}

/// Profiles and 1-D spectra along and across a feed direction.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LaySpectra {
    /// Positions along the lines, µm from the centre.
    pub position_um: Vec<f64>,
    /// The profile through the centre along the feed, µm.
    pub along_profile_um: Vec<f64>,
    /// The profile through the centre across the feed, µm.
    pub across_profile_um: Vec<f64>,
    /// Spectrum of lines along the feed (feed-mark period).
    pub along: LineSpectrum,
    /// Spectrum of lines across the feed (stepover).
    pub across: LineSpectrum,
}

/// A square of `n × n` nodes at spacing `d` centred on the map, its rows along `feed_deg`.
fn rotated_square(map: &HeightMap, feed_deg: f64) -> Option<(Vec<f64>, usize, f64)> {
    let d = map.dx_um.min(map.dy_um);
    let (s, c) = feed_deg.to_radians().sin_cos();
    let (ax, ay) = (
        (map.nx - 1) as f64 * map.dx_um / 2.0,
        (map.ny - 1) as f64 * map.dy_um / 2.0,
    );
    let h = ax.min(ay) / (c.abs() + s.abs()) * 0.999;
    let n = (2.0 * h / d).floor() as usize + 1;
    if n < 8 {
        return None;
    }
    let half = (n - 1) as f64 * d / 2.0;
    let mut z = vec![0.0; n * n];
    use rayon::prelude::*;
    z.par_chunks_exact_mut(n).enumerate().for_each(|(iv, row)| {
        let v = iv as f64 * d - half;
        for (iu, out) in row.iter_mut().enumerate() {
            let u = iu as f64 * d - half;
            let (x, y) = (ax + u * c - v * s, ay + u * s + v * c);
            *out = bilinear(map, x / map.dx_um, y / map.dy_um);
        }
    });
    Some((z, n, d))
}

/// Mean power spectrum of lines (each mean-removed, missing values as its mean, Hann window,
/// padded [`PAD_1D`] times, up to the next length of factors 2, 3 and 5). The lines are
/// real, so two at a time go through one complex FFT (`a + i·b`; the conjugate symmetry of
/// each one's spectrum separates them).
fn line_spectrum(lines: &[Vec<f64>], d: f64) -> LineSpectrum {
    use rayon::prelude::*;
    let n = lines.first().map_or(0, Vec::len);
    let m = super::fft::fast_len(PAD_1D * n.max(1));
    let fft = rustfft::FftPlanner::<f64>::new().plan_fft_forward(m);
    let mut power = vec![0.0; m / 2 + 1];
    let mut used = 0usize;
    let window: Vec<f64> = (0..n).map(|k| hann(k, n)).collect();
    // A line with at least half its values, mean-removed, missing values as 0, windowed.
    let windowed = |line: &Vec<f64>| -> Option<Vec<f64>> {
        let valid = line.iter().filter(|v| v.is_finite()).count();
        if 2 * valid < n {
            return None;
        }
        let mean = finite_mean(line);
        Some(
            line.iter()
                .zip(&window)
                .map(|(v, w)| if v.is_finite() { (v - mean) * w } else { 0.0 })
                .collect(),
        )
    };
    // |FFT|² over 0..=m/2 of one or two lines.
    let spectra = |pair: &[Vec<f64>]| -> Vec<Vec<f64>> {
        let mut buf = vec![Complex64::default(); m];
        for (k, v) in pair[0].iter().enumerate() {
            buf[k].re = *v;
        }
        if let Some(b) = pair.get(1) {
            for (k, v) in b.iter().enumerate() {
                buf[k].im = *v;
            }
        }
        fft.process(&mut buf);
        if pair.len() == 1 {
            return vec![buf[..=m / 2].iter().map(|z| z.norm_sqr()).collect()];
        }
        let (mut pa, mut pb) = (Vec::with_capacity(m / 2 + 1), Vec::with_capacity(m / 2 + 1));
        for k in 0..=m / 2 {
            let (z, zm) = (buf[k], buf[(m - k) % m].conj());
            pa.push((z + zm).norm_sqr() / 4.0);
            pb.push((z - zm).norm_sqr() / 4.0);
        }
        vec![pa, pb]
    };
    // The lines' spectra in parallel, a few at a time, summed in line order.
    for group in lines.chunks(LINES_AT_ONCE) {
        let kept: Vec<Vec<f64>> = group.par_iter().filter_map(windowed).collect();
        let powers: Vec<Vec<Vec<f64>>> = kept.par_chunks(2).map(spectra).collect();
        for line in powers.into_iter().flatten() {
            for (p, b) in power.iter_mut().zip(&line) {
                *p += b / (n as f64).powi(2);
            }
            used += 1;
        }
    }
    for p in power.iter_mut() {
        *p /= used.max(1) as f64;
    }
    let df = 1.0 / (m as f64 * d);
    let freq: Vec<f64> = (0..power.len()).map(|k| k as f64 * df).collect();
    let k0 = ((MIN_CYCLES * m as f64 / n.max(1) as f64).ceil() as usize).max(1);
    let mut peak = f64::NAN;
    if used > 0 && power.len() > k0 + 2 {
        let k = (k0..power.len() - 1).fold(k0, |b, k| if power[k] > power[b] { k } else { b });
        let ln = |k: usize| (power[k] + 1e-300).ln();
        let o = vertex(ln(k - 1), ln(k), ln(k + 1));
        peak = 1.0 / ((k as f64 + o) * df);
    }
    LineSpectrum {
        freq_per_um: freq,
        power,
        peak_period_um: peak,
    }
}

/// Profiles through the centre and 1-D spectra along and across the feed direction
/// `feed_deg`, on the largest centred square whose rotated sides fit in the map.
pub fn lay_spectra(map: &HeightMap, feed_deg: f64) -> Option<LaySpectra> {
    let (z, n, d) = rotated_square(map, feed_deg)?;
    let rows: Vec<Vec<f64>> = z.chunks_exact(n).map(<[f64]>::to_vec).collect();
    let cols: Vec<Vec<f64>> = (0..n)
        .map(|c| (0..n).map(|r| z[r * n + c]).collect())
        .collect();
    let half = (n - 1) as f64 * d / 2.0;
    Some(LaySpectra {
        position_um: (0..n).map(|k| k as f64 * d - half).collect(),
        along_profile_um: rows[n / 2].clone(),
        across_profile_um: cols[n / 2].clone(),
        along: line_spectrum(&rows, d),
        across: line_spectrum(&cols, d),
    })
}

/// A measured profile aligned to a predicted one (`crest plot profile --align`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileAlignment {
    /// Added to the measured positions, mm.
    pub shift_mm: f64,
    /// Added to the measured heights, µm (the difference of the means over the overlap).
    pub offset_um: f64,
    /// Correlation coefficient of the two over the overlap at that shift.
    pub correlation: f64,
}

/// The measured profile `z(x)` linearly interpolated at `x` (NaN outside, or where a
/// neighbour is NaN); `xs` ascending.
fn interpolate(xs: &[f64], zs: &[f64], x: f64) -> f64 {
    let k = xs.partition_point(|&v| v < x);
    if k == 0 {
        return if xs.first() == Some(&x) {
            zs[0]
        } else {
            f64::NAN
        };
    }
    if k >= xs.len() {
        return f64::NAN;
    }
    let (x0, x1) = (xs[k - 1], xs[k]);
    let t = if x1 > x0 { (x - x0) / (x1 - x0) } else { 0.0 };
    zs[k - 1] + (zs[k] - zs[k - 1]) * t
}

/// Correlation of the predicted profile with the measured one shifted by `shift` (mm) over
/// their overlap, and the number of points compared and the mean difference.
fn profile_correlation(
    pred: (&[f64], &[f64]),
    meas: (&[f64], &[f64]),
    shift: f64,
) -> (f64, usize, f64) {
    let mut pairs = Vec::new();
    for (&x, &z) in pred.0.iter().zip(pred.1) {
        let m = interpolate(meas.0, meas.1, x - shift);
        if z.is_finite() && m.is_finite() {
            pairs.push((z, m));
        }
    }
    let n = pairs.len();
    if n < 3 {
        return (f64::NAN, n, f64::NAN);
    }
    let (mp, mm) = pairs
        .iter()
        .fold((0.0, 0.0), |(a, b), (p, m)| (a + p, b + m));
    let (mp, mm) = (mp / n as f64, mm / n as f64);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (p, m) in &pairs {
        let (dp, dm) = (p - mp, m - mm);
        sxy += dp * dm;
        sxx += dp * dp;
        syy += dm * dm;
    }
    let r = if sxx > 0.0 && syy > 0.0 {
        sxy / (sxx * syy).sqrt()
    } else {
        f64::NAN
    };
    (r, n, mp - mm)
}

/// Align a measured profile (positions mm ascending, heights µm) to a predicted one: the
/// lateral shift that maximises their correlation over an overlap of at least half the
/// predicted profile, searched at the predicted spacing within ± half its length and refined
/// by a parabola through the best three, then the offset of the means. `None` when no shift
/// leaves enough overlap or the profiles are flat.
pub fn align_profile(pred: (&[f64], &[f64]), meas: (&[f64], &[f64])) -> Option<ProfileAlignment> {
    let (px, mx) = (pred.0, meas.0);
    if px.len() < 3
        || mx.len() < 3
        || mx
            .windows(2)
            .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
    {
        return None;
    }
    let step = (px[px.len() - 1] - px[0]) / (px.len() - 1) as f64;
    if !(step.is_finite() && step > 0.0) {
        return None;
    }
    let need = px.len().div_ceil(2);
    // Shifts that bring the measured profile's middle within ± half the predicted length
    // of the predicted profile's middle.
    let centre = 0.5 * (px[0] + px[px.len() - 1]) - 0.5 * (mx[0] + mx[mx.len() - 1]);
    let half = (px.len() / 2) as i64;
    let at = |k: i64| centre + k as f64 * step;
    let score = |k: i64| {
        let (r, n, _) = profile_correlation(pred, meas, at(k));
        if n >= need && r.is_finite() {
            r
        } else {
            f64::NEG_INFINITY
        }
    };
    let (best, r) = (-half..=half)
        .map(|k| (k, score(k)))
        .fold((0, f64::NEG_INFINITY), |b, c| if c.1 > b.1 { c } else { b });
    if !r.is_finite() {
        return None;
    }
    let (rm, rp) = (score(best - 1), score(best + 1));
    let frac = if rm.is_finite() && rp.is_finite() {
        vertex(rm, r, rp).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    let shift_mm = at(best) + frac * step;
    let (correlation, _, offset_um) = profile_correlation(pred, meas, shift_mm);
    Some(ProfileAlignment {
        shift_mm,
        offset_um,
        correlation,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stripes(nx: usize, ny: usize, deg: f64, period: f64) -> HeightMap {
        let (s, c) = deg.to_radians().sin_cos();
        let mut z = Vec::new();
        for r in 0..ny {
            for col in 0..nx {
                // Frequency vector perpendicular to the lay `deg`.
                let v = -(col as f64) * s + r as f64 * c;
                z.push((2.0 * std::f64::consts::PI * v / period).sin());
            }
        }
        HeightMap::from_rows(nx, ny, 1.0, 1.0, z).unwrap()
    }

    /// `snap_node` gives the values of the rule through `round`, bit for bit.
    #[test]
    fn snapping_matches_round() {
        let old = |t: f64| {
            if (t - t.round()).abs() < 1e-9 {
                t.round()
            } else {
                t
            }
        };
        let mut ts = vec![0.0, -0.0, 1e-10, -1e-10, 0.5, 1.5, 2.5, 0.49999999999999994];
        ts.extend([
            f64::NAN,
            f64::INFINITY,
            -3.2,
            4503599627370495.5,
            9.007199254740992e15,
        ]);
        for k in 0..200_000u64 {
            let base = (k % 5000) as f64;
            for off in [1e-9, 9.99e-10, 1.0000001e-9, 0.3, 0.5, 0.7] {
                ts.extend([base + off, base - off, base + 1.0 - off]);
            }
            ts.push(f64::from_bits(0x3ff0_0000_0000_0000 + k * 0x0123_4567_89ab));
        }
        for t in ts {
            assert_eq!(snap_node(t).to_bits(), old(t).to_bits(), "{t:e}");
        }
    }

    /// Two lines through one complex FFT give each line's power spectrum to rounding.
    #[test]
    fn lines_in_pairs_give_their_own_spectra() {
        let line = |f: f64, g: f64| -> Vec<f64> {
            (0..301)
                .map(|k| {
                    let x = k as f64;
                    if k % 37 == 5 {
                        f64::NAN
                    } else {
                        (x / f).sin() + 0.2 * (x / g).cos() + 1e-3 * (x * x / 7.0).sin()
                    }
                })
                .collect()
        };
        let (a, b, c) = (line(3.1, 17.0), line(5.3, 2.2), line(1.7, 40.0));
        let both = line_spectrum(&[a.clone(), b.clone(), c.clone()], 0.5);
        let one = |l: &Vec<f64>| line_spectrum(std::slice::from_ref(l), 0.5);
        let (pa, pb, pc) = (one(&a), one(&b), one(&c));
        let top = both.power.iter().cloned().fold(0.0, f64::max);
        for k in 0..both.power.len() {
            let mean = (pa.power[k] + pb.power[k] + pc.power[k]) / 3.0;
            assert!((both.power[k] - mean).abs() <= 1e-13 * top, "{k}");
        }
        assert_eq!(both.freq_per_um, pa.freq_per_um);
    }

    #[test]
    fn direction_of_stripes() {
        for deg in [0.0, 17.3, 45.0, 90.0, 121.7, 179.0] {
            let m = stripes(128, 96, deg, 13.0);
            let got = feed_direction_deg(&m).unwrap();
            let err = ((got - deg + 90.0).rem_euclid(180.0) - 90.0).abs();
            assert!(err < 0.1, "{deg}: {got}");
        }
    }

    #[test]
    fn shift_of_a_placed_map() {
        let a = stripes(64, 64, 30.0, 9.0);
        let b = stripes(64, 64, 100.0, 13.0);
        let mut n = a.clone();
        for (v, w) in n.z_um.iter_mut().zip(&b.z_um) {
            *v += w;
        }
        for (k, v) in n.z_um.iter_mut().enumerate() {
            *v += ((k * 7919 % 101) as f64 / 101.0) * 0.01;
        }
        let moved = place(
            &n,
            &n,
            &Placement {
                rotation_deg: 0.0,
                shift_um: [2.4, -1.3],
            },
        );
        let (s, _) = correlation_shift(&moved, &n).unwrap();
        assert!(
            (s[0] - 2.4).abs() < 0.5 && (s[1] + 1.3).abs() < 0.5,
            "{s:?}"
        );
        let (s0, c) = correlation_shift(&n, &n).unwrap();
        assert_eq!(s0, [0.0, 0.0]);
        assert!((c - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_shifted_offset_profile_aligns_back() {
        // A feed-mark-like profile (period 0.05 mm, asymmetric) on 2 µm steps; the
        // "measured" one is the same shifted by 0.01234 mm, raised 3 µm, sampled every
        // 1.5 µm with a little noise.
        let f = |x: f64| {
            let t = (x / 0.05).rem_euclid(1.0);
            4.0 * (t - 0.5).powi(2) + 0.3 * (2.0 * std::f64::consts::PI * x / 0.31).sin()
        };
        let px: Vec<f64> = (0..1000).map(|i| i as f64 * 0.002).collect();
        let pz: Vec<f64> = px.iter().map(|&x| f(x)).collect();
        let mx: Vec<f64> = (0..1300).map(|i| -0.2 + i as f64 * 0.0015).collect();
        let mz: Vec<f64> = mx
            .iter()
            .enumerate()
            .map(|(i, &x)| f(x + 0.01234) + 3.0 + 0.01 * ((i * 7919) % 13) as f64 / 13.0)
            .collect();
        let a = align_profile((&px, &pz), (&mx, &mz)).unwrap();
        assert!((a.shift_mm - 0.01234).abs() < 0.002, "{a:?}");
        assert!((a.offset_um + 3.0).abs() < 0.05, "{a:?}");
        assert!(a.correlation > 0.99, "{a:?}");
        // Flat or too short profiles do not align.
        assert!(align_profile((&px, &vec![1.0; 1000]), (&mx, &mz)).is_none());
        assert!(align_profile((&px[..2], &pz[..2]), (&mx, &mz)).is_none());
    }

    /// A map over `COARSE_NODES` goes through the block means and the climb at full
    /// resolution: a smooth bump field moved by a known fractional shift, with missing
    /// nodes, is found to a small fraction of a node, and its lay is found on block means.
    #[test]
    fn large_maps_are_registered_coarse_to_fine() {
        let n = 800;
        assert!(n * n > COARSE_NODES);
        let f = |x: f64, y: f64| {
            (x / 37.0).sin() * (y / 23.0).cos() + 0.5 * ((x + 2.0 * y) / 61.0).sin()
        };
        let (sx, sy) = (13.3, -7.6);
        let mut a = Vec::with_capacity(n * n);
        let mut b = Vec::with_capacity(n * n);
        for r in 0..n {
            for c in 0..n {
                let (x, y) = (c as f64, r as f64);
                // measured(n + t) = placed(n): measured is placed moved by (sx, sy).
                a.push(if (r * 7 + c * 13) % 97 == 0 {
                    f64::NAN
                } else {
                    f(x - sx, y - sy)
                });
                b.push(f(x, y));
            }
        }
        let meas = HeightMap::from_rows(n, n, 1.0, 1.0, a).unwrap();
        let placed = HeightMap::from_rows(n, n, 1.0, 1.0, b).unwrap();
        let (shift, peak) = correlation_shift(&meas, &placed).unwrap();
        assert!((shift[0] - sx).abs() < 0.2, "{shift:?}");
        assert!((shift[1] - sy).abs() < 0.2, "{shift:?}");
        assert!(peak > 0.9, "{peak}");
        let big = stripes(800, 800, 30.0, 40.0);
        let d = feed_direction_deg(&big).unwrap();
        assert!((d - 30.0).abs() < 0.1, "{d}");
    }

    /// The lags of one row of lags in one pass: each the single lag's sums, bit for bit.
    #[test]
    fn lagged_sums_of_a_row_are_each_lags() {
        let (nx, ny) = (37, 23);
        let field = |seed: usize| -> (Vec<f64>, Vec<f64>) {
            let z: Vec<f64> = (0..nx * ny)
                .map(|k| ((k * seed % 101) as f64 - 50.0) * 0.013)
                .collect();
            let v: Vec<f64> = (0..nx * ny)
                .map(|k| {
                    if (k + seed).is_multiple_of(7) {
                        0.0
                    } else {
                        1.0
                    }
                })
                .collect();
            let z = z.iter().zip(&v).map(|(z, v)| z * v).collect();
            (z, v)
        };
        let ((a, va), (b, vb)) = (field(31), field(57));
        let txs = [-40, -36, -5, -1, 0, 1, 2, 9, 36, 37];
        for ty in [-23, -22, -7, -1, 0, 1, 3, 22, 23] {
            let row = lagged_sums_row((&a, &va), (&b, &vb), (nx, ny), ty, &txs);
            for (&tx, got) in txs.iter().zip(row) {
                let one = lagged_sums((&a, &va), (&b, &vb), (nx, ny), (tx, ty));
                assert_eq!(got.map(f64::to_bits), one.map(f64::to_bits), "{tx} {ty}");
            }
        }
    }
}
