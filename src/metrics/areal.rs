//! Height (Sa … Sku) and hybrid (Sdq, Sdr) parameters: plain passes over the valid nodes of
//! `f64` or `f32` grids, on all threads, deterministic for any thread count.

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

/// A stored height: `f64` ([`HeightMap`]) or `f32` (a `.gsf` read as it is stored, half
/// the memory). Every computation widens to `f64` first, so an `f32` grid gives exactly the
/// values of the same heights held as `f64`.
pub trait Height: Copy + Send + Sync {
    /// The value as `f64` (exact).
    fn get(self) -> f64;
}

impl Height for f64 {
    #[inline(always)]
    fn get(self) -> f64 {
        self
    }
}

impl Height for f32 {
    #[inline(always)]
    fn get(self) -> f64 {
        f64::from(self)
    }
}

/// Values per block of the height sums. The blocks are fixed, their partial sums are added
/// in block order, so the result does not depend on the number of threads.
const BLOCK: usize = 4096;

/// Independent partial sums per block (heights) or row (Sdr cells): value `k` goes to lane
/// `k % LANES`, the lanes are added in order at the end (fixed, so deterministic; the
/// independent lanes let the compiler use vector instructions and hide add latency).
const LANES: usize = 8;

/// Height statistics of the finite values of `z`; `None` when there are none.
pub fn height_stats(z: &[f64]) -> Option<HeightStats> {
    height_stats_of(z)
}

