//! The plain-pass areal parameters (Sa … Sku, Sdq, Sdr) of a height map fed in pieces of
//! whole rows as a file is read, in a few rows of memory: the very values of the in-memory
//! functions, bit for bit, for any piece size and any number of threads.
//!
//! Pass 1 takes the block sums of the heights (the mean), Sdr and Sdq; pass 2, over the same
//! rows again, the moments about the mean (Sa, Sq, Ssk, Sku) and the extremes. The blocks of
//! the height sums are the in-memory ones (4096 values from the first, wherever the pieces
//! cut them: the values after the last whole block wait for the next piece), the row pairs
//! of Sdr and Sdq carry over from one piece to the next, and every sum is reduced in block
//! or row order, as in memory.

use super::areal::{self, BLOCK, Height, HeightSums, SdqSums, SdrSums};
use super::params::{PASS_PARAMS, pass_table};
use super::{MetricsError, Param, ParamSet};
use crate::math::wide::Isa;

/// The plain-pass parameters of a map fed row by row ([`RowStream::first`] with every row,
/// then, when [`RowStream::end_first`] says so, [`RowStream::second`] with every row again).
#[derive(Debug, Clone)]
pub struct RowStream<T> {
    nx: usize,
    ny: usize,
    dx_um: f64,
    dy_um: f64,
    set: ParamSet,
    isa: Isa,
    heights: bool,
    sdq: bool,
    sdr: bool,
    /// Values fed in the current pass.
    seen: usize,
    /// The values after the last whole block of the current pass.
    pending: Vec<T>,
    /// The finite values of each block (pass 1), read back in pass 2.
    counts: Vec<usize>,
    /// Blocks done in pass 2.
    blocks: usize,
    /// The last row of the previous piece (pass 1).
    last: Vec<T>,
    h: HeightSums,
    mean: Option<f64>,
    q: SdqSums,
    r: SdrSums,
}

impl<T: Height> RowStream<T> {
    /// A stream for an `nx × ny` map with spacings `dx_um`, `dy_um` and the parameters
    /// `set`; an error names a parameter that needs the whole map (not a plain pass).
    pub fn new(
        nx: usize,
        ny: usize,
        dx_um: f64,
        dy_um: f64,
        set: &ParamSet,
    ) -> Result<Self, MetricsError> {
        Self::new_on(Isa::Best, nx, ny, dx_um, dy_um, set)
    }

    pub(crate) fn new_on(
        isa: Isa,
        nx: usize,
        ny: usize,
        dx_um: f64,
        dy_um: f64,
        set: &ParamSet,
    ) -> Result<Self, MetricsError> {
        use Param::*;
        if let Some(p) = set.params().iter().find(|p| !PASS_PARAMS.contains(p)) {
            return Err(MetricsError::BadSetting(format!(
                "{} needs the whole height map (not a plain pass)",
                p.symbol()
            )));
        }
        Ok(RowStream {
            nx,
            ny,
            dx_um,
            dy_um,
            set: set.clone(),
            isa,
            heights: set.any(&[Sa, Sq, Sp, Sv, Sz, Ssk, Sku]),
            sdq: set.any(&[Sdq]),
            sdr: set.any(&[Sdr]) && nx >= 2 && ny >= 2,
            seen: 0,
            pending: Vec::new(),
            counts: Vec::new(),
            blocks: 0,
            last: Vec::new(),
            h: HeightSums::new(),
            mean: None,
            q: SdqSums::default(),
            r: SdrSums::default(),
        })
    }

    /// Rows per piece for pieces of about `bytes` bytes of `T` (at least one row).
    pub fn rows_per_piece(&self, bytes: usize) -> usize {
        (bytes / std::mem::size_of::<T>() / self.nx.max(1)).max(1)
    }

