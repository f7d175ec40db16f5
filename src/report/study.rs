//! Designed experiments (001 §4 and appendix): full-factorial designs over tool orientation
//! and cutting parameters, and the factor effects of 001 Eqs 7-8.
//!
//! A design lists factors with their levels; the runs are the full factorial in the order of
//! the 001 appendix: the first factor varies slowest, the last fastest. Each run gets one
//! value per response (a surface parameter such as `Sq`). The effect of factor i at level j
//! is `EF_ij = M_ij − M` (Eq 7), where `M_ij` is the mean response over the runs with factor
//! i at level j and `M` the mean over all runs; Eq 8 divides the first-level effect by the
//! mean, `EF_i1 = (M_i1 − M)/M`, so that parameters of different units compare.

/// One factor and its levels.
#[derive(Debug, Clone, PartialEq)]
pub struct Factor {
    /// Name, with its unit (`tilt_deg`, `feed_mm_min`).
    pub name: String,
    /// Levels in order.
    pub levels: Vec<f64>,
}

/// The runs of a full-factorial design: for each run, the level index of each factor, in
/// appendix order (first factor slowest, last fastest).
pub fn full_factorial(factors: &[Factor]) -> Vec<Vec<usize>> {
    let n_runs: usize = factors.iter().map(|f| f.levels.len()).product();
    if factors.is_empty() || n_runs == 0 {
        return Vec::new();
    }
    let mut runs = Vec::with_capacity(n_runs);
    for run in 0..n_runs {
        let mut rest = run;
        let mut idx = vec![0; factors.len()];
        for (i, f) in factors.iter().enumerate().rev() {
            idx[i] = rest % f.levels.len();
            rest /= f.levels.len();
        }
        runs.push(idx);
    }
    runs
}

/// Factor effects of one response.
#[derive(Debug, Clone, PartialEq)]
pub struct Effects {
    /// Mean over all runs, M.
    pub mean: f64,
    /// `effects[i][j] = M_ij − M` (Eq 7).
    pub effects: Vec<Vec<f64>>,
    /// `relative_first[i] = (M_i1 − M)/M` (Eq 8); NaN when M = 0.
    pub relative_first: Vec<f64>,
}

/// Eqs 7-8 for one response: `runs` as from [`full_factorial`], `response[run]`.
/// Runs whose response is not finite are left out of every mean.
pub fn factor_effects(factors: &[Factor], runs: &[Vec<usize>], response: &[f64]) -> Effects {
    let finite: Vec<(usize, f64)> = response
        .iter()
        .copied()
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .collect();
    let mean = if finite.is_empty() {
        f64::NAN
    } else {
        finite.iter().map(|(_, v)| v).sum::<f64>() / finite.len() as f64
    };
    let mut effects = Vec::with_capacity(factors.len());
    for (i, f) in factors.iter().enumerate() {
        let mut row = Vec::with_capacity(f.levels.len());
        for j in 0..f.levels.len() {
            let (sum, n) = finite
                .iter()
                .filter(|(r, _)| runs[*r][i] == j)
                .fold((0.0, 0usize), |(s, n), (_, v)| (s + v, n + 1));
            row.push(if n == 0 {
                f64::NAN
            } else {
                sum / n as f64 - mean
            });
        }
        effects.push(row);
    }
    let relative_first = effects
        .iter()
        .map(|row| {
            if mean != 0.0 {
                row.first().copied().unwrap_or(f64::NAN) / mean
            } else {
                f64::NAN
            }
        })
        .collect();
    Effects {
        mean,
        effects,
        relative_first,
    }
}

/// Errors from design files.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
pub enum StudyError {
    /// The design TOML does not parse or breaks a rule; `line`/`column` are 1-based (0 when
    /// the error has no position).
    #[error("{file}:{line}:{column}: {message}")]
    Design {
        /// File name as given.
        file: String,
        /// Line, 1-based.
        line: usize,
        /// Column, 1-based.
        column: usize,
        /// What is wrong.
        message: String,
    },
}

/// Factor levels of a design file; every key carries its unit. A factor left out keeps its
/// default (tilt, yaw and lead 0°); a factor with one level is held fixed.
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct FactorLevels {
    /// Yaw ψ (convention A, model.md §7), degrees.
    pub yaw_deg: Option<Vec<f64>>,
    /// Tilt λ, degrees.
    pub tilt_deg: Option<Vec<f64>>,
    /// Lead (tilt with yaw 0), degrees; excludes `tilt_deg` and `yaw_deg`.
    pub lead_deg: Option<Vec<f64>>,
    /// Scallop height, µm (exact swept envelope, model.md R6); excludes `stepover_mm`.
    pub scallop_um: Option<Vec<f64>>,
    /// Pass interval, mm.
    pub stepover_mm: Option<Vec<f64>>,
    /// Feed, mm/min.
    pub feed_mm_min: Option<Vec<f64>>,
}

