//! Designed experiments (001 §4 and appendix): full-factorial designs over tool orientation
//! and cutting parameters, and the factor effects of 001 Eqs 7-8.
//!
//! A design lists factors with their levels; the runs are the full factorial in the order of
//! the 001 appendix: the first factor varies slowest, the last fastest. Each run gets one
//! value per response (a surface parameter such as `Sq`). The effect of factor i at level j
//! is `EF_ij = M_ij − M` (Eq 7), where `M_ij` is the mean response over the runs with factor
//! i at level j and `M` the mean over all runs; Eq 8 divides the first-level effect by the
//! mean, `EF_i1 = (M_i1 − M)/M`, so that parameters of different units compare.

use serde::Serialize;

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

/// Default spindle step of the ICE model, degrees (model.md R7 used 0.25°).
pub const DEFAULT_DTHETA_DEG: f64 = 0.25;

/// How a scallop height becomes a pass interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
pub enum StepRule {
    /// The exact swept envelope of the simulated posture (convention A, model.md R6).
    #[default]
    #[serde(rename = "exact")]
    Exact,
    /// The exact envelope of the convention-B posture (yaw as a side tilt about f) while the
    /// surface is still cut in convention A: a CAM system that reads the angles the other
    /// way; it comes closer to the trials' printed steps (model.md R6).
    #[serde(rename = "convention-b")]
    ConventionB,
}

/// Factor levels of a design; every name carries its unit. A factor left out keeps its
/// default (tilt, yaw and lead 0°); a factor with one level is held fixed.
#[derive(Debug, Clone, Default, PartialEq)]
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

/// A designed experiment over a plane (`crest study`; read by [`crate::config::design`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    /// Title of the study.
    pub title: String,
    /// Where the design comes from.
    pub source: String,
    /// Tool file, relative to the design file.
    pub tool: std::path::PathBuf,
    /// Spindle speed, rpm.
    pub rpm: f64,
    /// Grid spacing of the simulated height map, µm.
    pub grid_um: f64,
    /// Evaluated window (along the feed, across), mm; absent = one unit cell fz × step.
    pub window_mm: Option<[f64; 2]>,
    /// Pass direction pattern.
    pub pattern: crate::synth::Pattern,
    /// Surface model.
    pub model: crate::surface::ModelKind,
    /// Largest spindle step of the ICE model, degrees (default [`DEFAULT_DTHETA_DEG`]).
    pub dtheta_deg: Option<f64>,
    /// How a scallop height becomes a pass interval.
    pub step_rule: StepRule,
    /// Response symbols (areal parameters such as `Sz`, `Sq`).
    pub responses: Vec<String>,
    /// The factors and their levels.
    pub factors: FactorLevels,
    /// Standard uncertainties of the inputs of `--monte-carlo` (the file's `[uncertainty]`).
    pub uncertainty: super::uncertainty::Uncertainty,
}

/// How the pass interval of a run is given.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StepSpec {
    /// Scallop height, µm.
    ScallopUm(f64),
    /// Pass interval, mm.
    StepoverMm(f64),
}

/// The settings of one run.
#[derive(Debug, Clone, PartialEq, Serialize)]
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
    /// The factor keys present, in appendix order, with their levels.
    pub fn factor_keys(&self) -> Vec<(&'static str, &Vec<f64>)> {
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

/// What the evaluation of one run gives: its responses (in [`Design::responses`] order) and
/// the feed per tooth and pass interval it used.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunOutput {
    /// Responses.
    pub responses: Vec<f64>,
    /// Feed per tooth, mm.
    pub fz_mm: f64,
    /// Pass interval (drive-plane spacing), mm.
    pub stepover_mm: f64,
    /// With `--monte-carlo`: the P5/P50/P95 band of every response, in response order.
    pub bands: Option<Vec<super::uncertainty::Band>>,
}

/// The outcome of one run: its responses (in [`Design::responses`] order) or why it failed.
#[derive(Debug, Clone, PartialEq, Serialize)]
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
    /// With `--monte-carlo`: the P5/P50/P95 band of every response (NaN bands where the run
    /// failed).
    pub bands: Option<Vec<super::uncertainty::Band>>,
}

