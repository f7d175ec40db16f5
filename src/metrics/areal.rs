//! Height (Sa … Sku) and hybrid (Sdq, Sdr) parameters: plain passes over the valid nodes.

use crate::surface::HeightMap;

/// Height statistics of the valid values, relative to their mean (µm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeightStats {
    /// Number of valid (finite) values.
    pub n: usize,
    /// Mean of the valid values (the reference plane), µm.
    pub mean: f64,
    /// Arithmetic mean height `mean|η|`.
    pub sa: f64,
    /// Root-mean-square height.
    pub sq: f64,
    /// Maximum peak height `max η`.
    pub sp: f64,
    /// Maximum pit depth `−min η` (positive).
    pub sv: f64,
    /// Skewness `mean η³ / Sq³` (`NaN` when Sq = 0).
    pub ssk: f64,
    /// Kurtosis `mean η⁴ / Sq⁴` (3 for a Gaussian; `NaN` when Sq = 0).
    pub sku: f64,
    /// Lowest valid value, µm (not relative to the mean).
    pub min: f64,
    /// Highest valid value, µm (not relative to the mean).
    pub max: f64,
}

impl HeightStats {
    /// Maximum height `Sp + Sv`.
    pub fn sz(&self) -> f64 {
        self.sp + self.sv
    }
}