/// A design file (`crest study design.toml`).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Design {
    /// Title of the study.
    #[serde(default)]
    pub title: String,
    /// Where the design comes from.
    #[serde(default)]
    pub source: String,
    /// Surface name (as `crest synth`): `plane`, ….
    pub surface: String,
    /// Tool file, relative to the design file.
    pub tool: std::path::PathBuf,
    /// Spindle speed, rpm.
    pub rpm: f64,
    /// Grid spacing of the simulated height map, µm.
    pub grid_um: f64,
    /// Evaluated window (along the feed, across), mm; absent = one unit cell fz × step.
    pub window_mm: Option<[f64; 2]>,
    /// `one-way` or `zigzag`.
    #[serde(default = "default_pattern")]
    pub pattern: String,
    /// Surface model: `ice` (the teeth's edges swept, default) or `dome`.
    #[serde(default = "default_model")]
    pub model: String,
    /// Largest spindle step of the ICE model, degrees (default 0.25, as model.md R7).
    pub dtheta_deg: Option<f64>,
    /// How a scallop height becomes a pass interval: `exact` (default: the exact swept
    /// envelope of the simulated posture, convention A, model.md R6) or `convention-b` (the
    /// exact envelope of the convention-B posture, yaw as a side tilt about f, while the
    /// surface is still cut in convention A: a CAM system that reads the angles the other
    /// way; it comes closer to the trials' printed steps, model.md R6).
    #[serde(default = "default_step_rule")]
    pub step_rule: String,
    /// Response symbols (areal parameters such as `Sz`, `Sq`).
    pub responses: Vec<String>,
    /// The factors and their levels.
    pub factors: FactorLevels,
}

fn default_pattern() -> String {
    "one-way".to_string()
}

fn default_step_rule() -> String {
    "exact".to_string()
}

fn default_model() -> String {
    "ice".to_string()
}

/// Default spindle step of the ICE model, degrees (model.md R7 used 0.25°).
pub const DEFAULT_DTHETA_DEG: f64 = 0.25;

/// How the pass interval of a run is given.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StepSpec {
    /// Scallop height, µm.
    ScallopUm(f64),
    /// Pass interval, mm.
    StepoverMm(f64),
}

/// The settings of one run.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RunPoint {
    /// Run number, 1-based, in appendix order.
    pub run: usize,
    /// Tilt, degrees (the lead when the design uses `lead_deg`).
    pub tilt_deg: f64,
    /// Yaw, degrees.
    pub yaw_deg: f64,
    /// Pass interval.
    pub step: StepSpec,
    /// Feed, mm/min.
    pub feed_mm_min: f64,
    /// The value of each design factor, in [`Design::factors`] order.
    pub values: Vec<f64>,
}

impl Design {
    /// Parse a design; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Design, StudyError> {
        let err = |line: usize, column: usize, message: String| StudyError::Design {
            file: file.to_string(),
            line,
            column,
            message,
        };
        let design: Design = toml::from_str(text).map_err(|e| {
            let (line, column) = e
                .span()
                .map(|s| line_column(text, s.start))
                .unwrap_or((0, 0));
            err(line, column, e.message().to_string())
        })?;
        // Rule violations are reported at the line of the offending key.
        let at = |key: &str, message: String| {
            let (line, column) = text
                .lines()
                .enumerate()
                .find(|(_, l)| l.trim_start().starts_with(key))
                .map(|(i, l)| (i + 1, l.len() - l.trim_start().len() + 1))
                .unwrap_or((0, 0));
            err(line, column, message)
        };
        let positive = |key: &str, v: f64| {
            if v > 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(at(key, format!("{key} must be positive, got {v}")))
            }
        };
        positive("rpm", design.rpm)?;
        positive("grid_um", design.grid_um)?;
        if let Some(w) = design.window_mm {
            positive("window_mm", w[0])?;
            positive("window_mm", w[1])?;
        }
        if !matches!(design.pattern.as_str(), "one-way" | "zigzag") {
            return Err(at(
                "pattern",
                format!(
                    "pattern must be one-way or zigzag, got '{}'",
                    design.pattern
                ),
            ));
        }
        if design.surface != "plane" {
            return Err(at(
                "surface",
                format!(
                    "crest study simulates unit cells of a plane; surface '{}' is not supported",
                    design.surface
                ),
            ));
        }
        if !matches!(design.model.as_str(), "ice" | "dome") {
            return Err(at(
                "model",
                format!("model must be ice or dome, got '{}'", design.model),
            ));
        }
        if !matches!(design.step_rule.as_str(), "exact" | "convention-b") {
            return Err(at(
                "step_rule",
                format!(
                    "step_rule must be exact or convention-b, got '{}'",
                    design.step_rule
                ),
            ));
        }
        if let Some(d) = design.dtheta_deg {
            if !(d.is_finite() && d > 0.0 && d <= 90.0) {
                return Err(at(
                    "dtheta_deg",
                    format!("dtheta_deg must lie in (0, 90], got {d}"),
                ));
            }
        }
        for r in &design.responses {
            match crate::metrics::Param::from_symbol(r) {
                Some(p) if !p.is_profile() => {}
                _ => {
                    return Err(at(
                        "responses",
                        format!("responses: '{r}' is not an areal (ISO 25178) parameter"),
                    ));
                }
            }
        }
        if design.responses.is_empty() {
            return Err(at(
                "responses",
                "responses must name at least one parameter".into(),
            ));
        }
        let f = &design.factors;
        match (&f.scallop_um, &f.stepover_mm) {
            (Some(_), Some(_)) => {
                return Err(at(
                    "stepover_mm",
                    "give scallop_um or stepover_mm, not both".into(),
                ));
            }
            (None, None) => {
                return Err(at(
                    "[factors]",
                    "factors need scallop_um or stepover_mm".into(),
                ));
            }
            _ => {}
        }
        if f.feed_mm_min.is_none() {
            return Err(at("[factors]", "factors need feed_mm_min".into()));
        }
        if f.lead_deg.is_some() && (f.tilt_deg.is_some() || f.yaw_deg.is_some()) {
            return Err(at(
                "lead_deg",
                "lead_deg excludes tilt_deg and yaw_deg (a lead is a tilt with yaw 0)".into(),
            ));
        }
        for (key, levels) in design.factor_keys() {
            if levels.is_empty() {
                return Err(at(key, format!("{key} needs at least one level")));
            }
            let ok = levels.iter().all(|v| {
                v.is_finite()
                    && match key {
                        "scallop_um" | "stepover_mm" | "feed_mm_min" => *v > 0.0,
                        "tilt_deg" | "lead_deg" => (0.0..90.0).contains(v),
                        _ => true,
                    }
            });
            if !ok {
                return Err(at(
                    key,
                    format!("{key} has a level out of range: {levels:?}"),
                ));
            }
        }
        Ok(design)
    }

    fn factor_keys(&self) -> Vec<(&'static str, &Vec<f64>)> {
        let f = &self.factors;
        [
            ("yaw_deg", &f.yaw_deg),
            ("tilt_deg", &f.tilt_deg),
            ("lead_deg", &f.lead_deg),
            ("scallop_um", &f.scallop_um),
            ("stepover_mm", &f.stepover_mm),
            ("feed_mm_min", &f.feed_mm_min),
        ]
        .into_iter()
        .filter_map(|(k, v)| v.as_ref().map(|v| (k, v)))
        .collect()
    }

    /// The factors in appendix order (yaw, tilt or lead, scallop or stepover, feed).
    pub fn factors(&self) -> Vec<Factor> {
        self.factor_keys()
            .into_iter()
            .map(|(k, v)| Factor {
                name: k.to_string(),
                levels: v.clone(),
            })
            .collect()
    }

    /// The runs of the full factorial, in appendix order.
    pub fn runs(&self) -> Vec<RunPoint> {
        let factors = self.factors();
        full_factorial(&factors)
            .into_iter()
            .enumerate()
            .map(|(r, idx)| {
                let values: Vec<f64> = idx
                    .iter()
                    .enumerate()
                    .map(|(i, &j)| factors[i].levels[j])
                    .collect();
                let get = |name: &str| {
                    factors
                        .iter()
                        .position(|f| f.name == name)
                        .map(|i| values[i])
                };
                let step = match get("scallop_um") {
                    Some(h) => StepSpec::ScallopUm(h),
                    None => StepSpec::StepoverMm(get("stepover_mm").unwrap_or(f64::NAN)),
                };
                RunPoint {
                    run: r + 1,
                    tilt_deg: get("tilt_deg").or(get("lead_deg")).unwrap_or(0.0),
                    yaw_deg: get("yaw_deg").unwrap_or(0.0),
                    step,
                    feed_mm_min: get("feed_mm_min").unwrap_or(f64::NAN),
                    values,
                }
            })
            .collect()
    }
}

fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// What the evaluation of one run gives: its responses (in [`Design::responses`] order) and
/// the feed per tooth and pass interval it used.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RunOutput {
    /// Responses.
    pub responses: Vec<f64>,
    /// Feed per tooth, mm.
    pub fz_mm: f64,
    /// Pass interval (drive-plane spacing), mm.
    pub stepover_mm: f64,
}

/// The outcome of one run: its responses (in [`Design::responses`] order) or why it failed.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RunResult {
    /// The settings.
    pub point: RunPoint,
    /// Responses; NaN where the run failed.
    pub responses: Vec<f64>,
    /// Feed per tooth, mm (NaN when the run failed).
    pub fz_mm: f64,
    /// Pass interval, mm (NaN when the run failed).
    pub stepover_mm: f64,
    /// Why the run failed, if it did.
    pub error: Option<String>,
}

/// Evaluate every run of `design` with `eval` in parallel (rayon); results come back in run
/// order whatever the thread count. `tick` is called once per finished run.
pub fn run_design<F, T>(design: &Design, eval: F, tick: T) -> Vec<RunResult>
where
    F: Fn(&RunPoint) -> Result<RunOutput, String> + Sync,
    T: Fn() + Sync,
{
    use rayon::prelude::*;
    let n = design.responses.len();
    design
        .runs()
        .into_par_iter()
        .map(|point| {
            let out = eval(&point);
            tick();
            match out {
                Ok(mut o) => {
                    o.responses.resize(n, f64::NAN);
                    RunResult {
                        point,
                        responses: o.responses,
                        fz_mm: o.fz_mm,
                        stepover_mm: o.stepover_mm,
                        error: None,
                    }
                }
                Err(e) => RunResult {
                    point,
                    responses: vec![f64::NAN; n],
                    fz_mm: f64::NAN,
                    stepover_mm: f64::NAN,
                    error: Some(e),
                },
            }
        })
        .collect()
}

/// The evaluated grid of a run: the unit cell or the design's window, in the WCS (passes
/// along +x, stepped along +y), and the extent of the path that covers it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunWindow {
    /// Grid placement.
    pub grid: crate::surface::GridSpec,
    /// Field of the synthetic path: length along the passes, width across, mm.
    pub field_mm: (f64, f64),
}

/// Highest surface height (above the plane) a run may reach, mm: passes and tooth passes
/// that stay higher than this over the window are left out of the path, and a run whose
/// window comes out higher fails rather than report a wrong value.
pub const REACH_HEIGHT_MM: f64 = 0.1;

