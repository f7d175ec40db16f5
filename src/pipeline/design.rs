//! `crest study`: a designed-experiment file read from disk, its tool loaded (relative to the
//! design file), every run simulated in parallel, the factor effects computed and the
//! outputs of `crest study` rendered.

use crate::io::tables::json_number;
use crate::io::text::read_text;
use crate::pipeline::{Error, Result};
use crate::study::design::{Design, Effects, RunResult, design_effects, run_design};
use crate::study::run::simulate_run;
use crate::tool::Cutter;
use std::path::Path;

/// A finished designed experiment.
#[derive(Debug, Clone)]
pub struct DesignRun {
    /// The design.
    pub design: Design,
    /// One result per run, in run order.
    pub results: Vec<RunResult>,
    /// Factor effects per response, in response order.
    pub effects: Vec<Effects>,
    /// With `--monte-carlo N --seed S`: (N, S); every result then has its bands.
    pub monte_carlo: Option<(usize, u64)>,
}

/// Read the design `path` and its tool (without running anything).
pub fn load_design(path: &Path) -> Result<(Design, Cutter)> {
    let t = load_design_texts(path)?;
    let design = crate::config::design::parse_design(&t.design_toml, &t.design_file)?;
    let cutter = tool_of(&t)?;
    Ok((design, cutter))
}

/// The texts of a design file and of the tool file it names, with their names: everything a
/// run needs, so a run can be evaluated where neither file is on disk
/// ([`super::tasks`]).
#[derive(Debug, Clone, PartialEq)]
pub struct DesignTexts {
    /// The design file's name, as given (for messages).
    pub design_file: String,
    /// The design file's text.
    pub design_toml: String,
    /// The tool file's name (relative to the working directory when read).
    pub tool_file: String,
    /// The tool file's text.
    pub tool_toml: String,
}

/// Read the design `path` and the tool file it names (relative to the design file).
pub fn load_design_texts(path: &Path) -> Result<DesignTexts> {
    let design_toml = read_text(path, "design", crate::io::input::CONFIG)?;
    let design_file = path.display().to_string();
    let design = crate::config::design::parse_design(&design_toml, &design_file)?;
    let tool_path = path.parent().unwrap_or(Path::new(".")).join(&design.tool);
    let tool_file = tool_path.display().to_string();
    let tool_toml = read_text(&tool_path, "tool file", crate::io::input::CONFIG).map_err(|e| {
        Error::DesignTool {
            design: design_file.clone(),
            tool: tool_file.clone(),
            source: Box::new(e.into()),
        }
    })?;
    Ok(DesignTexts {
        design_file,
        design_toml,
        tool_file,
        tool_toml,
    })
}

/// The cutter of a design's tool text.
pub fn tool_of(t: &DesignTexts) -> Result<Cutter> {
    super::tool_from_text(&t.tool_toml, &t.tool_file).map_err(|e| Error::DesignTool {
        design: t.design_file.clone(),
        tool: t.tool_file.clone(),
        source: Box::new(e),
    })
}

/// Run every run of `design` with `cutter` on the current rayon pool (`tick` once per
/// finished run). Fails, naming every failed run, unless all succeed.
pub fn run(
    design: Design,
    cutter: Cutter,
    file: &str,
    tick: &(dyn Fn() + Sync),
) -> Result<DesignRun> {
    run_monte_carlo(design, cutter, file, None, tick)
}

/// [`run`], with `monte_carlo` = (N, S) the P5/P50/P95 bands of every response of every run
/// over N samples of seed S ([`crate::study::montecarlo::run_bands`]); the same for any
/// thread count. N is checked (1 ≤ N ≤ [`crate::study::uncertainty::MAX_SAMPLES`]) before
/// any run.
pub fn run_monte_carlo(
    design: Design,
    cutter: Cutter,
    file: &str,
    monte_carlo: Option<(usize, u64)>,
    tick: &(dyn Fn() + Sync),
) -> Result<DesignRun> {
    if let Some((n, _)) = monte_carlo {
        crate::study::uncertainty::check_samples(n).map_err(Error::stage)?;
    }
    check_budget(&design, &cutter, file)?;
    let results = run_design(
        &design,
        |p| evaluate(&design, &cutter, p, monte_carlo),
        tick,
    );
    finish(design, results, file, monte_carlo)
}

/// Refuse a design any of whose runs is estimated past the budget of a run
/// ([`crate::study::run::check_runs`]: the grid's nodes, the resampled poses, the memory),
/// before the first run starts.
pub fn check_budget(design: &Design, cutter: &Cutter, file: &str) -> Result<()> {
    crate::study::run::check_runs(design, cutter).map_err(|e| Error::within(file, e))
}

/// Evaluate run `p` of `design`: [`simulate_run`], or with `monte_carlo` = (N, S)
/// [`crate::study::montecarlo::run_bands`].
pub fn evaluate(
    design: &Design,
    cutter: &Cutter,
    p: &crate::study::design::RunPoint,
    monte_carlo: Option<(usize, u64)>,
) -> Result<crate::study::design::RunOutput, crate::study::montecarlo::MonteCarloError> {
    match monte_carlo {
        None => Ok(simulate_run(design, cutter, p)?),
        Some((n, seed)) => crate::study::montecarlo::run_bands(design, cutter, p, n, seed),
    }
}

