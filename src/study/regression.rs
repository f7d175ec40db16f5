//! Regressions: simulated roughness held against measured confocal tables.
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
//! The writers ([`crate::report::regression`], [`crate::plot::regression`]) render a
//! [`Regression`]; everything here is pure.

use super::measured::Side;
use crate::surface::{ModelKind, Process};
use crate::tool::{Cutter, Rule, Runout, crest_height_mm};
use serde::Serialize;

/// Profile sampling step of the simulated profile, mm (0.5 µm).
pub const PROFILE_STEP_MM: f64 = 0.0005;

/// Which model predicts a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, serde::Deserialize)]
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

/// `[simulate]` settings of a study (used by cases with `model = "simulate"`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SimulateSpec {
    /// `ice` (default) or `dome`.
    pub surface_model: ModelKind,
    /// Grid spacing, µm (default 1).
    pub grid_um: f64,
    /// Largest spindle step of the ICE model, degrees (default 0.5).
    pub dtheta_deg: f64,
}

impl Default for SimulateSpec {
    fn default() -> Self {
        SimulateSpec {
            surface_model: ModelKind::Ice,
            grid_um: 1.0,
            dtheta_deg: 0.5,
        }
    }
}

/// One case of a study.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StudyCase {
    /// Lead angle (tool tilt in the feed direction), degrees.
    pub lead_deg: f64,
    /// Curvature side; matches the `side` column of the measured table.
    pub side: Side,
    /// Local radius of curvature of the surface in the feed direction, mm. Absent = plane.
    pub surface_radius_mm: Option<f64>,
    /// Feed per tooth for this case, mm (overrides the study's `fz_mm`).
    pub fz_mm: Option<f64>,
    /// Model for this case (overrides the study's `model`).
    pub model: Option<Model>,
}

/// A regression study: the cases of a measured table and how to predict them (read by
/// [`crate::config::regression`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Study {
    /// Title of the report.
    pub title: String,
    /// Where the measurements come from.
    pub source: Option<String>,
    /// Tool TOML file, relative to the study file.
    pub tool: String,
    /// Default model.
    pub model: Model,
    /// Programmed feed per tooth, mm.
    pub fz_mm: f64,
    /// Rule for the participating teeth.
    pub rule: Rule,
    /// Depth of cut along the normal, mm (for the effective radius, 002 Table 3).
    pub ap_mm: f64,
    /// Nominal cutting speed, m/min (informative).
    pub cutting_speed_m_min: Option<f64>,
    /// Distance between adjacent passes, mm: needed to predict the areal (Sa, Sz) and the
    /// stepover-direction (Rz, Ra) columns of a measured table.
    pub stepover_mm: Option<f64>,
    /// Run-out; when present it replaces the tool file's `[runout]` table entirely.
    pub runout: Option<Runout>,
    /// Settings of the `simulate` model.
    pub simulate: Option<SimulateSpec>,
    /// Free text (Markdown paragraphs) printed in the report's discussion.
    pub notes: Option<String>,
    /// Process effects (`[process]`; off by default) applied by both models.
    pub process: Process,
    /// Input uncertainties of the Monte Carlo bands (`[uncertainty]`).
    pub uncertainty: super::uncertainty::Uncertainty,
    /// The cases.
    pub cases: Vec<StudyCase>,
}

