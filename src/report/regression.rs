//! Regression reports: simulated roughness held against measured confocal tables.
//!
//! A *measured table* is a CSV with one row per case and sample (`lead_deg,side,sample,
//! Ra_um,Rz_um`, like 002 Table 2). A *study* (TOML) describes the cases: the tool file,
//! the run-out, the feed per tooth, the lead angle, the curvature side and the model that
//! predicts the surface. For every case the report computes the simulated Rz, Ra and crest
//! height, compares them with the measured mean ± σ (sample standard deviation, n − 1), and
//! marks each comparison pass or fail against a tolerance in percent of the measured mean.
//!
//! Models:
//! * `crest`: the closed-form model of 002 §3.3. The participating teeth (Eq 8, the paper's
//!   rule) are found from the tooth radii at the generating height, the feed mark spacing is
//!   fz_eff = fz·Z/zc (Eq 7), and the feed-direction profile is the periodic sequence of
//!   circular arcs of the tool radius spaced fz_eff. Its crest is Eq 14; Rz and Ra are
//!   computed on that profile (see [`profile_roughness`]).
//!
//! The writers render `report.md` and `report.html` (with inline SVG plots) from a
//! [`Regression`]; they compute no physics. Everything here is pure: the CLI reads the
//! files and writes the outputs atomically.

use crate::tool::{Cutter, crest_height_mm};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// The default tolerance of `crest report`, percent of the measured mean.
pub const DEFAULT_TOLERANCE_PCT: f64 = 20.0;

/// Profile sampling step of the simulated profile, mm (0.5 µm).
pub const PROFILE_STEP_MM: f64 = 0.0005;

/// Errors from measured tables and studies.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
pub enum ReportError {
    /// A value in the measured table could not be read.
    #[error("{file}:{line}:{column}: column `{name}`: {message}")]
    Cell {
        /// File name as given.
        file: String,
        /// 1-based line.
        line: u64,
        /// 1-based character column of the field.
        column: usize,
        /// Column name.
        name: String,
        /// What was wrong.
        message: String,
    },
    /// A malformed line in the measured table.
    #[error("{file}:{line}: {message}")]
    Line {
        /// File name as given.
        file: String,
        /// 1-based line.
        line: u64,
        /// What was wrong.
        message: String,
    },
    /// The header lacks required columns.
    #[error(
        "{file}:{line}: missing column(s) {missing}; the header must name lead_deg, side, sample and at least one of Ra_um, Rz_um"
    )]
    MissingColumns {
        /// File name as given.
        file: String,
        /// Line of the header.
        line: u64,
        /// The missing column names, comma separated.
        missing: String,
    },
    /// A study that parses but does not make sense, or does not match the table.
    #[error("{file}: {message}")]
    Study {
        /// File name as given.
        file: String,
        /// What was wrong.
        message: String,
    },
}

// ---------------------------------------------------------------------------------------
// Measured tables

/// The side of a curved part a case was measured on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
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

    fn parse(s: &str) -> Option<Side> {
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

const KNOWN_COLUMNS: [&str; 5] = ["lead_deg", "side", "sample", "Ra_um", "Rz_um"];

/// The 1-based line where a record starts: the csv crate may place a record that follows
/// blank or comment lines at the first of them, so skip those from its byte offset.
fn line_of_record(text: &str, pos: &csv::Position) -> u64 {
    let bytes = text.as_bytes();
    let mut at = usize::try_from(pos.byte())
        .unwrap_or(usize::MAX)
        .min(bytes.len());
    // Skip blank and comment lines (the record's offset may point at them).
    while at < bytes.len() {
        match bytes[at] {
            b'\n' | b'\r' => at += 1,
            b'#' => {
                at = bytes[at..]
                    .iter()
                    .position(|b| *b == b'\n')
                    .map_or(bytes.len(), |p| at + p + 1);
            }
            _ => break,
        }
    }
    1 + bytes[..at].iter().filter(|b| **b == b'\n').count() as u64
}

/// The 1-based character column where field `index` of a raw CSV line starts.
fn field_column(raw: &str, index: usize) -> usize {
    let mut field = 0;
    let mut in_quotes = false;
    for (col, ch) in raw.chars().enumerate() {
        if field == index {
            return col + 1;
        }
        match ch {
            '"' => in_quotes = !in_quotes,
            ',' if !in_quotes => field += 1,
            _ => {}
        }
    }
    raw.chars().count() + 1
}

/// Parse a measured table from CSV text. `file` names the file in error messages.
///
/// Lines starting with `#` are comments. The header must hold `lead_deg`, `side`,
/// `sample` and at least one of `Ra_um`, `Rz_um`, in any order; other columns are errors
/// (a misspelt unit must not be ignored). `side` is `concave`, `convex` or `plane`.
/// Roughness values must be finite and non-negative; each (lead, side, sample) appears once.
pub fn parse_measured(text: &str, file: &str) -> Result<MeasuredTable, ReportError> {
    let raw_lines: Vec<&str> = text.lines().collect();
    let raw_line = |line: u64| -> &str {
        usize::try_from(line)
            .ok()
            .and_then(|l| raw_lines.get(l.saturating_sub(1)))
            .copied()
            .unwrap_or("")
    };
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(text.as_bytes());
    let csv_err = |e: csv::Error| {
        let line = e.position().map(|p| p.line()).unwrap_or(0);
        ReportError::Line {
            file: file.to_string(),
            line,
            message: format!("not valid CSV: {e}"),
        }
    };
    let headers = reader.headers().map_err(csv_err)?.clone();
    let header_line = headers
        .position()
        .map(|p| line_of_record(text, p))
        .unwrap_or(1);
    if headers.is_empty() || headers.iter().all(|h| h.is_empty()) {
        return Err(ReportError::MissingColumns {
            file: file.to_string(),
            line: header_line,
            missing: "lead_deg, side, sample, Ra_um, Rz_um".to_string(),
        });
    }
    let mut index: BTreeMap<&str, usize> = BTreeMap::new();
    for (i, h) in headers.iter().enumerate() {
        let Some(known) = KNOWN_COLUMNS.iter().find(|k| **k == h) else {
            return Err(ReportError::Cell {
                file: file.to_string(),
                line: header_line,
                column: field_column(raw_line(header_line), i),
                name: h.to_string(),
                message: format!(
                    "unknown column; expected one of {} (units in the name)",
                    KNOWN_COLUMNS.join(", ")
                ),
            });
        };
        if index.insert(known, i).is_some() {
            return Err(ReportError::Cell {
                file: file.to_string(),
                line: header_line,
                column: field_column(raw_line(header_line), i),
                name: h.to_string(),
                message: "column given twice".to_string(),
            });
        }
    }
    let mut missing: Vec<&str> = ["lead_deg", "side", "sample"]
        .into_iter()
        .filter(|c| !index.contains_key(c))
        .collect();
    let columns = Columns {
        ra: index.contains_key("Ra_um"),
        rz: index.contains_key("Rz_um"),
    };
    if !columns.ra && !columns.rz {
        missing.push("Ra_um or Rz_um");
    }
    if !missing.is_empty() {
        return Err(ReportError::MissingColumns {
            file: file.to_string(),
            line: header_line,
            missing: missing.join(", "),
        });
    }

    let mut rows: Vec<MeasuredRow> = Vec::new();
    for record in reader.records() {
        let record = record.map_err(csv_err)?;
        let line = record
            .position()
            .map(|p| line_of_record(text, p))
            .unwrap_or(0);
        if record.iter().all(|f| f.is_empty()) {
            continue;
        }
        if record.len() != headers.len() {
            return Err(ReportError::Line {
                file: file.to_string(),
                line,
                message: format!(
                    "{} field(s) where the header has {}",
                    record.len(),
                    headers.len()
                ),
            });
        }
        let cell = |name: &str| -> (usize, &str) {
            let i = index[name];
            (i, record.get(i).unwrap_or(""))
        };
        let bad = |name: &str, i: usize, message: String| ReportError::Cell {
            file: file.to_string(),
            line,
            column: field_column(raw_line(line), i),
            name: name.to_string(),
            message,
        };
        let number = |name: &str, nonneg: bool| -> Result<f64, ReportError> {
            let (i, s) = cell(name);
            let v: f64 = s
                .parse()
                .map_err(|_| bad(name, i, format!("expected a number, found `{s}`")))?;
            if !v.is_finite() || (nonneg && v < 0.0) {
                return Err(bad(
                    name,
                    i,
                    format!("expected a finite non-negative number, found `{s}`"),
                ));
            }
            Ok(v)
        };
        let lead_deg = number("lead_deg", false)?;
        if !(-90.0..=90.0).contains(&lead_deg) {
            let (i, s) = cell("lead_deg");
            return Err(bad(
                "lead_deg",
                i,
                format!("lead angle must lie in [-90, 90] degrees, found `{s}`"),
            ));
        }
        let (si, s) = cell("side");
        let side = Side::parse(s).ok_or_else(|| {
            bad(
                "side",
                si,
                format!("expected concave, convex or plane, found `{s}`"),
            )
        })?;
        let (pi, sample) = cell("sample");
        if sample.is_empty() {
            return Err(bad("sample", pi, "empty sample label".to_string()));
        }
        let ra_um = if columns.ra {
            Some(number("Ra_um", true)?)
        } else {
            None
        };
        let rz_um = if columns.rz {
            Some(number("Rz_um", true)?)
        } else {
            None
        };
        if let Some(prev) = rows
            .iter()
            .find(|r| r.lead_deg == lead_deg && r.side == side && r.sample == sample)
        {
            return Err(bad(
                "sample",
                pi,
                format!(
                    "sample `{sample}` of lead {lead_deg}°, {} given twice (first on line {})",
                    side.name(),
                    prev.line
                ),
            ));
        }
        rows.push(MeasuredRow {
            lead_deg,
            side,
            sample: sample.to_string(),
            ra_um,
            rz_um,
            line,
        });
    }
    if rows.is_empty() {
        return Err(ReportError::Line {
            file: file.to_string(),
            line: header_line,
            message: "the table has a header but no data rows".to_string(),
        });
    }
    Ok(MeasuredTable { columns, rows })
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

// ---------------------------------------------------------------------------------------
// Studies

/// Which model predicts a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Model {
    /// Closed-form crest model: participating teeth (002 Eq 8, paper rule), fz_eff (Eq 7),
    /// Eq 14, and the periodic arc profile.
    #[default]
    Crest,
    /// Z-map simulation (`crate::surface`) of one straight pass over a plane at the case's
    /// lead, with the tool's edges (ICE) or bodies (dome); Rz and Ra on the centre line.
    Simulate,
}

impl Model {
    /// The name used in studies.
    pub fn name(self) -> &'static str {
        match self {
            Model::Crest => "crest",
            Model::Simulate => "simulate",
        }
    }
}

