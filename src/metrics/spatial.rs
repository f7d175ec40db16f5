//! Spatial parameters: Sal and Str from the autocorrelation function, Std and Ssw from the
//! amplitude spectrum.
//!
//! ACF: linear (zero-padded, non-circular) correlation through the FFT, each lag divided by
//! its number of valid overlapping pairs (the "unbiased" estimator surfalize 0.19.2 uses);
//! with missing nodes the pair counts come from the correlation of the validity mask.
//! Sal: the 4-connected region around zero lag where R > 0.2·R(0) is found, rays go from the
//! centre to each pixel of its outer boundary, R is interpolated bilinearly along each ray and
//! the first crossing of the threshold gives the decay length in that direction; Sal is the
//! shortest, Str = shortest / longest, and `NaN` when the region reaches the border of the lag
//! field (the ACF does not decay in some direction). The region and its rays read only lags
//! near it: the ACF is taken on a smaller padding where that padding's exact lags hold them
//! (guessed from the map's block means, checked, else the full padding).

use rustfft::FftDirection;
use rustfft::num_complex::Complex64;

use super::fft::{Fft2, padded_forward};
use crate::surface::HeightMap;

/// Decay lengths of the ACF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AcfLengths {
    /// Autocorrelation length Sal, µm (`NaN` when the ACF never decays to the threshold).
    pub sal: f64,
    /// Longest decay length found, µm (a lower bound when `decays_everywhere` is false).
    pub longest: f64,
    /// Texture aspect ratio Str (`NaN` when not `decays_everywhere`).
    pub str_ratio: f64,
    /// Whether the thresholded central region stays inside the lag field.
    pub decays_everywhere: bool,
}

/// The mean of the valid heights (0 without any), and whether any height was missing.
fn valid_mean(map: &HeightMap) -> (f64, bool) {
    let (mut sum, mut n) = (0.0, 0usize);
    for &v in &map.z_um {
        if v.is_finite() {
            sum += v;
            n += 1;
        }
    }
    let mean = if n > 0 { sum / n as f64 } else { 0.0 };
    (mean, n < map.z_um.len())
}

/// Mean-removed heights with missing nodes as 0, and whether any was missing.
#[cfg(test)]
fn centred(map: &HeightMap) -> (Vec<f64>, bool) {
    let (mean, missing) = valid_mean(map);
    let e = map
        .z_um
        .iter()
        .map(|&v| if v.is_finite() { v - mean } else { 0.0 })
        .collect();
    (e, missing)
}

/// Linear autocorrelation of a `ny × nx` field on the padded `py × px` lattice, unscaled
/// (the real parts times `1 / (px·py)` are the correlation sums).
///
/// One complex buffer of the padded lattice (16 bytes per lattice node), transformed in
/// place: rows then columns forward, columns then rows back (the order of the 1-D FFTs of
/// the former transposing form, so the same values bit for bit). The forward rows past the
/// field's are zero and stay so (their transforms are left out). The field is `value(k)`
/// at node k (real), written straight into the buffer.
fn linear_autocorr(
    value: impl Fn(usize) -> Complex64,
    nx: usize,
    ny: usize,
    px: usize,
    py: usize,
) -> Vec<Complex64> {
    let mut buf = padded_forward(nx, ny, px, py, value);
    for v in buf.iter_mut() {
        *v = Complex64::new(v.norm_sqr(), 0.0);
    }
    inverse_exact_rows(&mut buf, ny, px, py);
    buf
}

/// The inverse transform of a padded `py × px` spectrum, columns then rows; below the full
/// padding (`py < 2ny − 1`) only the rows of lags `|ty| ≤ py − ny` (those [`Lags::exact`]
/// lets be read: the others wrap) are transformed back along x, the rest are left as they
/// are.
fn inverse_exact_rows(buf: &mut [Complex64], ny: usize, px: usize, py: usize) {
    let mut inv = Fft2::new(py, px, FftDirection::Inverse);
    inv.columns(buf);
    if py >= 2 * ny - 1 {
        inv.rows(buf);
    } else {
        let w = py - ny;
        let (low, high) = buf.split_at_mut((w + 1) * px);
        inv.rows(low);
        inv.rows(&mut high[(py - w - (w + 1)) * px..]);
    }
}