/// Why a case cannot be predicted. The messages name the study's keys.
#[derive(Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PredictError {
    /// The engagement cannot be analysed (feed, depth of cut, lead).
    #[error(transparent)]
    Tool(#[from] crate::tool::ToolError),
    /// A surface radius on a side that is only a label.
    #[error("side `{0}` is a plain label: a surface radius needs side concave or convex")]
    PlainSide(String),
    /// A surface radius with a tool that is not a ball end.
    #[error("the curvature correction needs a ball-end tool")]
    CurvatureNeedsBall,
    /// A concave surface tighter than the tool.
    #[error(
        "a concave surface of radius {surface_mm} mm is tighter than the tool radius {tool_mm} mm"
    )]
    TightConcave {
        /// Surface radius, mm.
        surface_mm: f64,
        /// Tool radius, mm.
        tool_mm: f64,
    },
    /// The straight pass of the simulate model would need too many samples.
    #[error("the simulated pass needs too many samples; fz is too small")]
    TooManySamples,
    /// The simulation failed.
    #[error(transparent)]
    Surface(#[from] crate::surface::SurfaceError),
    /// The simulated window has no row to measure.
    #[error("the simulated window is empty")]
    EmptyWindow,
    /// The measured row has nodes no tooth reached.
    #[error("the simulated centre line has nodes no tooth reached")]
    NotReached,
    /// The simulate model with a surface radius.
    #[error(
        "the simulate model runs on a plane; remove surface_radius_mm or use model = \"crest\""
    )]
    SimulateOnCurve,
}

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
    /// The evaluated feed-direction profile, µm, evenly spaced over 5λc (for the areal
    /// estimate of [`super::stepover`]; not printed).
    #[serde(skip)]
    pub profile_um: Vec<f64>,
    /// The step of `profile_um`, mm.
    #[serde(skip)]
    pub profile_step_mm: f64,
    /// R_ef,max of the nominal tool for the lead and ap (002 Table 3), mm.
    pub effective_radius_mm: f64,
    /// Radius of the generating point (R sin β for a ball), mm.
    pub contact_radius_mm: f64,
    /// Cutting-speed ratio R_ef,max / R (002 Table 3 "Vc,ef max" / 100).
    pub cutting_speed_ratio: f64,
}

/// A periodic feed-direction profile: period `period_mm`, one height (mm) per position in
/// the period. Returns (Rz µm, Ra µm, λc mm, peak-to-valley over one period µm, the
/// evaluated profile in µm and its step in mm).
///
/// The period is sampled in an even number of steps of at most [`PROFILE_STEP_MM`] (so
/// that the crest between two evenly spaced marks is a sample), and the profile repeated
/// over 5 sampling lengths λc chosen by ISO 4288 from `rsm_mm`.
fn periodic_roughness(
    period_mm: f64,
    rsm_mm: f64,
    height_mm: &dyn Fn(f64) -> f64,
) -> (f64, f64, f64, f64, Profile) {
    let lc = crate::metrics::sampling_length_mm(rsm_mm);
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
    let (rz, ra) = crate::metrics::rz_ra(&heights);
    (rz, ra, lc, (hi - lo) * 1e3, (heights, dx))
}

/// An evaluated profile: heights in µm and their step in mm.
type Profile = (Vec<f64>, f64);

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
    let (rz, ra, lc, _, _) = periodic_roughness(spacing_mm, spacing_mm, &arc);
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
) -> Result<CrestPrediction, PredictError> {
    crest_model_with(
        cutter,
        lead_deg,
        ap_mm,
        fz_mm,
        rule,
        side,
        surface_radius_mm,
        &Process::default(),
    )
}

