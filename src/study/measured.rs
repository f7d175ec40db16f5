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
/// (`Rz_um`, `Ra_um`), areal Sz, Sa, Sq (`Sz_um`, `Sa_um`, `Sq_um`) and Sdq (`Sdq`, a
/// ratio) and stepover-direction profile Rz and Ra (`Rz_stepover_um`, `Ra_stepover_um`).
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
    /// Areal Sq.
    Sq,
    /// Areal Sdq (root mean square gradient, a ratio).
    Sdq,
}

impl Param {
    /// Every parameter, in the order reports compare them.
    pub const ALL: [Param; 8] = [
        Param::Rz,
        Param::Ra,
        Param::Sz,
        Param::Sa,
        Param::Sq,
        Param::Sdq,
        Param::RzStepover,
        Param::RaStepover,
    ];

    /// The parameters beyond feed-direction Rz and Ra, in the order of [`Extra`].
    pub const EXTRA: [Param; 6] = [
        Param::Sz,
        Param::Sa,
        Param::RzStepover,
        Param::RaStepover,
        Param::Sq,
        Param::Sdq,
    ];

    /// The parameters a measured file gives (feed-direction profile and areal).
    pub const FROM_FILE: [Param; 6] = [
        Param::Rz,
        Param::Ra,
        Param::Sz,
        Param::Sa,
        Param::Sq,
        Param::Sdq,
    ];

    /// The unit of its values (`µm`, or empty for the ratio Sdq).
    pub fn unit(self) -> &'static str {
        match self {
            Param::Sdq => "",
            _ => "µm",
        }
    }

    /// The column of the measured table.
    pub fn column(self) -> &'static str {
        match self {
            Param::Rz => "Rz_um",
            Param::Ra => "Ra_um",
            Param::Sz => "Sz_um",
            Param::Sa => "Sa_um",
            Param::RzStepover => "Rz_stepover_um",
            Param::RaStepover => "Ra_stepover_um",
            Param::Sq => "Sq_um",
            Param::Sdq => "Sdq",
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
            Param::Sq => "Sq",
            Param::Sdq => "Sdq",
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
            Param::Sq => "sq",
            Param::Sdq => "sdq",
        }
    }

    /// Whether it is one of the parameters beyond feed-direction Rz and Ra.
    pub fn is_extra(self) -> bool {
        !matches!(self, Param::Rz | Param::Ra)
    }
}

/// Measured values of the parameters beyond feed-direction Rz and Ra (areal, stepover
/// direction), in [`Param::EXTRA`] order; absent ones are `None`.
pub type Extra<T> = [Option<T>; 6];