/// [`linear_autocorr`] of two real fields at once: one complex field `a + i·b`, whose
/// spectrum gives both power spectra by its conjugate symmetry, and one inverse transform of
/// `|A|² + i·|B|²` (both even and real, so the real and imaginary parts of the result are
/// the two autocorrelations, unscaled). Half the transforms of two separate calls. The
/// fields are `value(k) = a[k] + i·b[k]` at node k.
fn linear_autocorr_pair(
    value: impl Fn(usize) -> Complex64,
    nx: usize,
    ny: usize,
    px: usize,
    py: usize,
) -> Vec<Complex64> {
    let mut buf = padded_forward(nx, ny, px, py, value);
    // A = (Z[k] + conj Z[−k]) / 2, B = (Z[k] − conj Z[−k]) / 2i: |A|² and |B|² at k and −k
    // (the same values), written in place pair by pair.
    for ky in 0..py {
        let my = (py - ky) % py;
        for kx in 0..px {
            let mx = (px - kx) % px;
            let (k, m) = (ky * px + kx, my * px + mx);
            if m < k {
                continue;
            }
            let (z, zm) = (buf[k], buf[m].conj());
            let pa = (z + zm).norm_sqr() / 4.0;
            let pb = (z - zm).norm_sqr() / 4.0;
            buf[k] = Complex64::new(pa, pb);
            buf[m] = Complex64::new(pa, pb);
        }
    }
    inverse_exact_rows(&mut buf, ny, px, py);
    buf
}

/// The normalised ACF in the padded lattice's own layout (lag (ty, tx) at row ty mod py and
/// column tx mod px), written over the transform's buffer (no second field).
struct Lags {
    r: Vec<f64>,
    px: usize,
    py: usize,
    nx: usize,
    ny: usize,
}

impl Lags {
    /// The value at node (i, j) of the centred lag field `(2ny−1) × (2nx−1)`, zero lag at
    /// `(ny−1, nx−1)`.
    fn at(&self, i: usize, j: usize) -> f64 {
        let ry = if i + 1 < self.ny {
            i + self.py + 1 - self.ny
        } else {
            i + 1 - self.ny
        };
        let rx = if j + 1 < self.nx {
            j + self.px + 1 - self.nx
        } else {
            j + 1 - self.nx
        };
        self.r[ry * self.px + rx]
    }

    /// The largest `|ty|` and `|tx|` that a node of the decay region may have for the region,
    /// its boundary and the rays to it (bilinear, one node further) to read only exact lags:
    /// every lag on the full padding, `p − n − 2` below it.
    fn exact(&self) -> (usize, usize) {
        let lim = |p: usize, n: usize| {
            if p >= 2 * n - 1 {
                n - 1
            } else {
                p.saturating_sub(n + 2)
            }
        };
        (lim(self.py, self.ny), lim(self.px, self.nx))
    }
}

/// The padding of the whole lag field: any padding to 2n − 1 or more gives the linear ACF;
/// lengths of factors 2, 3, 5 are fast.
fn full_padding(map: &HeightMap) -> (usize, usize) {
    use super::fft::fast_len;
    (fast_len(2 * map.nx), fast_len(2 * map.ny))
}

/// The normalised ACF of a map ([`Lags`]) on the padded `py × px` lattice (`py ≥ ny + 2`,
/// `px ≥ nx + 2`). A circular correlation of period `p` is the linear one at every lag
/// `|t| ≤ p − n`; below the full padding the lags beyond are wrong (wrapped), see
/// [`Lags::exact`].
fn lags(map: &HeightMap, (px, py): (usize, usize)) -> Lags {
    let (nx, ny) = (map.nx, map.ny);
    let (mean, missing) = valid_mean(map);
    let z = &map.z_um;
    let scale = 1.0 / (px * py) as f64;
    // The sums (real parts) and, with missing nodes, the counts of valid pairs (imaginary
    // parts), scaled as they are read. The mean-removed heights (missing as 0) and the
    // validity mask go straight into the transform's buffer (no field of either).
    let sums = if missing {
        let value = |k: usize| {
            let v = z[k];
            if v.is_finite() {
                Complex64::new(v - mean, 1.0)
            } else {
                Complex64::default()
            }
        };
        linear_autocorr_pair(value, nx, ny, px, py)
    } else {
        linear_autocorr(|k| Complex64::new(z[k] - mean, 0.0), nx, ny, px, py)
    };
    // Collected in place (the same allocation); lags beyond ±(n − 1) have no pair.
    let r = sums
        .into_iter()
        .enumerate()
        .map(|(k, v)| {
            let cnt = if missing {
                round_count(v.im * scale)
            } else {
                let (ry, rx) = (k / px, k % px);
                let ay = if ry < ny { ry } else { py - ry };
                let ax = if rx < nx { rx } else { px - rx };
                if ay < ny && ax < nx {
                    ((ny - ay) * (nx - ax)) as f64
                } else {
                    0.0
                }
            };
            if cnt >= 1.0 {
                v.re * scale / cnt
            } else {
                f64::NAN
            }
        })
        .collect();
    Lags { r, px, py, nx, ny }
}