/// The surface model of the `simulate` model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SurfaceModel {
    /// Pondered movement: the teeth's edges sweep between spindle steps (002 §2.4.2).
    #[default]
    Ice,
    /// Instantaneous positions: the revolved body of each tooth every fz (002 §2.4.1).
    Dome,
}

/// `[simulate]` settings of a study (used by cases with `model = "simulate"`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulateSpec {
    /// `ice` (default) or `dome`.
    #[serde(default)]
    pub surface_model: SurfaceModel,
    /// Grid spacing, µm (default 1).
    #[serde(default = "default_grid_um")]
    pub grid_um: f64,
    /// Largest spindle step of the ICE model, degrees (default 0.5).
    #[serde(default = "default_dtheta_deg")]
    pub dtheta_deg: f64,
}

fn default_grid_um() -> f64 {
    1.0
}

fn default_dtheta_deg() -> f64 {
    0.5
}

impl Default for SimulateSpec {
    fn default() -> Self {
        SimulateSpec {
            surface_model: SurfaceModel::Ice,
            grid_um: default_grid_um(),
            dtheta_deg: default_dtheta_deg(),
        }
    }
}

/// Which rule decides the participating teeth (model.md §3.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Rule {
    /// 002 Eq 8: r_j(z_c) > max r − hc(nominal fz) (reproduces 002's fz_eff = 0.2 mm).
    #[default]
    Paper,
    /// The exact one-dimensional envelope of the teeth's marks.
    Exact,
}

impl Rule {
    /// The name used in studies.
    pub fn name(self) -> &'static str {
        match self {
            Rule::Paper => "paper",
            Rule::Exact => "exact",
        }
    }

    fn to_tool(self) -> crate::tool::Rule {
        match self {
            Rule::Paper => crate::tool::Rule::Paper,
            Rule::Exact => crate::tool::Rule::Exact,
        }
    }
}

/// Run-out as written in TOML (the `[runout]` table of a tool file), interface units.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunoutSpec {
    /// e0, µm.
    #[serde(default)]
    pub offset_um: f64,
    /// φ_e, degrees.
    #[serde(default)]
    pub offset_phase_deg: f64,
    /// τ, degrees.
    #[serde(default)]
    pub axis_tilt_deg: f64,
    /// φ_τ, degrees.
    #[serde(default)]
    pub axis_tilt_phase_deg: f64,
    /// δ_j, µm, one per tooth (empty = all zero).
    #[serde(default)]
    pub tooth_radius_deviation_um: Vec<f64>,
}

impl RunoutSpec {
    /// The run-out in internal units (mm, rad).
    pub fn to_runout(&self) -> crate::tool::Runout {
        crate::tool::Runout {
            offset_mm: self.offset_um * 1e-3,
            offset_phase_rad: self.offset_phase_deg.to_radians(),
            tilt_rad: self.axis_tilt_deg.to_radians(),
            tilt_phase_rad: self.axis_tilt_phase_deg.to_radians(),
            tooth_radius_dev_mm: self
                .tooth_radius_deviation_um
                .iter()
                .map(|d| d * 1e-3)
                .collect(),
        }
    }
}

/// One case of a study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyCase {
    /// Lead angle (tool tilt in the feed direction), degrees.
    pub lead_deg: f64,
    /// Curvature side; matches the `side` column of the measured table.
    pub side: Side,
    /// Local radius of curvature of the surface in the feed direction, mm. Absent = plane.
    #[serde(default)]
    pub surface_radius_mm: Option<f64>,
    /// Feed per tooth for this case, mm (overrides the study's `fz_mm`).
    #[serde(default)]
    pub fz_mm: Option<f64>,
    /// Model for this case (overrides the study's `model`).
    #[serde(default)]
    pub model: Option<Model>,
}

/// A study: the cases of a measured table and how to predict them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Study {
    /// Title of the report.
    pub title: String,
    /// Where the measurements come from.
    #[serde(default)]
    pub source: Option<String>,
    /// Tool TOML file, relative to the study file.
    pub tool: String,
    /// Default model.
    #[serde(default)]
    pub model: Model,
    /// Programmed feed per tooth, mm.
    pub fz_mm: f64,
    /// Rule for the participating teeth (`paper` by default, or `exact`).
    #[serde(default)]
    pub rule: Rule,
    /// Depth of cut along the normal, mm (for the effective radius, 002 Table 3).
    pub ap_mm: f64,
    /// Nominal cutting speed, m/min (informative).
    #[serde(default)]
    pub cutting_speed_m_min: Option<f64>,
    /// Run-out; when present it replaces the tool file's `[runout]` table entirely.
    #[serde(default)]
    pub runout: Option<RunoutSpec>,
    /// Settings of the `simulate` model.
    #[serde(default)]
    pub simulate: Option<SimulateSpec>,
    /// Free text (Markdown paragraphs) printed in the report's discussion.
    #[serde(default)]
    pub notes: Option<String>,
    /// The cases.
    #[serde(rename = "case")]
    pub cases: Vec<StudyCase>,
}

/// Parse a study from TOML text; `file` names the file in error messages. Unknown keys,
/// missing keys and impossible values are errors (toml reports line and column).
pub fn parse_study(text: &str, file: &str) -> Result<Study, ReportError> {
    let study: Study = toml::from_str(text).map_err(|e| ReportError::Study {
        file: file.to_string(),
        message: e.to_string().trim_end().to_string(),
    })?;
    let err = |message: String| ReportError::Study {
        file: file.to_string(),
        message,
    };
    if !(study.fz_mm.is_finite() && study.fz_mm > 0.0) {
        return Err(err(format!(
            "fz_mm must be positive, found {}",
            study.fz_mm
        )));
    }
    if !(study.ap_mm.is_finite() && study.ap_mm >= 0.0) {
        return Err(err(format!(
            "ap_mm must be a non-negative number, found {}",
            study.ap_mm
        )));
    }
    if let Some(sim) = &study.simulate {
        if !(sim.grid_um.is_finite() && sim.grid_um >= 0.1 && sim.grid_um <= 50.0) {
            return Err(err(format!(
                "[simulate] grid_um must lie in [0.1, 50], found {}",
                sim.grid_um
            )));
        }
        if !(sim.dtheta_deg.is_finite() && sim.dtheta_deg > 0.0 && sim.dtheta_deg <= 10.0) {
            return Err(err(format!(
                "[simulate] dtheta_deg must lie in (0, 10], found {}",
                sim.dtheta_deg
            )));
        }
    }
    if study.cases.is_empty() {
        return Err(err("the study has no [[case]]".to_string()));
    }
    for (i, c) in study.cases.iter().enumerate() {
        let n = i + 1;
        if !(c.lead_deg.is_finite() && (0.0..90.0).contains(&c.lead_deg)) {
            return Err(err(format!(
                "case {n}: lead_deg must lie in [0, 90), found {}",
                c.lead_deg
            )));
        }
        if let Some(f) = c.fz_mm
            && !(f.is_finite() && f > 0.0)
        {
            return Err(err(format!("case {n}: fz_mm must be positive, found {f}")));
        }
        if let Some(rs) = c.surface_radius_mm {
            if !(rs.is_finite() && rs > 0.0) {
                return Err(err(format!(
                    "case {n}: surface_radius_mm must be positive, found {rs}"
                )));
            }
            if c.side == Side::Plane {
                return Err(err(format!(
                    "case {n}: surface_radius_mm is given but side is plane"
                )));
            }
        }
        if let Some(j) = study.cases[..i]
            .iter()
            .position(|d| d.lead_deg == c.lead_deg && d.side == c.side)
        {
            return Err(err(format!(
                "case {n} repeats case {} (lead {}°, {})",
                j + 1,
                c.lead_deg,
                c.side.name()
            )));
        }
    }
    Ok(study)
}