/// How far from its lowest point the swept body of `cutter` (unit axis `axis_fgn` in
/// (f, g, n)) stays within `h_mm` of the plane: (along f, across along g), mm. A pass (or a
/// tooth pass) farther than this from a node cannot cut it lower than `h_mm`.
pub fn reach_mm(
    cutter: &crate::tool::Cutter,
    axis_fgn: &crate::math::Vec3,
    h_mm: f64,
) -> Result<(f64, f64), String> {
    let one = |axis: &crate::math::Vec3| -> Result<f64, String> {
        let cs = crate::synth::CrossSection::new(cutter, axis).map_err(|e| e.to_string())?;
        let [yb, zb] = cs.bottom();
        let step = 0.005;
        let mut reach: f64 = 0.0;
        for sign in [-1.0, 1.0] {
            let mut k = 1usize;
            loop {
                let y = yb + sign * step * k as f64;
                match cs.lower(y) {
                    Some(z) if z - zb <= h_mm && k < 100_000 => k += 1,
                    _ => break,
                }
            }
            reach = reach.max(step * k as f64);
        }
        Ok(reach)
    };
    let a = axis_fgn;
    // Seen along g instead of f: (f, g, n) → (g, −f, n).
    let along = one(&crate::math::Vec3::new(a.y, -a.x, a.z))?;
    let across = one(a)?;
    Ok((along, across))
}

/// The window of a run with feed per tooth `fz_mm` and pass interval `step_mm`: without
/// `window_mm`, one unit cell `fz × s` (`fz × 2s` for zigzag passes) with its last column
/// and row left out, so that the periodic surface is counted once; with it, a window of that
/// size centred on the origin. The path field (centred on the origin) reaches `reach_mm`
/// (along, across; see [`reach_mm`]) plus 0.2 mm beyond the window on every side.
pub fn run_window(design: &Design, reach_mm: (f64, f64), fz_mm: f64, step_mm: f64) -> RunWindow {
    let d = design.grid_um * 1e-3;
    let across = if design.pattern == "zigzag" {
        2.0 * step_mm
    } else {
        step_mm
    };
    let (grid, a, b) = match design.window_mm {
        None => (
            crate::surface::GridSpec::Window {
                x0_mm: 0.0,
                y0_mm: 0.0,
                x1_mm: fz_mm - d,
                y1_mm: across - d,
            },
            fz_mm,
            across,
        ),
        Some([a, b]) => (
            crate::surface::GridSpec::Window {
                x0_mm: -0.5 * a,
                y0_mm: -0.5 * b,
                x1_mm: 0.5 * a,
                y1_mm: 0.5 * b,
            },
            a,
            b,
        ),
    };
    RunWindow {
        grid,
        field_mm: (2.0 * (a + reach_mm.0 + 0.2), 2.0 * (b + reach_mm.1 + 0.2)),
    }
}

/// The tool axis in (f, g, n) by convention B of model.md §7: lead λ about g, then a side
/// tilt ψ about f, `a = R_f(ψ)(sin λ f + cos λ n)`.
pub fn convention_b_axis(tilt_rad: f64, yaw_rad: f64) -> crate::math::Vec3 {
    crate::math::Vec3::new(
        tilt_rad.sin(),
        -yaw_rad.sin() * tilt_rad.cos(),
        yaw_rad.cos() * tilt_rad.cos(),
    )
}