/// The normalised ACF on the centred lag field `(2ny−1) × (2nx−1)`, zero lag at
/// `(ny−1, nx−1)`.
#[cfg(test)]
pub(crate) fn acf(map: &HeightMap) -> Vec<f64> {
    let l = lags(map, full_padding(map));
    let (wy, wx) = (2 * map.ny - 1, 2 * map.nx - 1);
    (0..wy)
        .flat_map(|i| (0..wx).map(move |j| (i, j)))
        .map(|(i, j)| l.at(i, j))
        .collect()
}

/// `c.round()` where it is at least 1, else 0 (or `NaN`): a count of valid pairs. From the
/// truncation for 0.5 ≤ c < 2⁵² (its remainder is exact, ties away from zero like `round`)
/// without `round`'s call into libm; `round` beyond.
fn round_count(c: f64) -> f64 {
    const EXACT: f64 = (1u64 << 52) as f64;
    if c < 0.5 {
        0.0
    } else if c < EXACT {
        let f = c as u64 as f64;
        if c - f >= 0.5 { f + 1.0 } else { f }
    } else {
        c.round()
    }
}

/// The 4-connected region around zero lag where R > `thr`, on the centred lag field.
struct Region {
    /// Membership, `(2ny−1) × (2nx−1)` row-major.
    inside: Vec<bool>,
    /// The first and last row of the field holding a node of the region.
    rows: (usize, usize),
    /// Whether the region reaches the border of the field.
    touches: bool,
}

/// The decay region of `r` (flood fill from zero lag), or `None` when it holds a node
/// beyond `r`'s exact lags ([`Lags::exact`]): then the region and its rays need a larger
/// padding.
fn decay_region(r: &Lags, thr: f64) -> Option<Region> {
    let (wy, wx) = (2 * r.ny - 1, 2 * r.nx - 1);
    let (cy, cx) = (r.ny - 1, r.nx - 1);
    let (ly, lx) = r.exact();
    let mut inside = vec![false; wy * wx];
    let mut stack = vec![(cy, cx)];
    inside[cy * wx + cx] = true;
    let (mut top, mut bottom) = (cy, cy);
    let mut touches = false;
    while let Some((i, j)) = stack.pop() {
        if i.abs_diff(cy) > ly || j.abs_diff(cx) > lx {
            return None;
        }
        top = top.min(i);
        bottom = bottom.max(i);
        if i == 0 || j == 0 || i == wy - 1 || j == wx - 1 {
            touches = true;
        }
        let mut visit = |a: usize, b: usize| {
            let k = a * wx + b;
            if !inside[k] && r.at(a, b) > thr {
                inside[k] = true;
                stack.push((a, b));
            }
        };
        if i > 0 {
            visit(i - 1, j);
        }
        if i + 1 < wy {
            visit(i + 1, j);
        }
        if j > 0 {
            visit(i, j - 1);
        }
        if j + 1 < wx {
            visit(i, j + 1);
        }
    }
    Some(Region {
        inside,
        rows: (top, bottom),
        touches,
    })
}

/// Nodes averaged along each side of a block for [`padding_guess`].
const COARSE: usize = 8;