/// [`crest_model`] with process effects: when `process` is not off, Rz and Ra come from the
/// feed-direction profile built mark by mark in cutting order with the chip rule of
/// [`crate::surface::process`] (the same marks: one tooth every fz_eff for the paper rule,
/// every tooth at its own position and normal deviation for the exact rule), the texture
/// added along the line y = 0, over 5 sampling lengths after 20 periods of run-in.
#[allow(clippy::too_many_arguments)]
pub fn crest_model_with(
    cutter: &Cutter,
    lead_deg: f64,
    ap_mm: f64,
    fz_mm: f64,
    rule: Rule,
    side: Side,
    surface_radius_mm: Option<f64>,
    process: &Process,
) -> Result<CrestPrediction, PredictError> {
    use crate::tool::{FeedProfile, feed_profile_for, mark_positions_mm, normal_deviation_mm};
    let a = crate::tool::analyse(cutter, lead_deg, ap_mm, fz_mm, rule)?;
    let r = cutter.radius_mm;
    let is_ball = matches!(cutter.shape, crate::tool::Shape::Ball);
    let arc_radius = match (&side, surface_radius_mm) {
        (Side::Plane, _) | (_, None) => r,
        (Side::Other(label), Some(_)) => {
            return Err(PredictError::PlainSide(label.clone()));
        }
        (_, Some(_)) if !is_ball => {
            return Err(PredictError::CurvatureNeedsBall);
        }
        (Side::Convex, Some(rs)) => r * rs / (rs + r),
        (Side::Concave, Some(rs)) => {
            if rs <= r {
                return Err(PredictError::TightConcave {
                    surface_mm: rs,
                    tool_mm: r,
                });
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
        feed_profile_for(cutter, lead)
    };
    let fz_eff = a.fz_effective_mm;
    let marks: Vec<(f64, f64)> = match rule {
        Rule::Paper => vec![(0.0, 0.0)],
        Rule::Exact => {
            let period = cutter.teeth() as f64 * fz_mm;
            mark_positions_mm(cutter, fz_mm)
                .iter()
                .enumerate()
                .map(|(j, p)| {
                    (
                        p.rem_euclid(period),
                        normal_deviation_mm(cutter, j, a.generating_height_mm, lead),
                    )
                })
                .collect()
        }
    };
    let period = match rule {
        Rule::Paper => fz_eff,
        Rule::Exact => cutter.teeth() as f64 * fz_mm,
    };
    let (rz, ra, lc, crest_mm, (profile_um, profile_step_mm)) = if process.is_off() {
        geometric_roughness(rule, &profile, fz_eff, period, &marks, &a, arc_radius == r)
    } else {
        processed_roughness(&profile, fz_eff, period, &marks, process)
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
        profile_um,
        profile_step_mm,
        effective_radius_mm: a.effective_radius_mm,
        contact_radius_mm: a.contact_radius_mm,
        cutting_speed_ratio: a.cutting_speed_ratio,
    })
}

/// Height of a mark of `profile` lowered by the normal deviation `d` at distance `x`.
fn mark_height(profile: &crate::tool::FeedProfile, d: f64, x: f64) -> f64 {
    use crate::tool::FeedProfile;
    let h = match *profile {
        FeedProfile::Circle { radius_mm } => FeedProfile::Circle {
            radius_mm: (radius_mm + d).max(0.0),
        }
        .height(x),
        _ => profile.height(x),
    };
    h - d
}

/// The geometric profile's (Rz, Ra, λc, crest, profile µm): the envelope of the marks.
fn geometric_roughness(
    rule: Rule,
    profile: &crate::tool::FeedProfile,
    fz_eff: f64,
    period: f64,
    marks: &[(f64, f64)],
    a: &crate::tool::Analysis,
    plane: bool,
) -> (f64, f64, f64, f64, Profile) {
    match rule {
        Rule::Paper => {
            let h = |u: f64| {
                (-1..=2)
                    .map(|k| profile.height(u - f64::from(k) * fz_eff))
                    .fold(f64::INFINITY, f64::min)
            };
            let (rz, ra, lc, p2v, um) = periodic_roughness(fz_eff, fz_eff, &h);
            let crest = if plane {
                a.crest_height_corrected_mm
            } else {
                p2v * 1e-3
            };
            (rz, ra, lc, crest, um)
        }
        Rule::Exact => {
            let h = |u: f64| {
                let mut best = f64::INFINITY;
                for &(p, d) in marks {
                    for k in [-1.0, 0.0, 1.0] {
                        best = best.min(mark_height(profile, d, u - p - k * period));
                    }
                }
                best
            };
            let (rz, ra, lc, p2v, um) = periodic_roughness(period, fz_eff, &h);
            let crest = if plane {
                a.crest_height_exact_mm
            } else {
                p2v * 1e-3
            };
            (rz, ra, lc, crest, um)
        }
    }
}

/// Run-in periods before the evaluated profile of the processed model.
const RUN_IN_PERIODS: f64 = 20.0;

/// The processed profile's (Rz, Ra, λc, peak-to-valley, profile µm): marks in cutting order (the tool
/// moves +x, so by position) through the chip rule, texture added, over 5λc after the
/// run-in; sampled every ≤ [`PROFILE_STEP_MM`].
fn processed_roughness(
    profile: &crate::tool::FeedProfile,
    fz_eff: f64,
    period: f64,
    marks: &[(f64, f64)],
    process: &Process,
) -> (f64, f64, f64, f64, Profile) {
    let lc = crate::metrics::sampling_length_mm(fz_eff);
    let total = 5.0 * lc;
    let steps_per_period = 2.0 * (0.5 * period / PROFILE_STEP_MM).ceil().max(1.0);
    let dx = period / steps_per_period;
    let n = (total / dx).round().max(1.0) as usize;
    let xs: Vec<f64> = (0..=n).map(|i| i as f64 * dx).collect();
    // Marks from the run-in to past the end, ordered by position.
    let m0 = -(RUN_IN_PERIODS.max(1.0)).ceil() as i64;
    let m1 = (total / period).ceil() as i64 + RUN_IN_PERIODS as i64;
    let mut centres: Vec<(f64, f64)> = (m0..=m1)
        .flat_map(|m| marks.iter().map(move |&(p, d)| (p + m as f64 * period, d)))
        .collect();
    centres.sort_by(|a, b| a.0.total_cmp(&b.0));
    let texture = process
        .texture
        .filter(|t| t.sq_mm > 0.0)
        .map(|t| crate::surface::process::texture_row(&t, dx, n));
    let heights: Vec<f64> = xs
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            let z = centres.iter().fold(f64::INFINITY, |z, &(c, d)| {
                let w = mark_height(profile, d, x - c);
                crate::surface::process::apply_pass(z, w, process.min_chip_mm, process.recovery)
            });
            z + texture.as_ref().map_or(0.0, |t| t[i])
        })
        .collect();
    let lo = heights.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = heights.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let um: Vec<f64> = heights.iter().map(|h| (h - lo) * 1e3).collect();
    let (rz, ra) = crate::metrics::rz_ra(&um);
    (rz, ra, lc, hi - lo, (um, dx))
}