/// Simulate one run of a design: the synthetic path (plane, passes along +x, tool posture
/// by convention A, pass interval from the scallop by the exact swept envelope), resampled
/// at a constant spindle step, the surface model of the design on [`run_window`], and the
/// areal parameters of the raw window (no levelling: a unit cell of a plane is periodic).
/// Every pass starts at the same spindle phase (model.md §8). The responses come back in
/// [`Design::responses`] order.
pub fn simulate_run(
    design: &Design,
    cutter: &crate::tool::Cutter,
    p: &RunPoint,
) -> Result<RunOutput, String> {
    use crate::synth::{Orientation, PathSpec, Pattern, Step, Surface};
    let lead = design.factors.lead_deg.is_some();
    let orientation = if lead {
        Orientation::Lead {
            lead_rad: p.tilt_deg.to_radians(),
        }
    } else {
        Orientation::TiltYaw {
            tilt_rad: p.tilt_deg.to_radians(),
            yaw_rad: p.yaw_deg.to_radians(),
        }
    };
    let step_mm = match p.step {
        StepSpec::StepoverMm(s) => s,
        StepSpec::ScallopUm(h) => {
            let axis = if design.step_rule == "convention-b" {
                convention_b_axis(p.tilt_deg.to_radians(), p.yaw_deg.to_radians())
            } else {
                orientation.axis_fgn()
            };
            crate::synth::exact_step_mm(cutter, &axis, h * 1e-3).map_err(|e| e.to_string())?
        }
    };
    let z = cutter.teeth().max(1) as f64;
    let fz_mm = p.feed_mm_min / (z * design.rpm);
    let reach = reach_mm(cutter, &orientation.axis_fgn(), REACH_HEIGHT_MM)?;
    let win = run_window(design, reach, fz_mm, step_mm);
    let mut spec = PathSpec::new(
        Surface::Plane,
        cutter.clone(),
        orientation,
        Step::Stepover {
            spacing_mm: step_mm,
        },
        win.field_mm,
    );
    spec.pattern = if design.pattern == "zigzag" {
        Pattern::Zigzag
    } else {
        Pattern::OneWay
    };
    spec.point_step_mm = 1.0;
    spec.clearance_mm = 1.0;
    spec.feed_mm_min = p.feed_mm_min;
    spec.spindle_rpm = design.rpm;
    let synth = crate::synth::generate(&spec).map_err(|e| e.to_string())?;
    let path = synth
        .program
        .paths
        .first()
        .ok_or_else(|| "the synthetic program has no tool path".to_string())?;

    let dtheta = design.dtheta_deg.unwrap_or(DEFAULT_DTHETA_DEG).to_radians();
    let (model, mode) = if design.model == "dome" {
        (
            crate::surface::Model::Dome,
            crate::resample::Mode::FeedPerTooth,
        )
    } else {
        // Resample every ≥ 8° of spindle; the engine subdivides to Δθ (as `crest simulate`).
        let coarse = dtheta * (8f64.to_radians() / dtheta).floor().max(1.0);
        (
            crate::surface::Model::Ice { dtheta_rad: dtheta },
            crate::resample::Mode::SpindleStep { dtheta_rad: coarse },
        )
    };
    let ropts = crate::resample::Options::new(mode, fz_mm, cutter.teeth())
        .with_rpm(design.rpm)
        .with_feed_mm_min(p.feed_mm_min);
    let samples = crate::resample::resample(path, &ropts).map_err(|e| e.to_string())?;
    let sopts = crate::surface::Options::new(model, win.grid, design.grid_um * 1e-3);
    let sim = crate::surface::simulate(&samples, cutter, &sopts, &|_, _| {})
        .map_err(|e| e.to_string())?;
    let nodes = sim.map.nx * sim.map.ny;
    if sim.nodes_cut != nodes {
        return Err(format!(
            "{} of {nodes} nodes of the window were not reached",
            nodes - sim.nodes_cut
        ));
    }
    let top = sim
        .map
        .z_um
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    if top > 1e3 * REACH_HEIGHT_MM {
        return Err(format!(
            "the window reaches {top:.1} µm above the plane, beyond the {} µm the path covers",
            1e3 * REACH_HEIGHT_MM
        ));
    }
    let params: Vec<crate::metrics::Param> = design
        .responses
        .iter()
        .map(|r| {
            crate::metrics::Param::from_symbol(r)
                .filter(|p| !p.is_profile())
                .ok_or_else(|| format!("'{r}' is not an areal parameter"))
        })
        .collect::<Result<_, _>>()?;
    let mut set_list: Vec<&str> = params.iter().map(|p| p.symbol()).collect();
    set_list.dedup();
    let set =
        crate::metrics::ParamSet::parse(&set_list.join(","), false).map_err(|e| e.to_string())?;
    let values = crate::metrics::areal_parameters(&sim.map, &set).map_err(|e| e.to_string())?;
    let responses = params
        .iter()
        .map(|p| {
            values
                .iter()
                .find(|(q, _)| q == p)
                .map_or(f64::NAN, |(_, v)| *v)
        })
        .collect();
    Ok(RunOutput {
        responses,
        fz_mm,
        stepover_mm: synth.stepover_mm,
    })
}

/// Eqs 7-8 for every response of a finished design, in [`Design::responses`] order.
pub fn design_effects(design: &Design, results: &[RunResult]) -> Vec<Effects> {
    let factors = design.factors();
    let runs = full_factorial(&factors);
    (0..design.responses.len())
        .map(|k| {
            let y: Vec<f64> = results.iter().map(|r| r.responses[k]).collect();
            factor_effects(&factors, &runs, &y)
        })
        .collect()
}

/// `runs.csv`: one row per run, `run`, the factor values, the responses and `error`.
pub fn write_runs_csv(
    design: &Design,
    results: &[RunResult],
    w: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    let mut head = vec!["run".to_string()];
    head.extend(design.factors().into_iter().map(|f| f.name));
    head.push("fz_mm".into());
    head.push("step_mm".into());
    // Response columns are named by their symbol only: units follow iso25178.md.
    head.extend(design.responses.iter().cloned());
    head.push("error".into());
    writeln!(w, "{}", head.join(","))?;
    for r in results {
        let mut row = vec![r.point.run.to_string()];
        row.extend(r.point.values.iter().map(|v| format!("{v}")));
        row.push(fmt_value(r.fz_mm));
        row.push(fmt_value(r.stepover_mm));
        row.extend(r.responses.iter().map(|v| fmt_value(*v)));
        row.push(
            r.error
                .as_deref()
                .map(|e| format!("\"{}\"", e.replace('"', "'")))
                .unwrap_or_default(),
        );
        writeln!(w, "{}", row.join(","))?;
    }
    Ok(())
}

fn fmt_value(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6}")
    } else {
        String::new()
    }
}

/// `effects.csv`: one row per response, factor and level: `response,factor,level,mean,
/// effect` (Eq 7, M_ij − M) and `relative_first` (Eq 8, filled on the first level only).
pub fn write_effects_csv(
    design: &Design,
    effects: &[Effects],
    w: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    writeln!(w, "response,factor,level,mean,effect,relative_first")?;
    let factors = design.factors();
    for (resp, e) in design.responses.iter().zip(effects) {
        for (i, f) in factors.iter().enumerate() {
            for (j, level) in f.levels.iter().enumerate() {
                let rel = if j == 0 {
                    fmt_value(e.relative_first[i])
                } else {
                    String::new()
                };
                writeln!(
                    w,
                    "{resp},{},{level},{},{},{rel}",
                    f.name,
                    fmt_value(e.mean),
                    fmt_value(e.effects[i][j]),
                )?;
            }
        }
    }
    Ok(())
}

