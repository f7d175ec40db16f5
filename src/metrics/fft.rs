//! Two-dimensional complex FFTs on row-major buffers (rustfft along rows, transpose, rows).

use rustfft::num_complex::Complex64;
use rustfft::{FftDirection, FftPlanner};

/// In-place 2-D FFT of a `rows × cols` row-major buffer. The result is left **transposed**
/// (`cols × rows`) when `leave_transposed`, which saves a transpose when only element-wise
/// work follows before the inverse.
pub(crate) fn fft2(
    data: &mut Vec<Complex64>,
    rows: usize,
    cols: usize,
    dir: FftDirection,
    leave_transposed: bool,
) {
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
    if leave_transposed {
        *data = t;
    } else {
        transpose::transpose(&t, data, rows, cols);
    }
}
