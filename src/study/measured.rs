//! Measured roughness: the rows of a measured table (one per case and sample, like 002 Table
//! 2), grouped into cases (lead angle, side) with their mean and sample standard deviation.
//! The CSV reader is [`crate::io::measured`].

use serde::Serialize;

/// The side of a curved part a case was measured on.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// Concave region: the surface curves around the tool.
    Concave,
    /// Convex region: the surface curves away from the tool.
    Convex,
    /// A plane (no curvature).
    Plane,
}

impl Side {
    /// The name used in tables and files.
    pub fn name(self) -> &'static str {
        match self {
            Side::Concave => "concave",
            Side::Convex => "convex",
            Side::Plane => "plane",
        }
    }

    /// Read a side name (`concave`, `convex`, `plane` or `flat`, any case).
    pub fn parse(s: &str) -> Option<Side> {
        match s.trim().to_ascii_lowercase().as_str() {
            "concave" => Some(Side::Concave),
            "convex" => Some(Side::Convex),
            "plane" | "flat" => Some(Side::Plane),
            _ => None,
        }
    }
}

/// One measured sample (one row of the table).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeasuredRow {
    /// Lead angle, degrees.
    pub lead_deg: f64,
    /// Curvature side.
    pub side: Side,
    /// Sample label (e.g. `S1`).
    pub sample: String,
    /// Ra, µm (when the table has the column).
    pub ra_um: Option<f64>,
    /// Rz, µm (when the table has the column).
    pub rz_um: Option<f64>,
    /// 1-based line in the file.
    pub line: u64,
}

/// Which roughness columns a table holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Columns {
    /// The table has `Ra_um`.
    pub ra: bool,
    /// The table has `Rz_um`.
    pub rz: bool,
}

/// A measured table: rows in file order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeasuredTable {
    /// Roughness columns present.
    pub columns: Columns,
    /// The rows.
    pub rows: Vec<MeasuredRow>,
}

/// Mean and sample standard deviation of a set of measurements.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stat {
    /// Number of samples.
    pub n: usize,
    /// Arithmetic mean.
    pub mean: f64,
    /// Sample standard deviation with the n − 1 (Bessel) convention, as 002 Table 2 prints
    /// it; `None` for a single sample.
    pub sd: Option<f64>,
}

impl Stat {
    /// Mean and sample standard deviation (n − 1) of `values`; `None` when empty.
    pub fn of(values: &[f64]) -> Option<Stat> {
        let n = values.len();
        if n == 0 {
            return None;
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        let sd = (n > 1).then(|| {
            let ss: f64 = values.iter().map(|v| (v - mean) * (v - mean)).sum();
            (ss / (n - 1) as f64).sqrt()
        });
        Some(Stat { n, mean, sd })
    }
}

/// The measurements of one case (lead angle and side), summarised.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeasuredCase {
    /// Lead angle, degrees.
    pub lead_deg: f64,
    /// Curvature side.
    pub side: Side,
    /// Sample labels in file order.
    pub samples: Vec<String>,
    /// Ra per sample, µm (file order).
    pub ra_values_um: Vec<f64>,
    /// Rz per sample, µm (file order).
    pub rz_values_um: Vec<f64>,
    /// Ra statistics, µm.
    pub ra: Option<Stat>,
    /// Rz statistics, µm.
    pub rz: Option<Stat>,
}

/// Group a table's rows by (lead, side) in order of first appearance and summarise them.
pub fn summarize(table: &MeasuredTable) -> Vec<MeasuredCase> {
    let mut cases: Vec<MeasuredCase> = Vec::new();
    for row in &table.rows {
        let pos = cases
            .iter()
            .position(|c| c.lead_deg == row.lead_deg && c.side == row.side);
        let case = match pos {
            Some(p) => &mut cases[p],
            None => {
                cases.push(MeasuredCase {
                    lead_deg: row.lead_deg,
                    side: row.side,
                    samples: Vec::new(),
                    ra_values_um: Vec::new(),
                    rz_values_um: Vec::new(),
                    ra: None,
                    rz: None,
                });
                let last = cases.len() - 1;
                &mut cases[last]
            }
        };
        case.samples.push(row.sample.clone());
        case.ra_values_um.extend(row.ra_um);
        case.rz_values_um.extend(row.rz_um);
    }
    for c in &mut cases {
        c.ra = Stat::of(&c.ra_values_um);
        c.rz = Stat::of(&c.rz_values_um);
    }
    cases
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn sigma_uses_n_minus_one() {
        let s = Stat::of(&[2.07, 2.29]).unwrap();
        assert_relative_eq!(s.mean, 2.18, epsilon = 1e-12);
        assert_relative_eq!(s.sd.unwrap(), 0.22 / 2f64.sqrt(), epsilon = 1e-12);
        assert!(Stat::of(&[1.0]).unwrap().sd.is_none());
        assert!(Stat::of(&[]).is_none());
    }
}
