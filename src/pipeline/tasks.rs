//! Studies split into independent tasks, one run each, for batch schedulers and Dask:
//! [`design_tasks`] gives the tasks of a designed experiment, [`run_task`] evaluates one
//! (anywhere: a task carries the texts of its design and tool files), [`merge`] assembles
//! the results into the [`DesignRun`] that `crest study` renders, bit for bit.
//!
//! Tasks and results are plain serde data (JSON objects): `crest study --shard K/N` writes
//! one shard's results as JSON lines, `crest merge` reads them, and the Python package hands
//! them to workers as dictionaries. Floats go through JSON as their shortest round-trip
//! decimal (serde_json's `float_roundtrip` parses them back to the same bits); a missing
//! value (NaN) is `null`.
//!
//! Part maps split the same way into tile tasks ([`map`]), run-out sweeps into case tasks
//! ([`runout`]); [`run_any`] and [`merge_any`] take a task or results of any kind by their
//! `kind`.

pub mod atlas;
pub mod map;
pub mod runout;

use super::design::{DesignRun, DesignTexts, finish, tool_of};
use crate::pipeline::{Error, Result};
use crate::study::design::{Design, RunResult};
use crate::study::uncertainty::Band;
use serde::{Deserialize, Serialize};

/// The `kind` of a designed-experiment run.
pub const DESIGN_RUN: &str = "design-run";

/// One run of a designed experiment, with everything needed to evaluate it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Task {
    /// What the task is: [`DESIGN_RUN`].
    pub kind: String,
    /// The design file's name (for messages).
    pub design_file: String,
    /// The design file's text.
    pub design_toml: String,
    /// The tool file's name (for messages).
    pub tool_file: String,
    /// The tool file's text.
    pub tool_toml: String,
    /// Run number, 1-based, in appendix order.
    pub run: usize,
    /// Number of runs of the design.
    pub runs: usize,
    /// Monte Carlo bands to compute, if any (absent in tasks without them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub monte_carlo: Option<MonteCarlo>,
}

/// The Monte Carlo settings of a task (`crest study --monte-carlo N --seed S`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MonteCarlo {
    /// Number of samples N.
    pub samples: usize,
    /// Seed S.
    pub seed: u64,
}

impl MonteCarlo {
    /// From `(N, S)`.
    pub fn of(settings: Option<(usize, u64)>) -> Option<MonteCarlo> {
        settings.map(|(samples, seed)| MonteCarlo { samples, seed })
    }

    /// As `(N, S)`.
    pub fn pair(settings: Option<MonteCarlo>) -> Option<(usize, u64)> {
        settings.map(|m| (m.samples, m.seed))
    }
}

/// One response's Monte Carlo band in a task result (`null` where not finite).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskBand {
    /// 5th percentile.
    pub p5: Option<f64>,
    /// Median.
    pub p50: Option<f64>,
    /// 95th percentile.
    pub p95: Option<f64>,
}

fn task_bands(bands: Option<Vec<Band>>) -> Option<Vec<TaskBand>> {
    bands.map(|b| {
        b.into_iter()
            .map(|b| TaskBand {
                p5: finite(b.p5),
                p50: finite(b.p50),
                p95: finite(b.p95),
            })
            .collect()
    })
}

/// The outcome of one task: the run's responses or why it failed, with its design (so that
/// results merge without the files).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskResult {
    /// What the task was: [`DESIGN_RUN`].
    pub kind: String,
    /// The design file's name.
    pub design_file: String,
    /// The design file's text.
    pub design_toml: String,
    /// Run number, 1-based.
    pub run: usize,
    /// Number of runs of the design.
    pub runs: usize,
    /// Responses in the design's order (`null` where not finite).
    pub responses: Vec<Option<f64>>,
    /// Feed per tooth, mm.
    pub fz_mm: Option<f64>,
    /// Pass interval, mm.
    pub stepover_mm: Option<f64>,
    /// Why the run failed, if it did.
    pub error: Option<String>,
    /// The task's Monte Carlo settings, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub monte_carlo: Option<MonteCarlo>,
    /// With Monte Carlo: the band of every response, in the design's order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bands: Option<Vec<TaskBand>>,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