/// A design's results (one per run, in run order) checked and completed with the effects:
/// fails, naming every failed run, unless all succeeded. `monte_carlo` is recorded as given.
pub fn finish(
    design: Design,
    results: Vec<RunResult>,
    file: &str,
    monte_carlo: Option<(usize, u64)>,
) -> Result<DesignRun> {
    let failed: Vec<String> = results
        .iter()
        .filter_map(|r| {
            r.error
                .as_ref()
                .map(|e| format!("run {}: {e}", r.point.run))
        })
        .collect();
    if !failed.is_empty() {
        return Err(Error::Result(format!(
            "{file}: {} of {} runs failed, nothing written:\n  {}",
            failed.len(),
            results.len(),
            failed.join("\n  ")
        )));
    }
    let effects = design_effects(&design, &results);
    Ok(DesignRun {
        design,
        results,
        effects,
        monte_carlo,
    })
}

/// The files `crest study` writes for a finished design, rendered in memory, in writing
/// order: `runs.csv`, `effects.csv`, `effects.svg` (when it has a series), `bands.svg`
/// (with Monte Carlo bands) and `effects-<factor>.svg` for each factor with more than two
/// levels.
pub fn render_outputs(done: &DesignRun) -> Result<Vec<(String, Vec<u8>)>> {
    use crate::io::tables::{write_effects_csv, write_runs_csv};
    use crate::plot::effects::{effects_chart, level_chart};
    let (design, results, effects) = (&done.design, &done.results, &done.effects);
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    let mut table = |name: &str, f: &dyn Fn(&mut Vec<u8>) -> std::io::Result<()>| {
        let mut buf = Vec::new();
        f(&mut buf).map_err(|e| Error::output(format_args!("write {name}"), e))?;
        files.push((name.to_string(), buf));
        Ok::<(), Error>(())
    };
    table("runs.csv", &|w| write_runs_csv(design, results, w))?;
    table("effects.csv", &|w| write_effects_csv(design, effects, w))?;
    crate::plot::init_fonts();
    let chart = effects_chart(design, effects);
    if !chart.series.is_empty() {
        files.push((
            "effects.svg".to_string(),
            crate::plot::effects::bar_chart_svg(&chart)
                .map_err(|e| Error::output("draw effects.svg", e))?,
        ));
    }
    if let Some(c) =
        crate::plot::effects::bands_chart(design, results, done.monte_carlo.map_or(0, |m| m.0))
    {
        let svg = c
            .check_finite()
            .map_err(|e| Error::output("draw bands.svg", e))
            .and_then(|()| {
                crate::plot::chart::render_svg(&c).map_err(|e| Error::output("draw bands.svg", e))
            })?;
        files.push(("bands.svg".to_string(), svg.into_bytes()));
    }
    for (i, f) in design.factors().iter().enumerate() {
        if f.levels.len() <= 2 {
            continue;
        }
        if let Some(c) = level_chart(design, effects, i) {
            let name = format!("effects-{}.svg", f.name);
            let svg = c
                .check_finite()
                .map_err(|e| Error::output(format_args!("draw {name}"), e))
                .and_then(|()| {
                    crate::plot::chart::render_svg(&c)
                        .map_err(|e| Error::output(format_args!("draw {name}"), e))
                })?;
            files.push((name, svg.into_bytes()));
        }
    }
    Ok(files)
}

/// One run as the JSON object of `crest study --json` (`run`, `factors`, `tilt_deg`,
/// `yaw_deg`, `feed_mm_min`, `fz_mm`, `stepover_mm`, `responses`, `error`; with Monte
/// Carlo bands also `bands`: response → `p5`, `p50`, `p95`).
pub fn run_json(design: &Design, r: &RunResult) -> serde_json::Value {
    let factors: serde_json::Map<String, serde_json::Value> = design
        .factors()
        .iter()
        .zip(&r.point.values)
        .map(|(f, v)| (f.name.clone(), json_number(*v)))
        .collect();
    let responses: serde_json::Map<String, serde_json::Value> = design
        .responses
        .iter()
        .zip(&r.responses)
        .map(|(k, v)| (k.clone(), json_number(*v)))
        .collect();
    let mut j = serde_json::json!({
        "run": r.point.run,
        "factors": factors,
        "tilt_deg": json_number(r.point.tilt_deg),
        "yaw_deg": json_number(r.point.yaw_deg),
        "feed_mm_min": json_number(r.point.feed_mm_min),
        "fz_mm": json_number(r.fz_mm),
        "stepover_mm": json_number(r.stepover_mm),
        "responses": responses,
        "error": r.error,
    });
    if let Some(bands) = &r.bands {
        let b: serde_json::Map<String, serde_json::Value> = design
            .responses
            .iter()
            .zip(bands)
            .map(|(k, b)| {
                (
                    k.clone(),
                    serde_json::json!({"p5": json_number(b.p5), "p50": json_number(b.p50), "p95": json_number(b.p95)}),
                )
            })
            .collect();
        j["bands"] = serde_json::Value::Object(b);
    }
    j
}

/// The effects as the JSON array of `crest study --json`: per response its `mean` and, per
/// factor, `levels`, `effects` and `relative_first`.
pub fn effects_json(design: &Design, effects: &[Effects]) -> Vec<serde_json::Value> {
    let factors = design.factors();
    design
        .responses
        .iter()
        .zip(effects)
        .map(|(name, e)| {
            let per: Vec<serde_json::Value> = factors
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    serde_json::json!({
                        "factor": f.name,
                        "levels": f.levels.iter().map(|v| json_number(*v)).collect::<Vec<_>>(),
                        "effects": e.effects[i].iter().map(|v| json_number(*v)).collect::<Vec<_>>(),
                        "relative_first": json_number(e.relative_first[i]),
                    })
                })
                .collect();
            serde_json::json!({
                "response": name,
                "mean": json_number(e.mean),
                "factors": per,
            })
        })
        .collect()
}
