//! Measured roughness: the rows of a measured table (one per case and sample, like 002 Table
//! 2), grouped into cases (lead angle, side) with their mean and sample standard deviation.
//! The CSV reader is [`crate::io::measured`].

use serde::Serialize;

/// The side of a curved part a case was measured on, or any other grouping label.
///
/// `concave`, `convex` and `plane` (or `flat`), in any case, carry physics (the curvature
/// correction of the crest model); any other label (e.g. `blade-tip`, `S-2`) only groups the
/// rows into cases and names them in tables and plots, exactly as written.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Side {
    /// Concave region: the surface curves around the tool.
    Concave,
    /// Convex region: the surface curves away from the tool.
    Convex,
    /// A plane (no curvature).
    Plane,
    /// Any other label: a plain grouping label, without curvature.
    Other(String),
}

impl Side {
    /// The name used in tables and files.
    pub fn name(&self) -> &str {
        match self {
            Side::Concave => "concave",
            Side::Convex => "convex",
            Side::Plane => "plane",
            Side::Other(label) => label,
        }
    }

    /// Read a side: `concave`, `convex`, `plane` or `flat` (any case), else the label as
    /// written (trimmed); `None` only for an empty label.
    pub fn parse(s: &str) -> Option<Side> {
        let t = s.trim();
        match t.to_ascii_lowercase().as_str() {
            "" => None,
            "concave" => Some(Side::Concave),
            "convex" => Some(Side::Convex),
            "plane" | "flat" => Some(Side::Plane),
            _ => Some(Side::Other(t.to_string())),
        }
    }

    /// Whether the side carries curvature (`concave` or `convex`).
    pub fn is_curved(&self) -> bool {
        matches!(self, Side::Concave | Side::Convex)
    }
}

impl std::fmt::Display for Side {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Serialize for Side {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for Side {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Side, D::Error> {
        let s = <String as serde::Deserialize>::deserialize(d)?;
        Side::parse(&s).ok_or_else(|| serde::de::Error::custom("empty side label"))
    }
}

/// A roughness parameter a measured table can hold: feed-direction profile Rz and Ra
/// (`Rz_um`, `Ra_um`), areal Sz and Sa (`Sz_um`, `Sa_um`) and stepover-direction profile Rz
/// and Ra (`Rz_stepover_um`, `Ra_stepover_um`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Param {
    /// Feed-direction profile Rz.
    Rz,
    /// Feed-direction profile Ra.
    Ra,
    /// Areal Sz.
    Sz,
    /// Areal Sa.
    Sa,
    /// Stepover-direction profile Rz.
    RzStepover,
    /// Stepover-direction profile Ra.
    RaStepover,
}

impl Param {
    /// Every parameter, in the order reports compare them.
    pub const ALL: [Param; 6] = [
        Param::Rz,
        Param::Ra,
        Param::Sz,
        Param::Sa,
        Param::RzStepover,
        Param::RaStepover,
    ];

    /// The column of the measured table.
    pub fn column(self) -> &'static str {
        match self {
            Param::Rz => "Rz_um",
            Param::Ra => "Ra_um",
            Param::Sz => "Sz_um",
            Param::Sa => "Sa_um",
            Param::RzStepover => "Rz_stepover_um",
            Param::RaStepover => "Ra_stepover_um",
        }
    }

    /// The name in reports (the `parameter` of a comparison).
    pub fn label(self) -> &'static str {
        match self {
            Param::Rz => "Rz",
            Param::Ra => "Ra",
            Param::Sz => "Sz",
            Param::Sa => "Sa",
            Param::RzStepover => "Rz stepover",
            Param::RaStepover => "Ra stepover",
        }
    }

    /// The parameter named `label`.
    pub fn from_label(label: &str) -> Option<Param> {
        Param::ALL.into_iter().find(|p| p.label() == label)
    }

    /// The stem of its plot file (`rz` → `rz.svg`).
    pub fn file_stem(self) -> &'static str {
        match self {
            Param::Rz => "rz",
            Param::Ra => "ra",
            Param::Sz => "sz",
            Param::Sa => "sa",
            Param::RzStepover => "rz-stepover",
            Param::RaStepover => "ra-stepover",
        }
    }

    /// Whether it is one of the parameters beyond feed-direction Rz and Ra.
    pub fn is_extra(self) -> bool {
        !matches!(self, Param::Rz | Param::Ra)
    }
}