fn parse(t: &DesignTexts) -> Result<Design> {
    Ok(crate::config::design::parse_design(
        &t.design_toml,
        &t.design_file,
    )?)
}

/// The tasks of a design (its texts as [`super::design::load_design_texts`] reads them), one
/// per run in run order. The design and its tool are checked here, so a task fails only in
/// its run.
pub fn design_tasks(t: &DesignTexts) -> Result<Vec<Task>> {
    design_tasks_with(t, None)
}

/// [`design_tasks`] with Monte Carlo bands of `monte_carlo` samples (checked here).
pub fn design_tasks_with(t: &DesignTexts, monte_carlo: Option<MonteCarlo>) -> Result<Vec<Task>> {
    let design = parse(t)?;
    tool_of(t)?;
    if let Some(m) = monte_carlo {
        crate::study::uncertainty::check_samples(m.samples).map_err(Error::stage)?;
    }
    let runs = design.runs().len();
    Ok((1..=runs)
        .map(|run| Task {
            kind: DESIGN_RUN.to_string(),
            design_file: t.design_file.clone(),
            design_toml: t.design_toml.clone(),
            tool_file: t.tool_file.clone(),
            tool_toml: t.tool_toml.clone(),
            run,
            runs,
            monte_carlo,
        })
        .collect())
}

/// Evaluate one task. A run that fails comes back with its `error` (as in `crest study`'s
/// `runs.csv`); a task that is not valid (unknown kind, a design or tool that does not
/// parse, a run number out of range) is an error.
pub fn run_task(task: &Task) -> Result<TaskResult> {
    if task.kind != DESIGN_RUN {
        return Err(Error::Tasks(format!(
            "unknown task kind '{}' (expected '{DESIGN_RUN}')",
            task.kind
        )));
    }
    let texts = DesignTexts {
        design_file: task.design_file.clone(),
        design_toml: task.design_toml.clone(),
        tool_file: task.tool_file.clone(),
        tool_toml: task.tool_toml.clone(),
    };
    let design = parse(&texts)?;
    let cutter = tool_of(&texts)?;
    let points = design.runs();
    if points.len() != task.runs || task.run == 0 || task.run > points.len() {
        return Err(Error::Tasks(format!(
            "{}: task for run {} of {}, but the design has {} runs",
            task.design_file,
            task.run,
            task.runs,
            points.len()
        )));
    }
    let point = &points[task.run - 1];
    let n = design.responses.len();
    let mc = MonteCarlo::pair(task.monte_carlo);
    if let Some((samples, _)) = mc {
        crate::study::uncertainty::check_samples(samples).map_err(Error::stage)?;
    }
    let out = super::design::evaluate(&design, &cutter, point, mc);
    let (responses, fz_mm, stepover_mm, error, bands) = match out {
        Ok(mut o) => {
            o.responses.resize(n, f64::NAN);
            if let Some(b) = &mut o.bands {
                b.resize(n, Band::NAN);
            }
            (o.responses, o.fz_mm, o.stepover_mm, None, o.bands)
        }
        Err(e) => (
            vec![f64::NAN; n],
            f64::NAN,
            f64::NAN,
            Some(e.to_string()),
            None,
        ),
    };
    Ok(TaskResult {
        kind: DESIGN_RUN.to_string(),
        design_file: task.design_file.clone(),
        design_toml: task.design_toml.clone(),
        run: task.run,
        runs: task.runs,
        responses: responses.into_iter().map(finite).collect(),
        fz_mm: finite(fz_mm),
        stepover_mm: finite(stepover_mm),
        error,
        monte_carlo: task.monte_carlo,
        bands: task_bands(bands),
    })
}

