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
//!
//! [`RowStream::by_parts`] instead cuts the rows into one range per thread, each read and
//! reduced on its thread into lists (block sums, moments, row pairs) that are then added
//! in order: the blocks straddling two ranges and the row pairs across them are computed
//! whole at the merge. A few hand-offs per pass, and the copying out of the page cache
//! shared by the threads.

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

    /// What the row pairs of Sdr and Sdq need.
    fn pairs_spec(&self) -> PairsSpec {
        PairsSpec {
            isa: self.isa,
            nx: self.nx,
            dx_um: self.dx_um,
            dy_um: self.dy_um,
            sdr: self.sdr,
            sdq: self.sdq,
        }
    }

    /// Add row pairs, in their order.
    fn add_pairs(&mut self, p: &Pairs) {
        self.r.add(&p.sdr);
        for &(s, c) in &p.along {
            self.q.add_along(s, c);
        }
        for &(s, c) in &p.across {
            self.q.add_across(s, c);
        }
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
        let spec = self.pairs_spec();
        let mut pairs = Pairs::default();
        let RowStream {
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
            || spec.of_rows(last, rows, &mut pairs),
        );
        self.add_pairs(&pairs);
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

impl<T: Height> RowStream<T> {
    /// Both passes over the rows cut into `parts` ranges of whole rows, each range read and
    /// reduced on its own thread (`read` hands the rows of a range to its callback in
    /// pieces of whole rows, in order): a few hand-offs per pass instead of one per piece,
    /// and the reading itself on all threads. The same values as [`RowStream::first`] and
    /// [`RowStream::second`] with every row, bit for bit: each range gives back its block
    /// sums, moments and row pairs as lists, added in block and row order; the blocks that
    /// straddle two ranges and the row pairs across them are taken whole here. The first
    /// error of `read`, in row order, stops the passes.
    pub fn by_parts<E: Send>(
        mut self,
        parts: usize,
        read: impl Fn(std::ops::Range<usize>, &mut dyn FnMut(&[T])) -> Result<(), E> + Sync,
    ) -> Result<Self, E> {
        use rayon::prelude::*;
        let (nx, ny) = (self.nx, self.ny);
        debug_assert!(self.seen == 0, "a fresh stream");
        if nx == 0 || ny == 0 {
            self.end_first();
            return Ok(self);
        }
        let parts = parts.clamp(1, ny);
        let ranges: Vec<_> = (0..parts)
            .map(|k| k * ny / parts..(k + 1) * ny / parts)
            .collect();
        let isa = self.isa;
        let spec = self.pairs_spec();
        let firsts = ranges
            .par_iter()
            .map(|rows| {
                let mut p = Part::new(nx, rows.clone());
                read(rows.clone(), &mut |piece| p.first(isa, &spec, piece))?;
                Ok(p)
            })
            .collect::<Vec<Result<_, E>>>()
            .into_iter()
            .collect::<Result<Vec<_>, E>>()?;
        // Pass 1 merged: the block sums in block order (the straddling blocks whole), the
        // row pairs in row order (the pairs across two ranges between theirs).
        let mut sums = Vec::with_capacity((nx * ny).div_ceil(BLOCK));
        let mut straddles: Vec<(usize, Vec<T>)> = Vec::new();
        let mut carry: Vec<T> = Vec::new();
        let mut pairs = Pairs::default();
        for (k, p) in firsts.iter().enumerate() {
            carry.extend_from_slice(&p.head);
            if p.boundary {
                if !carry.is_empty() {
                    sums.extend(areal::sums_of(isa, &carry));
                    straddles.push((sums.len() - 1, std::mem::take(&mut carry)));
                }
                sums.extend_from_slice(&p.sums);
                carry.extend_from_slice(&p.tail);
            }
            if k > 0 {
                spec.across(&firsts[k - 1].last, &p.top, &mut pairs);
            }
            pairs.append(&p.pairs);
        }
        if !carry.is_empty() {
            sums.extend(areal::sums_of(isa, &carry));
            straddles.push((sums.len() - 1, carry));
        }
        self.seen = firsts.iter().map(|p| p.got).sum();
        let whole = firsts
            .iter()
            .zip(&ranges)
            .all(|(p, r)| p.got == r.len() * nx);
        drop(firsts);
        self.h.add_sums(&sums);
        self.counts = sums.iter().map(|s| s.1).collect();
        self.add_pairs(&pairs);
        // Rows missing or too many: no pass 2 (`finish` says so).
        if !self.end_first() || !whole {
            return Ok(self);
        }
        let Some(mean) = self.mean else {
            return Ok(self);
        };
        // Pass 2: the moments of each range's whole blocks, then of the straddling blocks
        // kept from pass 1, added in block order.
        let counts = &self.counts;
        let seconds = ranges
            .par_iter()
            .map(|rows| {
                let mut p = Moments::new(nx, rows);
                read(rows.clone(), &mut |piece| {
                    p.second(isa, piece, counts, mean)
                })?;
                Ok((p.got, p.moments))
            })
            .collect::<Vec<Result<_, E>>>()
            .into_iter()
            .collect::<Result<Vec<_>, E>>()?;
        let mut moments = vec![None; counts.len()];
        for ((got, m), rows) in seconds.iter().zip(&ranges) {
            let start = Cut::of(nx, rows).first_block;
            self.seen += got;
            for (k, m) in m.iter().enumerate() {
                moments[start + k] = Some(*m);
            }
        }
        for (b, z) in &straddles {
            moments[*b] = Some(areal::moments_of(isa, z, &counts[*b..*b + 1], mean)[0]);
        }
        // A block left out (rows missing) leaves `seen` short: `finish` says so.
        let moments: Vec<[f64; 6]> = moments.into_iter().flatten().collect();
        self.h.add_moments(&moments);
        self.blocks = moments.len();
        Ok(self)
    }
}

/// Pass 1 over one range of rows ([`RowStream::by_parts`]).
struct Part<T> {
    nx: usize,
    /// Values fed.
    got: usize,
    /// The values of the range before its first block boundary (all of them when none is
    /// inside the range).
    head: Vec<T>,
    /// Values of the head still to come.
    head_left: usize,
    /// Whether a block boundary lies in the range (at its first value or after).
    boundary: bool,
    /// The sums of the whole blocks, in order.
    sums: Vec<(f64, usize)>,
    /// The values after the last block boundary (the block goes on in the next range).
    tail: Vec<T>,
    /// The first and the last row seen.
    top: Vec<T>,
    last: Vec<T>,
    pairs: Pairs,
}

impl<T: Height> Part<T> {
    fn new(nx: usize, rows: std::ops::Range<usize>) -> Self {
        let cut = Cut::of(nx, &rows);
        Part {
            nx,
            got: 0,
            head: Vec::new(),
            head_left: cut.head,
            boundary: cut.boundary,
            sums: Vec::new(),
            tail: Vec::new(),
            top: Vec::new(),
            last: Vec::new(),
            pairs: Pairs::default(),
        }
    }

    fn first(&mut self, isa: Isa, spec: &PairsSpec, rows: &[T]) {
        let nx = self.nx;
        debug_assert_eq!(rows.len() % nx, 0, "pieces are whole rows");
        if rows.is_empty() {
            return;
        }
        self.got += rows.len();
        let take = self.head_left.min(rows.len());
        self.head.extend_from_slice(&rows[..take]);
        self.head_left -= take;
        let sums = &mut self.sums;
        feed_blocks(&mut self.tail, &rows[take..], |z| {
            sums.extend(areal::sums_of(isa, z))
        });
        if self.top.is_empty() {
            self.top.extend_from_slice(&rows[..nx]);
        }
        spec.of_rows(&self.last, rows, &mut self.pairs);
        self.last.clear();
        self.last.extend_from_slice(&rows[rows.len() - nx..]);
    }
}

/// The row pairs of Sdr and Sdq, in row order.
#[derive(Debug, Clone, Default)]
struct Pairs {
    sdr: Vec<(f64, usize)>,
    along: Vec<(f64, usize)>,
    across: Vec<(f64, usize)>,
}

impl Pairs {
    fn append(&mut self, p: &Pairs) {
        self.sdr.extend_from_slice(&p.sdr);
        self.along.extend_from_slice(&p.along);
        self.across.extend_from_slice(&p.across);
    }
}

/// What the row pairs of Sdr and Sdq need: the map's width and spacings, which of the two
/// are asked for, the instruction set.
#[derive(Debug, Clone, Copy)]
struct PairsSpec {
    isa: Isa,
    nx: usize,
    dx_um: f64,
    dy_um: f64,
    sdr: bool,
    sdq: bool,
}

impl PairsSpec {
    /// The pair across from `prev` (the row before, empty for none) to `next` (a row).
    fn across<T: Height>(&self, prev: &[T], next: &[T], out: &mut Pairs) {
        if prev.is_empty() || !(self.sdr || self.sdq) {
            return;
        }
        let mut joined = prev.to_vec();
        joined.extend_from_slice(&next[..self.nx]);
        if self.sdr {
            out.sdr.extend(areal::sdr_pairs_of(
                self.isa, &joined, self.nx, self.dx_um, self.dy_um,
            ));
        }
        if self.sdq {
            out.across.extend(areal::sdq_across_of(&joined, self.nx));
        }
    }

    /// The pair across from `prev` to the first of `rows` (whole rows), then the pairs
    /// inside `rows`.
    fn of_rows<T: Height>(&self, prev: &[T], rows: &[T], out: &mut Pairs) {
        let nx = self.nx;
        self.across(prev, rows, out);
        if self.sdr {
            out.sdr.extend(areal::sdr_pairs_of(
                self.isa, rows, nx, self.dx_um, self.dy_um,
            ));
        }
        if self.sdq {
            out.along.extend(areal::sdq_along_of(rows, nx));
            out.across.extend(areal::sdq_across_of(rows, nx));
        }
    }
}

/// Pass 2 over one range of rows: the moments of its whole blocks.
struct Moments<T> {
    got: usize,
    head_left: usize,
    block: usize,
    pending: Vec<T>,
    moments: Vec<[f64; 6]>,
}

impl<T: Height> Moments<T> {
    fn new(nx: usize, rows: &std::ops::Range<usize>) -> Self {
        let cut = Cut::of(nx, rows);
        Moments {
            got: 0,
            head_left: cut.head,
            block: cut.first_block,
            pending: Vec::new(),
            moments: Vec::new(),
        }
    }

    fn second(&mut self, isa: Isa, rows: &[T], counts: &[usize], mean: f64) {
        self.got += rows.len();
        let take = self.head_left.min(rows.len());
        self.head_left -= take;
        let Moments {
            ref mut block,
            ref mut pending,
            ref mut moments,
            ..
        } = *self;
        feed_blocks(pending, &rows[take..], |z| {
            let n = z.len().div_ceil(BLOCK);
            moments.extend(areal::moments_of(isa, z, &counts[*block..*block + n], mean));
            *block += n;
        });
    }
}

/// Where the blocks of [`BLOCK`] values (counted from the map's first value) cut a range of
/// rows of `nx` values each; both passes of [`RowStream::by_parts`] start from it.
struct Cut {
    /// The values before the first block boundary at or after the range's first value: the
    /// head that pass 1 keeps and pass 2 skips.
    head: usize,
    /// Whether a block boundary lies in the range (at its first value or after).
    boundary: bool,
    /// The index of the first block that starts in the range (after the head).
    first_block: usize,
}

impl Cut {
    fn of(nx: usize, rows: &std::ops::Range<usize>) -> Cut {
        let (a, b) = (rows.start * nx, rows.end * nx);
        let f = a.next_multiple_of(BLOCK);
        Cut {
            head: f.min(b) - a,
            boundary: f < b,
            first_block: f / BLOCK,
        }
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

    /// The parameters by [`RowStream::by_parts`] with `parts` ranges read in pieces of
    /// `rows` rows.
    fn in_parts(
        isa: Isa,
        z: &[f32],
        (nx, ny): (usize, usize),
        set: &ParamSet,
        parts: usize,
        rows: usize,
    ) -> Result<(Vec<(Param, f64)>, usize), MetricsError> {
        let s = RowStream::new_on(isa, nx, ny, 0.5, 0.7, set)?;
        let read = |r: std::ops::Range<usize>, each: &mut dyn FnMut(&[f32])| {
            for piece in z[r.start * nx..r.end * nx].chunks(rows * nx) {
                each(piece);
            }
            Ok::<(), ()>(())
        };
        let s = s.by_parts(parts, read).unwrap();
        let valid = s.valid();
        Ok((s.finish()?, valid))
    }

    #[test]
    fn by_parts_gives_the_in_memory_values_for_any_cut() {
        let all = ParamSet::parse("Sa,Sq,Sp,Sv,Sz,Ssk,Sku,Sdq,Sdr", false).unwrap();
        let sdr = ParamSet::parse("Sdr", false).unwrap();
        let sq = ParamSet::parse("Sq,Sdq", false).unwrap();
        // Blocks straddling the cuts (301, 7, 1000 wide), a block per row (4096), rows that
        // cut blocks evenly (64, 2048), ranges holding no block boundary (7 × 1200 in 5
        // parts: 1680 values each), 1 to 3 rows, one column.
        let sizes = [
            (301, 67),
            (7, 1200),
            (1, 50),
            (64, 200),
            (2048, 5),
            (4096, 3),
            (1000, 9),
            (13, 1),
            (4100, 2),
            (5, 3),
        ];
        for_each_case(
            &sizes,
            &[&all, &sdr, &sq],
            |z, (nx, ny), set, pool, want, valid| {
                for parts in [1, 2, 3, 5, 8] {
                    for rows in [1, 2, 64, ny] {
                        for isa in [Isa::Best, Isa::Baseline] {
                            let (got, n) = pool
                                .install(|| in_parts(isa, z, (nx, ny), set, parts, rows))
                                .unwrap();
                            let threads = pool.current_num_threads();
                            assert_eq!(
                                bits(&got),
                                want,
                                "{nx}×{ny} {parts} parts {rows} rows {threads} threads"
                            );
                            assert_eq!(n, valid);
                        }
                    }
                }
            },
        );
    }

    #[test]
    fn by_parts_stops_at_the_first_error_in_row_order_and_sees_missing_rows() {
        let set = ParamSet::parse("Sa,Sdr", false).unwrap();
        let (nx, ny) = (5, 12);
        let z = rough(nx, ny, false);
        // Ranges from row 3 on fail, each with its first row: the first is reported.
        let s = RowStream::<f32>::new(nx, ny, 1.0, 1.0, &set).unwrap();
        let e = s
            .by_parts(4, |r, each| {
                if r.start >= 3 {
                    return Err(r.start);
                }
                each(&z[r.start * nx..r.end * nx]);
                Ok(())
            })
            .unwrap_err();
        assert_eq!(e, 3);
        // A reader that hands on too few rows: an error, not a wrong value.
        let s = RowStream::<f32>::new(nx, ny, 1.0, 1.0, &set).unwrap();
        let s = s
            .by_parts(3, |r, each| {
                each(&z[r.start * nx..(r.end - 1) * nx]);
                Ok::<(), ()>(())
            })
            .unwrap();
        assert!(s.finish().is_err());
        // No valid height: as with `first`.
        let nan = vec![f32::NAN; nx * ny];
        let s = RowStream::<f32>::new(nx, ny, 1.0, 1.0, &set).unwrap();
        let s = s
            .by_parts(2, |r, each| {
                each(&nan[r.start * nx..r.end * nx]);
                Ok::<(), ()>(())
            })
            .unwrap();
        assert!(matches!(s.finish(), Err(MetricsError::TooFew(_))));
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
        let sizes = [(301, 67), (7, 1200), (1, 50)];
        for_each_case(
            &sizes,
            &[&all, &sdr, &sa],
            |z, (nx, ny), set, pool, want, valid| {
                for rows in [1, 2, 5, 64, ny] {
                    for isa in [Isa::Best, Isa::Baseline] {
                        let (got, n) = pool
                            .install(|| streamed(isa, z, nx, ny, set, rows))
                            .unwrap();
                        let threads = pool.current_num_threads();
                        assert_eq!(bits(&got), want, "{nx}×{ny} {rows} rows {threads}");
                        assert_eq!(n, valid);
                    }
                }
            },
        );
    }

    /// Every size, with and without NaN heights, every set, on 1, 2 and 3 threads: `check`
    /// gets the heights, the size, the set, the pool, the in-memory values (bits) and the
    /// number of valid heights.
    fn for_each_case(
        sizes: &[(usize, usize)],
        sets: &[&ParamSet],
        mut check: impl FnMut(
            &[f32],
            (usize, usize),
            &ParamSet,
            &rayon::ThreadPool,
            &[(Param, u64)],
            usize,
        ),
    ) {
        for &(nx, ny) in sizes {
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
                for set in sets {
                    let want = bits(&areal_parameters_of(g, set).unwrap());
                    for threads in [1, 2, 3] {
                        let pool = rayon::ThreadPoolBuilder::new()
                            .num_threads(threads)
                            .build()
                            .unwrap();
                        check(&z, (nx, ny), set, &pool, &want, valid);
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