/// [`height_stats`] of `f64` or `f32` heights (the same bits for the same values).
///
/// Two passes, each over fixed blocks of 4096 values on all threads: the mean, then the
/// moments of `η = z − mean`. Per-block sums keep the rounding small on large maps and are
/// reduced in block order (deterministic for any thread count).
// The lane loops index several accumulator arrays by lane (struct of arrays, which the
// compiler turns into vector code).
#[allow(clippy::needless_range_loop)]
pub fn height_stats_of<T: Height>(z: &[T]) -> Option<HeightStats> {
    use rayon::prelude::*;
    let sums: Vec<(f64, usize)> = z
        .par_chunks(BLOCK)
        .map(|chunk| {
            // Value k goes to lane k % LANES; the lanes are added in order (fixed, so the
            // result does not depend on the threads; independent lanes let the loop run as
            // vector code).
            let (mut s, mut c) = ([0.0f64; LANES], [0usize; LANES]);
            let mut it = chunk.chunks_exact(LANES);
            for g in &mut it {
                for l in 0..LANES {
                    let v = g[l].get();
                    let ok = v.is_finite();
                    s[l] += if ok { v } else { 0.0 };
                    c[l] += usize::from(ok);
                }
            }
            let (mut sum, mut n) = (0.0, 0usize);
            for &v in it.remainder() {
                let v = v.get();
                if v.is_finite() {
                    sum += v;
                    n += 1;
                }
            }
            for l in 0..LANES {
                sum += s[l];
                n += c[l];
            }
            (sum, n)
        })
        .collect();
    let mut n = 0usize;
    let mut sum = 0.0;
    for &(s, c) in &sums {
        sum += s;
        n += c;
    }
    if n == 0 {
        return None;
    }
    let mean = sum / n as f64;
    let moments: Vec<[f64; 6]> = z
        .par_chunks(BLOCK)
        .zip(sums.par_iter())
        .map(|(chunk, &(_, c))| {
            let (mut a1, mut a2, mut a3, mut a4) = (0.0, 0.0, 0.0, 0.0);
            let mut lo = f64::INFINITY;
            let mut hi = f64::NEG_INFINITY;
            let mut rest = chunk;
            if c == chunk.len() {
                // No missing value: branch-free lanes (as in the first pass).
                let mut m = [[0.0f64; LANES]; 4];
                let mut mn = [f64::INFINITY; LANES];
                let mut mx = [f64::NEG_INFINITY; LANES];
                let mut it = chunk.chunks_exact(LANES);
                for g in &mut it {
                    for l in 0..LANES {
                        let v = g[l].get();
                        let e = v - mean;
                        let e2 = e * e;
                        m[0][l] += e.abs();
                        m[1][l] += e2;
                        m[2][l] += e2 * e;
                        m[3][l] += e2 * e2;
                        mn[l] = mn[l].min(v);
                        mx[l] = mx[l].max(v);
                    }
                }
                for l in 0..LANES {
                    a1 += m[0][l];
                    a2 += m[1][l];
                    a3 += m[2][l];
                    a4 += m[3][l];
                    lo = lo.min(mn[l]);
                    hi = hi.max(mx[l]);
                }
                rest = it.remainder();
            }
            for &v in rest {
                let v = v.get();
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
            [a1, a2, a3, a4, lo, hi]
        })
        .collect();
    let (mut s1, mut s2, mut s3, mut s4) = (0.0, 0.0, 0.0, 0.0);
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for m in &moments {
        s1 += m[0];
        s2 += m[1];
        s3 += m[2];
        s4 += m[3];
        lo = lo.min(m[4]);
        hi = hi.max(m[5]);
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

/// A row-major grid of heights borrowed from a [`HeightMap`] or an `f32` field.
#[derive(Debug, Clone, Copy)]
pub struct Grid<'a, T> {
    /// Columns (x).
    pub nx: usize,
    /// Rows (y).
    pub ny: usize,
    /// Spacing along x, µm.
    pub dx_um: f64,
    /// Spacing along y, µm.
    pub dy_um: f64,
    /// `z[row * nx + col]`, µm.
    pub z: &'a [T],
}

impl<'a> Grid<'a, f64> {
    /// The grid of a height map.
    pub fn of(map: &'a HeightMap) -> Self {
        Grid {
            nx: map.nx,
            ny: map.ny,
            dx_um: map.dx_um,
            dy_um: map.dy_um,
            z: &map.z_um,
        }
    }
}

impl<T> Grid<'_, T> {
    fn row(&self, r: usize) -> &[T] {
        &self.z[r * self.nx..(r + 1) * self.nx]
    }
}

/// Root-mean-square gradient Sdq (µm/µm): forward differences, each direction averaged over
/// its own count of valid pairs (surfalize's form). `NaN` when no pair is valid.
pub fn sdq(map: &HeightMap) -> f64 {
    sdq_of(Grid::of(map))
}

/// [`sdq`] of any grid: rows on all threads, per-row sums reduced in row order.
pub fn sdq_of<T: Height>(g: Grid<'_, T>) -> f64 {
    use rayon::prelude::*;
    let ny = g.ny;
    let rows: Vec<(f64, usize, f64, usize)> = (0..ny)
        .into_par_iter()
        .with_min_len(16)
        .map(|r| {
            let row = g.row(r);
            let (mut sx, mut cx, mut sy, mut cy) = (0.0, 0usize, 0.0, 0usize);
            for w in row.windows(2) {
                let d = w[1].get() - w[0].get();
                if d.is_finite() {
                    sx += d * d;
                    cx += 1;
                }
            }
            if r + 1 < ny {
                for (a, b) in row.iter().zip(g.row(r + 1)) {
                    let d = b.get() - a.get();
                    if d.is_finite() {
                        sy += d * d;
                        cy += 1;
                    }
                }
            }
            (sx, cx, sy, cy)
        })
        .collect();
    let (mut sx, mut cx, mut sy, mut cy) = (0.0, 0usize, 0.0, 0usize);
    for &(a, b, c, d) in &rows {
        sx += a;
        cx += b;
        sy += c;
        cy += d;
    }
    if cx == 0 && cy == 0 {
        return f64::NAN;
    }
    let mx = if cx > 0 {
        sx / cx as f64 / (g.dx_um * g.dx_um)
    } else {
        0.0
    };
    let my = if cy > 0 {
        sy / cy as f64 / (g.dy_um * g.dy_um)
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
    sdr_percent_of(Grid::of(map))
}

/// [`sdr_percent`] of any grid, in one pass over the heights (no copy): row pairs on all
/// threads, per-row sums reduced in row order (deterministic for any thread count).
pub fn sdr_percent_of<T: Height>(g: Grid<'_, T>) -> f64 {
    use rayon::prelude::*;
    let (nx, ny) = (g.nx, g.ny);
    if nx < 2 || ny < 2 {
        return f64::NAN;
    }
    let (dx, dy) = (g.dx_um, g.dy_um);
    let d = dx * dy;
    let d2 = d * d;
    // With A = (r, j), B = (r, j+1), C = (r+1, j+1), D = (r+1, j) and the edge differences
    // ab = B − A, dc = C − D (along x), ad = D − A, bc = C − B (along y), the doubled
    // triangle areas are |(dy·ab, dx·bc, dxdy)| (ABC), |(dy·dc, dx·ad, dxdy)| (ACD),
    // |(dy·ab, dx·ad, dxdy)| (ABD) and |(dy·dc, dx·bc, dxdy)| (BCD).
    let cell = |top: &[T], bot: &[T], j: usize| -> f64 {
        let (a, b) = (top[j].get(), top[j + 1].get());
        let (dd, c) = (bot[j].get(), bot[j + 1].get());
        let ab = dy * (b - a);
        let dc = dy * (c - dd);
        let ad = dx * (dd - a);
        let bc = dx * (c - b);
        let (ab2, dc2, ad2, bc2) = (ab * ab, dc * dc, ad * ad, bc * bc);
        excess(ab2, bc2, d2, d)
            + excess(dc2, ad2, d2, d)
            + excess(ab2, ad2, d2, d)
            + excess(dc2, bc2, d2, d)
    };
    let rows: Vec<(f64, usize)> = (0..ny - 1)
        .into_par_iter()
        .with_min_len(8)
        .map(|r| {
            let (top, bot) = (g.row(r), g.row(r + 1));
            // Without a short cut (`all` stops at the first NaN, so it runs value by
            // value): one vector loop per row.
            let finite = |row: &[T]| row.iter().fold(true, |ok, v| ok & v.get().is_finite());
            if finite(top) && finite(bot) {
                let mut lanes = [0.0f64; LANES];
                let groups = (nx - 1) / LANES;
                for k in 0..groups {
                    let j0 = k * LANES;
                    for (l, acc) in lanes.iter_mut().enumerate() {
                        *acc += cell(top, bot, j0 + l);
                    }
                }
                let mut acc = 0.0;
                for j in groups * LANES..nx - 1 {
                    acc += cell(top, bot, j);
                }
                for l in lanes {
                    acc += l;
                }
                (acc, nx - 1)
            } else {
                let (mut acc, mut cells) = (0.0, 0usize);
                for j in 0..nx - 1 {
                    let e = cell(top, bot, j);
                    if e.is_finite() {
                        acc += e;
                        cells += 1;
                    }
                }
                (acc, cells)
            }
        })
        .collect();
    let mut total = 0.0;
    let mut cells = 0usize;
    for &(acc, c) in &rows {
        total += 0.25 * acc;
        cells += c;
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

    /// A rough test surface with a few missing nodes (`nan`) and odd sizes (remainders).
    fn rough(nx: usize, ny: usize, nan: bool) -> Vec<f32> {
        (0..nx * ny)
            .map(|k| {
                let (x, y) = ((k % nx) as f32, (k / nx) as f32);
                if nan && k % 997 == 13 {
                    f32::NAN
                } else {
                    (0.3 * x).sin() + 0.2 * (0.17 * y).cos() + 0.01 * ((k * 7919) % 101) as f32
                }
            })
            .collect()
    }

    #[test]
    fn f32_grid_gives_the_f64_values_for_any_thread_count() {
        for nan in [false, true] {
            let (nx, ny) = (203, 77);
            let z32 = rough(nx, ny, nan);
            let z64: Vec<f64> = z32.iter().map(|&v| f64::from(v)).collect();
            let map = HeightMap::from_rows(nx, ny, 0.5, 0.7, z64).unwrap();
            let g32 = Grid {
                nx,
                ny,
                dx_um: 0.5,
                dy_um: 0.7,
                z: &z32[..],
            };
            let all = || {
                (
                    height_stats_of(g32.z).unwrap(),
                    sdq_of(g32),
                    sdr_percent_of(g32),
                )
            };
            let (s, q, r) = all();
            assert_eq!(s, height_stats(&map.z_um).unwrap());
            assert_eq!(q.to_bits(), sdq(&map).to_bits());
            assert_eq!(r.to_bits(), sdr_percent(&map).to_bits());
            for threads in [1, 2, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let (s1, q1, r1) = pool.install(all);
                assert_eq!(s1, s);
                assert_eq!((q1.to_bits(), r1.to_bits()), (q.to_bits(), r.to_bits()));
            }
        }
    }
}