    /// Pass 1: the next whole rows, in order.
    pub fn first(&mut self, rows: &[T]) {
        let nx = self.nx;
        debug_assert_eq!(rows.len() % nx.max(1), 0, "pieces are whole rows");
        if rows.is_empty() {
            return;
        }
        self.seen += rows.len();
        let isa = self.isa;
        let (mut pairs, mut along, mut across) = (Vec::new(), Vec::new(), Vec::new());
        let RowStream {
            sdq,
            sdr,
            dx_um,
            dy_um,
            ref mut pending,
            ref mut h,
            ref mut counts,
            ref last,
            ..
        } = *self;
        rayon::join(
            || {
                feed_blocks(pending, rows, |z| {
                    let s = areal::sums_of(isa, z);
                    h.add_sums(&s);
                    counts.extend(s.iter().map(|s| s.1));
                })
            },
            || {
                // The pair across the cut first, then the pairs inside this piece.
                let mut joined = Vec::new();
                if !last.is_empty() && (sdr || sdq) {
                    joined.extend_from_slice(last);
                    joined.extend_from_slice(&rows[..nx]);
                }
                if sdr {
                    pairs = areal::sdr_pairs_of(isa, &joined, nx, dx_um, dy_um);
                    pairs.extend(areal::sdr_pairs_of(isa, rows, nx, dx_um, dy_um));
                }
                if sdq {
                    along = areal::sdq_along_of(rows, nx);
                    across = areal::sdq_across_of(&joined, nx);
                    across.extend(areal::sdq_across_of(rows, nx));
                }
            },
        );
        self.r.add(&pairs);
        for &(s, c) in &along {
            self.q.add_along(s, c);
        }
        for &(s, c) in &across {
            self.q.add_across(s, c);
        }
        self.last.clear();
        self.last.extend_from_slice(&rows[rows.len() - nx..]);
    }

    /// End pass 1; whether pass 2 is needed (height parameters asked for and some heights
    /// valid).
    pub fn end_first(&mut self) -> bool {
        if !self.pending.is_empty() {
            let s = areal::sums_of(self.isa, &self.pending);
            self.h.add_sums(&s);
            self.counts.extend(s.iter().map(|s| s.1));
            self.pending.clear();
        }
        self.last = Vec::new();
        self.mean = if self.heights { self.h.mean() } else { None };
        self.mean.is_some()
    }

    /// The number of valid (finite) heights, known after pass 1.
    pub fn valid(&self) -> usize {
        self.h.n()
    }

    /// Pass 2: the same rows again, in order.
    pub fn second(&mut self, rows: &[T]) {
        let Some(mean) = self.mean else { return };
        self.seen += rows.len();
        let isa = self.isa;
        let RowStream {
            ref mut pending,
            ref mut h,
            ref counts,
            ref mut blocks,
            ..
        } = *self;
        feed_blocks(pending, rows, |z| {
            let n = z.len().div_ceil(BLOCK);
            h.add_moments(&areal::moments_of(
                isa,
                z,
                &counts[*blocks..*blocks + n],
                mean,
            ));
            *blocks += n;
        });
    }

    /// The values of the parameters, in the order of the set.
    pub fn finish(mut self) -> Result<Vec<(Param, f64)>, MetricsError> {
        let passes = if self.mean.is_some() { 2 } else { 1 };
        if self.seen != passes * self.nx * self.ny {
            return Err(MetricsError::BadSetting(format!(
                "internal: {} values fed for {passes} passes over {}×{} nodes",
                self.seen, self.nx, self.ny
            )));
        }
        if let Some(mean) = self.mean {
            let (isa, pending) = (self.isa, std::mem::take(&mut self.pending));
            if !pending.is_empty() {
                let n = self.blocks;
                let m = areal::moments_of(isa, &pending, &self.counts[n..n + 1], mean);
                self.h.add_moments(&m);
            }
        }
        let stats = if self.heights {
            Some(
                self.h
                    .stats()
                    .ok_or_else(|| MetricsError::TooFew("the map has no valid height".into()))?,
            )
        } else {
            None
        };
        let sdq = self.sdq.then(|| self.q.sdq(self.dx_um, self.dy_um));
        let sdr = self
            .set
            .any(&[Param::Sdr])
            .then(|| self.r.percent(self.dx_um, self.dy_um));
        Ok(pass_table(&self.set, stats, sdq, sdr))
    }
}