/// Evaluate shard `k` of `n` of a design in this process (the runs in parallel on the
/// current rayon pool, `tick` once per finished run): the results of [`run_task`] on each of
/// the shard's [`shard`] tasks, in run order.
pub fn run_shard(
    t: &DesignTexts,
    k: usize,
    n: usize,
    tick: &(dyn Fn() + Sync),
) -> Result<Vec<TaskResult>> {
    run_shard_with(t, k, n, None, tick)
}

/// [`run_shard`] with Monte Carlo bands of `monte_carlo` samples (checked before any run).
pub fn run_shard_with(
    t: &DesignTexts,
    k: usize,
    n: usize,
    monte_carlo: Option<MonteCarlo>,
    tick: &(dyn Fn() + Sync),
) -> Result<Vec<TaskResult>> {
    let design = parse(t)?;
    let cutter = tool_of(t)?;
    let mc = MonteCarlo::pair(monte_carlo);
    if let Some((samples, _)) = mc {
        crate::study::uncertainty::check_samples(samples).map_err(Error::stage)?;
    }
    // Every run of the design, as `crest study` checks them: a shard is refused like the
    // whole.
    super::design::check_budget(&design, &cutter, &t.design_file)?;
    let all = design.runs();
    let runs = all.len();
    let points: Vec<_> = all
        .into_iter()
        .enumerate()
        .filter(|(i, _)| n > 0 && i % n + 1 == k)
        .map(|(_, p)| p)
        .collect();
    let results = crate::study::design::run_points(
        &design,
        points,
        |p| super::design::evaluate(&design, &cutter, p, mc),
        tick,
    );
    Ok(results
        .into_iter()
        .map(|r| TaskResult {
            kind: DESIGN_RUN.to_string(),
            design_file: t.design_file.clone(),
            design_toml: t.design_toml.clone(),
            run: r.point.run,
            runs,
            responses: r.responses.into_iter().map(finite).collect(),
            fz_mm: finite(r.fz_mm),
            stepover_mm: finite(r.stepover_mm),
            error: r.error,
            monte_carlo,
            bands: task_bands(r.bands),
        })
        .collect())
}

/// The tasks of shard `k` of `n` (1-based): every n-th task from the k-th, so that shards
/// of a design whose run cost grows along a factor get a fair share.
pub fn shard(tasks: Vec<Task>, k: usize, n: usize) -> Vec<Task> {
    tasks
        .into_iter()
        .enumerate()
        .filter(|(i, _)| n > 0 && i % n + 1 == k)
        .map(|(_, t)| t)
        .collect()
}

/// Check the shards of a split task list (`crest merge`): each shard `1..=shards` given
/// once, each holding exactly the items `i` (0-based, of `total`) with `i % shards + 1` its
/// number (`items`: the shard and its item indices in order; `what`: "cells", "cases").
pub(crate) fn check_shards(
    file: &str,
    shards: usize,
    total: usize,
    items: impl IntoIterator<Item = (usize, Vec<usize>)>,
    what: &str,
) -> Result<()> {
    let mut seen = vec![false; shards];
    for (shard, got) in items {
        let slot = shard
            .checked_sub(1)
            .and_then(|i| seen.get_mut(i))
            .ok_or_else(|| {
                Error::Tasks(format!(
                    "{file}: shard {shard} is out of range 1..={shards}"
                ))
            })?;
        if *slot {
            return Err(Error::Tasks(format!(
                "{file}: shard {shard} of {shards} is given twice"
            )));
        }
        *slot = true;
        let want: Vec<usize> = (0..total).filter(|i| i % shards + 1 == shard).collect();
        if got != want {
            return Err(Error::Tasks(format!(
                "{file}: shard {shard} of {shards} does not hold its {what} ({} of {} expected)",
                got.len(),
                want.len()
            )));
        }
    }
    let missing: Vec<String> = seen
        .iter()
        .enumerate()
        .filter(|(_, s)| !**s)
        .map(|(i, _)| (i + 1).to_string())
        .collect();
    if !missing.is_empty() {
        return Err(Error::Tasks(format!(
            "{file}: {} of {shards} shards are missing: {}",
            missing.len(),
            missing.join(", ")
        )));
    }
    Ok(())
}