/// Measured values of the parameters beyond feed-direction Rz and Ra (areal, stepover
/// direction), in [`Param::ALL`] order; absent ones are `None`.
pub type Extra<T> = [Option<T>; 4];

fn extra_index(p: Param) -> Option<usize> {
    match p {
        Param::Rz | Param::Ra => None,
        Param::Sz => Some(0),
        Param::Sa => Some(1),
        Param::RzStepover => Some(2),
        Param::RaStepover => Some(3),
    }
}

fn no_extra<T>(e: &Extra<T>) -> bool {
    e.iter().all(Option::is_none)
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
    /// Sz, Sa, stepover Rz, stepover Ra, µm (when the table has the columns).
    #[serde(skip_serializing_if = "no_extra")]
    pub extra_um: Extra<f64>,
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
    /// The table has `Sz_um`, `Sa_um`, `Rz_stepover_um`, `Ra_stepover_um`.
    #[serde(skip_serializing_if = "no_extra_columns")]
    pub extra: [bool; 4],
}

fn no_extra_columns(e: &[bool; 4]) -> bool {
    !e.iter().any(|b| *b)
}

impl Columns {
    /// Whether the table has the column of `p`.
    pub fn has(&self, p: Param) -> bool {
        match extra_index(p) {
            None if p == Param::Rz => self.rz,
            None => self.ra,
            Some(i) => self.extra[i],
        }
    }
}

impl MeasuredRow {
    /// The row's value of `p`, µm.
    pub fn value(&self, p: Param) -> Option<f64> {
        match extra_index(p) {
            None if p == Param::Rz => self.rz_um,
            None => self.ra_um,
            Some(i) => self.extra_um[i],
        }
    }
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
    /// Per sample values of Sz, Sa, stepover Rz, stepover Ra, µm (empty when absent).
    #[serde(skip_serializing_if = "no_extra_values")]
    pub extra_values_um: [Vec<f64>; 4],
    /// Their statistics, µm.
    #[serde(skip_serializing_if = "no_extra")]
    pub extra: Extra<Stat>,
}

fn no_extra_values(e: &[Vec<f64>; 4]) -> bool {
    e.iter().all(Vec::is_empty)
}

impl MeasuredCase {
    /// The per-sample values of `p`, µm (file order).
    pub fn values(&self, p: Param) -> &[f64] {
        match extra_index(p) {
            None if p == Param::Rz => &self.rz_values_um,
            None => &self.ra_values_um,
            Some(i) => &self.extra_values_um[i],
        }
    }

    /// The statistics of `p`, µm, when the case has values of it.
    pub fn stat(&self, p: Param) -> Option<Stat> {
        match extra_index(p) {
            None if p == Param::Rz => self.rz,
            None => self.ra,
            Some(i) => self.extra[i],
        }
    }
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
                    side: row.side.clone(),
                    samples: Vec::new(),
                    ra_values_um: Vec::new(),
                    rz_values_um: Vec::new(),
                    ra: None,
                    rz: None,
                    extra_values_um: Default::default(),
                    extra: [None; 4],
                });
                let last = cases.len() - 1;
                &mut cases[last]
            }
        };
        case.samples.push(row.sample.clone());
        case.ra_values_um.extend(row.ra_um);
        case.rz_values_um.extend(row.rz_um);
        for (values, v) in case.extra_values_um.iter_mut().zip(row.extra_um) {
            values.extend(v);
        }
    }
    for c in &mut cases {
        c.ra = Stat::of(&c.ra_values_um);
        c.rz = Stat::of(&c.rz_values_um);
        for i in 0..4 {
            c.extra[i] = Stat::of(&c.extra_values_um[i]);
        }
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