/// The chart of 001 Fig 11: relative first-level effect EF_i1 (Eq 8, %) per parameter (x =
/// 1…n in [`Design::responses`] order), one series per factor with more than one level.
pub fn effects_chart(design: &Design, effects: &[Effects]) -> crate::plot::profile::LineChart {
    let factors = design.factors();
    let x: Vec<f64> = (1..=design.responses.len()).map(|k| k as f64).collect();
    let series = factors
        .iter()
        .enumerate()
        .filter(|(_, f)| f.levels.len() > 1)
        .map(|(i, f)| {
            let y: Vec<f64> = effects
                .iter()
                .map(|e| 100.0 * e.relative_first[i])
                .collect();
            crate::plot::profile::Series::new(format!("{} = {}", f.name, f.levels[0]), &x, &y)
        })
        .collect();
    let series: Vec<crate::plot::profile::Series> = series;
    let mut title = if design.title.is_empty() {
        "Relative first-level effects (001 Eq 8)".to_string()
    } else {
        format!("{}: relative first-level effects (Eq 8)", design.title)
    };
    // A single line gets no legend: name it in the title.
    if let [only] = series.as_slice() {
        title = format!("{title}, {}", only.label);
    }
    crate::plot::profile::LineChart {
        title,
        x_label: format!("parameter ({})", design.responses.join(", ")),
        y_label: "EF_i1 [%]".into(),
        series,
    }
}