/// A padding for the ACF of a map of at least `32·COARSE` nodes a side that probably holds
/// its decay region at threshold `s` exactly, from the region of the ACF of the map's
/// `COARSE × COARSE` block means (a cheap guess, checked by [`decay_region`]); `None` when
/// the guess is the full padding or there is none.
fn padding_guess(map: &HeightMap, s: f64) -> Option<(usize, usize)> {
    use super::fft::fast_len;
    let (nx, ny) = (map.nx, map.ny);
    if nx.min(ny) < 32 * COARSE {
        return None;
    }
    let (bx, by) = (nx / COARSE, ny / COARSE);
    let mut sums = vec![(0.0, 0usize); bx * by];
    for (y, row) in map.z_um.chunks_exact(nx).take(by * COARSE).enumerate() {
        let blocks = &mut sums[(y / COARSE) * bx..][..bx];
        for (b, cells) in blocks.iter_mut().zip(row.chunks_exact(COARSE)) {
            for &v in cells {
                if v.is_finite() {
                    b.0 += v;
                    b.1 += 1;
                }
            }
        }
    }
    let z = sums
        .into_iter()
        .map(|(sum, n)| if n > 0 { sum / n as f64 } else { f64::NAN })
        .collect();
    let d = COARSE as f64;
    let coarse = HeightMap::from_rows(bx, by, map.dx_um * d, map.dy_um * d, z)?;
    let r = lags(&coarse, full_padding(&coarse));
    let r0 = r.at(by - 1, bx - 1);
    if r0.is_nan() || r0 <= 0.0 {
        return None;
    }
    let region = decay_region(&r, s * r0)?;
    let (mut ey, mut ex) = (0, 0);
    for (k, _) in region.inside.iter().enumerate().filter(|(_, v)| **v) {
        let (i, j) = (k / (2 * bx - 1), k % (2 * bx - 1));
        ey = ey.max(i.abs_diff(by - 1));
        ex = ex.max(j.abs_diff(bx - 1));
    }
    // Three blocks beyond the coarse region, then the margin of `Lags::exact`.
    let pad = |n: usize, e: usize| {
        let p = fast_len(n + (e + 3) * COARSE + 2);
        if p >= 2 * n - 1 { fast_len(2 * n) } else { p }
    };
    let guess = (pad(nx, ex), pad(ny, ey));
    (guess != full_padding(map)).then_some(guess)
}

/// Sal, Str (threshold `s`, normally 0.2) of a height map.
///
/// The ACF is first taken on the padding of [`padding_guess`], whose exact lags (those of
/// the linear ACF) usually hold the decay region and the rays to it; where they do not,
/// on the full padding. The lengths are those of the full lag field either way, up to the
/// rounding of the transforms' lengths.
pub fn acf_lengths(map: &HeightMap, s: f64) -> AcfLengths {
    acf_lengths_from(map, s, padding_guess(map, s))
}