/// Hand `rows` to `f` in whole blocks of [`BLOCK`] values counted from the first value of the
/// pass: first the pending block once `rows` completes it, then the whole blocks of `rows`
/// (one call); the rest waits in `pending` for the next rows.
fn feed_blocks<T: Copy>(pending: &mut Vec<T>, rows: &[T], mut f: impl FnMut(&[T])) {
    let mut rows = rows;
    if !pending.is_empty() {
        let take = (BLOCK - pending.len()).min(rows.len());
        pending.extend_from_slice(&rows[..take]);
        rows = &rows[take..];
        if pending.len() < BLOCK {
            return;
        }
        f(pending);
        pending.clear();
    }
    let whole = rows.len() / BLOCK * BLOCK;
    if whole > 0 {
        f(&rows[..whole]);
    }
    pending.extend_from_slice(&rows[whole..]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::{Grid, areal_parameters_of};

    /// A rough test surface, a few missing nodes when `nan`.
    fn rough(nx: usize, ny: usize, nan: bool) -> Vec<f32> {
        (0..nx * ny)
            .map(|k| {
                let (x, y) = ((k % nx) as f32, (k / nx) as f32);
                if nan && k % 1231 == 17 {
                    f32::NAN
                } else {
                    (0.21 * x).sin() + 0.3 * (0.13 * y).cos() + 0.02 * ((k * 7919) % 97) as f32
                }
            })
            .collect()
    }

    fn streamed(
        isa: Isa,
        z: &[f32],
        nx: usize,
        ny: usize,
        set: &ParamSet,
        rows: usize,
    ) -> Result<(Vec<(Param, f64)>, usize), MetricsError> {
        let mut s = RowStream::new_on(isa, nx, ny, 0.5, 0.7, set)?;
        for piece in z.chunks(rows * nx) {
            s.first(piece);
        }
        if s.end_first() {
            for piece in z.chunks(rows * nx) {
                s.second(piece);
            }
        }
        let valid = s.valid();
        Ok((s.finish()?, valid))
    }

    fn bits(v: &[(Param, f64)]) -> Vec<(Param, u64)> {
        v.iter().map(|(p, x)| (*p, x.to_bits())).collect()
    }

    #[test]
    fn the_in_memory_values_for_any_piece_size_thread_count_and_isa() {
        let all = ParamSet::parse("Sa,Sq,Sp,Sv,Sz,Ssk,Sku,Sdq,Sdr", false).unwrap();
        let sdr = ParamSet::parse("Sdr", false).unwrap();
        let sa = ParamSet::parse("Sa", false).unwrap();
        // 301 × 67: 4096-value blocks straddle the pieces and the rows.
        for (nx, ny) in [(301, 67), (7, 1200), (1, 50)] {
            for nan in [false, true] {
                let z = rough(nx, ny, nan);
                let g = Grid {
                    nx,
                    ny,
                    dx_um: 0.5,
                    dy_um: 0.7,
                    z: &z[..],
                };
                let valid = z.iter().filter(|v| v.is_finite()).count();
                for set in [&all, &sdr, &sa] {
                    let want = bits(&areal_parameters_of(g, set).unwrap());
                    for threads in [1, 2, 3] {
                        let pool = rayon::ThreadPoolBuilder::new()
                            .num_threads(threads)
                            .build()
                            .unwrap();
                        for rows in [1, 2, 5, 64, ny] {
                            for isa in [Isa::Best, Isa::Baseline] {
                                let (got, n) = pool
                                    .install(|| streamed(isa, &z, nx, ny, set, rows))
                                    .unwrap();
                                assert_eq!(bits(&got), want, "{nx}×{ny} {rows} rows {threads}");
                                assert_eq!(n, valid);
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn no_valid_height_and_whole_map_parameters_are_errors() {
        let set = ParamSet::parse("Sa,Sdr", false).unwrap();
        let z = vec![f32::NAN; 12];
        let e = streamed(Isa::Best, &z, 4, 3, &set, 2).unwrap_err();
        assert!(matches!(e, MetricsError::TooFew(_)), "{e}");
        let sal = ParamSet::parse("Sa,Sal", false).unwrap();
        assert!(RowStream::<f32>::new(4, 3, 1.0, 1.0, &sal).is_err());
        // Sdr alone needs no valid height and one pass.
        let only = ParamSet::parse("Sdr", false).unwrap();
        let (v, n) = streamed(Isa::Best, &z, 4, 3, &only, 2).unwrap();
        assert!(v[0].1.is_nan() && n == 0);
        // Rows missing: an error, not a wrong value.
        let mut s = RowStream::<f32>::new(4, 3, 1.0, 1.0, &set).unwrap();
        s.first(&[1.0; 8]);
        s.end_first();
        s.second(&[1.0; 8]);
        assert!(s.finish().is_err());
    }
}