/// The chart of 001 Fig 12: the relative effect `EF_ij/M` (%) of one factor at each of its
/// levels (x = the level), one series per response.
pub fn level_chart(
    design: &Design,
    effects: &[Effects],
    factor: usize,
) -> Option<crate::plot::profile::LineChart> {
    let f = design.factors().into_iter().nth(factor)?;
    let series = design
        .responses
        .iter()
        .zip(effects)
        .map(|(name, e)| {
            let y: Vec<f64> = e
                .effects
                .get(factor)
                .map(|row| {
                    row.iter()
                        .map(|v| {
                            if e.mean != 0.0 {
                                100.0 * v / e.mean
                            } else {
                                f64::NAN
                            }
                        })
                        .collect()
                })
                .unwrap_or_default();
            crate::plot::profile::Series::new(name.clone(), &f.levels, &y)
        })
        .collect();
    Some(crate::plot::profile::LineChart {
        title: if design.title.is_empty() {
            format!("Effect of {} (001 Eq 7 / M)", f.name)
        } else {
            format!("{}: effect of {} (Eq 7 / M)", design.title, f.name)
        },
        x_label: f.name.clone(),
        y_label: "EF_ij / M [%]".into(),
        series,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn doe16() -> Vec<Factor> {
        let f = |name: &str, levels: &[f64]| Factor {
            name: name.into(),
            levels: levels.to_vec(),
        };
        vec![
            f("yaw_deg", &[0.0, 20.0]),
            f("tilt_deg", &[1.0, 10.0]),
            f("scallop_um", &[5.0, 10.0]),
            f("feed_mm_min", &[2000.0, 4000.0]),
        ]
    }

    #[test]
    fn full_factorial_follows_the_001_appendix_order() {
        let factors = doe16();
        let runs = full_factorial(&factors);
        assert_eq!(runs.len(), 16);
        // Appendix rows 1, 2, 5, 9 and 16.
        let value = |r: usize| -> Vec<f64> {
            runs[r]
                .iter()
                .enumerate()
                .map(|(i, &j)| factors[i].levels[j])
                .collect()
        };
        assert_eq!(value(0), vec![0.0, 1.0, 5.0, 2000.0]);
        assert_eq!(value(1), vec![0.0, 1.0, 5.0, 4000.0]);
        assert_eq!(value(4), vec![0.0, 10.0, 5.0, 2000.0]);
        assert_eq!(value(8), vec![20.0, 1.0, 5.0, 2000.0]);
        assert_eq!(value(15), vec![20.0, 10.0, 10.0, 4000.0]);
    }

    #[test]
    fn effects_of_an_additive_response_are_its_coefficients() {
        // y = 10 + 3·[yaw high] − 2·[feed high]: a balanced design recovers ±1.5 and ∓1.
        let factors = doe16();
        let runs = full_factorial(&factors);
        let y: Vec<f64> = runs
            .iter()
            .map(|r| 10.0 + 3.0 * r[0] as f64 - 2.0 * r[3] as f64)
            .collect();
        let e = factor_effects(&factors, &runs, &y);
        assert_relative_eq!(e.mean, 10.5, epsilon = 1e-12);
        assert_relative_eq!(e.effects[0][0], -1.5, epsilon = 1e-12);
        assert_relative_eq!(e.effects[0][1], 1.5, epsilon = 1e-12);
        assert_relative_eq!(e.effects[1][0], 0.0, epsilon = 1e-12);
        assert_relative_eq!(e.effects[3][0], 1.0, epsilon = 1e-12);
        assert_relative_eq!(e.relative_first[0], -1.5 / 10.5, epsilon = 1e-12);
        // Effects over the levels of a factor sum to zero in a balanced design.
        for row in &e.effects {
            assert_relative_eq!(row.iter().sum::<f64>(), 0.0, epsilon = 1e-12);
        }
    }

    const DOE16: &str = include_str!("../../samples/studies/lavernhe-doe16.toml");
    const YAW6: &str = include_str!("../../samples/studies/lavernhe-yaw6.toml");

    #[test]
    fn the_sample_designs_parse_into_the_001_runs() {
        let d = Design::parse(DOE16, "doe16").unwrap();
        let names: Vec<String> = d.factors().into_iter().map(|f| f.name).collect();
        assert_eq!(names, ["yaw_deg", "tilt_deg", "scallop_um", "feed_mm_min"]);
        let runs = d.runs();
        assert_eq!(runs.len(), 16);
        // Appendix run 6: yaw 0, tilt 10, scallop 5 µm, feed 4000.
        let r = &runs[5];
        assert_eq!(r.run, 6);
        assert_eq!((r.yaw_deg, r.tilt_deg, r.feed_mm_min), (0.0, 10.0, 4000.0));
        assert_eq!(r.step, StepSpec::ScallopUm(5.0));
        assert_eq!(d.factors(), doe16());
        let y6 = Design::parse(YAW6, "yaw6").unwrap();
        assert_eq!(y6.runs().len(), 48);
        assert_eq!(
            y6.factors()[0].levels,
            vec![0.0, 2.0, 5.0, 10.0, 15.0, 20.0]
        );
    }

    #[test]
    fn reach_follows_the_effective_radii() {
        // R 5, rc 1.5, tilt 10°, yaw 0: across, z ≈ y²/(2 R_eff) with R_eff = 21.656 mm
        // (model.md R6); along, the corner circle rc in front: y = √(2 rc h).
        let cutter = crate::tool::Cutter::new(
            crate::tool::Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            1,
            0.0,
        );
        let a = crate::synth::axis_convention_a(10f64.to_radians(), 0.0);
        let h = 0.001;
        let (along, across) = reach_mm(&cutter, &a, h).unwrap();
        assert!(
            (across - (2.0 * 21.656 * h).sqrt()).abs() < 0.006,
            "{across}"
        );
        assert!((along - (2.0 * 1.5 * h).sqrt()).abs() < 0.006, "{along}");
        // At tilt 1° the end face trails at slope tan 1°: 0.1 mm is reached 5.73 mm behind.
        let a1 = crate::synth::axis_convention_a(1f64.to_radians(), 0.0);
        let (along, _) = reach_mm(&cutter, &a1, REACH_HEIGHT_MM).unwrap();
        let want = REACH_HEIGHT_MM / 1f64.to_radians().tan();
        assert!((along - want).abs() < 0.05, "{along} vs {want}");
    }

    #[test]
    fn convention_b_gives_the_r6_step_of_test_4() {
        // model.md R6, test 4 (B): yaw 20°, tilt 10°, h = 10 µm → s = 0.5259 mm; A: 1.2385.
        let cutter = crate::tool::Cutter::new(
            crate::tool::Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            1,
            0.0,
        );
        let (l, p) = (10f64.to_radians(), 20f64.to_radians());
        let b = crate::synth::exact_step_mm(&cutter, &convention_b_axis(l, p), 0.01).unwrap();
        assert!((b - 0.5259).abs() < 1e-3, "{b}");
        let a = crate::synth::exact_step_mm(&cutter, &crate::synth::axis_convention_a(l, p), 0.01)
            .unwrap();
        assert!((a - 1.2385).abs() < 1e-3, "{a}");
        // Without yaw the conventions agree.
        let a0 = crate::synth::axis_convention_a(l, 0.0);
        assert!((convention_b_axis(l, 0.0) - a0).norm() < 1e-15);
        let (_, msg) = design_err(&format!(
            "step_rule = \"cam\"\n{}",
            "surface = \"plane\"\ntool = \"t\"\nrpm = 1.0\ngrid_um = 1.0\nresponses = [\"Sq\"]\n\
             [factors]\nscallop_um = [5.0]\nfeed_mm_min = [1.0]\n"
        ));
        assert!(msg.contains("convention-b"), "{msg}");
    }

    fn design_err(text: &str) -> (usize, String) {
        match Design::parse(text, "d.toml") {
            Err(StudyError::Design { line, message, .. }) => (line, message),
            Ok(_) => panic!("accepted: {text}"),
        }
    }

    #[test]
    fn bad_designs_are_rejected_at_their_line() {
        let base = "surface = \"plane\"\ntool = \"t.toml\"\nrpm = 15000.0\ngrid_um = 4.0\n\
                    responses = [\"Sq\"]\n[factors]\nscallop_um = [5.0]\nfeed_mm_min = [2000.0]\n";
        assert!(Design::parse(base, "d.toml").is_ok());
        let (line, msg) = design_err(&base.replace("grid_um", "grid"));
        assert_eq!(line, 4, "{msg}");
        let (line, msg) = design_err(&format!("{base}stepover_mm = [0.5]\n"));
        assert_eq!(line, 9, "{msg}");
        assert!(msg.contains("not both"), "{msg}");
        let (line, msg) = design_err(&base.replace("rpm = 15000.0", "rpm = -1.0"));
        assert_eq!(line, 3, "{msg}");
        let (_, msg) = design_err(&format!("{base}tilt_deg = [95.0]\n"));
        assert!(msg.contains("out of range"), "{msg}");
        let (_, msg) = design_err(&format!("{base}lead_deg = [5.0]\nyaw_deg = [0.0]\n"));
        assert!(msg.contains("excludes"), "{msg}");
        let (_, msg) = design_err(&base.replace("responses = [\"Sq\"]", "responses = []"));
        assert!(msg.contains("at least one"), "{msg}");
        let (line, msg) = design_err(&base.replace("[\"Sq\"]", "[\"Sq\", \"Ra\"]"));
        assert_eq!(line, 5, "{msg}");
        assert!(msg.contains("'Ra'"), "{msg}");
        let (line, msg) = design_err(&base.replace("\"plane\"", "\"sphere\""));
        assert_eq!(line, 1, "{msg}");
        let (_, msg) = design_err(&format!("model = \"exact\"\n{base}"));
        assert!(msg.contains("ice or dome"), "{msg}");
        let (line, msg) = design_err(&format!("dtheta_deg = 0.0\n{base}"));
        assert_eq!(line, 1, "{msg}");
    }

    /// A synthetic response with known effects: Sq = 1 + 0.5·[yaw 20] + 0.1·scallop.
    fn fake(p: &RunPoint) -> Result<RunOutput, String> {
        let h = match p.step {
            StepSpec::ScallopUm(h) => h,
            StepSpec::StepoverMm(_) => return Err("no scallop".into()),
        };
        let sq = 1.0 + 0.5 * (p.yaw_deg / 20.0) + 0.1 * h;
        Ok(RunOutput {
            responses: vec![6.0 * sq, sq],
            fz_mm: p.feed_mm_min / 15000.0,
            stepover_mm: 0.1 * h,
        })
    }

    #[test]
    fn runs_in_parallel_come_back_in_order_for_any_thread_count() {
        let mut d = Design::parse(DOE16, "doe16").unwrap();
        d.responses = vec!["Sz".into(), "Sq".into()];
        let count = std::sync::atomic::AtomicUsize::new(0);
        let tick = || {
            count.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        };
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let a = one.install(|| run_design(&d, fake, tick));
        let b = two.install(|| run_design(&d, fake, tick));
        assert_eq!(a, b);
        assert_eq!(count.load(std::sync::atomic::Ordering::Relaxed), 32);
        assert!(a.iter().enumerate().all(|(i, r)| r.point.run == i + 1));
        let e = design_effects(&d, &a);
        // M(Sq) = 1 + 0.25 + 0.75 = 2; yaw at 0° lowers it by 0.25; scallop 5 µm by 0.25.
        assert_relative_eq!(e[1].mean, 2.0, epsilon = 1e-12);
        assert_relative_eq!(e[1].effects[0][0], -0.25, epsilon = 1e-12);
        assert_relative_eq!(e[1].relative_first[2], -0.125, epsilon = 1e-12);
        assert_relative_eq!(e[1].relative_first[1], 0.0, epsilon = 1e-12);
        // Eq 8 removes the unit: Sz = 6 Sq has the same relative effects.
        for i in 0..4 {
            assert_relative_eq!(
                e[0].relative_first[i],
                e[1].relative_first[i],
                epsilon = 1e-12
            );
        }

        let mut runs = Vec::new();
        write_runs_csv(&d, &a, &mut runs).unwrap();
        let runs = String::from_utf8(runs).unwrap();
        let lines: Vec<&str> = runs.lines().collect();
        assert_eq!(lines.len(), 17);
        assert_eq!(
            lines[0],
            "run,yaw_deg,tilt_deg,scallop_um,feed_mm_min,fz_mm,step_mm,Sz,Sq,error"
        );
        assert_eq!(
            lines[16],
            "16,20,10,10,4000,0.266667,1.000000,15.000000,2.500000,"
        );
        let mut eff = Vec::new();
        write_effects_csv(&d, &e, &mut eff).unwrap();
        let eff = String::from_utf8(eff).unwrap();
        assert_eq!(eff.lines().count(), 1 + 2 * 4 * 2);
        assert!(
            eff.contains("Sq,yaw_deg,0,2.000000,-0.250000,-0.125000\n"),
            "{eff}"
        );
        let chart = effects_chart(&d, &e);
        assert_eq!(chart.series.len(), 4);
        assert_eq!(chart.series[0].y, vec![-12.5, -12.5]);
        // Fig 12 style: the yaw effect at its two levels, ∓0.25/2 of Sq.
        let yaw = level_chart(&d, &e, 0).unwrap();
        assert_eq!(yaw.series.len(), 2);
        assert_eq!(yaw.series[1].x, vec![0.0, 20.0]);
        assert_relative_eq!(yaw.series[1].y[0], -12.5, epsilon = 1e-9);
        assert_relative_eq!(yaw.series[1].y[1], 12.5, epsilon = 1e-9);
        assert!(level_chart(&d, &e, 9).is_none());
    }

    #[test]
    fn failed_runs_are_kept_with_their_error_and_left_out_of_the_means() {
        let mut d = Design::parse(DOE16, "doe16").unwrap();
        d.responses = vec!["Sq".into()];
        let r = run_design(
            &d,
            |p| {
                if p.run == 1 {
                    Err("boom".into())
                } else {
                    Ok(RunOutput {
                        responses: vec![1.0],
                        fz_mm: 0.1,
                        stepover_mm: 1.0,
                    })
                }
            },
            || {},
        );
        assert_eq!(r[0].error.as_deref(), Some("boom"));
        assert!(r[0].responses[0].is_nan());
        let e = design_effects(&d, &r);
        assert_relative_eq!(e[0].mean, 1.0, epsilon = 1e-12);
    }
}
