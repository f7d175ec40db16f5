//! Height (Sa … Sku) and hybrid (Sdq, Sdr) parameters: plain passes over the valid nodes of
//! `f64` or `f32` grids, on all threads, deterministic for any thread count.

use crate::math::wide;
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
    /// The values as `f32` when they are (for the kernels written for `f32` lanes).
    fn as_f32s(z: &[Self]) -> Option<&[f32]>;
}

impl Height for f64 {
    #[inline(always)]
    fn get(self) -> f64 {
        self
    }
    #[inline(always)]
    fn as_f32s(_: &[f64]) -> Option<&[f32]> {
        None
    }
}

impl Height for f32 {
    #[inline(always)]
    fn get(self) -> f64 {
        f64::from(self)
    }
    #[inline(always)]
    fn as_f32s(z: &[f32]) -> Option<&[f32]> {
        Some(z)
    }
}

/// The smaller of `a` and `b`, `b` when they compare equal (`±0`): what `vminps`/`vminpd`
/// return for finite values, so that the scalar and the vector kernels agree to the sign of
/// zero (`f64::min` leaves it open).
#[inline(always)]
fn lower(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// The larger of `a` and `b`, `b` when they compare equal (as `vmaxps`/`vmaxpd`).
#[inline(always)]
fn higher(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

/// Values per block of the height sums. The blocks are fixed, their partial sums are added
/// in block order, so the result does not depend on the number of threads.
pub(crate) const BLOCK: usize = 4096;

/// Independent partial sums per block (heights) or row (Sdr cells): value `k` goes to lane
/// `k % LANES`, the lanes are added in order at the end (fixed, so deterministic; the
/// independent lanes let the compiler use vector instructions and hide add latency).
const LANES: usize = 8;

/// Height statistics of the finite values of `z`; `None` when there are none.
pub fn height_stats(z: &[f64]) -> Option<HeightStats> {
    height_stats_of(z)
}

/// Pass 1 of the height statistics on one block: the sum and the count of its finite
/// values. Value k goes to lane k % LANES; the lanes are added in order (fixed, so the
/// result does not depend on the threads; independent lanes let the loop run as vector
/// code).
// The lane loops index several accumulator arrays by lane (struct of arrays, which the
// compiler turns into vector code).
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn block_sum<T: Height>(chunk: &[T]) -> (f64, usize) {
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
}

/// Pass 2 of the height statistics on one block that holds `c` finite values: the sums of
/// `|η|, η², η³, η⁴` (`η = z − mean`), the lowest and the highest value.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn block_moments<T: Height>(chunk: &[T], c: usize, mean: f64) -> [f64; 6] {
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
                mn[l] = lower(v, mn[l]);
                mx[l] = higher(v, mx[l]);
            }
        }
        for l in 0..LANES {
            a1 += m[0][l];
            a2 += m[1][l];
            a3 += m[2][l];
            a4 += m[3][l];
            lo = lower(mn[l], lo);
            hi = higher(mx[l], hi);
        }
        rest = it.remainder();
    }
    let mut out = [a1, a2, a3, a4, lo, hi];
    for &v in rest {
        let v = v.get();
        if v.is_finite() {
            add_moments(&mut out, v, mean);
        }
    }
    out
}

/// One value added to the moment sums about `mean` and the extremes `[Σ|e|, Σe², Σe³, Σe⁴,
/// min, max]`, one after the other (the scalar tail of the block kernels).
#[inline(always)]
fn add_moments(m: &mut [f64; 6], v: f64, mean: f64) {
    let e = v - mean;
    let e2 = e * e;
    m[0] += e.abs();
    m[1] += e2;
    m[2] += e2 * e;
    m[3] += e2 * e2;
    m[4] = lower(v, m[4]);
    m[5] = higher(v, m[5]);
}

/// [`block_sum`] of every block of `z` (blocks of [`BLOCK`] values from its start).
struct BlockSums<'a, T>(&'a [T]);

