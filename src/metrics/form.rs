//! Form removal (the F-operator): least-squares plane or polynomial of any total degree,
//! fitted to the valid nodes and subtracted.
//!
//! Coordinates are scaled to [−1, 1] over the grid before fitting so that the normal
//! equations stay well conditioned up to degree 5 (the 002 paper's 5th-order form); they are
//! accumulated per row (`Σ x^p` and `Σ x^p z` per row, then weighted by `y^q`), so a fit costs
//! about `3N` operations per node instead of `N²`.

use nalgebra::{DMatrix, DVector};

use crate::surface::HeightMap;

/// Form removal before the parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Level {
    /// Nothing removed (heights are still referred to their mean).
    #[default]
    None,
    /// Least-squares plane (degree 1).
    Plane,
    /// Least-squares polynomial of total degree N (`poly:1` = plane).
    Poly(u32),
}

/// Why a levelling's text is not a [`Level`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LevelError {
    /// Not `none`, `plane` or `poly:N`.
    #[error("expected none, plane or poly:N, found {0:?}")]
    Form(String),
    /// A degree that is not a whole number up to 12.
    #[error("bad polynomial degree {0:?} (0..=12)")]
    Degree(String),
}

impl Level {
    /// Polynomial degree (0 for none).
    pub fn degree(self) -> u32 {
        match self {
            Level::None => 0,
            Level::Plane => 1,
            Level::Poly(n) => n,
        }
    }

    /// Parse `none`, `plane` or `poly:N`.
    pub fn parse(s: &str) -> Result<Level, LevelError> {
        let t = s.trim().to_ascii_lowercase();
        match t.as_str() {
            "none" => Ok(Level::None),
            "plane" => Ok(Level::Plane),
            _ => match t.strip_prefix("poly:") {
                Some(n) => n
                    .parse::<u32>()
                    .ok()
                    .filter(|&n| n <= 12)
                    .map(Level::Poly)
                    .ok_or_else(|| LevelError::Degree(n.to_string())),
                None => Err(LevelError::Form(s.to_string())),
            },
        }
    }

    /// Text for outputs (`none`, `plane`, `poly:N`).
    pub fn label(self) -> String {
        match self {
            Level::None => "none".into(),
            Level::Plane => "plane".into(),
            Level::Poly(n) => format!("poly:{n}"),
        }
    }
}

fn scaled(n: usize) -> Vec<f64> {
    let h = (n as f64 - 1.0) / 2.0;
    (0..n)
        .map(|k| if h > 0.0 { (k as f64 - h) / h } else { 0.0 })
        .collect()
}

fn solve(a: DMatrix<f64>, b: DVector<f64>) -> Option<DVector<f64>> {
    if let Some(ch) = a.clone().cholesky() {
        return Some(ch.solve(&b));
    }
    a.svd(true, true).solve(&b, 1e-12).ok()
}