/// Evaluate every run of `design` with `eval` in parallel (rayon); results come back in run
/// order whatever the thread count. `tick` is called once per finished run.
pub fn run_design<F, T, E>(design: &Design, eval: F, tick: T) -> Vec<RunResult>
where
    F: Fn(&RunPoint) -> Result<RunOutput, E> + Sync,
    E: std::fmt::Display,
    T: Fn() + Sync,
{
    run_points(design, design.runs(), eval, tick)
}

/// Evaluate the runs `points` of `design` (some of [`Design::runs`], e.g. one shard) with
/// `eval` in parallel (rayon); results come back in the order of `points`.
pub fn run_points<F, T, E>(
    design: &Design,
    points: Vec<RunPoint>,
    eval: F,
    tick: T,
) -> Vec<RunResult>
where
    F: Fn(&RunPoint) -> Result<RunOutput, E> + Sync,
    E: std::fmt::Display,
    T: Fn() + Sync,
{
    use rayon::prelude::*;
    let n = design.responses.len();
    points
        .into_par_iter()
        .map(|point| {
            let out = eval(&point);
            tick();
            match out {
                Ok(mut o) => {
                    o.responses.resize(n, f64::NAN);
                    if let Some(b) = &mut o.bands {
                        b.resize(n, super::uncertainty::Band::NAN);
                    }
                    RunResult {
                        point,
                        responses: o.responses,
                        fz_mm: o.fz_mm,
                        stepover_mm: o.stepover_mm,
                        error: None,
                        bands: o.bands,
                    }
                }
                Err(e) => RunResult {
                    point,
                    responses: vec![f64::NAN; n],
                    fz_mm: f64::NAN,
                    stepover_mm: f64::NAN,
                    error: Some(e.to_string()),
                    bands: None,
                },
            }
        })
        .collect()
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

    fn doe16_design() -> Design {
        crate::config::design::parse_design(DOE16, "doe16").unwrap()
    }

    /// A synthetic response with known effects: Sq = 1 + 0.5·[yaw 20] + 0.1·scallop.
    fn fake(p: &RunPoint) -> Result<RunOutput, &'static str> {
        let h = match p.step {
            StepSpec::ScallopUm(h) => h,
            StepSpec::StepoverMm(_) => return Err("no scallop"),
        };
        let sq = 1.0 + 0.5 * (p.yaw_deg / 20.0) + 0.1 * h;
        Ok(RunOutput {
            responses: vec![6.0 * sq, sq],
            fz_mm: p.feed_mm_min / 15000.0,
            stepover_mm: 0.1 * h,
            bands: None,
        })
    }

    #[test]
    fn runs_in_parallel_come_back_in_order_for_any_thread_count() {
        let mut d = doe16_design();
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
        crate::io::tables::write_runs_csv(&d, &a, &mut runs).unwrap();
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
        crate::io::tables::write_effects_csv(&d, &e, &mut eff).unwrap();
        let eff = String::from_utf8(eff).unwrap();
        assert_eq!(eff.lines().count(), 1 + 2 * 4 * 2);
        assert!(
            eff.contains("Sq,yaw_deg,0,2.000000,-0.250000,-0.125000\n"),
            "{eff}"
        );
        let chart = crate::plot::effects::effects_chart(&d, &e);
        assert_eq!(chart.series.len(), 4);
        assert_eq!(chart.series[0].y, vec![-12.5, -12.5]);
        // Fig 12 style: the yaw effect at its two levels, ∓0.25/2 of Sq.
        let yaw = crate::plot::effects::level_chart(&d, &e, 0).unwrap();
        let yaw = &yaw.panels[0];
        assert_eq!(yaw.series.len(), 2);
        let x: Vec<f64> = yaw.series[1].points.iter().map(|p| p.0).collect();
        assert_eq!(x, vec![0.0, 20.0]);
        assert_relative_eq!(yaw.series[1].points[0].1, -12.5, epsilon = 1e-9);
        assert_relative_eq!(yaw.series[1].points[1].1, 12.5, epsilon = 1e-9);
        assert!(crate::plot::effects::level_chart(&d, &e, 9).is_none());
    }

    #[test]
    fn failed_runs_are_kept_with_their_error_and_left_out_of_the_means() {
        let mut d = doe16_design();
        d.responses = vec!["Sq".into()];
        let r = run_design(
            &d,
            |p| {
                if p.run == 1 {
                    Err("boom")
                } else {
                    Ok(RunOutput {
                        responses: vec![1.0],
                        fz_mm: 0.1,
                        stepover_mm: 1.0,
                        bands: None,
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
