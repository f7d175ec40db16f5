//! Small dense linear systems: Gaussian elimination with partial pivoting (the normal
//! equations of the calibration and of run-out identification, a handful of unknowns).

/// Solve `a x = b` for a square `a` (rows); `None` when `a` is singular.
pub fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for i in 0..n {
        let p = (i..n).max_by(|&x, &y| a[x][i].abs().total_cmp(&a[y][i].abs()))?;
        if a[p][i].abs() < 1e-300 {
            return None;
        }
        a.swap(i, p);
        b.swap(i, p);
        let (top, rest) = a.split_at_mut(i + 1);
        let pivot = &top[i];
        for (k, row) in rest.iter_mut().enumerate() {
            let f = row[i] / pivot[i];
            for (v, p) in row[i..].iter_mut().zip(&pivot[i..]) {
                *v -= f * p;
            }
            b[i + 1 + k] -= f * b[i];
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|c| a[i][c] * x[c]).sum();
        x[i] = (b[i] - s) / a[i][i];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_3x3_and_refuses_a_singular_matrix() {
        let a = vec![
            vec![0.0, 2.0, 1.0],
            vec![1.0, 1.0, 0.0],
            vec![2.0, 0.0, 3.0],
        ];
        let x = solve(a, vec![7.0, 3.0, 11.0]).unwrap();
        for (v, w) in x.iter().zip([1.0, 2.0, 3.0]) {
            assert!((v - w).abs() < 1e-12, "{x:?}");
        }
        assert!(solve(vec![vec![1.0, 2.0], vec![2.0, 4.0]], vec![1.0, 2.0]).is_none());
    }
}