impl<T: Height> wide::Kernel for BlockSums<'_, T> {
    type Output = Vec<(f64, usize)>;
    #[inline(always)]
    fn call(self) -> Self::Output {
        // A plain loop, not an iterator chain: the chain's `fold` would be a function of its
        // own, compiled without the vector instructions of this copy.
        let mut out = Vec::with_capacity(self.0.len().div_ceil(BLOCK));
        for chunk in self.0.chunks(BLOCK) {
            out.push(block_sum(chunk));
        }
        out
    }
}

/// [`block_moments`] of every block of `z`, with the counts of pass 1.
struct BlockMoments<'a, T>(&'a [T], &'a [usize], f64);

impl<T: Height> wide::Kernel for BlockMoments<'_, T> {
    type Output = Vec<[f64; 6]>;
    #[inline(always)]
    fn call(self) -> Self::Output {
        let BlockMoments(z, counts, mean) = self;
        let mut out = Vec::with_capacity(counts.len());
        for (k, chunk) in z.chunks(BLOCK).enumerate() {
            out.push(block_moments(chunk, counts[k], mean));
        }
        out
    }
}

/// [`block_sum`] of `f32` values with explicit AVX2 vectors: the same lanes (value `k` in
/// lane `k % 8`, the selected value widened exactly and added as `f64`), the same bits.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn block_sum_v3(simd: wide::V3, chunk: &[f32]) -> (f64, usize) {
    use pulp::{Simd, f32x4, f32x8, u32x8};
    let inf = simd.splat_f32x8(f32::INFINITY);
    let zero = simd.splat_f32x8(0.0);
    let mut s = [simd.splat_f64x4(0.0); 2];
    let mut c = simd.splat_u32x8(0);
    let mut it = chunk.chunks_exact(LANES);
    for g in &mut it {
        let v: f32x8 = pulp::cast(<[f32; LANES]>::try_from(g).unwrap_or_default());
        // |v| < ∞: false for ±∞ and NaN (an all-ones lane when finite).
        let ok = simd.less_than_f32s(simd.abs_f32s(v), inf);
        let [lo, hi]: [f32x4; 2] = pulp::cast(simd.select_f32x8(ok, v, zero));
        s[0] = simd.add_f64s(s[0], simd.convert_f32x4_to_f64x4(lo));
        s[1] = simd.add_f64s(s[1], simd.convert_f32x4_to_f64x4(hi));
        c = simd.sub_u32s(c, pulp::cast::<_, u32x8>(ok));
    }
    let (mut sum, mut n) = (0.0, 0usize);
    for &v in it.remainder() {
        let v = f64::from(v);
        if v.is_finite() {
            sum += v;
            n += 1;
        }
    }
    let s: [f64; LANES] = pulp::cast(s);
    let c: [u32; LANES] = pulp::cast(c);
    for l in 0..LANES {
        sum += s[l];
        n += c[l] as usize;
    }
    (sum, n)
}