// ---------------------------------------------------------------------------------------
// The crest model

/// What the `crest` model predicts for one case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CrestPrediction {
    /// Rule that decided the participating teeth.
    pub rule: String,
    /// Height of the generating point above the tip, mm: R(1 − cos β) for a ball on a plane.
    pub generating_height_mm: f64,
    /// Local radius of every tooth at the generating height, mm (tooth 1 first).
    pub tooth_radius_mm: Vec<f64>,
    /// Participating teeth, 1-based, in cutting order.
    pub teeth: Vec<usize>,
    /// Number of participating teeth zc.
    pub zc: usize,
    /// Nominal crest (Eq 14 with the programmed fz), µm: the threshold of Eq 8.
    pub nominal_crest_um: f64,
    /// Effective (mean) feed mark spacing fz·Z/zc, mm.
    pub fz_eff_mm: f64,
    /// Radius of the profile arcs of a ball end, mm (R on a plane; R·Rs/(Rs ± R) when curved).
    pub arc_radius_mm: f64,
    /// Crest height between marks, µm: Eq 14 at fz_eff (paper rule) or the exact
    /// envelope's crest (exact rule), on the curved profile when a surface radius is given.
    pub crest_um: f64,
    /// Rz of the simulated profile, µm (mean of 5 sampling lengths).
    pub rz_um: f64,
    /// Ra of the simulated profile, µm.
    pub ra_um: f64,
    /// Sampling length λc used for the profile, mm.
    pub sampling_length_mm: f64,
    /// R_ef,max of the nominal tool for the lead and ap (002 Table 3), mm.
    pub effective_radius_mm: f64,
    /// Radius of the generating point (R sin β for a ball), mm.
    pub contact_radius_mm: f64,
    /// Cutting-speed ratio R_ef,max / R (002 Table 3 "Vc,ef max" / 100).
    pub cutting_speed_ratio: f64,
}

/// ISO 4288 sampling length (λc) for a periodic profile of mean spacing `rsm_mm`, mm.
pub fn sampling_length_mm(rsm_mm: f64) -> f64 {
    match rsm_mm {
        s if s <= 0.04 => 0.08,
        s if s <= 0.13 => 0.25,
        s if s <= 0.4 => 0.8,
        s if s <= 1.3 => 2.5,
        _ => 8.0,
    }
}

/// Rz and Ra (µm) of a profile sampled every `dx_mm`, evaluated over 5 sampling lengths
/// of `lc_mm` (the samples must cover 5·λc): Ra = mean |z − z̄|, Rz = mean of the five
/// peak-to-valley heights (002 Eq 15). No filter: the caller's profile has no form.
pub fn rz_ra(heights_um: &[f64], dx_mm: f64, lc_mm: f64) -> (f64, f64) {
    let n = heights_um.len();
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let mean = heights_um.iter().sum::<f64>() / n as f64;
    let ra = heights_um.iter().map(|h| (h - mean).abs()).sum::<f64>() / n as f64;
    let per_len = ((lc_mm / dx_mm).round() as usize).max(1);
    let mut rz_sum = 0.0;
    for part in 0..5 {
        let lo = (part * per_len).min(n - 1);
        let hi = ((part + 1) * per_len).min(n - 1);
        let seg = &heights_um[lo..=hi];
        let max = seg.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let min = seg.iter().copied().fold(f64::INFINITY, f64::min);
        rz_sum += max - min;
    }
    (rz_sum / 5.0, ra)
}

/// A periodic feed-direction profile: period `period_mm`, one height (mm) per position in
/// the period. Returns (Rz µm, Ra µm, λc mm, peak-to-valley over one period µm).
///
/// The period is sampled in an even number of steps of at most [`PROFILE_STEP_MM`] (so
/// that the crest between two evenly spaced marks is a sample), and the profile repeated
/// over 5 sampling lengths λc chosen by ISO 4288 from `rsm_mm`.
fn periodic_roughness(
    period_mm: f64,
    rsm_mm: f64,
    height_mm: &dyn Fn(f64) -> f64,
) -> (f64, f64, f64, f64) {
    let lc = sampling_length_mm(rsm_mm);
    let total = 5.0 * lc;
    let mut steps = 2.0 * (0.5 * period_mm / PROFILE_STEP_MM).ceil().max(1.0);
    // Keep the evaluation under ~2 M points even for tiny periods.
    while total / (period_mm / steps) > 2.0e6 && steps > 2.0 {
        steps = 2.0 * (0.25 * steps).ceil();
    }
    let dx = period_mm / steps;
    let m = steps as usize;
    let one: Vec<f64> = (0..m).map(|i| height_mm(i as f64 * dx)).collect();
    let lo = one.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = one.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let n = (total / dx).round().max(1.0) as usize;
    let heights: Vec<f64> = (0..=n).map(|i| (one[i % m] - lo) * 1e3).collect();
    let (rz, ra) = rz_ra(&heights, dx, lc);
    (rz, ra, lc, (hi - lo) * 1e3)
}

/// Rz and Ra (µm) of the periodic profile of circular arcs of radius `radius_mm` whose
/// lowest points are `spacing_mm` apart, and the sampling length used (mm).
///
/// The profile is sampled every [`PROFILE_STEP_MM`] or finer (so that every crest and every
/// valley is a sample) over 5 sampling lengths λc chosen by ISO 4288 from RSm = spacing. It
/// has no form and no waviness, so no filter is applied: Ra is the mean |z − z̄| over the
/// evaluation length and Rz the mean of the 5 peak-to-valley heights (002 Eq 15). For
/// sampling lengths that hold a whole crest Rz equals the crest of Eq 14, and Ra tends to
/// 4/(9√3) = 0.2566 times it for small spacing.
pub fn profile_roughness(radius_mm: f64, spacing_mm: f64) -> (f64, f64, f64) {
    let arc = |u: f64| {
        let d = if u > 0.5 * spacing_mm {
            spacing_mm - u
        } else {
            u
        };
        crest_height_mm(radius_mm, 2.0 * d)
    };
    let (rz, ra, lc, _) = periodic_roughness(spacing_mm, spacing_mm, &arc);
    (rz, ra, lc)
}