/// Remove the least-squares polynomial of total degree `degree` from the valid nodes of a
/// map (in place). Returns false (map unchanged) when there are too few valid nodes.
pub fn fit_remove_map(map: &mut HeightMap, degree: u32) -> bool {
    if degree == 0 {
        return true;
    }
    let d = degree as usize;
    let (nx, ny) = (map.nx, map.ny);
    // Terms x^a y^b with a + b <= d; along an axis with one node only b = 0 (or a = 0).
    let terms: Vec<(usize, usize)> = (0..=d)
        .flat_map(|t| (0..=t).map(move |b| (t - b, b)))
        .filter(|&(a, b)| (nx > 1 || a == 0) && (ny > 1 || b == 0))
        .collect();
    let m = terms.len();
    let xs = scaled(nx);
    let ys = scaled(ny);
    let xp: Vec<Vec<f64>> = xs
        .iter()
        .map(|&x| (0..=2 * d).map(|p| x.powi(p as i32)).collect())
        .collect();
    let mut ata = DMatrix::<f64>::zeros(m, m);
    let mut atz = DVector::<f64>::zeros(m);
    let mut valid = 0usize;
    let mut sx = vec![0.0; 2 * d + 1];
    let mut sz = vec![0.0; d + 1];
    for (r, &y) in ys.iter().enumerate() {
        sx.iter_mut().for_each(|v| *v = 0.0);
        sz.iter_mut().for_each(|v| *v = 0.0);
        let row = &map.z_um[r * nx..(r + 1) * nx];
        for (c, &z) in row.iter().enumerate() {
            if !z.is_finite() {
                continue;
            }
            valid += 1;
            let p = &xp[c];
            for (k, s) in sx.iter_mut().enumerate() {
                *s += p[k];
            }
            for (k, s) in sz.iter_mut().enumerate() {
                *s += p[k] * z;
            }
        }
        let yp: Vec<f64> = (0..=2 * d).map(|q| y.powi(q as i32)).collect();
        for (i, &(a, b)) in terms.iter().enumerate() {
            atz[i] += yp[b] * sz[a];
            for (j, &(a2, b2)) in terms.iter().enumerate().skip(i) {
                ata[(i, j)] += yp[b + b2] * sx[a + a2];
            }
        }
    }
    if valid < m {
        return false;
    }
    for i in 0..m {
        for j in 0..i {
            ata[(i, j)] = ata[(j, i)];
        }
    }
    let Some(coef) = solve(ata, atz) else {
        return false;
    };
    for (r, &y) in ys.iter().enumerate() {
        // Coefficient of x^a in this row.
        let mut cx = vec![0.0; d + 1];
        for (i, &(a, b)) in terms.iter().enumerate() {
            cx[a] += coef[i] * y.powi(b as i32);
        }
        for (c, z) in map.z_um[r * nx..(r + 1) * nx].iter_mut().enumerate() {
            if z.is_finite() {
                let x = xs[c];
                let f = cx.iter().rev().fold(0.0, |acc, &k| acc * x + k);
                *z -= f;
            }
        }
    }
    true
}

/// Remove the least-squares polynomial of degree `degree` from the valid values of a profile.
pub fn fit_remove_line(z: &mut [f64], degree: u32) -> bool {
    let mut map = HeightMap::from_rows(z.len(), 1, 1.0, 1.0, z.to_vec()).expect("length is nx * 1");
    let ok = fit_remove_map(&mut map, degree);
    z.copy_from_slice(&map.z_um);
    ok
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn removes_a_quintic_exactly() {
        let (nx, ny) = (40, 30);
        let z: Vec<f64> = (0..nx * ny)
            .map(|k| {
                let (x, y) = ((k % nx) as f64 * 0.1, (k / nx) as f64 * 0.2);
                1.0 + 0.5 * x - 0.2 * y + 0.03 * x.powi(5) - 0.01 * x * x * y.powi(3)
                    + y.powi(4) * 0.002
            })
            .collect();
        let mut m = HeightMap::from_rows(nx, ny, 0.1, 0.2, z).unwrap();
        m.z_um[17] = f64::NAN;
        assert!(fit_remove_map(&mut m, 5));
        let worst = m
            .z_um
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(worst < 1e-9, "{worst}");
        assert!(m.z_um[17].is_nan());
    }

    #[test]
    fn plane_leaves_sine_residual_orthogonal() {
        let mut z: Vec<f64> = (0..101).map(|k| 2.0 + 0.1 * k as f64).collect();
        assert!(fit_remove_line(&mut z, 1));
        assert!(z.iter().all(|v| v.abs() < 1e-10));
    }

    #[test]
    fn parses_levels() {
        assert_eq!(Level::parse("poly:5"), Ok(Level::Poly(5)));
        assert_eq!(Level::parse("Plane"), Ok(Level::Plane));
        assert!(Level::parse("poly:x").is_err());
        assert!(Level::parse("cylinder").is_err());
    }
}