/// [`block_moments`] of `f32` values with explicit AVX2 vectors (a block without missing
/// values; others go to the scalar code): the same lanes and operations, the same bits. The
/// extremes are taken in `f32` (exact; [`lower`] and [`higher`] pick as `vminps`, `vmaxps`).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn block_moments_v3(simd: wide::V3, chunk: &[f32], c: usize, mean: f64) -> [f64; 6] {
    use pulp::{Simd, f32x4, f32x8};
    if c != chunk.len() {
        return block_moments(chunk, c, mean);
    }
    let m0 = simd.splat_f64x4(mean);
    let mut m = [[simd.splat_f64x4(0.0); 2]; 4];
    let mut mn = simd.splat_f32x8(f32::INFINITY);
    let mut mx = simd.splat_f32x8(f32::NEG_INFINITY);
    let mut it = chunk.chunks_exact(LANES);
    for g in &mut it {
        let v: f32x8 = pulp::cast(<[f32; LANES]>::try_from(g).unwrap_or_default());
        mn = simd.min_f32s(v, mn);
        mx = simd.max_f32s(v, mx);
        let halves: [f32x4; 2] = pulp::cast(v);
        for (h, &v) in halves.iter().enumerate() {
            let e = simd.sub_f64s(simd.convert_f32x4_to_f64x4(v), m0);
            let e2 = simd.mul_f64s(e, e);
            m[0][h] = simd.add_f64s(m[0][h], simd.abs_f64s(e));
            m[1][h] = simd.add_f64s(m[1][h], e2);
            m[2][h] = simd.add_f64s(m[2][h], simd.mul_f64s(e2, e));
            m[3][h] = simd.add_f64s(m[3][h], simd.mul_f64s(e2, e2));
        }
    }
    let mut a = [0.0f64; 4];
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mn: [f32; LANES] = pulp::cast(mn);
    let mx: [f32; LANES] = pulp::cast(mx);
    for l in 0..LANES {
        for (k, a) in a.iter_mut().enumerate() {
            let lanes: [f64; LANES] = pulp::cast(m[k]);
            *a += lanes[l];
        }
        lo = lower(f64::from(mn[l]), lo);
        hi = higher(f64::from(mx[l]), hi);
    }
    let mut out = [a[0], a[1], a[2], a[3], lo, hi];
    for &v in it.remainder() {
        add_moments(&mut out, f64::from(v), mean);
    }
    out
}

/// Blocks per rayon task of the height passes (fixed; results do not depend on it).
const TASK_BLOCKS: usize = 16;

/// [`block_sum`] of every block of `task`, with explicit AVX2 vectors for `f32` values when
/// `isa` allows.
fn task_sums<T: Height>(isa: wide::Isa, task: &[T]) -> Vec<(f64, usize)> {
    #[cfg(target_arch = "x86_64")]
    if let (Some(simd), Some(z)) = (wide::v3(isa), T::as_f32s(task)) {
        return simd.vectorize(
            #[inline(always)]
            || {
                let mut out = Vec::with_capacity(z.len().div_ceil(BLOCK));
                for chunk in z.chunks(BLOCK) {
                    out.push(block_sum_v3(simd, chunk));
                }
                out
            },
        );
    }
    wide::run_on(isa, BlockSums(task))
}

/// [`block_moments`] of every block of `task`, as [`task_sums`].
fn task_moments<T: Height>(
    isa: wide::Isa,
    task: &[T],
    counts: &[usize],
    mean: f64,
) -> Vec<[f64; 6]> {
    #[cfg(target_arch = "x86_64")]
    if let (Some(simd), Some(z)) = (wide::v3(isa), T::as_f32s(task)) {
        return simd.vectorize(
            #[inline(always)]
            || {
                let mut out = Vec::with_capacity(counts.len());
                for (k, chunk) in z.chunks(BLOCK).enumerate() {
                    out.push(block_moments_v3(simd, chunk, counts[k], mean));
                }
                out
            },
        );
    }
    wide::run_on(isa, BlockMoments(task, counts, mean))
}

/// Pass 1 over `z` (whole blocks from a block boundary, the last one may be short): the
/// sum and count of each block, on all threads.
pub(crate) fn sums_of<T: Height>(isa: wide::Isa, z: &[T]) -> Vec<(f64, usize)> {
    use rayon::prelude::*;
    z.par_chunks(BLOCK * TASK_BLOCKS)
        .flat_map_iter(|task| task_sums(isa, task))
        .collect()
}

/// Pass 2 over `z` (as [`sums_of`]) with the counts of its blocks from pass 1.
pub(crate) fn moments_of<T: Height>(
    isa: wide::Isa,
    z: &[T],
    counts: &[usize],
    mean: f64,
) -> Vec<[f64; 6]> {
    use rayon::prelude::*;
    z.par_chunks(BLOCK * TASK_BLOCKS)
        .zip(counts.par_chunks(TASK_BLOCKS))
        .flat_map_iter(|(task, c)| task_moments(isa, task, c, mean))
        .collect()
}