/// What the `simulate` model predicts for one case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ZmapPrediction {
    /// Surface model (`ice` or `dome`).
    pub surface_model: ModelKind,
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
    /// The simulated window (for the 3-D viewer; not printed).
    #[serde(skip)]
    pub map: crate::surface::HeightMap,
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
) -> Result<ZmapPrediction, PredictError> {
    simulate_case_with(
        cutter,
        lead_deg,
        ap_mm,
        fz_mm,
        rsm_mm,
        spec,
        &Process::default(),
        0.0,
    )
}

/// [`simulate_case`] with process effects and the spindle at `phase_rad` at the start.
#[allow(clippy::too_many_arguments)]
pub fn simulate_case_with(
    cutter: &Cutter,
    lead_deg: f64,
    ap_mm: f64,
    fz_mm: f64,
    rsm_mm: f64,
    spec: &SimulateSpec,
    process: &Process,
    phase_rad: f64,
) -> Result<ZmapPrediction, PredictError> {
    use crate::surface::{GridSpec, Model as Zmodel, Options, simulate};
    let lc = crate::metrics::sampling_length_mm(rsm_mm);
    let eval = 5.0 * lc;
    let teeth = cutter.teeth() as f64;
    // The tool's marks reach a few revolutions back; the ball's sag does the rest.
    let margin = 0.5 + 3.0 * teeth * fz_mm;
    // Samples every 10° of spindle; the engine subdivides to Δθ.
    let length = eval + 2.0 * margin;
    let mut samples = crate::synth::pass::straight_pass(
        cutter,
        lead_deg.to_radians(),
        fz_mm,
        -margin,
        length,
        10.0,
    )
    .ok_or(PredictError::TooManySamples)?;
    if phase_rad != 0.0 {
        for s in &mut samples {
            s.theta_rad += phase_rad;
        }
    }
    let dx = spec.grid_um * 1e-3;
    let grid = GridSpec::Window {
        x0_mm: 0.0,
        y0_mm: -2.0 * dx,
        x1_mm: eval,
        y1_mm: 2.0 * dx,
    };
    let model = match spec.surface_model {
        ModelKind::Ice => Zmodel::Ice {
            dtheta_rad: spec.dtheta_deg.to_radians(),
        },
        ModelKind::Dome => Zmodel::Dome,
        ModelKind::Swept => Zmodel::Swept,
    };
    let mut opts = Options::new(model, grid, dx);
    opts.depth_mm = ap_mm.max(dx);
    opts.process = *process;
    let sim = simulate(&samples, cutter, &opts, &|_, _| {})?;
    let map = &sim.map;
    if map.ny == 0 || map.nx < 2 {
        return Err(PredictError::EmptyWindow);
    }
    let row = map.row(map.ny / 2);
    if row.iter().any(|h| !h.is_finite()) {
        return Err(PredictError::NotReached);
    }
    let dx_mm = map.dx_um * 1e-3;
    let (rz, ra) = crate::metrics::rz_ra(row);
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
        map: map.clone(),
    })
}

