//! Two-dimensional complex FFTs on row-major buffers, in place: rustfft along rows, and
//! along columns a few at a time through a small gathered block (no second buffer of the
//! whole field). The rows, and the column blocks, are transformed in parallel (rayon); each
//! 1-D FFT is the same whichever thread runs it, so the result is too.

use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftDirection, FftPlanner};

/// Columns gathered into one contiguous block for their FFTs.
const BLOCK: usize = 64;

/// Rows of a column block gathered at a time.
const TILE: usize = 8;

/// Column blocks transformed in parallel before they are written back (bounds the memory
/// held at once to this many blocks).
const BLOCKS_AT_ONCE: usize = 4;

/// The smallest length at least `n` whose only prime factors are 2, 3 and 5 (rustfft's
/// fast sizes; a zero padding to it gives the same linear correlation as any other).
pub(crate) fn fast_len(n: usize) -> usize {
    let mut best = usize::MAX;
    let mut p2 = 1usize;
    while p2 < 2 * n.max(1) {
        let mut p3 = p2;
        while p3 < 2 * n.max(1) {
            let mut p5 = p3;
            while p5 < n {
                p5 *= 5;
            }
            best = best.min(p5);
            p3 *= 3;
        }
        p2 *= 2;
    }
    best
}

/// The `py × px` lattice with `value(r·nx + c)` at the field's nodes (row r < ny, column
/// c < nx) and zero elsewhere, written once in order (no zeroing pass first).
pub(crate) fn padded(
    nx: usize,
    ny: usize,
    px: usize,
    py: usize,
    value: impl Fn(usize) -> Complex64,
) -> Vec<Complex64> {
    let mut buf = Vec::with_capacity(px * py);
    for r in 0..ny {
        buf.extend((r * nx..(r + 1) * nx).map(&value));
        buf.resize((r + 1) * px, Complex64::default());
    }
    buf.resize(px * py, Complex64::default());
    buf
}

/// [`padded`], transformed forward: rows then columns, the rows past the field's left out
/// (zero, they stay so).
pub(crate) fn padded_forward(
    nx: usize,
    ny: usize,
    px: usize,
    py: usize,
    value: impl Fn(usize) -> Complex64,
) -> Vec<Complex64> {
    let mut buf = padded(nx, ny, px, py, value);
    let mut fwd = Fft2::new(py, px, FftDirection::Forward);
    fwd.rows(&mut buf[..ny * px]);
    fwd.columns(&mut buf);
    buf
}

/// The 1-D FFTs of one direction over a `rows × cols` row-major buffer.
pub(crate) struct Fft2 {
    f_row: std::sync::Arc<dyn Fft<f64>>,
    f_col: std::sync::Arc<dyn Fft<f64>>,
    rows: usize,
    cols: usize,
}

impl Fft2 {
    /// Plans for a `rows × cols` field in direction `dir`.
    pub(crate) fn new(rows: usize, cols: usize, dir: FftDirection) -> Fft2 {
        let mut planner = FftPlanner::<f64>::new();
        let f_row = planner.plan_fft(cols, dir);
        let f_col = planner.plan_fft(rows, dir);
        Fft2 {
            f_row,
            f_col,
            rows,
            cols,
        }
    }

    /// The FFT of every row, in place.
    pub(crate) fn rows(&mut self, data: &mut [Complex64]) {
        use rayon::prelude::*;
        let f = &self.f_row;
        let len = f.get_inplace_scratch_len();
        data.par_chunks_exact_mut(self.cols).for_each_init(
            || vec![Complex64::default(); len],
            |scratch, r| f.process_with_scratch(r, scratch),
        );
    }

    /// The FFT of every column, in place (each column is copied out, transformed and copied
    /// back, so it gets the values a transposed buffer would give it, bit for bit). A block's
    /// columns are gathered [`TILE`] rows at a time (runs of `TILE` contiguous writes rather
    /// than `BLOCK` writes a column apart, which share a cache set), and written back row by
    /// row in parallel.
    pub(crate) fn columns(&mut self, data: &mut [Complex64]) {
        use rayon::prelude::*;
        let (rows, cols) = (self.rows, self.cols);
        let f = &self.f_col;
        let len = f.get_inplace_scratch_len();
        let starts: Vec<usize> = (0..cols).step_by(BLOCK).collect();
        for group in starts.chunks(BLOCKS_AT_ONCE) {
            let blocks: Vec<(usize, usize, Vec<Complex64>)> = {
                let data = &*data;
                group
                    .par_iter()
                    .map_init(
                        || vec![Complex64::default(); len],
                        |scratch, &c0| {
                            let w = BLOCK.min(cols - c0);
                            let mut block = vec![Complex64::default(); w * rows];
                            for r0 in (0..rows).step_by(TILE) {
                                let r1 = (r0 + TILE).min(rows);
                                for k in 0..w {
                                    let col = &mut block[k * rows + r0..k * rows + r1];
                                    for (r, v) in (r0..r1).zip(col) {
                                        *v = data[r * cols + c0 + k];
                                    }
                                }
                            }
                            for col in block.chunks_exact_mut(rows) {
                                f.process_with_scratch(col, scratch);
                            }
                            (c0, w, block)
                        },
                    )
                    .collect()
            };
            data.par_chunks_exact_mut(cols)
                .enumerate()
                .for_each(|(r, row)| {
                    for (c0, w, block) in &blocks {
                        for (k, v) in row[*c0..c0 + w].iter_mut().enumerate() {
                            *v = block[k * rows + r];
                        }
                    }
                });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_lengths_are_5_smooth_and_least() {
        assert_eq!(fast_len(1), 1);
        assert_eq!(fast_len(1334), 1350);
        assert_eq!(fast_len(15200), 15360);
        assert_eq!(fast_len(4000), 4000);
        assert_eq!(fast_len(17), 18);
    }

    /// The previous form: rows, a transpose into a second buffer, rows again.
    fn transposed_fft2(data: &mut [Complex64], rows: usize, cols: usize, dir: FftDirection) {
        let mut planner = FftPlanner::<f64>::new();
        let f_row = planner.plan_fft(cols, dir);
        let f_col = planner.plan_fft(rows, dir);
        let mut scratch = vec![
            Complex64::default();
            f_row
                .get_inplace_scratch_len()
                .max(f_col.get_inplace_scratch_len())
        ];
        for r in data.chunks_exact_mut(cols) {
            f_row.process_with_scratch(r, &mut scratch);
        }
        let mut t = vec![Complex64::default(); rows * cols];
        transpose::transpose(data, &mut t, cols, rows);
        for c in t.chunks_exact_mut(rows) {
            f_col.process_with_scratch(c, &mut scratch);
        }
        transpose::transpose(&t, data, rows, cols);
    }

    #[test]
    fn in_place_columns_give_the_transposed_bits() {
        for (rows, cols) in [(6, 40), (34, 17), (1, 5), (50, 1)] {
            let start: Vec<Complex64> = (0..rows * cols)
                .map(|k| Complex64::new(((k * 37 % 101) as f64).sin(), 0.0))
                .collect();
            let mut old = start.clone();
            transposed_fft2(&mut old, rows, cols, FftDirection::Forward);
            let mut new = start;
            let mut f = Fft2::new(rows, cols, FftDirection::Forward);
            f.rows(&mut new);
            f.columns(&mut new);
            assert!(
                old.iter()
                    .zip(&new)
                    .all(|(a, b)| a.re.to_bits() == b.re.to_bits()
                        && a.im.to_bits() == b.im.to_bits()),
                "{rows}×{cols}"
            );
        }
    }
}