/// Running totals of the two height passes, fed with block results in block order (so the
/// same bits whichever way the blocks were cut into tasks or pieces).
#[derive(Debug, Clone, Default)]
pub(crate) struct HeightSums {
    sum: f64,
    n: usize,
    s: [f64; 4],
    lo: f64,
    hi: f64,
}

impl HeightSums {
    pub(crate) fn new() -> Self {
        HeightSums {
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
            ..Default::default()
        }
    }

    /// Add the pass-1 results of the next blocks.
    pub(crate) fn add_sums(&mut self, sums: &[(f64, usize)]) {
        for &(s, c) in sums {
            self.sum += s;
            self.n += c;
        }
    }

    /// The number of finite values (after pass 1).
    pub(crate) fn n(&self) -> usize {
        self.n
    }

    /// The mean after pass 1 (`None` when no value is finite).
    pub(crate) fn mean(&self) -> Option<f64> {
        (self.n > 0).then(|| self.sum / self.n as f64)
    }

    /// Add the pass-2 results of the next blocks.
    pub(crate) fn add_moments(&mut self, moments: &[[f64; 6]]) {
        for m in moments {
            self.s[0] += m[0];
            self.s[1] += m[1];
            self.s[2] += m[2];
            self.s[3] += m[3];
            self.lo = lower(m[4], self.lo);
            self.hi = higher(m[5], self.hi);
        }
    }

    /// The statistics after both passes.
    pub(crate) fn stats(&self) -> Option<HeightStats> {
        let mean = self.mean()?;
        let n = self.n;
        let [s1, s2, s3, s4] = self.s;
        let (min, max) = (self.lo, self.hi);
        let (lo, hi) = (min - mean, max - mean);
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
}

/// [`height_stats`] of `f64` or `f32` heights (the same bits for the same values).
///
/// Two passes, each over fixed blocks of 4096 values on all threads: the mean, then the
/// moments of `η = z − mean`. Per-block sums keep the rounding small on large maps and are
/// reduced in block order (deterministic for any thread count).
pub fn height_stats_of<T: Height>(z: &[T]) -> Option<HeightStats> {
    height_stats_on(wide::Isa::Best, z)
}

/// [`height_stats_of`] with the instruction set `isa`.
pub(crate) fn height_stats_on<T: Height>(isa: wide::Isa, z: &[T]) -> Option<HeightStats> {
    let sums = sums_of(isa, z);
    let mut acc = HeightSums::new();
    acc.add_sums(&sums);
    let mean = acc.mean()?;
    let counts: Vec<usize> = sums.iter().map(|s| s.1).collect();
    acc.add_moments(&moments_of(isa, z, &counts, mean));
    acc.stats()
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
            let (sx, cx) = sdq_along(row);
            let (sy, cy) = if r + 1 < ny {
                sdq_across(row, g.row(r + 1))
            } else {
                (0.0, 0)
            };
            (sx, cx, sy, cy)
        })
        .collect();
    let mut acc = SdqSums::default();
    for &(a, b, c, d) in &rows {
        acc.add_along(a, b);
        acc.add_across(c, d);
    }
    acc.sdq(g.dx_um, g.dy_um)
}

/// The squared forward differences along a row and their count.
#[inline]
pub(crate) fn sdq_along<T: Height>(row: &[T]) -> (f64, usize) {
    let (mut sx, mut cx) = (0.0, 0usize);
    for w in row.windows(2) {
        let d = w[1].get() - w[0].get();
        if d.is_finite() {
            sx += d * d;
            cx += 1;
        }
    }
    (sx, cx)
}

/// The squared differences from row `top` to the next row `bot` and their count.
#[inline]
pub(crate) fn sdq_across<T: Height>(top: &[T], bot: &[T]) -> (f64, usize) {
    let (mut sy, mut cy) = (0.0, 0usize);
    for (a, b) in top.iter().zip(bot) {
        let d = b.get() - a.get();
        if d.is_finite() {
            sy += d * d;
            cy += 1;
        }
    }
    (sy, cy)
}