/// The `crest` model for one case: `cutter` (with its run-out) at lead `lead_deg`, depth of
/// cut `ap_mm` and `fz_mm` per tooth, on a plane or on a surface of local radius
/// `surface_radius_mm` (feed direction) on `side`; teeth by `rule`.
///
/// * [`crate::tool::analyse`] gives the generating height, the local tooth radii, the
///   participating teeth, fz_eff = fz·Z/zc (Eq 7) and the crest (Eq 14 at fz_eff for the
///   paper rule, the exact envelope for the exact rule), and the effective radius.
/// * The feed-direction profile: paper rule, the nominal profile repeated every fz_eff;
///   exact rule, the lower envelope of every tooth's profile (its normal deviation included)
///   at its own mark positions, period Z·fz. Rz and Ra are computed on it (see
///   [`profile_roughness`]).
/// * On a curved surface of radius Rs (ball end only) the arcs take the relative radius
///   R·Rs/(Rs ± R) (+ convex, − concave), so hc ≈ fz_eff²/8·(1/R ± 1/Rs), the curved-surface
///   correction of model.md §7, with the marks fz_eff apart on the surface (second order in
///   the spacing; exact on a plane).
pub fn crest_model(
    cutter: &Cutter,
    lead_deg: f64,
    ap_mm: f64,
    fz_mm: f64,
    rule: Rule,
    side: Side,
    surface_radius_mm: Option<f64>,
) -> Result<CrestPrediction, String> {
    use crate::tool::{FeedProfile, feed_profile, mark_positions_mm, normal_deviation_mm};
    let a = crate::tool::analyse(cutter, lead_deg, ap_mm, fz_mm, rule.to_tool())
        .map_err(|e| e.to_string())?;
    let r = cutter.radius_mm;
    let is_ball = matches!(cutter.shape, crate::tool::Shape::Ball);
    let arc_radius = match (side, surface_radius_mm) {
        (Side::Plane, _) | (_, None) => r,
        (_, Some(_)) if !is_ball => {
            return Err("the curvature correction needs a ball-end tool".to_string());
        }
        (Side::Convex, Some(rs)) => r * rs / (rs + r),
        (Side::Concave, Some(rs)) => {
            if rs <= r {
                return Err(format!(
                    "a concave surface of radius {rs} mm is tighter than the tool radius {r} mm"
                ));
            }
            r * rs / (rs - r)
        }
    };
    let lead = lead_deg.to_radians();
    let profile = if is_ball {
        FeedProfile::Circle {
            radius_mm: arc_radius,
        }
    } else {
        feed_profile(r, cutter.corner_radius_mm(), lead)
    };
    let fz_eff = a.fz_effective_mm;
    let (rz, ra, lc, crest_mm) = match rule {
        Rule::Paper => {
            let h = |u: f64| {
                (-1..=2)
                    .map(|k| profile.height(u - f64::from(k) * fz_eff))
                    .fold(f64::INFINITY, f64::min)
            };
            let (rz, ra, lc, p2v) = periodic_roughness(fz_eff, fz_eff, &h);
            let crest = if arc_radius == r {
                a.crest_height_corrected_mm
            } else {
                p2v * 1e-3
            };
            (rz, ra, lc, crest)
        }
        Rule::Exact => {
            let period = cutter.teeth() as f64 * fz_mm;
            let pos = mark_positions_mm(cutter, fz_mm);
            let dev: Vec<f64> = (0..cutter.teeth())
                .map(|j| normal_deviation_mm(cutter, j, a.generating_height_mm, lead))
                .collect();
            let h = |u: f64| {
                let mut best = f64::INFINITY;
                for (p, d) in pos.iter().zip(&dev) {
                    for k in [-1.0, 0.0, 1.0] {
                        let x = u - p.rem_euclid(period) - k * period;
                        let v = match profile {
                            FeedProfile::Circle { radius_mm } => FeedProfile::Circle {
                                radius_mm: (radius_mm + d).max(0.0),
                            }
                            .height(x),
                            _ => profile.height(x),
                        } - d;
                        best = best.min(v);
                    }
                }
                best
            };
            let (rz, ra, lc, p2v) = periodic_roughness(period, fz_eff, &h);
            let crest = if arc_radius == r {
                a.crest_height_exact_mm
            } else {
                p2v * 1e-3
            };
            (rz, ra, lc, crest)
        }
    };
    Ok(CrestPrediction {
        rule: rule.name().to_string(),
        generating_height_mm: a.generating_height_mm,
        tooth_radius_mm: a.teeth.iter().map(|t| t.local_radius_mm).collect(),
        teeth: a
            .teeth
            .iter()
            .filter(|t| t.participates)
            .map(|t| t.index)
            .collect(),
        zc: a.zc,
        nominal_crest_um: a.crest_height_mm * 1e3,
        fz_eff_mm: fz_eff,
        arc_radius_mm: arc_radius,
        crest_um: crest_mm * 1e3,
        rz_um: rz,
        ra_um: ra,
        sampling_length_mm: lc,
        effective_radius_mm: a.effective_radius_mm,
        contact_radius_mm: a.contact_radius_mm,
        cutting_speed_ratio: a.cutting_speed_ratio,
    })
}

/// What the `simulate` model predicts for one case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ZmapPrediction {
    /// Surface model (`ice` or `dome`).
    pub surface_model: SurfaceModel,
    /// Grid spacing, µm.
    pub grid_um: f64,
    /// Largest spindle step, degrees (ICE).
    pub dtheta_deg: f64,
    /// Length of the evaluated centre-line profile, mm (5 sampling lengths).
    pub evaluation_length_mm: f64,
    /// Rz of the centre-line profile, µm (mean of 5 sampling lengths).
    pub rz_um: f64,
    /// Ra of the centre-line profile, µm.
    pub ra_um: f64,
    /// Peak-to-valley height of the whole profile, µm.
    pub pv_um: f64,
    /// Grid nodes computed.
    pub nodes: usize,
}

/// The `simulate` model: one straight pass along +x over the plane z = 0, the tool axis
/// tilted by the lead in the feed plane (model.md §1.2: axis = (sin β, 0, cos β)), spindle
/// phase 0 at the start, fz per tooth; a window 5λc long (λc from RSm = `rsm_mm`) and five
/// nodes wide on the pass centre is simulated with `crate::surface::simulate`, and Rz, Ra
/// are computed on its centre row as for the crest model (no filter; the plane has no form).
pub fn simulate_case(
    cutter: &Cutter,
    lead_deg: f64,
    ap_mm: f64,
    fz_mm: f64,
    rsm_mm: f64,
    spec: &SimulateSpec,
) -> Result<ZmapPrediction, String> {
    use crate::math::{Point3, Vec3};
    use crate::resample::Sample;
    use crate::surface::{GridSpec, Model as Zmodel, Options, simulate};
    use std::f64::consts::TAU;
    let lc = sampling_length_mm(rsm_mm);
    let eval = 5.0 * lc;
    let teeth = cutter.teeth() as f64;
    // The tool's marks reach a few revolutions back; the ball's sag does the rest.
    let margin = 0.5 + 3.0 * teeth * fz_mm;
    let lead = lead_deg.to_radians();
    let axis = Vec3::new(lead.sin(), 0.0, lead.cos());
    // Tool tip that puts the lowest point of the body on z = 0 at contact c.
    let rc = cutter.corner_radius_mm();
    let rd = cutter.radius_mm - rc;
    let z = Vec3::z();
    let down = -(z - axis * axis.z);
    let e = if down.norm() < 1e-12 {
        Vec3::zeros()
    } else {
        down.normalize()
    };
    let tip = |c: Point3| c - axis * rc - e * rd + z * rc;
    // Samples every 10° of spindle; the engine subdivides to Δθ.
    let ds = teeth * fz_mm * 10.0 / 360.0;
    let length = eval + 2.0 * margin;
    let n = (length / ds).ceil() as usize;
    if n > 2_000_000 {
        return Err(format!(
            "the simulated pass needs {n} samples; fz is too small"
        ));
    }
    let samples: Vec<Sample> = (0..=n)
        .map(|k| {
            let s = k as f64 * ds;
            let c = Point3::new(s - margin, 0.0, 0.0);
            Sample {
                run: 0,
                s_mm: s,
                t_s: 0.0,
                theta_rad: TAU * s / (teeth * fz_mm),
                position: tip(c),
                axis,
                contact: Some(c),
                normal: Some(z),
                feed_dir: Vec3::x(),
                feed_mm_min: 1000.0,
            }
        })
        .collect();
    let dx = spec.grid_um * 1e-3;
    let grid = GridSpec::Window {
        x0_mm: 0.0,
        y0_mm: -2.0 * dx,
        x1_mm: eval,
        y1_mm: 2.0 * dx,
    };
    let model = match spec.surface_model {
        SurfaceModel::Ice => Zmodel::Ice {
            dtheta_rad: spec.dtheta_deg.to_radians(),
        },
        SurfaceModel::Dome => Zmodel::Dome,
    };
    let mut opts = Options::new(model, grid, dx);
    opts.depth_mm = ap_mm.max(dx);
    let sim = simulate(&samples, cutter, &opts, &|_, _| {}).map_err(|e| e.to_string())?;
    let map = &sim.map;
    if map.ny == 0 || map.nx < 2 {
        return Err("the simulated window is empty".to_string());
    }
    let row = map.row(map.ny / 2);
    if row.iter().any(|h| !h.is_finite()) {
        return Err("the simulated centre line has nodes no tooth reached".to_string());
    }
    let dx_mm = map.dx_um * 1e-3;
    let (rz, ra) = rz_ra(row, dx_mm, lc);
    let lo = row.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = row.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Ok(ZmapPrediction {
        surface_model: spec.surface_model,
        grid_um: map.dx_um,
        dtheta_deg: spec.dtheta_deg,
        evaluation_length_mm: (row.len() - 1) as f64 * dx_mm,
        rz_um: rz,
        ra_um: ra,
        pv_um: hi - lo,
        nodes: sim.nodes_cut,
    })
}

// ---------------------------------------------------------------------------------------
// Comparison