/// [`acf_lengths`] with the ACF first taken on the padding `first` (the full padding where
/// its exact lags do not hold the decay region, or without one).
fn acf_lengths_from(map: &HeightMap, s: f64, first: Option<(usize, usize)>) -> AcfLengths {
    let undefined = AcfLengths {
        sal: f64::NAN,
        longest: f64::NAN,
        str_ratio: f64::NAN,
        decays_everywhere: false,
    };
    if map.nx < 2 || map.ny < 2 {
        return undefined;
    }
    let (wy, wx) = (2 * map.ny - 1, 2 * map.nx - 1);
    let (cy, cx) = (map.ny - 1, map.nx - 1);
    let with_padding = |p: (usize, usize)| -> Option<(Lags, f64, Option<Region>)> {
        let r = lags(map, p);
        let r0 = r.at(cy, cx);
        if r0.is_nan() || r0 <= 0.0 {
            return None;
        }
        let region = decay_region(&r, s * r0);
        Some((r, r0, region))
    };
    let found = match first.map(with_padding) {
        Some(Some((r, r0, Some(region)))) => Some((r, r0, region)),
        _ => with_padding(full_padding(map))
            .map(|(r, r0, region)| (r, r0, region.expect("the full padding has every lag"))),
    };
    let Some((r, r0, region)) = found else {
        return undefined;
    };
    let thr = s * r0;
    let (touches, inside) = (region.touches, &region.inside);
    // y, x ≥ 0 (on the rays from the centre to nodes of the field): truncation is the floor.
    let at = |y: f64, x: f64| -> f64 {
        let (i, j) = (y as usize, x as usize);
        let (y0, x0) = (i as f64, j as f64);
        let (fy, fx) = (y - y0, x - x0);
        let i1 = (i + 1).min(wy - 1);
        let j1 = (j + 1).min(wx - 1);
        let v00 = r.at(i, j);
        let v01 = r.at(i, j1);
        let v10 = r.at(i1, j);
        let v11 = r.at(i1, j1);
        (1.0 - fy) * ((1.0 - fx) * v00 + fx * v01) + fy * ((1.0 - fx) * v10 + fx * v11)
    };
    // The rays of each row of the lag field in parallel: the shortest and longest are the
    // same in any order.
    use rayon::prelude::*;
    let row_rays = |i: usize| -> (f64, f64) {
        let (mut shortest, mut longest) = (f64::INFINITY, f64::NEG_INFINITY);
        for j in 0..wx {
            if inside[i * wx + j] {
                continue;
            }
            let adjacent = (i > 0 && inside[(i - 1) * wx + j])
                || (i + 1 < wy && inside[(i + 1) * wx + j])
                || (j > 0 && inside[i * wx + j - 1])
                || (j + 1 < wx && inside[i * wx + j + 1]);
            if !adjacent {
                continue;
            }
            let (vy, vx) = (i as f64 - cy as f64, j as f64 - cx as f64);
            let dist = ((vy * map.dy_um).powi(2) + (vx * map.dx_um).powi(2)).sqrt();
            // One sample per pixel step along the ray; the crossing is interpolated linearly.
            let steps = vy.abs().max(vx.abs()).ceil().max(1.0) as usize;
            let mut prev = r0;
            let mut found = 1.0;
            for k in 1..=steps {
                let t = k as f64 / steps as f64;
                let v = at(cy as f64 + t * vy, cx as f64 + t * vx);
                if v.is_nan() || v <= thr {
                    let t_prev = (k - 1) as f64 / steps as f64;
                    let f = if v.is_finite() && prev > v {
                        (prev - thr) / (prev - v)
                    } else {
                        1.0
                    };
                    found = t_prev + f / steps as f64;
                    break;
                }
                prev = v;
            }
            let len = found * dist;
            shortest = shortest.min(len);
            longest = longest.max(len);
        }
        (shortest, longest)
    };
    // The boundary nodes lie in the region's rows and the rows next to them.
    let rows = region.rows.0.saturating_sub(1)..(region.rows.1 + 2).min(wy);
    let (shortest, longest) = rows.into_par_iter().map(row_rays).reduce(
        || (f64::INFINITY, f64::NEG_INFINITY),
        |a, b| (a.0.min(b.0), a.1.max(b.1)),
    );
    if !shortest.is_finite() {
        return undefined;
    }
    AcfLengths {
        sal: shortest,
        longest,
        str_ratio: if touches {
            f64::NAN
        } else {
            shortest / longest
        },
        decays_everywhere: !touches,
    }
}

/// Texture direction and dominant wavelength from the amplitude spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spectrum {
    /// Std, degrees in [0, 180): lower edge of the 0.5° bin with the largest summed amplitude
    /// of the frequency vectors, counter-clockwise from +x with y = row·dy (the map's frame).
    pub std_deg: f64,
    /// Ssw, µm: wavelength of the largest Fourier amplitude.
    pub ssw: f64,
}

