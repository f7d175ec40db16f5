//! Run-out sweeps split into independent tasks: [`runout_tasks`] cuts a `crest runout`
//! study into `n` tasks (task k evaluates cases k-1, k-1+n, … of the sweep; by default one
//! case per task), [`run_runout_task`] evaluates one, [`merge_runout`] puts the rows back
//! in case order into the [`RunoutRun`] the single process makes (the same `runout.csv`
//! and charts, byte for byte).
//!
//! A task carries the study and tool texts (and the tool file's name, whose stem titles
//! the charts), so it runs where neither file is. Results are serde data; floats go
//! through JSON as shortest round-trip decimals, a value that is not finite as the string
//! `"NaN"`, `"inf"` or `"-inf"`.

use crate::pipeline::runout::{RunoutRun, RunoutTexts, finish, prepare};
use crate::pipeline::{Error, Result};
use crate::study::runout::{RunoutRow, run_cases};
use serde::{Deserialize, Serialize};

/// The `kind` of a run-out task and of its result.
pub const RUNOUT_CASES: &str = "runout-cases";

/// One shard of the cases of a run-out sweep, with the texts that define the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunoutTask {
    /// What the task is: [`RUNOUT_CASES`].
    pub kind: String,
    /// The study file's name (for messages).
    pub study_file: String,
    /// The study file's text.
    pub study_toml: String,
    /// The tool file's name, resolved against the study file.
    pub tool_file: String,
    /// The tool file's text.
    pub tool_toml: String,
    /// This task's shard, 1-based.
    pub shard: usize,
    /// Number of shards.
    pub shards: usize,
}

/// The evaluated numbers of one case (its swept values follow from the study).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunoutCaseResult {
    /// The case's number (0-based, in case order).
    pub case: usize,
    /// Participating teeth under the study's rule.
    pub zc: usize,
    /// zc of the paper rule.
    pub zc_paper: usize,
    /// zc of the exact rule.
    pub zc_exact: usize,
    /// 1-based indices of the participating teeth, `;`-separated.
    pub participating_teeth: String,
    /// fz·Z/zc, mm.
    #[serde(with = "num")]
    pub fz_effective_mm: f64,
    /// Eq 14 at the nominal fz, µm.
    #[serde(with = "num")]
    pub crest_height_um: f64,
    /// Crest corrected for run-out under the rule, µm.
    #[serde(with = "num")]
    pub crest_height_corrected_um: f64,
    /// Exact 1-D envelope crest, µm.
    #[serde(with = "num")]
    pub crest_height_exact_um: f64,
    /// R_ef,max, mm.
    #[serde(with = "num")]
    pub effective_radius_mm: f64,
    /// R_ef,max / R.
    #[serde(with = "num")]
    pub cutting_speed_ratio: f64,
    /// Spread of the teeth's normal deviation at the generating height, µm.
    #[serde(with = "num")]
    pub normal_runout_spread_um: f64,
}

/// The outcome of a [`RunoutTask`]: its cases' rows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunoutResult {
    /// What the task was: [`RUNOUT_CASES`].
    pub kind: String,
    /// The study file's name.
    pub study_file: String,
    /// The study file's text.
    pub study_toml: String,
    /// The tool file's name, resolved against the study file.
    pub tool_file: String,
    /// The tool file's text.
    pub tool_toml: String,
    /// The task's shard, 1-based.
    pub shard: usize,
    /// Number of shards.
    pub shards: usize,
    /// Cases of the whole sweep.
    pub cases_total: usize,
    /// This shard's cases, in case order.
    pub cases: Vec<RunoutCaseResult>,
}

/// A float as a JSON number, or as `"NaN"`, `"inf"`, `"-inf"` when not finite (so that
/// every value comes back with the bits it had).
mod num {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_f64(*v)
        } else if v.is_nan() {
            s.serialize_str("NaN")
        } else if *v > 0.0 {
            s.serialize_str("inf")
        } else {
            s.serialize_str("-inf")
        }
    }

    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Num {
        N(f64),
        S(String),
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        match Num::deserialize(d)? {
            Num::N(v) => Ok(v),
            Num::S(s) => match s.as_str() {
                "NaN" => Ok(f64::NAN),
                "inf" => Ok(f64::INFINITY),
                "-inf" => Ok(f64::NEG_INFINITY),
                _ => Err(serde::de::Error::custom(format!(
                    "'{s}' is not a number (nor \"NaN\", \"inf\", \"-inf\")"
                ))),
            },
        }
    }
}