fn extra_index(p: Param) -> Option<usize> {
    match p {
        Param::Rz | Param::Ra => None,
        Param::Sz => Some(0),
        Param::Sa => Some(1),
        Param::RzStepover => Some(2),
        Param::RaStepover => Some(3),
        Param::Sq => Some(4),
        Param::Sdq => Some(5),
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
    /// Sz, Sa, stepover Rz, stepover Ra, Sq (µm) and Sdq (when the table has the columns or
    /// the row names a measured file).
    #[serde(skip_serializing_if = "no_extra")]
    pub extra_um: Extra<f64>,
    /// The measured file the row names (`measured_file`), as written in the table.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measured_file: Option<String>,
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
    /// The table has `Sz_um`, `Sa_um`, `Rz_stepover_um`, `Ra_stepover_um`, `Sq_um`, `Sdq`
    /// (or, for those a measured file gives, a row that names one).
    #[serde(skip_serializing_if = "no_extra_columns")]
    pub extra: [bool; 6],
    /// The table has `measured_file`.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub file: bool,
}

fn no_extra_columns(e: &[bool; 6]) -> bool {
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
    /// The measured file of each sample as written in the table (empty when the row names
    /// none).
    #[serde(skip_serializing_if = "no_files")]
    pub files: Vec<String>,
    /// Ra per sample, µm (file order).
    pub ra_values_um: Vec<f64>,
    /// Rz per sample, µm (file order).
    pub rz_values_um: Vec<f64>,
    /// Ra statistics, µm.
    pub ra: Option<Stat>,
    /// Rz statistics, µm.
    pub rz: Option<Stat>,
    /// Per sample values of Sz, Sa, stepover Rz, stepover Ra, Sq (µm) and Sdq (empty when
    /// absent).
    #[serde(skip_serializing_if = "no_extra_values")]
    pub extra_values_um: [Vec<f64>; 6],
    /// Their statistics, µm.
    #[serde(skip_serializing_if = "no_extra")]
    pub extra: Extra<Stat>,
}

fn no_files(files: &[String]) -> bool {
    files.iter().all(String::is_empty)
}

fn no_extra_values(e: &[Vec<f64>; 6]) -> bool {
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

/// The sampling lengths of a measured file's feed-direction profiles (as `crest metrics
/// --profile` by default, and as the predictions: Rz is the mean of 5 peak-to-valley heights).
pub const FILE_SECTIONS: usize = 5;

/// The parameters of a measured height map, in [`Param::FROM_FILE`] order (Rz, Ra, Sz, Sa
/// in µm, Sq in µm, Sdq), with the predictions' filters: the least-squares plane removed
/// (the predictions lie on a plane) and no S- or L-filter (the predictions have none).
///
/// * Sz, Sa, Sq, Sdq: `crest metrics FILE --level plane` (areal, missing nodes left out).
/// * Rz, Ra along the feed (the map's x, its rows, as crest writes maps): the mean over the
///   rows of `crest metrics FILE --level plane --profile row:K` (each row levelled by its
///   own line, Rz over [`FILE_SECTIONS`] sampling lengths); rows without a valid value
///   (missing nodes) are left out.
pub fn measure_map(
    map: &crate::surface::HeightMap,
) -> Result<[f64; 6], crate::metrics::MetricsError> {
    use crate::metrics::{
        Level, MetricsError, ParamSet, Preprocess, ProfileSpec, areal_parameters, extract_profile,
        preprocess_map, preprocess_profile, profile_parameters,
    };
    let pp = Preprocess {
        level: Level::Plane,
        ..Preprocess::default()
    };
    let areal = areal_parameters(
        &preprocess_map(map, &pp)?,
        &ParamSet::parse("Sz,Sa,Sq,Sdq", false)?,
    )?;
    let set = ParamSet::parse("Rz,Ra", true)?;
    let (mut rz, mut ra, mut n) = (0.0, 0.0, 0usize);
    for k in 0..map.ny {
        let Ok(prof) = extract_profile(map, ProfileSpec::Row(k)) else {
            continue;
        };
        let Ok(prof) = preprocess_profile(&prof, &pp) else {
            continue;
        };
        let Ok(v) = profile_parameters(&prof, &set, FILE_SECTIONS) else {
            continue;
        };
        let of = |symbol: &str| {
            v.iter()
                .find(|(p, _)| p.symbol() == symbol)
                .map_or(f64::NAN, |(_, x)| *x)
        };
        let (z, a) = (of("Rz"), of("Ra"));
        if z.is_finite() && a.is_finite() {
            rz += z;
            ra += a;
            n += 1;
        }
    }
    if n == 0 {
        return Err(MetricsError::TooFew(
            "no row of the map gives Rz and Ra along the feed (x)".to_string(),
        ));
    }
    let a = |symbol: &str| {
        areal
            .iter()
            .find(|(p, _)| p.symbol() == symbol)
            .map_or(f64::NAN, |(_, v)| *v)
    };
    Ok([
        rz / n as f64,
        ra / n as f64,
        a("Sz"),
        a("Sa"),
        a("Sq"),
        a("Sdq"),
    ])
}

impl MeasuredRow {
    /// Fill the values a measured file gives (`values` as [`measure_map`] returns them) that
    /// the row does not hold itself: a number written beside the file is kept as written.
    pub fn fill_from_file(&mut self, values: &[f64; 6]) {
        for (p, v) in Param::FROM_FILE.into_iter().zip(values) {
            let slot = match extra_index(p) {
                None if p == Param::Rz => &mut self.rz_um,
                None => &mut self.ra_um,
                Some(i) => &mut self.extra_um[i],
            };
            if slot.is_none() {
                *slot = Some(*v);
            }
        }
    }
}

impl MeasuredTable {
    /// Mark the columns a measured file fills as present (after [`MeasuredRow::fill_from_file`]).
    pub fn note_file_columns(&mut self) {
        if !self.rows.iter().any(|r| r.measured_file.is_some()) {
            return;
        }
        self.columns.ra = true;
        self.columns.rz = true;
        for p in Param::FROM_FILE {
            if let Some(i) = extra_index(p) {
                self.columns.extra[i] = true;
            }
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
                    files: Vec::new(),
                    ra_values_um: Vec::new(),
                    rz_values_um: Vec::new(),
                    ra: None,
                    rz: None,
                    extra_values_um: Default::default(),
                    extra: [None; 6],
                });
                let last = cases.len() - 1;
                &mut cases[last]
            }
        };
        case.samples.push(row.sample.clone());
        case.files
            .push(row.measured_file.clone().unwrap_or_default());
        case.ra_values_um.extend(row.ra_um);
        case.rz_values_um.extend(row.rz_um);
        for (values, v) in case.extra_values_um.iter_mut().zip(row.extra_um) {
            values.extend(v);
        }
    }
    for c in &mut cases {
        c.ra = Stat::of(&c.ra_values_um);
        c.rz = Stat::of(&c.rz_values_um);
        for (stat, values) in c.extra.iter_mut().zip(&c.extra_values_um) {
            *stat = Stat::of(values);
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