/// A shard's text that is not `K/N` with 1 ≤ K ≤ N.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("'{0}' is not a shard K/N with 1 ≤ K ≤ N (e.g. 2/8)")]
pub struct BadShard(pub String);

/// Parse `K/N` (1 ≤ K ≤ N).
pub fn parse_shard(s: &str) -> Result<(usize, usize), BadShard> {
    let bad = || BadShard(s.to_string());
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let k: usize = k.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if k == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}

/// Assemble the results of every task of one design (in any order) into the finished
/// design `crest study` renders. Fails if the results are of different designs, if a run
/// is missing or given twice, or (as `crest study`) if a run failed, naming every one.
pub fn merge(results: Vec<TaskResult>) -> Result<DesignRun> {
    let first = results
        .first()
        .ok_or_else(|| Error::Tasks("no task results to merge".into()))?;
    if let Some(r) = results.iter().find(|r| r.kind != DESIGN_RUN) {
        return Err(Error::Tasks(format!(
            "unknown task kind '{}' (expected '{DESIGN_RUN}')",
            r.kind
        )));
    }
    let (file, text, runs, monte_carlo) = (
        first.design_file.clone(),
        first.design_toml.clone(),
        first.runs,
        first.monte_carlo,
    );
    if let Some(r) = results
        .iter()
        .find(|r| r.design_toml != text || r.runs != runs)
    {
        return Err(Error::Tasks(format!(
            "the results are of different designs: run {} of {} ({}) is not of the design of {file}",
            r.run, r.design_file, r.runs
        )));
    }
    if let Some(r) = results.iter().find(|r| r.monte_carlo != monte_carlo) {
        let say = |m: Option<MonteCarlo>| {
            m.map_or("no Monte Carlo".to_string(), |m| {
                format!("‹monte_carlo› {} ‹seed› {}", m.samples, m.seed)
            })
        };
        return Err(Error::Tasks(format!(
            "{file}: the results were run with different Monte Carlo settings: run {} with {}, run {} with {}",
            first.run,
            say(monte_carlo),
            r.run,
            say(r.monte_carlo)
        )));
    }
    let design = crate::config::design::parse_design(&text, &file)?;
    let points = design.runs();
    if points.len() != runs {
        return Err(Error::Tasks(format!(
            "{file}: the results count {runs} runs, but the design has {}",
            points.len()
        )));
    }
    let mut slots: Vec<Option<TaskResult>> = vec![None; runs];
    for r in results {
        let run = r.run;
        let slot = run
            .checked_sub(1)
            .and_then(|i| slots.get_mut(i))
            .ok_or_else(|| Error::Tasks(format!("{file}: run {run} is out of range 1..={runs}")))?;
        if slot.is_some() {
            return Err(Error::Tasks(format!("{file}: run {run} is given twice")));
        }
        *slot = Some(r);
    }
    let missing: Vec<String> = slots
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_none())
        .map(|(i, _)| (i + 1).to_string())
        .collect();
    if !missing.is_empty() {
        return Err(Error::Tasks(format!(
            "{file}: {} of {runs} runs are missing: {}",
            missing.len(),
            missing.join(", ")
        )));
    }
    let n = design.responses.len();
    let results: Vec<RunResult> = slots
        .into_iter()
        .flatten()
        .zip(points)
        .map(|(r, point)| {
            let mut responses: Vec<f64> =
                r.responses.iter().map(|v| v.unwrap_or(f64::NAN)).collect();
            responses.resize(n, f64::NAN);
            let nan = |v: Option<f64>| v.unwrap_or(f64::NAN);
            let bands = r.bands.map(|b| {
                let mut b: Vec<Band> = b
                    .iter()
                    .map(|b| Band {
                        p5: nan(b.p5),
                        p50: nan(b.p50),
                        p95: nan(b.p95),
                    })
                    .collect();
                b.resize(n, Band::NAN);
                b
            });
            RunResult {
                point,
                responses,
                fz_mm: r.fz_mm.unwrap_or(f64::NAN),
                stepover_mm: r.stepover_mm.unwrap_or(f64::NAN),
                error: r.error,
                bands,
            }
        })
        .collect();
    finish(design, results, &file, MonteCarlo::pair(monte_carlo))
}