/// What a study's model predicts for one case.
#[derive(Debug, Clone, PartialEq)]
pub struct CasePrediction {
    /// Rz of the case's model, µm.
    pub rz_um: f64,
    /// Ra of the case's model, µm.
    pub ra_um: f64,
    /// The case model's evaluated feed-direction profile, µm (evenly spaced).
    pub profile_um: Vec<f64>,
    /// The step of `profile_um`, mm.
    pub profile_step_mm: f64,
    /// The crest model (always computed).
    pub crest: CrestPrediction,
    /// The z-map, for `model = "simulate"`.
    pub zmap: Option<ZmapPrediction>,
}

/// Predict case `c` of `study` with `cutter` (run-out applied), process effects `process`
/// and, for the simulate model, the spindle at `phase_rad` at the start of the pass.
pub fn predict_case(
    study: &Study,
    cutter: &Cutter,
    c: &StudyCase,
    process: &Process,
    phase_rad: f64,
) -> Result<CasePrediction, PredictError> {
    let fz = c.fz_mm.unwrap_or(study.fz_mm);
    let model = c.model.unwrap_or(study.model);
    let crest = crest_model_with(
        cutter,
        c.lead_deg,
        study.ap_mm,
        fz,
        study.rule,
        c.side.clone(),
        c.surface_radius_mm,
        process,
    )?;
    let zmap = match model {
        Model::Crest => None,
        Model::Simulate => {
            if c.surface_radius_mm.is_some() {
                return Err(PredictError::SimulateOnCurve);
            }
            let spec = study.simulate.unwrap_or_default();
            Some(simulate_case_with(
                cutter,
                c.lead_deg,
                study.ap_mm,
                fz,
                crest.fz_eff_mm,
                &spec,
                process,
                phase_rad,
            )?)
        }
    };
    let (rz_um, ra_um, profile_um, profile_step_mm) = match &zmap {
        Some(z) => (
            z.rz_um,
            z.ra_um,
            z.map.row(z.map.ny / 2).to_vec(),
            z.map.dx_um * 1e-3,
        ),
        None => (
            crest.rz_um,
            crest.ra_um,
            crest.profile_um.clone(),
            crest.profile_step_mm,
        ),
    };
    Ok(CasePrediction {
        rz_um,
        ra_um,
        profile_um,
        profile_step_mm,
        crest,
        zmap,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::{Cutter, Shape};
    use approx::assert_relative_eq;

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