/// Height statistics of the finite values of `z`; `None` when there are none.
///
/// Two passes: the mean, then the moments of `η = z − mean`. Sums are accumulated per
/// block of 4096 values to keep rounding small on large maps.
pub fn height_stats(z: &[f64]) -> Option<HeightStats> {
    const BLOCK: usize = 4096;
    let mut n = 0usize;
    let mut sum = 0.0;
    let mut complete = Vec::with_capacity(z.len() / BLOCK + 1);
    for chunk in z.chunks(BLOCK) {
        let (mut s, mut c) = (0.0, 0usize);
        for &v in chunk {
            if v.is_finite() {
                s += v;
                c += 1;
            }
        }
        complete.push(c == chunk.len());
        sum += s;
        n += c;
    }
    if n == 0 {
        return None;
    }
    let mean = sum / n as f64;
    let (mut s1, mut s2, mut s3, mut s4) = (0.0, 0.0, 0.0, 0.0);
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for (chunk, &full) in z.chunks(BLOCK).zip(&complete) {
        let (mut a1, mut a2, mut a3, mut a4) = (0.0, 0.0, 0.0, 0.0);
        if full {
            // No missing value: a branch-free loop the compiler can vectorise.
            for &v in chunk {
                let e = v - mean;
                let e2 = e * e;
                a1 += e.abs();
                a2 += e2;
                a3 += e2 * e;
                a4 += e2 * e2;
                lo = lo.min(v);
                hi = hi.max(v);
            }
        } else {
            for &v in chunk {
                if v.is_finite() {
                    let e = v - mean;
                    let e2 = e * e;
                    a1 += e.abs();
                    a2 += e2;
                    a3 += e2 * e;
                    a4 += e2 * e2;
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
        s1 += a1;
        s2 += a2;
        s3 += a3;
        s4 += a4;
    }
    let (min, max) = (lo, hi);
    let (lo, hi) = (lo - mean, hi - mean);
    let nf = n as f64;
    let sq = (s2 / nf).sqrt();
    let (ssk, sku) = if sq > 0.0 {
        (s3 / nf / (sq * sq * sq), s4 / nf / (sq * sq * sq * sq))
    } else {
        (f64::NAN, f64::NAN)
    };
    Some(HeightStats {
        n,
        mean,
        sa: s1 / nf,
        sq,
        sp: hi,
        sv: -lo,
        ssk,
        sku,
        min,
        max,
    })
}

/// Root-mean-square gradient Sdq (µm/µm): forward differences, each direction averaged over
/// its own count of valid pairs (surfalize's form). `NaN` when no pair is valid.
pub fn sdq(map: &HeightMap) -> f64 {
    let (nx, ny) = (map.nx, map.ny);
    let z = &map.z_um;
    let (mut sx, mut cx, mut sy, mut cy) = (0.0, 0usize, 0.0, 0usize);
    for r in 0..ny {
        let row = &z[r * nx..(r + 1) * nx];
        let mut acc = 0.0;
        for w in row.windows(2) {
            let d = w[1] - w[0];
            if d.is_finite() {
                acc += d * d;
                cx += 1;
            }
        }
        sx += acc;
        if r + 1 < ny {
            let next = &z[(r + 1) * nx..(r + 2) * nx];
            let mut acc = 0.0;
            for (a, b) in row.iter().zip(next) {
                let d = b - a;
                if d.is_finite() {
                    acc += d * d;
                    cy += 1;
                }
            }
            sy += acc;
        }
    }
    if cx == 0 && cy == 0 {
        return f64::NAN;
    }
    let mx = if cx > 0 {
        sx / cx as f64 / (map.dx_um * map.dx_um)
    } else {
        0.0
    };
    let my = if cy > 0 {
        sy / cy as f64 / (map.dy_um * map.dy_um)
    } else {
        0.0
    };
    (mx + my).sqrt()
}

/// `|u × v| − dx·dy` for a triangle spanning half a cell, from the two components `p`, `q`
/// of the cross product that vanish on a flat cell (the third is `dx·dy`). The absolute
/// rounding error is about 1e-16·dx·dy per cell, i.e. ~1e-14 % on Sdr, so the plain
/// difference is used (no division).
#[inline(always)]
fn excess(p2: f64, q2: f64, d2: f64, d: f64) -> f64 {
    (p2 + q2 + d2).sqrt() - d
}

/// Developed interfacial area ratio Sdr in %: every cell between four valid nodes is split
/// into two triangles both ways (ABC + ACD and ABD + BCD), the two areas averaged, and the
/// excess over the projected cell area summed; divided by the projected area of those
/// cells. `NaN` when no cell is complete.
pub fn sdr_percent(map: &HeightMap) -> f64 {
    let (nx, ny) = (map.nx, map.ny);
    if nx < 2 || ny < 2 {
        return f64::NAN;
    }
    let (dx, dy) = (map.dx_um, map.dy_um);
    let d = dx * dy;
    let d2 = d * d;
    let z = &map.z_um;
    let finite_row: Vec<bool> = z
        .chunks_exact(nx)
        .map(|r| r.iter().all(|v| v.is_finite()))
        .collect();
    let mut total = 0.0;
    let mut cells = 0usize;
    // With A = (r, j), B = (r, j+1), C = (r+1, j+1), D = (r+1, j) and the edge differences
    // ab = B − A, dc = C − D (along x), ad = D − A, bc = C − B (along y), the doubled
    // triangle areas are |(dy·ab, dx·bc, dxdy)| (ABC), |(dy·dc, dx·ad, dxdy)| (ACD),
    // |(dy·ab, dx·ad, dxdy)| (ABD) and |(dy·dc, dx·bc, dxdy)| (BCD).
    for r in 0..ny - 1 {
        let top = &z[r * nx..(r + 1) * nx];
        let bot = &z[(r + 1) * nx..(r + 2) * nx];
        let mut acc = 0.0;
        if finite_row[r] && finite_row[r + 1] {
            for j in 0..nx - 1 {
                let ab = dy * (top[j + 1] - top[j]);
                let dc = dy * (bot[j + 1] - bot[j]);
                let ad = dx * (bot[j] - top[j]);
                let bc = dx * (bot[j + 1] - top[j + 1]);
                let (ab2, dc2, ad2, bc2) = (ab * ab, dc * dc, ad * ad, bc * bc);
                acc += excess(ab2, bc2, d2, d)
                    + excess(dc2, ad2, d2, d)
                    + excess(ab2, ad2, d2, d)
                    + excess(dc2, bc2, d2, d);
            }
            cells += nx - 1;
        } else {
            for j in 0..nx - 1 {
                let ab = dy * (top[j + 1] - top[j]);
                let dc = dy * (bot[j + 1] - bot[j]);
                let ad = dx * (bot[j] - top[j]);
                let bc = dx * (bot[j + 1] - top[j + 1]);
                if !(ab.is_finite() && dc.is_finite() && ad.is_finite() && bc.is_finite()) {
                    continue;
                }
                let (ab2, dc2, ad2, bc2) = (ab * ab, dc * dc, ad * ad, bc * bc);
                acc += excess(ab2, bc2, d2, d)
                    + excess(dc2, ad2, d2, d)
                    + excess(ab2, ad2, d2, d)
                    + excess(dc2, bc2, d2, d);
                cells += 1;
            }
        }
        total += 0.25 * acc;
    }
    if cells == 0 {
        return f64::NAN;
    }
    total / (cells as f64 * d) * 100.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_skip_nan() {
        let s = height_stats(&[1.0, f64::NAN, 3.0]).unwrap();
        assert_eq!(s.n, 2);
        assert_eq!(s.mean, 2.0);
        assert_eq!(s.sa, 1.0);
        assert_eq!(s.sz(), 2.0);
        assert!(height_stats(&[f64::NAN]).is_none());
    }

    #[test]
    fn tilted_plane_sdr_and_sdq() {
        // z = 0.3 x + 0.4 y: slope 0.5, area factor sqrt(1.25).
        let (nx, ny, d) = (6, 5, 0.5);
        let z = (0..nx * ny)
            .map(|k| 0.3 * (k % nx) as f64 * d + 0.4 * (k / nx) as f64 * d)
            .collect();
        let m = HeightMap::from_rows(nx, ny, d, d, z).unwrap();
        assert!((sdq(&m) - 0.5).abs() < 1e-12);
        assert!((sdr_percent(&m) - (1.25f64.sqrt() - 1.0) * 100.0).abs() < 1e-10);
    }
}