/// One parameter of one case held against its measurement.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// Parameter name (`Rz` or `Ra`).
    pub parameter: String,
    /// Measured statistics, µm.
    pub measured: Stat,
    /// Simulated value, µm.
    pub simulated_um: f64,
    /// simulated / measured mean.
    pub ratio: f64,
    /// 100·(simulated − mean)/mean.
    pub deviation_pct: f64,
    /// Whether the simulated value lies within mean ± σ.
    pub within_sigma: bool,
    /// |deviation| ≤ tolerance.
    pub pass: bool,
}

impl Comparison {
    fn new(parameter: &str, measured: Stat, simulated_um: f64, tolerance_pct: f64) -> Self {
        let ratio = simulated_um / measured.mean;
        let deviation_pct = 100.0 * (simulated_um - measured.mean) / measured.mean;
        let within_sigma = measured
            .sd
            .is_some_and(|sd| (simulated_um - measured.mean).abs() <= sd);
        // A zero mean gives an infinite or NaN deviation, which fails.
        let pass = deviation_pct.abs() <= tolerance_pct;
        Comparison {
            parameter: parameter.to_string(),
            measured,
            simulated_um,
            ratio,
            deviation_pct,
            within_sigma,
            pass,
        }
    }
}

/// The result of one case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseResult {
    /// Lead angle, degrees.
    pub lead_deg: f64,
    /// Curvature side.
    pub side: Side,
    /// Local surface radius, mm (None = plane).
    pub surface_radius_mm: Option<f64>,
    /// Model used.
    pub model: Model,
    /// Programmed feed per tooth, mm.
    pub fz_mm: f64,
    /// The measurements.
    pub measured: MeasuredCase,
    /// The crest model's prediction (always computed, also for reference).
    pub prediction: CrestPrediction,
    /// The z-map prediction, for `model = "simulate"`.
    pub zmap: Option<ZmapPrediction>,
    /// Comparisons (Rz first, then Ra, for the columns the table has).
    pub comparisons: Vec<Comparison>,
    /// Every comparison passes.
    pub pass: bool,
}

/// A whole regression: what the writers render and `--json` prints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Regression {
    /// Study title.
    pub title: String,
    /// Source of the measurements.
    pub source: Option<String>,
    /// Notes from the study.
    pub notes: Option<String>,
    /// Measured table file, as given.
    pub measured_file: String,
    /// Study file, as given.
    pub study_file: String,
    /// Tool file, as written in the study.
    pub tool_file: String,
    /// Tool description (one line).
    pub tool: String,
    /// Run-out description (one line).
    pub runout: String,
    /// Depth of cut, mm.
    pub ap_mm: f64,
    /// Nominal cutting speed, m/min.
    pub cutting_speed_m_min: Option<f64>,
    /// Tolerance, percent of the measured mean.
    pub tolerance_pct: f64,
    /// The command that made the report.
    pub command: String,
    /// crest version.
    pub version: String,
    /// Per case.
    pub cases: Vec<CaseResult>,
    /// Every case passes.
    pub pass: bool,
}

/// Inputs of [`regress`] besides the parsed files.
#[derive(Debug, Clone)]
pub struct Provenance {
    /// Measured table file, as given.
    pub measured_file: String,
    /// Study file, as given.
    pub study_file: String,
    /// The command line that made the report.
    pub command: String,
}

/// Hold every case of `study` against `table`. `cutter` is the study's tool with the run-out
/// already applied. Every measured case must have a study case and vice versa.
pub fn regress(
    table: &MeasuredTable,
    study: &Study,
    cutter: &Cutter,
    tolerance_pct: f64,
    provenance: Provenance,
) -> Result<Regression, ReportError> {
    let err = |message: String| ReportError::Study {
        file: provenance.study_file.clone(),
        message,
    };
    let measured = summarize(table);
    for m in &measured {
        if !study
            .cases
            .iter()
            .any(|c| c.lead_deg == m.lead_deg && c.side == m.side)
        {
            return Err(err(format!(
                "the measured table ({}) has lead {}°, {} but the study has no such [[case]]",
                provenance.measured_file,
                m.lead_deg,
                m.side.name()
            )));
        }
    }
    let mut cases = Vec::new();
    for (i, c) in study.cases.iter().enumerate() {
        let Some(m) = measured
            .iter()
            .find(|m| m.lead_deg == c.lead_deg && m.side == c.side)
        else {
            return Err(err(format!(
                "case {} (lead {}°, {}) has no rows in the measured table {}",
                i + 1,
                c.lead_deg,
                c.side.name(),
                provenance.measured_file
            )));
        };
        let fz = c.fz_mm.unwrap_or(study.fz_mm);
        let model = c.model.unwrap_or(study.model);
        let prediction = crest_model(
            cutter,
            c.lead_deg,
            study.ap_mm,
            fz,
            study.rule,
            c.side,
            c.surface_radius_mm,
        )
        .map_err(|e| err(format!("case {}: {e}", i + 1)))?;
        let zmap = match model {
            Model::Crest => None,
            Model::Simulate => {
                if c.surface_radius_mm.is_some() {
                    return Err(err(format!(
                        "case {}: the simulate model runs on a plane; remove surface_radius_mm or use model = \"crest\"",
                        i + 1
                    )));
                }
                let spec = study.simulate.unwrap_or_default();
                Some(
                    simulate_case(
                        cutter,
                        c.lead_deg,
                        study.ap_mm,
                        fz,
                        prediction.fz_eff_mm,
                        &spec,
                    )
                    .map_err(|e| err(format!("case {}: {e}", i + 1)))?,
                )
            }
        };
        let (sim_rz, sim_ra) = match &zmap {
            Some(z) => (z.rz_um, z.ra_um),
            None => (prediction.rz_um, prediction.ra_um),
        };
        let mut comparisons = Vec::new();
        if let Some(rz) = m.rz {
            comparisons.push(Comparison::new("Rz", rz, sim_rz, tolerance_pct));
        }
        if let Some(ra) = m.ra {
            comparisons.push(Comparison::new("Ra", ra, sim_ra, tolerance_pct));
        }
        let pass = comparisons.iter().all(|c| c.pass);
        cases.push(CaseResult {
            lead_deg: c.lead_deg,
            side: c.side,
            surface_radius_mm: c.surface_radius_mm,
            model,
            fz_mm: fz,
            measured: m.clone(),
            prediction,
            zmap,
            comparisons,
            pass,
        });
    }
    let pass = cases.iter().all(|c| c.pass);
    Ok(Regression {
        title: study.title.clone(),
        source: study.source.clone(),
        notes: study.notes.clone(),
        measured_file: provenance.measured_file,
        study_file: provenance.study_file,
        tool_file: study.tool.clone(),
        tool: describe_tool(cutter),
        runout: describe_runout(cutter),
        ap_mm: study.ap_mm,
        cutting_speed_m_min: study.cutting_speed_m_min,
        tolerance_pct,
        command: provenance.command,
        version: env!("CARGO_PKG_VERSION").to_string(),
        cases,
        pass,
    })
}

fn describe_tool(c: &Cutter) -> String {
    let shape = match c.shape {
        crate::tool::Shape::Ball => "ball end".to_string(),
        crate::tool::Shape::Torus { corner_radius_mm } => {
            format!("torus, corner radius {corner_radius_mm} mm")
        }
        crate::tool::Shape::Flat => "flat end".to_string(),
    };
    format!(
        "{shape}, R = {} mm, {} teeth, helix {}°",
        c.radius_mm,
        c.teeth(),
        fmt_g(c.helix_rad.to_degrees())
    )
}

fn describe_runout(c: &Cutter) -> String {
    let r = &c.runout;
    let mut parts = Vec::new();
    if r.offset_mm != 0.0 {
        parts.push(format!(
            "offset e0 = {} µm at {}°",
            fmt_g(r.offset_mm * 1e3),
            fmt_g(r.offset_phase_rad.to_degrees())
        ));
    }
    if r.tilt_rad != 0.0 {
        parts.push(format!(
            "axis tilt {}° at {}°",
            fmt_g(r.tilt_rad.to_degrees()),
            fmt_g(r.tilt_phase_rad.to_degrees())
        ));
    }
    if r.tooth_radius_dev_mm.iter().any(|d| *d != 0.0) {
        let devs: Vec<String> = r
            .tooth_radius_dev_mm
            .iter()
            .map(|d| fmt_g(d * 1e3))
            .collect();
        let radii: Vec<String> = r
            .tooth_radius_dev_mm
            .iter()
            .map(|d| format!("{:.3}", c.radius_mm + d))
            .collect();
        parts.push(format!(
            "tooth radius deviations {} µm (tooth radii {} mm)",
            devs.join(" / "),
            radii.join(" / ")
        ));
    }
    if parts.is_empty() {
        "none".to_string()
    } else {
        parts.join("; ")
    }
}