/// [`sdq_along`] of every row of `rows` (whole rows of `nx` values), in order, on all threads.
pub(crate) fn sdq_along_of<T: Height>(rows: &[T], nx: usize) -> Vec<(f64, usize)> {
    use rayon::prelude::*;
    rows.par_chunks(nx.max(1))
        .with_min_len(16)
        .map(sdq_along)
        .collect()
}

/// [`sdq_across`] of every pair of consecutive rows of `rows`, in order, on all threads.
pub(crate) fn sdq_across_of<T: Height>(rows: &[T], nx: usize) -> Vec<(f64, usize)> {
    use rayon::prelude::*;
    let pairs = (rows.len() / nx.max(1)).saturating_sub(1);
    (0..pairs)
        .into_par_iter()
        .with_min_len(16)
        .map(|r| {
            sdq_across(
                &rows[r * nx..(r + 1) * nx],
                &rows[(r + 1) * nx..(r + 2) * nx],
            )
        })
        .collect()
}

/// Running sums of Sdq, fed row by row in row order.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SdqSums {
    sx: f64,
    cx: usize,
    sy: f64,
    cy: usize,
}

impl SdqSums {
    /// Add a row's [`sdq_along`].
    pub(crate) fn add_along(&mut self, s: f64, c: usize) {
        self.sx += s;
        self.cx += c;
    }

    /// Add a row pair's [`sdq_across`].
    pub(crate) fn add_across(&mut self, s: f64, c: usize) {
        self.sy += s;
        self.cy += c;
    }

    /// Sdq from the sums.
    pub(crate) fn sdq(&self, dx_um: f64, dy_um: f64) -> f64 {
        let &SdqSums { sx, cx, sy, cy } = self;
        if cx == 0 && cy == 0 {
            return f64::NAN;
        }
        let mx = if cx > 0 {
            sx / cx as f64 / (dx_um * dx_um)
        } else {
            0.0
        };
        let my = if cy > 0 {
            sy / cy as f64 / (dy_um * dy_um)
        } else {
            0.0
        };
        (mx + my).sqrt()
    }
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

/// The summed excess area (four half-cell triangles per cell, not yet × 1/4) of the cells
/// between row `top` and the next row `bot` (spacing `dx`, `dy`), and the number of complete
/// cells.
#[inline(always)]
fn sdr_pair<T: Height>(top: &[T], bot: &[T], dx: f64, dy: f64) -> (f64, usize) {
    let nx = top.len();
    let d = dx * dy;
    let d2 = d * d;
    // With A = (r, j), B = (r, j+1), C = (r+1, j+1), D = (r+1, j) and the edge differences
    // ab = B − A, dc = C − D (along x), ad = D − A, bc = C − B (along y), the doubled
    // triangle areas are |(dy·ab, dx·bc, dxdy)| (ABC), |(dy·dc, dx·ad, dxdy)| (ACD),
    // |(dy·ab, dx·ad, dxdy)| (ABD) and |(dy·dc, dx·bc, dxdy)| (BCD).
    let cell = |j: usize| -> f64 {
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
    // Without a short cut (`all` stops at the first NaN, so it runs value by value): one
    // vector loop per row.
    let finite = |row: &[T]| {
        let mut ok = true;
        for v in row {
            ok &= v.get().is_finite();
        }
        ok
    };
    if finite(top) && finite(bot) {
        // The excess of each cell into a small buffer (a plain element-wise loop, which the
        // compiler vectorises at any width), then the buffer summed into the lanes: cell j
        // goes to lane j % LANES, in order, as a loop over the cells would add it.
        let mut lanes = [0.0f64; LANES];
        let whole = (nx - 1) / LANES * LANES;
        let mut e = [0.0f64; STRIP];
        let mut j0 = 0;
        while j0 < whole {
            let m = STRIP.min(whole - j0);
            for (j, o) in e[..m].iter_mut().enumerate() {
                *o = cell(j0 + j);
            }
            for g in e[..m].chunks_exact(LANES) {
                for (acc, v) in lanes.iter_mut().zip(g) {
                    *acc += v;
                }
            }
            j0 += m;
        }
        let mut acc = 0.0;
        for j in whole..nx - 1 {
            acc += cell(j);
        }
        for l in lanes {
            acc += l;
        }
        (acc, nx - 1)
    } else {
        let (mut acc, mut cells) = (0.0, 0usize);
        for j in 0..nx - 1 {
            let e = cell(j);
            if e.is_finite() {
                acc += e;
                cells += 1;
            }
        }
        (acc, cells)
    }
}

/// [`sdr_pair`] of the row pairs `(r, r + 1)` of `rows` (whole rows of `nx` values).
struct SdrPairs<'a, T> {
    rows: &'a [T],
    nx: usize,
    dx: f64,
    dy: f64,
}

impl<T: Height> wide::Kernel for SdrPairs<'_, T> {
    type Output = Vec<(f64, usize)>;
    #[inline(always)]
    fn call(self) -> Self::Output {
        let SdrPairs { rows, nx, dx, dy } = self;
        let n = (rows.len() / nx).saturating_sub(1);
        let mut out = Vec::with_capacity(n);
        for r in 0..n {
            let top = &rows[r * nx..(r + 1) * nx];
            let bot = &rows[(r + 1) * nx..(r + 2) * nx];
            out.push(sdr_pair(top, bot, dx, dy));
        }
        out
    }
}

