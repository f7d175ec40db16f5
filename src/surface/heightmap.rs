//! A regular grid of heights.

/// Heights on a regular grid: `ny` rows (y ascending) of `nx` columns (x ascending).
///
/// Heights are µm; a node no tooth reached (or a missing measurement) is `NaN`.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightMap {
    /// Columns (x).
    pub nx: usize,
    /// Rows (y).
    pub ny: usize,
    /// Spacing along x, µm.
    pub dx_um: f64,
    /// Spacing along y, µm.
    pub dy_um: f64,
    /// x of column 0, mm (in the frame of the grid).
    pub x0_mm: f64,
    /// y of row 0, mm.
    pub y0_mm: f64,
    /// Row-major heights, µm: `z[row * nx + col]`.
    pub z_um: Vec<f64>,
}

impl HeightMap {
    /// A grid filled with `NaN` (nothing known yet).
    pub fn new_nan(nx: usize, ny: usize, dx_um: f64, dy_um: f64) -> HeightMap {
        HeightMap {
            nx,
            ny,
            dx_um,
            dy_um,
            x0_mm: 0.0,
            y0_mm: 0.0,
            z_um: nan_heights(nx * ny),
        }
    }

    /// A grid from row-major heights; `None` when the length is not `nx * ny`.
    pub fn from_rows(
        nx: usize,
        ny: usize,
        dx_um: f64,
        dy_um: f64,
        z_um: Vec<f64>,
    ) -> Option<HeightMap> {
        (z_um.len() == nx * ny).then_some(HeightMap {
            nx,
            ny,
            dx_um,
            dy_um,
            x0_mm: 0.0,
            y0_mm: 0.0,
            z_um,
        })
    }

    /// Height at (`col`, `row`).
    pub fn get(&self, col: usize, row: usize) -> f64 {
        self.z_um[row * self.nx + col]
    }

    /// Row `row` as a slice.
    pub fn row(&self, row: usize) -> &[f64] {
        &self.z_um[row * self.nx..(row + 1) * self.nx]
    }

    /// Number of finite (known) nodes.
    pub fn known(&self) -> usize {
        self.z_um.iter().filter(|z| z.is_finite()).count()
    }
}

/// `n` NaN heights; a large grid is filled by every thread (its pages are first touched,
/// and zeroed by the system, on both cores: 10-15 ms of B-SIM's 4 M nodes otherwise spent on
/// one).
fn nan_heights(n: usize) -> Vec<f64> {
    use rayon::prelude::*;
    if n < 1 << 16 {
        return vec![f64::NAN; n];
    }
    let mut z = Vec::new();
    (0..n)
        .into_par_iter()
        .map(|_| f64::NAN)
        .collect_into_vec(&mut z);
    z
}