/// A number without trailing zeros (up to 4 decimals).
fn fmt_g(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

// ---------------------------------------------------------------------------------------
// Writers

/// Format a statistic as `mean ± σ` (σ omitted for one sample).
fn fmt_stat(s: &Stat, decimals: usize) -> String {
    match s.sd {
        Some(sd) => format!("{:.d$} ± {:.d$}", s.mean, sd, d = decimals),
        None => format!("{:.d$} (n = 1)", s.mean, d = decimals),
    }
}

fn teeth_list(p: &CrestPrediction) -> String {
    let t: Vec<String> = p.teeth.iter().map(|t| t.to_string()).collect();
    format!("[{}]", t.join(", "))
}

/// The row cells of the main table, shared by Markdown and HTML.
fn table_rows(r: &Regression) -> Vec<[String; 10]> {
    let mut rows = Vec::new();
    for c in &r.cases {
        for cmp in &c.comparisons {
            rows.push([
                fmt_g(c.lead_deg),
                c.side.name().to_string(),
                cmp.parameter.clone(),
                fmt_stat(&cmp.measured, 4),
                format!("{:.4}", cmp.simulated_um),
                format!("{:.3}", cmp.ratio),
                format!("{:.3}", 1.0 / cmp.ratio),
                format!("{:+.1}", cmp.deviation_pct),
                if cmp.within_sigma { "yes" } else { "no" }.to_string(),
                if cmp.pass { "pass" } else { "FAIL" }.to_string(),
            ]);
        }
    }
    rows
}

const TABLE_HEAD: [&str; 10] = [
    "lead (°)",
    "side",
    "param",
    "measured mean ± σ (µm)",
    "simulated (µm)",
    "ratio sim/meas",
    "meas/sim",
    "deviation (%)",
    "within ±σ",
    "result",
];

fn model_rows(r: &Regression) -> Vec<[String; 11]> {
    r.cases
        .iter()
        .map(|c| {
            let p = &c.prediction;
            let radii: Vec<String> = p
                .tooth_radius_mm
                .iter()
                .map(|x| format!("{x:.4}"))
                .collect();
            [
                fmt_g(c.lead_deg),
                c.side.name().to_string(),
                match &c.zmap {
                    Some(z) => format!(
                        "simulate ({}, grid {} µm{}; teeth by the {} rule)",
                        match z.surface_model {
                            SurfaceModel::Ice => "ICE",
                            SurfaceModel::Dome => "dome",
                        },
                        fmt_g(z.grid_um),
                        match z.surface_model {
                            SurfaceModel::Ice => format!(", Δθ {}°", fmt_g(z.dtheta_deg)),
                            SurfaceModel::Dome => String::new(),
                        },
                        p.rule
                    ),
                    None => format!("{} ({} rule)", c.model.name(), p.rule),
                },
                format!("{:.4}", p.generating_height_mm),
                radii.join(" / "),
                format!("{} (zc = {})", teeth_list(p), p.zc),
                format!("{} → {}", fmt_g(c.fz_mm), fmt_g(p.fz_eff_mm)),
                format!("{:.4}", p.crest_um),
                format!("{:.3} / {:.3}", p.contact_radius_mm, p.effective_radius_mm),
                format!("{:.1}", 100.0 * p.cutting_speed_ratio),
                match &c.zmap {
                    Some(z) => format!("{:.4} / {:.4}", z.rz_um, z.ra_um),
                    None => "—".to_string(),
                },
            ]
        })
        .collect()
}

const MODEL_HEAD: [&str; 11] = [
    "lead (°)",
    "side",
    "model",
    "generating height z (mm)",
    "tooth radii r_j(z) (mm)",
    "participating teeth",
    "fz → fz_eff (mm)",
    "crest hc (µm)",
    "R at contact / R_ef,max (mm)",
    "Vc,ef,max (% of Vc)",
    "z-map Rz / Ra (µm)",
];

/// Ranges of measured/simulated over all comparisons of one parameter.
fn ratio_range(r: &Regression, parameter: &str) -> Option<(f64, f64)> {
    let v: Vec<f64> = r
        .cases
        .iter()
        .flat_map(|c| c.comparisons.iter())
        .filter(|c| c.parameter == parameter)
        .map(|c| c.measured.mean / c.simulated_um)
        .filter(|x| x.is_finite())
        .collect();
    if v.is_empty() {
        return None;
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Some((lo, hi))
}

/// The plain-language findings: which cases fail and by how much.
fn findings(r: &Regression) -> Vec<String> {
    let mut out = Vec::new();
    let failing: Vec<&CaseResult> = r.cases.iter().filter(|c| !c.pass).collect();
    if failing.is_empty() {
        out.push(format!(
            "Every case is within ±{}% of the measured mean: the model explains the measurements to this tolerance.",
            fmt_g(r.tolerance_pct)
        ));
    } else {
        out.push(format!(
            "{} of {} cases are outside ±{}% of the measured mean: there the model does not explain the measurement.",
            failing.len(),
            r.cases.len(),
            fmt_g(r.tolerance_pct)
        ));
    }
    for p in ["Rz", "Ra"] {
        if let Some((lo, hi)) = ratio_range(r, p) {
            let under = r
                .cases
                .iter()
                .flat_map(|c| c.comparisons.iter())
                .filter(|c| c.parameter == p)
                .all(|c| c.simulated_um < c.measured.mean);
            let dir = if under {
                "every simulated value lies below the measurement"
            } else {
                "the simulated values straddle the measurements"
            };
            out.push(format!(
                "Measured {p} is {lo:.2}× to {hi:.2}× the simulated {p}; {dir}."
            ));
        }
    }
    out.push(
        "The models are purely geometric: a rigid tool with the given run-out sweeping its \
         circular arcs (crest) or its edges (z-map). They have no plowing, elastic recovery or \
         side flow of the material, no tool wear or edge radius, no vibration, and no \
         measurement noise or filtering; any excess of the measured roughness over the \
         simulated one is outside what they can explain."
            .to_string(),
    );
    out
}

fn method_text(r: &Regression) -> Vec<String> {
    let mut v = vec![
        "Measured: mean and sample standard deviation σ (n − 1 convention) of the samples of \
         each case, as 002 Table 2 prints them."
            .to_string(),
        "Crest model (002 §3.3, computed by `crest::tool::analyse`): the generating point of a \
         ball end at lead β lies at height z = R(1 − cos β). Paper rule: the teeth whose local \
         radius r_j(z) (run-out included) exceeds max r_j − hc(fz) cut (002 Eq 8; hc is Eq 14 \
         at the programmed fz), the marks are fz_eff = fz·Z/zc apart (Eq 7) and the crest is \
         Eq 14 with fz_eff. Exact rule: the profile is the lower envelope of every tooth's arc \
         (radius R + Δ_j, Δ_j its run-out along the normal) at its own mark, period Z·fz, and \
         the crest is its peak-to-valley height (model.md §3.2)."
            .to_string(),
        format!(
            "Simulated Rz and Ra: computed on that feed-direction profile (paper rule: circular \
             arcs of the tool radius spaced fz_eff), sampled every {} µm (or finer, so that every crest and \
             valley is a sample) over 5 sampling lengths λc chosen by ISO 4288 from RSm = fz_eff \
             (λc = 0.8 mm for 0.13 < RSm ≤ 0.4 mm). The periodic profile has no form, so no \
             filter is applied: Ra = mean |z − z̄| over the evaluation length, Rz = mean of the \
             5 peak-to-valley heights (002 Eq 15), which equals the crest hc for evenly spaced marks.",
            fmt_g(PROFILE_STEP_MM * 1e3)
        ),
        "Curvature: without a local surface radius a case is computed as on a plane, so the \
         concave and convex sides get the same prediction. With `surface_radius_mm` = Rs the \
         marks stay fz_eff apart on the surface (feed at the contact point) and the profile \
         arcs take the relative radius R·Rs/(Rs ± R) (+ convex, − concave), i.e. \
         hc ≈ fz_eff²/8·(1/R ± 1/Rs) (model.md §7)."
            .to_string(),
        format!(
            "Pass/fail: a parameter passes when |simulated − measured mean| ≤ {}% of the measured \
             mean; a case passes when all its parameters pass. 'within ±σ' is informative.",
            fmt_g(r.tolerance_pct)
        ),
    ];
    if let Some(z) = r.cases.iter().find_map(|c| c.zmap.as_ref()) {
        v.push(format!(
            "Simulate model: one straight pass along +x over the plane z = 0, tool axis tilted by \
             the lead in the feed plane, spindle phase 0 at the start, simulated by \
             `crest::surface::simulate` ({} model) on a window 5λc long and 5 nodes wide at {} µm; \
             Rz and Ra on its centre row as above (no filter). The crest-model columns stay for \
             reference.",
            match z.surface_model {
                SurfaceModel::Ice => "ICE",
                SurfaceModel::Dome => "dome",
            },
            fmt_g(z.grid_um)
        ));
    }
    v.push(format!(
        "Effective radius (002 Table 3, model.md §6): R_ef,max = R sin(β + acos((R − ap)/R)) at \
         ap = {} mm; Vc,ef/Vc = R_ef,max/R{}. It does not enter the crest; it shows how close \
         the slow tool centre is to the cut (plowing).",
        fmt_g(r.ap_mm),
        match r.cutting_speed_m_min {
            Some(vc) => format!(" (nominal Vc = {} m/min)", fmt_g(vc)),
            None => String::new(),
        }
    ));
    v
}

/// Render `report.md`. `plots` are the file names of the SVG plots written beside it.
pub fn render_markdown(r: &Regression, plots: &[(String, String)]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# {}\n", r.title);
    let _ = writeln!(
        s,
        "Made by `{}` (crest {}). Regenerate from the repository root with\n\n```sh\ncargo run --release -- {}\n```\n",
        r.command,
        r.version,
        r.command.strip_prefix("crest ").unwrap_or(&r.command)
    );
    let _ = writeln!(
        s,
        "The command exits with status {} ({}).\n",
        if r.pass { 0 } else { 1 },
        if r.pass {
            "every case within tolerance"
        } else {
            "at least one case beyond tolerance"
        }
    );
    let _ = writeln!(s, "- Measured table: `{}`", r.measured_file);
    let _ = writeln!(s, "- Study: `{}`", r.study_file);
    if let Some(src) = &r.source {
        let _ = writeln!(s, "- Source: {src}");
    }
    let _ = writeln!(
        s,
        "- Tool: `{}` (relative to the study): {}",
        r.tool_file, r.tool
    );
    let _ = writeln!(s, "- Run-out: {}", r.runout);
    let _ = writeln!(
        s,
        "- Tolerance: ±{}% of the measured mean\n",
        fmt_g(r.tolerance_pct)
    );

    let _ = writeln!(s, "## Verdict\n");
    for f in findings(r) {
        let _ = writeln!(s, "- {f}");
    }
    let _ = writeln!(s);

    let _ = writeln!(s, "## Measured against simulated\n");
    let _ = writeln!(s, "| {} |", TABLE_HEAD.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(TABLE_HEAD.len()));
    for row in table_rows(r) {
        let _ = writeln!(s, "| {} |", row.join(" | "));
    }
    let _ = writeln!(s);

    let _ = writeln!(s, "## Model\n");
    let _ = writeln!(s, "| {} |", MODEL_HEAD.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(MODEL_HEAD.len()));
    for row in model_rows(r) {
        let _ = writeln!(s, "| {} |", row.join(" | "));
    }
    let _ = writeln!(s);

    let _ = writeln!(s, "## Measured samples\n");
    let _ = writeln!(s, "| lead (°) | side | sample | Ra (µm) | Rz (µm) |");
    let _ = writeln!(s, "|---|---|---|---|---|");
    for c in &r.cases {
        let m = &c.measured;
        for (i, name) in m.samples.iter().enumerate() {
            let ra = m
                .ra_values_um
                .get(i)
                .map_or("".to_string(), |v| format!("{v:.3}"));
            let rz = m
                .rz_values_um
                .get(i)
                .map_or("".to_string(), |v| format!("{v:.3}"));
            let _ = writeln!(
                s,
                "| {} | {} | {name} | {ra} | {rz} |",
                fmt_g(c.lead_deg),
                c.side.name()
            );
        }
    }
    let _ = writeln!(s);

    if !plots.is_empty() {
        let _ = writeln!(s, "## Plots\n");
        for (file, caption) in plots {
            let _ = writeln!(s, "![{caption}]({file})\n");
        }
    }

    if let Some(notes) = &r.notes {
        let _ = writeln!(s, "## Discussion\n\n{}\n", notes.trim());
    }

    let _ = writeln!(s, "## Method\n");
    for m in method_text(r) {
        let _ = writeln!(s, "- {m}");
    }
    s
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Inline Markdown code spans (`x`) to `<code>`, on escaped text.
fn inline_code(s: &str) -> String {
    let e = esc(s);
    let mut out = String::new();
    for (i, part) in e.split('`').enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<code>{part}</code>");
        } else {
            out.push_str(part);
        }
    }
    out
}

/// Render `report.html`: the same content as the Markdown, with the SVG plots inline.
/// `plots` holds (caption, SVG text).
pub fn render_html(r: &Regression, plots: &[(String, String)]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>",
        esc(&r.title)
    );
    let _ = writeln!(
        s,
        "<style>body{{font-family:sans-serif;max-width:72em;margin:2em auto;padding:0 1em;line-height:1.4}}\
         table{{border-collapse:collapse;margin:1em 0}}th,td{{border:1px solid #bbb;padding:.25em .6em;text-align:right}}\
         th{{background:#eee}}td:nth-child(2),td:nth-child(3){{text-align:left}}.fail{{color:#b00;font-weight:bold}}\
         .pass{{color:#070}}pre,code{{background:#f4f4f4}}pre{{padding:.5em;overflow-x:auto}}</style>\n</head>\n<body>"
    );
    let _ = writeln!(s, "<h1>{}</h1>", esc(&r.title));
    let _ = writeln!(
        s,
        "<p>Made by <code>{}</code> (crest {}). Regenerate from the repository root with</p>\n<pre>cargo run --release -- {}</pre>",
        esc(&r.command),
        esc(&r.version),
        esc(r.command.strip_prefix("crest ").unwrap_or(&r.command))
    );
    let _ = writeln!(
        s,
        "<p>The command exits with status {}.</p>\n<ul>",
        if r.pass { 0 } else { 1 }
    );
    let _ = writeln!(
        s,
        "<li>Measured table: <code>{}</code></li>",
        esc(&r.measured_file)
    );
    let _ = writeln!(s, "<li>Study: <code>{}</code></li>", esc(&r.study_file));
    if let Some(src) = &r.source {
        let _ = writeln!(s, "<li>Source: {}</li>", esc(src));
    }
    let _ = writeln!(
        s,
        "<li>Tool: <code>{}</code> (relative to the study): {}</li>\n<li>Run-out: {}</li>\n<li>Tolerance: ±{}% of the measured mean</li>\n</ul>",
        esc(&r.tool_file),
        esc(&r.tool),
        esc(&r.runout),
        fmt_g(r.tolerance_pct)
    );
    let _ = writeln!(s, "<h2>Verdict</h2>\n<ul>");
    for f in findings(r) {
        let _ = writeln!(s, "<li>{}</li>", esc(&f));
    }
    let _ = writeln!(
        s,
        "</ul>\n<h2>Measured against simulated</h2>\n<table>\n<tr>"
    );
    for h in TABLE_HEAD {
        let _ = write!(s, "<th>{}</th>", esc(h));
    }
    let _ = writeln!(s, "</tr>");
    for row in table_rows(r) {
        let _ = write!(s, "<tr>");
        for (i, cell) in row.iter().enumerate() {
            if i == row.len() - 1 {
                let class = if cell == "pass" { "pass" } else { "fail" };
                let _ = write!(s, "<td class=\"{class}\">{}</td>", esc(cell));
            } else {
                let _ = write!(s, "<td>{}</td>", esc(cell));
            }
        }
        let _ = writeln!(s, "</tr>");
    }
    let _ = writeln!(s, "</table>\n<h2>Model</h2>\n<table>\n<tr>");
    for h in MODEL_HEAD {
        let _ = write!(s, "<th>{}</th>", esc(h));
    }
    let _ = writeln!(s, "</tr>");
    for row in model_rows(r) {
        let _ = write!(s, "<tr>");
        for cell in &row {
            let _ = write!(s, "<td>{}</td>", esc(cell));
        }
        let _ = writeln!(s, "</tr>");
    }
    let _ = writeln!(s, "</table>");
    if !plots.is_empty() {
        let _ = writeln!(s, "<h2>Plots</h2>");
        for (caption, svg) in plots {
            let body = svg
                .find("<svg")
                .map_or(svg.as_str(), |i| &svg[i..])
                .trim_end();
            let _ = writeln!(
                s,
                "<figure>\n{body}\n<figcaption>{}</figcaption>\n</figure>",
                esc(caption)
            );
        }
    }
    if let Some(notes) = &r.notes {
        let _ = writeln!(s, "<h2>Discussion</h2>");
        for para in notes.trim().split("\n\n") {
            let _ = writeln!(s, "<p>{}</p>", inline_code(para.trim()));
        }
    }
    let _ = writeln!(s, "<h2>Method</h2>\n<ul>");
    for m in method_text(r) {
        let _ = writeln!(s, "<li>{}</li>", inline_code(&m));
    }
    let _ = writeln!(s, "</ul>\n</body>\n</html>");
    s
}