fn texts_of(t: &RunoutTask) -> RunoutTexts {
    RunoutTexts {
        study_file: t.study_file.clone(),
        study_toml: t.study_toml.clone(),
        tool_file: t.tool_file.clone(),
        tool_toml: t.tool_toml.clone(),
    }
}

/// The tasks of a run-out study (its texts as [`crate::pipeline::runout::load_runout_texts`]
/// reads them): `n` tasks (task k: cases k-1, k-1+n, …), or one per case when `n` is
/// `None`. The study and its tool are checked here.
pub fn runout_tasks(t: &RunoutTexts, n: Option<usize>) -> Result<Vec<RunoutTask>> {
    let p = prepare(t)?;
    let n = match n {
        Some(0) => {
            return Err(Error::Request(
                "a run-out study needs at least one task".into(),
            ));
        }
        Some(n) => n,
        None => p.study.cases(&p.cutter).len(),
    };
    Ok((1..=n)
        .map(|shard| RunoutTask {
            kind: RUNOUT_CASES.to_string(),
            study_file: t.study_file.clone(),
            study_toml: t.study_toml.clone(),
            tool_file: t.tool_file.clone(),
            tool_toml: t.tool_toml.clone(),
            shard,
            shards: n,
        })
        .collect())
}

/// Evaluate one task (its cases in parallel on the current rayon pool). A case that cannot
/// be evaluated fails the task, as it fails `crest runout`.
pub fn run_runout_task(task: &RunoutTask) -> Result<RunoutResult> {
    if task.kind != RUNOUT_CASES {
        return Err(Error::Tasks(format!(
            "unknown task kind '{}' (expected '{RUNOUT_CASES}')",
            task.kind
        )));
    }
    if task.shard == 0 || task.shard > task.shards {
        return Err(Error::Tasks(format!(
            "task for shard {} of {}: not a shard K/N with 1 ≤ K ≤ N",
            task.shard, task.shards
        )));
    }
    let p = prepare(&texts_of(task))?;
    let all = p.study.cases(&p.cutter);
    let cases_total = all.len();
    let mine: Vec<_> = all
        .into_iter()
        .filter(|c| c.case % task.shards + 1 == task.shard)
        .collect();
    let rows = run_cases(&p.cutter, &p.study, &mine).map_err(Error::stage)?;
    Ok(RunoutResult {
        kind: RUNOUT_CASES.to_string(),
        study_file: task.study_file.clone(),
        study_toml: task.study_toml.clone(),
        tool_file: task.tool_file.clone(),
        tool_toml: task.tool_toml.clone(),
        shard: task.shard,
        shards: task.shards,
        cases_total,
        cases: rows
            .into_iter()
            .map(|r| RunoutCaseResult {
                case: r.case.case,
                zc: r.zc,
                zc_paper: r.zc_paper,
                zc_exact: r.zc_exact,
                participating_teeth: r.participating_teeth,
                fz_effective_mm: r.fz_effective_mm,
                crest_height_um: r.crest_height_um,
                crest_height_corrected_um: r.crest_height_corrected_um,
                crest_height_exact_um: r.crest_height_exact_um,
                effective_radius_mm: r.effective_radius_mm,
                cutting_speed_ratio: r.cutting_speed_ratio,
                normal_runout_spread_um: r.normal_runout_spread_um,
            })
            .collect(),
    })
}