/// Std and Ssw of the mean-removed map (missing nodes set to the mean, no window).
pub fn spectrum_direction(map: &HeightMap) -> Spectrum {
    let (nx, ny) = (map.nx, map.ny);
    let (mean, _) = valid_mean(map);
    let mut buf: Vec<Complex64> = map
        .z_um
        .iter()
        .map(|&v| Complex64::new(if v.is_finite() { v - mean } else { 0.0 }, 0.0))
        .collect();
    let mut fwd = Fft2::new(ny, nx, FftDirection::Forward);
    fwd.rows(&mut buf);
    fwd.columns(&mut buf);
    let freq = |k: usize, n: usize, d: f64| {
        let s = if k < n.div_ceil(2) {
            k as f64
        } else {
            k as f64 - n as f64
        };
        s / (n as f64 * d)
    };
    const STEP: f64 = 0.5;
    let nb = (180.0 / STEP) as usize;
    let mut bins = vec![0.0; nb];
    let (mut best, mut best_f) = (-1.0, 0.0);
    for i in 0..ny {
        let fy = freq(i, ny, map.dy_um);
        for j in 0..nx {
            let fx = freq(j, nx, map.dx_um);
            let a = buf[i * nx + j].norm();
            let theta = fy.atan2(fx).to_degrees().rem_euclid(180.0);
            let b = ((theta / STEP) as usize).min(nb - 1);
            bins[b] += a;
            if a > best {
                best = a;
                best_f = fx.hypot(fy);
            }
        }
    }
    let mut ib = 0;
    for (k, &v) in bins.iter().enumerate() {
        if v > bins[ib] {
            ib = k;
        }
    }
    Spectrum {
        std_deg: ib as f64 * STEP,
        ssw: if best_f > 0.0 {
            1.0 / best_f
        } else {
            f64::INFINITY
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn acf_of_white_pair_is_exact() {
        // Two columns: z = [1, -1] in every row → R(0) = 1, R(tx=±1) = -1.
        let m =
            HeightMap::from_rows(2, 3, 1.0, 1.0, vec![1.0, -1.0, 1.0, -1.0, 1.0, -1.0]).unwrap();
        let r = acf(&m);
        let wx = 3;
        assert!((r[2 * wx + 1] - 1.0).abs() < 1e-12);
        assert!((r[2 * wx + 2] + 1.0).abs() < 1e-12);
        assert!((r[2 * wx] + 1.0).abs() < 1e-12);
    }

    /// `round_count` is `round` wherever the count is used (at least 1), bit for bit.
    #[test]
    fn counts_round_like_round() {
        let old = |c: f64| {
            let r = c.round();
            if r >= 1.0 { r } else { f64::NAN }
        };
        let new = |c: f64| {
            let r = round_count(c);
            if r >= 1.0 { r } else { f64::NAN }
        };
        let mut cs = vec![
            f64::NAN,
            -0.0,
            0.0,
            0.4999999999999999,
            0.5,
            1.5,
            2.5,
            1e300,
        ];
        for k in 0..100_000u64 {
            let base = (k % 3000) as f64;
            for off in [-0.5, 0.5, -1e-9, 1e-9, 0.49999999999, -0.4999999, 0.0] {
                cs.push(base + off);
            }
            cs.push(f64::from_bits(0x4000_0000_0000_0000 + k * 0x3123_4567_89ab));
        }
        for c in cs {
            assert_eq!(new(c).to_bits(), old(c).to_bits(), "{c:e}");
        }
    }

    /// The lag field against the sums over valid pairs taken directly, with and without
    /// missing nodes, on a field of unequal sides (lags at every offset of both signs).
    #[test]
    fn acf_is_the_mean_over_valid_pairs() {
        let (nx, ny) = (7, 5);
        for holes in [false, true] {
            let z: Vec<f64> = (0..nx * ny)
                .map(|k| {
                    if holes && k % 6 == 4 {
                        f64::NAN
                    } else {
                        ((k * 37 % 11) as f64 - 5.0) * 0.3
                    }
                })
                .collect();
            let m = HeightMap::from_rows(nx, ny, 1.0, 1.0, z.clone()).unwrap();
            let (e, _) = centred(&m);
            let r = acf(&m);
            let (wy, wx) = (2 * ny - 1, 2 * nx - 1);
            for i in 0..wy {
                for j in 0..wx {
                    let (ty, tx) = (i as isize - ny as isize + 1, j as isize - nx as isize + 1);
                    let (mut sum, mut n) = (0.0, 0usize);
                    for y in 0..ny as isize {
                        for x in 0..nx as isize {
                            let (y2, x2) = (y + ty, x + tx);
                            if y2 < 0 || x2 < 0 || y2 >= ny as isize || x2 >= nx as isize {
                                continue;
                            }
                            let (a, b) = (
                                (y * nx as isize + x) as usize,
                                (y2 * nx as isize + x2) as usize,
                            );
                            if z[a].is_finite() && z[b].is_finite() {
                                sum += e[a] * e[b];
                                n += 1;
                            }
                        }
                    }
                    let got = r[i * wx + j];
                    if n == 0 {
                        assert!(got.is_nan(), "{holes} {ty},{tx}: {got}");
                    } else {
                        assert!((got - sum / n as f64).abs() < 1e-12, "{holes} {ty},{tx}");
                    }
                }
            }
        }
    }

    #[test]
    fn acf_with_missing_nodes_uses_valid_pairs() {
        let mut z: Vec<f64> = (0..64)
            .map(|k| ((k * 37 % 11) as f64 - 5.0) * 0.3)
            .collect();
        let full = HeightMap::from_rows(8, 8, 1.0, 1.0, z.clone()).unwrap();
        let r_full = acf(&full);
        z[9] = f64::NAN;
        let part = HeightMap::from_rows(8, 8, 1.0, 1.0, z).unwrap();
        let r_part = acf(&part);
        // Zero lag: mean of squares over valid nodes (the mean changes slightly).
        let c = 7 * 15 + 7;
        assert!(r_part[c].is_finite() && r_full[c] > 0.0);
    }

    /// A lay tilted by 4° (the region runs out of the field along it) and box-smoothed
    /// noise (it decays everywhere), each whole and with missing nodes: `acf_lengths` on the
    /// guessed padding gives the full padding's lengths up to rounding, and a padding too
    /// small for the region falls back to the full one (the same bits).
    #[test]
    fn smaller_padding_gives_the_full_lengths() {
        let (nx, ny) = (300, 264);
        let noise = |k: usize| {
            // splitmix64
            let mut h = (k as u64)
                .wrapping_add(1)
                .wrapping_mul(0x9E37_79B9_7F4A_7C15);
            h = (h ^ (h >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            h = (h ^ (h >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            h ^= h >> 31;
            ((h >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let lay: Vec<f64> = (0..nx * ny)
            .map(|k| {
                let (x, y) = ((k % nx) as f64, (k / nx) as f64);
                let (s, c) = 4f64.to_radians().sin_cos();
                (std::f64::consts::TAU * (y * c - x * s) / 40.0).sin() + 0.2 * noise(k)
            })
            .collect();
        let smooth: Vec<f64> = (0..nx * ny)
            .map(|k| {
                let (x, y) = (k % nx, k / nx);
                let mut sum = 0.0;
                for dy in 0..9 {
                    for dx in 0..9 {
                        sum += noise((y + dy) * (nx + 9) + x + dx);
                    }
                }
                sum
            })
            .collect();
        for (name, z, decays) in [("lay", lay, false), ("smooth", smooth, true)] {
            for holes in [false, true] {
                let mut z = z.clone();
                if holes {
                    for k in (0..z.len()).step_by(47) {
                        z[k] = f64::NAN;
                    }
                }
                let m = HeightMap::from_rows(nx, ny, 1.0, 1.5, z).unwrap();
                let guess = padding_guess(&m, 0.2).expect("a padding below the full one");
                assert!(guess.0 * guess.1 < full_padding(&m).0 * full_padding(&m).1);
                let r = lags(&m, guess);
                let r0 = r.at(ny - 1, nx - 1);
                assert!(
                    decay_region(&r, 0.2 * r0).is_some(),
                    "{name} {holes}: {guess:?}"
                );
                let full = acf_lengths_from(&m, 0.2, None);
                let got = acf_lengths(&m, 0.2);
                assert_eq!(got.decays_everywhere, decays, "{name} {holes}");
                assert_eq!(full.decays_everywhere, decays, "{name} {holes}");
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
                assert!(close(got.sal, full.sal), "{name} {holes}: {got:?} {full:?}");
                assert!(close(got.longest, full.longest), "{name} {holes}");
                assert_eq!(got.str_ratio.is_nan(), !decays, "{name} {holes}");
                if decays {
                    assert!(close(got.str_ratio, full.str_ratio), "{name} {holes}");
                }
                let small = acf_lengths_from(&m, 0.2, Some((nx + 4, ny + 4)));
                assert_eq!(small.sal.to_bits(), full.sal.to_bits(), "{name} {holes}");
                assert_eq!(small.longest.to_bits(), full.longest.to_bits());
                assert_eq!(small.str_ratio.to_bits(), full.str_ratio.to_bits());
            }
        }
    }
}