/// Draw one parameter (`Rz` or `Ra`), measured mean ± σ with the samples against simulated,
/// over the lead angle, one colour per side. Returns the SVG text.
pub fn render_plot(r: &Regression, parameter: &str) -> Result<String, String> {
    let mut svg = String::new();
    {
        let root = plotters::prelude::SVGBackend::with_string(&mut svg, PLOT_SIZE);
        draw_plot(r, parameter, root)?;
    }
    Ok(svg)
}

const PLOT_SIZE: (u32, u32) = (760, 480);

fn draw_plot<DB: plotters::prelude::DrawingBackend>(
    r: &Regression,
    parameter: &str,
    backend: DB,
) -> Result<(), String> {
    use plotters::prelude::*;
    crate::plot::init_fonts();
    let font = crate::plot::FONT;
    let mut sides: Vec<Side> = r.cases.iter().map(|c| c.side).collect();
    sides.sort();
    sides.dedup();
    let pts: Vec<(&CaseResult, &Comparison)> = r
        .cases
        .iter()
        .flat_map(|c| {
            c.comparisons
                .iter()
                .filter(|k| k.parameter == parameter)
                .map(move |k| (c, k))
        })
        .collect();
    if pts.is_empty() {
        return Err(format!("no {parameter} values to plot"));
    }
    let samples = |c: &CaseResult| -> Vec<f64> {
        if parameter == "Rz" {
            c.measured.rz_values_um.clone()
        } else {
            c.measured.ra_values_um.clone()
        }
    };
    let mut ymax: f64 = 0.0;
    for (c, k) in &pts {
        ymax = ymax
            .max(k.measured.mean + k.measured.sd.unwrap_or(0.0))
            .max(k.simulated_um);
        for v in samples(c) {
            ymax = ymax.max(v);
        }
    }
    let ymax = if ymax > 0.0 { ymax * 1.15 } else { 1.0 };
    let lmin = pts
        .iter()
        .map(|(c, _)| c.lead_deg)
        .fold(f64::INFINITY, f64::min);
    let lmax = pts
        .iter()
        .map(|(c, _)| c.lead_deg)
        .fold(f64::NEG_INFINITY, f64::max);
    let pad = ((lmax - lmin) * 0.15).max(2.0);
    let (x0, x1) = (lmin - pad, lmax + pad);
    let offset = (x1 - x0) * 0.012;

    {
        let root = backend.into_drawing_area();
        let e = |x: DrawingAreaErrorKind<_>| x.to_string();
        root.fill(&WHITE).map_err(e)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{parameter}: measured (mean ± σ, samples) against simulated"),
                (font, 20),
            )
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, 0.0..ymax)
            .map_err(|x| x.to_string())?;
        chart
            .configure_mesh()
            .x_desc("lead angle (°)")
            .x_label_formatter(&|x| fmt_g(*x))
            .y_desc(format!("{parameter} (µm)"))
            .label_style((font, 14))
            .axis_desc_style((font, 15))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(|x| x.to_string())?;
        let palette = [
            RGBColor(31, 119, 180),
            RGBColor(214, 39, 40),
            RGBColor(44, 160, 44),
        ];
        for (si, side) in sides.iter().enumerate() {
            let colour = palette[si % palette.len()];
            let dx = if sides.len() > 1 {
                offset * (2.0 * si as f64 - (sides.len() - 1) as f64)
            } else {
                0.0
            };
            let mine: Vec<&(&CaseResult, &Comparison)> =
                pts.iter().filter(|(c, _)| c.side == *side).collect();
            // Error bars (mean ± σ) with the mean marker.
            chart
                .draw_series(mine.iter().map(|(c, k)| {
                    let sd = k.measured.sd.unwrap_or(0.0);
                    ErrorBar::new_vertical(
                        c.lead_deg + dx,
                        k.measured.mean - sd,
                        k.measured.mean,
                        k.measured.mean + sd,
                        colour.filled(),
                        8,
                    )
                }))
                .map_err(|x| x.to_string())?
                .label(format!("measured {} (mean ± σ)", side.name()))
                .legend(move |(x, y)| Circle::new((x + 10, y), 4, colour.filled()));
            // Individual samples, hollow.
            let samples_series = chart
                .draw_series(mine.iter().flat_map(|(c, _)| {
                    samples(c)
                        .into_iter()
                        .map(move |v| Circle::new((c.lead_deg + dx, v), 4, colour.stroke_width(1)))
                }))
                .map_err(|x| x.to_string())?;
            if si + 1 == sides.len() {
                samples_series
                    .label("single samples")
                    .legend(|(x, y)| Circle::new((x + 10, y), 4, BLACK.stroke_width(1)));
            }
            // Simulated, dashed-look line with crosses.
            let mut sim: Vec<(f64, f64)> = mine
                .iter()
                .map(|(c, k)| (c.lead_deg + dx, k.simulated_um))
                .collect();
            sim.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(
                    sim.clone(),
                    colour.mix(0.6).stroke_width(2),
                ))
                .map_err(|x| x.to_string())?
                .label(format!(
                    "simulated {} ({})",
                    side.name(),
                    r.cases[0].model.name()
                ))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.mix(0.6).stroke_width(2))
                });
            chart
                .draw_series(
                    sim.iter()
                        .map(|p| Cross::new(*p, 6, colour.stroke_width(2))),
                )
                .map_err(|x| x.to_string())?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .label_font((font, 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()
            .map_err(|x| x.to_string())?;
        root.present().map_err(e)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::Shape;
    use approx::assert_relative_eq;

    #[test]
    fn sigma_uses_n_minus_one() {
        let s = Stat::of(&[2.07, 2.29]).unwrap();
        assert_relative_eq!(s.mean, 2.18, epsilon = 1e-12);
        assert_relative_eq!(s.sd.unwrap(), 0.22 / 2f64.sqrt(), epsilon = 1e-12);
        assert!(Stat::of(&[1.0]).unwrap().sd.is_none());
        assert!(Stat::of(&[]).is_none());
    }

    #[test]
    fn field_columns_count_characters() {
        assert_eq!(field_column("5,concave,S1,x,2", 0), 1);
        assert_eq!(field_column("5,concave,S1,x,2", 3), 14);
        assert_eq!(field_column("5,\"a,b\",S1", 2), 9);
    }

    #[test]
    fn profile_of_arcs_has_closed_form_rz_and_ra() {
        // Rz = Eq 14 exactly; Ra → 4/(9√3)·hc for a parabola, the arcs differ by O((fz/R)²).
        let (rz, ra, lc) = profile_roughness(5.0, 0.2);
        assert_relative_eq!(rz, 1.0001000, epsilon = 1e-6);
        assert_eq!(lc, 0.8);
        assert_relative_eq!(ra, 4.0 / (9.0 * 3f64.sqrt()) * rz, max_relative = 1e-3);
        let (rz, _, lc) = profile_roughness(5.0, 0.05);
        assert_relative_eq!(rz, 0.0625004, epsilon = 1e-6);
        assert_eq!(lc, 0.25);
    }

    #[test]
    fn curvature_reduces_to_plane_and_orders_sides() {
        let mut c = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        c.runout.tooth_radius_dev_mm = vec![-0.010, -0.015, -0.024, -0.025];
        let plane = crest_model(&c, 15.0, 0.4, 0.05, Rule::Paper, Side::Plane, None).unwrap();
        let far = crest_model(&c, 15.0, 0.4, 0.05, Rule::Paper, Side::Convex, Some(1e9)).unwrap();
        assert_relative_eq!(plane.crest_um, far.crest_um, max_relative = 1e-6);
        let vex = crest_model(&c, 15.0, 0.4, 0.05, Rule::Paper, Side::Convex, Some(20.0)).unwrap();
        let cave =
            crest_model(&c, 15.0, 0.4, 0.05, Rule::Paper, Side::Concave, Some(20.0)).unwrap();
        // Second-order closed form: hc ≈ fz²/8·(1/R ± 1/Rs), + convex.
        let approx = |sign: f64| 0.2 * 0.2 / 8.0 * (1.0 / 5.0 + sign / 20.0) * 1e3;
        assert_relative_eq!(vex.crest_um, approx(1.0), max_relative = 1e-3);
        assert_relative_eq!(cave.crest_um, approx(-1.0), max_relative = 1e-3);
        assert!(vex.crest_um > plane.crest_um && plane.crest_um > cave.crest_um);
        assert!(crest_model(&c, 15.0, 0.4, 0.05, Rule::Paper, Side::Concave, Some(4.0)).is_err());
    }
}
