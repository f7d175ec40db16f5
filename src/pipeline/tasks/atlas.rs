//! Roughness atlases split into independent patch tasks: task k of n simulates patches k,
//! k + n, … of a `crest atlas` request ([`run_atlas_task`], `crest atlas --shard K/N`), and
//! [`merge_atlas`] puts the rows back in patch order into the [`Atlas`] the single process
//! makes (`crest merge`, the same table and point cloud). A task carries the request (its
//! file paths as given: every worker must see the files there); each task reads the path
//! and places every patch, then simulates its own. Rows are serde data; numbers go through
//! JSON as shortest round-trip decimals, a missing number as `null`.

use crate::pipeline::atlas::{Atlas, AtlasRequest};
use crate::pipeline::{Error, Result};
use crate::study::atlas::AtlasRow;
use serde::{Deserialize, Serialize};

/// The `kind` of an atlas task and of its result.
pub const ATLAS_PATCHES: &str = "atlas-patches";

/// One shard of the patches of an atlas.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AtlasTask {
    /// What the task is: [`ATLAS_PATCHES`].
    pub kind: String,
    /// The `crest atlas` request.
    pub request: AtlasRequest,
    /// This task's shard, 1-based.
    pub shard: usize,
    /// Number of shards.
    pub shards: usize,
}

/// The outcome of an [`AtlasTask`]: its patches' rows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AtlasResult {
    /// What the task was: [`ATLAS_PATCHES`].
    pub kind: String,
    /// The request of the atlas.
    pub request: AtlasRequest,
    /// The task's shard, 1-based.
    pub shard: usize,
    /// Number of shards.
    pub shards: usize,
    /// Patches of the whole atlas.
    pub patches_total: usize,
    /// Finishing regions of the atlas.
    pub regions: usize,
    /// Warnings common to the run.
    pub warnings: Vec<String>,
    /// This shard's rows, in patch order.
    pub rows: Vec<AtlasRow>,
}

/// The `n` tasks of an atlas request (task k: patches k, k + n, …).
pub fn atlas_tasks(req: &AtlasRequest, n: usize) -> Result<Vec<AtlasTask>> {
    if n == 0 {
        return Err(Error::Request("an atlas needs at least one task".into()));
    }
    Ok((1..=n)
        .map(|shard| AtlasTask {
            kind: ATLAS_PATCHES.to_string(),
            request: req.clone(),
            shard,
            shards: n,
        })
        .collect())
}

/// Run one task on the current rayon pool, reporting to `progress`.
pub fn run_atlas_task_with(
    task: &AtlasTask,
    progress: &dyn crate::pipeline::Progress,
) -> Result<AtlasResult> {
    if task.kind != ATLAS_PATCHES {
        return Err(Error::Tasks(format!(
            "unknown task kind '{}' (expected '{ATLAS_PATCHES}')",
            task.kind
        )));
    }
    let atlas =
        crate::pipeline::atlas::run(&task.request, Some((task.shard, task.shards)), progress)?;
    Ok(AtlasResult {
        kind: ATLAS_PATCHES.to_string(),
        request: task.request.clone(),
        shard: task.shard,
        shards: task.shards,
        patches_total: atlas.patches_total,
        regions: atlas.regions,
        warnings: atlas.warnings,
        rows: atlas.rows,
    })
}

/// Run one task (no progress).
pub fn run_atlas_task(task: &AtlasTask) -> Result<AtlasResult> {
    run_atlas_task_with(task, &crate::pipeline::Silent)
}

/// Assemble the results of every task of one atlas (any order) into the atlas of the single
/// process. Fails if the results are of different requests, if a shard is missing or given
/// twice, or if a shard does not hold exactly its patches.
pub fn merge_atlas(results: Vec<AtlasResult>) -> Result<Atlas> {
    let first = results
        .first()
        .ok_or_else(|| Error::Tasks("no task results to merge".into()))?;
    if let Some(r) = results.iter().find(|r| r.kind != ATLAS_PATCHES) {
        return Err(Error::Tasks(format!(
            "unknown task kind '{}' (expected '{ATLAS_PATCHES}')",
            r.kind
        )));
    }
    let (request, shards, total) = (first.request.clone(), first.shards, first.patches_total);
    let regions = first.regions;
    let file = request.simulate.file.display().to_string();
    if let Some(r) = results
        .iter()
        .find(|r| r.request != request || r.shards != shards || r.patches_total != total)
    {
        return Err(Error::Tasks(format!(
            "the results are of different atlases: shard {} of {} is not of the atlas of shard {} of {shards} ({file})",
            r.shard, r.shards, first.shard
        )));
    }
    super::check_shards(
        &file,
        shards,
        total,
        results.iter().map(|r| {
            (
                r.shard,
                r.rows.iter().map(|row| row.patch.wrapping_sub(1)).collect(),
            )
        }),
        "patches",
    )?;
    let mut warnings: Vec<String> = Vec::new();
    for w in results.iter().flat_map(|r| r.warnings.iter()) {
        if !warnings.contains(w) {
            warnings.push(w.clone());
        }
    }
    let mut rows: Vec<AtlasRow> = results.into_iter().flat_map(|r| r.rows).collect();
    rows.sort_by_key(|r| r.patch);
    Ok(Atlas {
        file,
        every_mm: request.every_mm,
        rows,
        patches_total: total,
        regions,
        warnings,
    })
}