/// Assemble the results of every task of one run-out study (any order) into the study the
/// single process finishes. Fails if the results are of different studies (or of its files
/// at other paths: the tool file's name titles the charts), if a shard is missing or given
/// twice, or if a shard does not hold exactly its cases.
pub fn merge_runout(results: Vec<RunoutResult>) -> Result<RunoutRun> {
    let first = results
        .first()
        .ok_or_else(|| Error::Tasks("no task results to merge".into()))?;
    if let Some(r) = results.iter().find(|r| r.kind != RUNOUT_CASES) {
        return Err(Error::Tasks(format!(
            "unknown task kind '{}' (expected '{RUNOUT_CASES}')",
            r.kind
        )));
    }
    let file = first.study_file.clone();
    let (shards, total) = (first.shards, first.cases_total);
    if let Some(r) = results.iter().find(|r| {
        r.study_toml != first.study_toml
            || r.tool_toml != first.tool_toml
            || r.tool_file != first.tool_file
            || r.shards != shards
            || r.cases_total != total
    }) {
        return Err(Error::Tasks(format!(
            "the results are of different run-out studies: shard {} of {} ({}, tool {}) is not of the study of shard {} of {shards} ({file}, tool {})",
            r.shard, r.shards, r.study_file, r.tool_file, first.shard, first.tool_file
        )));
    }
    let texts = RunoutTexts {
        study_file: file.clone(),
        study_toml: first.study_toml.clone(),
        tool_file: first.tool_file.clone(),
        tool_toml: first.tool_toml.clone(),
    };
    let p = prepare(&texts)?;
    let cases = p.study.cases(&p.cutter);
    if cases.len() != total {
        return Err(Error::Tasks(format!(
            "{file}: the results count {total} cases, but the study has {}",
            cases.len()
        )));
    }
    super::check_shards(
        &file,
        shards,
        total,
        results
            .iter()
            .map(|r| (r.shard, r.cases.iter().map(|c| c.case).collect())),
        "cases",
    )?;
    let mut got: Vec<RunoutCaseResult> = results.into_iter().flat_map(|r| r.cases).collect();
    got.sort_by_key(|c| c.case);
    let rule = p.study.rule.name();
    let rows = got
        .into_iter()
        .zip(cases)
        .map(|(r, case)| RunoutRow {
            case,
            rule,
            zc: r.zc,
            zc_paper: r.zc_paper,
            zc_exact: r.zc_exact,
            participating_teeth: r.participating_teeth,
            fz_effective_mm: r.fz_effective_mm,
            crest_height_um: r.crest_height_um,
            crest_height_corrected_um: r.crest_height_corrected_um,
            crest_height_exact_um: r.crest_height_exact_um,
            effective_radius_mm: r.effective_radius_mm,
            cutting_speed_ratio: r.cutting_speed_ratio,
            normal_runout_spread_um: r.normal_runout_spread_um,
        })
        .collect();
    Ok(finish(p, rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts() -> RunoutTexts {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        crate::pipeline::runout::load_runout_texts(&dir.join("samples/studies/runout.toml"))
            .unwrap()
    }

    #[test]
    fn tasks_through_json_merge_to_the_single_process_rows() {
        let t = texts();
        let p = prepare(&t).unwrap();
        let single = crate::study::runout::run_study(&p.cutter, &p.study).unwrap();
        for n in [None, Some(1), Some(5)] {
            let tasks = runout_tasks(&t, n).unwrap();
            assert_eq!(tasks.len(), n.unwrap_or(single.len()));
            let mut results: Vec<RunoutResult> = tasks
                .iter()
                .rev()
                .map(|task| {
                    let json = serde_json::to_string(task).unwrap();
                    let r = run_runout_task(&serde_json::from_str(&json).unwrap()).unwrap();
                    serde_json::from_str(&serde_json::to_string(&r).unwrap()).unwrap()
                })
                .collect();
            let merged = merge_runout(results.clone()).unwrap();
            assert_eq!(merged.rows, single);
            results.pop();
            assert!(merge_runout(results).is_err());
        }
    }

    #[test]
    fn floats_that_are_not_finite_come_back() {
        let mut r = RunoutCaseResult {
            case: 0,
            zc: 1,
            zc_paper: 1,
            zc_exact: 1,
            participating_teeth: "1".into(),
            fz_effective_mm: f64::NAN,
            crest_height_um: f64::INFINITY,
            crest_height_corrected_um: f64::NEG_INFINITY,
            crest_height_exact_um: -0.0,
            effective_radius_mm: 0.1 + 0.2,
            cutting_speed_ratio: f64::MIN_POSITIVE,
            normal_runout_spread_um: 1e300,
        };
        let back: RunoutCaseResult =
            serde_json::from_str(&serde_json::to_string(&r).unwrap()).unwrap();
        assert!(back.fz_effective_mm.is_nan());
        r.fz_effective_mm = 0.0;
        let mut b = back.clone();
        b.fz_effective_mm = 0.0;
        assert_eq!(b, r);
        assert!(b.crest_height_exact_um.is_sign_negative());
        let bad = serde_json::to_string(&r)
            .unwrap()
            .replace("\"inf\"", "\"big\"");
        assert!(serde_json::from_str::<RunoutCaseResult>(&bad).is_err());
    }
}