/// Cells per strip of [`sdr_pair`]'s buffer (a multiple of [`LANES`]).
const STRIP: usize = 256;

/// Row pairs per rayon task of Sdr (fixed; results do not depend on it).
const TASK_PAIRS: usize = 8;

/// [`sdr_pair`] of every pair of consecutive rows of `rows` (whole rows of `nx ≥ 2` values),
/// in order, on all threads.
pub(crate) fn sdr_pairs_of<T: Height>(
    isa: wide::Isa,
    rows: &[T],
    nx: usize,
    dx: f64,
    dy: f64,
) -> Vec<(f64, usize)> {
    use rayon::prelude::*;
    let pairs = (rows.len() / nx).saturating_sub(1);
    (0..pairs.div_ceil(TASK_PAIRS))
        .into_par_iter()
        .flat_map_iter(|t| {
            let r0 = t * TASK_PAIRS;
            let r1 = (r0 + TASK_PAIRS).min(pairs);
            let rows = &rows[r0 * nx..(r1 + 1) * nx];
            wide::run_on(isa, SdrPairs { rows, nx, dx, dy })
        })
        .collect()
}

/// Running sums of Sdr, fed with row pairs in row order.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SdrSums {
    total: f64,
    cells: usize,
}

impl SdrSums {
    /// Add the results of the next row pairs.
    pub(crate) fn add(&mut self, pairs: &[(f64, usize)]) {
        for &(acc, c) in pairs {
            self.total += 0.25 * acc;
            self.cells += c;
        }
    }

    /// Sdr in % from the sums.
    pub(crate) fn percent(&self, dx_um: f64, dy_um: f64) -> f64 {
        if self.cells == 0 {
            return f64::NAN;
        }
        self.total / (self.cells as f64 * (dx_um * dy_um)) * 100.0
    }
}

/// [`sdr_percent`] of any grid, in one pass over the heights (no copy): row pairs on all
/// threads, per-row sums reduced in row order (deterministic for any thread count).
pub fn sdr_percent_of<T: Height>(g: Grid<'_, T>) -> f64 {
    sdr_percent_on(wide::Isa::Best, g)
}

/// [`sdr_percent_of`] with the instruction set `isa`.
pub(crate) fn sdr_percent_on<T: Height>(isa: wide::Isa, g: Grid<'_, T>) -> f64 {
    if g.nx < 2 || g.ny < 2 {
        return f64::NAN;
    }
    let mut acc = SdrSums::default();
    acc.add(&sdr_pairs_of(
        isa,
        &g.z[..g.nx * g.ny],
        g.nx,
        g.dx_um,
        g.dy_um,
    ));
    acc.percent(g.dx_um, g.dy_um)
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