/// What [`merge_any`] assembled: a designed experiment or a part map.
#[derive(Debug)]
pub enum Merged {
    /// The finished design (`crest study`'s outputs).
    Design(Box<DesignRun>),
    /// The part map (`crest simulate --map-mm`'s PLY).
    Map(crate::surface::PartMap),
    /// The run-out study (`crest runout`'s outputs).
    Runout(Box<super::runout::RunoutRun>),
    /// The roughness atlas (`crest atlas`'s table or point cloud).
    Atlas(Box<super::atlas::Atlas>),
}

fn kind_of(v: &serde_json::Value) -> &str {
    v.get("kind").and_then(|k| k.as_str()).unwrap_or("")
}

/// Run one task given as JSON (a design run, a part-map shard or a run-out shard, by its
/// `kind`); the result as JSON.
pub fn run_any(task: serde_json::Value) -> Result<serde_json::Value> {
    let bad = |e: serde_json::Error| Error::within("not a crest task", e);
    let out = match kind_of(&task) {
        map::MAP_TILES => serde_json::to_value(map::run_map_task(
            &serde_json::from_value(task).map_err(bad)?,
        )?),
        runout::RUNOUT_CASES => serde_json::to_value(runout::run_runout_task(
            &serde_json::from_value(task).map_err(bad)?,
        )?),
        atlas::ATLAS_PATCHES => serde_json::to_value(atlas::run_atlas_task(
            &serde_json::from_value(task).map_err(bad)?,
        )?),
        _ => serde_json::to_value(run_task(&serde_json::from_value(task).map_err(bad)?)?),
    };
    out.map_err(|e| Error::output("encode the task result", e))
}

/// The group a result of this `kind` merges with: a part map, a run-out study, or else a
/// designed experiment (whose merge names a kind it does not know).
fn group_of(v: &serde_json::Value) -> &'static str {
    match kind_of(v) {
        map::MAP_TILES => map::MAP_TILES,
        runout::RUNOUT_CASES => runout::RUNOUT_CASES,
        atlas::ATLAS_PATCHES => atlas::ATLAS_PATCHES,
        _ => DESIGN_RUN,
    }
}

/// Assemble task results given as JSON, each with where it comes from (`file:line`, for
/// messages): all of one design ([`merge`]), all of one part map ([`map::merge_map`]) or
/// all of one run-out study ([`runout::merge_runout`]).
pub fn merge_any(results: Vec<(String, serde_json::Value)>) -> Result<Merged> {
    let group = results.first().map_or(DESIGN_RUN, |(_, v)| group_of(v));
    if let Some((at, v)) = results.iter().find(|(_, v)| group_of(v) != group) {
        return Err(Error::Tasks(format!(
            "{at}: a result of kind '{}' among results of kind '{group}': merge the results of one study, one run-out study, one part map or one atlas",
            kind_of(v),
        )));
    }
    fn parse<T: serde::de::DeserializeOwned>(
        results: Vec<(String, serde_json::Value)>,
    ) -> Result<Vec<T>> {
        results
            .into_iter()
            .map(|(at, v)| {
                serde_json::from_value(v)
                    .map_err(|e| Error::within(format_args!("{at}: not a task result"), e))
            })
            .collect()
    }
    match group {
        map::MAP_TILES => Ok(Merged::Map(map::merge_map(parse(results)?)?)),
        runout::RUNOUT_CASES => Ok(Merged::Runout(Box::new(runout::merge_runout(parse(
            results,
        )?)?))),
        atlas::ATLAS_PATCHES => Ok(Merged::Atlas(Box::new(atlas::merge_atlas(parse(
            results,
        )?)?))),
        _ => Ok(Merged::Design(Box::new(merge(parse(results)?)?))),
    }
}
