//! Part maps split into independent tile tasks: [`map_tasks`] cuts a `crest simulate
//! --map-mm` request into `n` tasks (task k simulates cells k, k+n, … of the map),
//! [`run_map_task`] runs one, [`merge_map`] puts the cells back in order into the
//! [`PartMap`] the single process makes, bit for bit (the PLY `crest simulate` writes).
//!
//! A task carries the request (its file paths as given: every worker must see the files at
//! those paths). Each task reads and resamples the whole path and simulates only its cells;
//! a cell's points do not depend on the other cells. Results are serde data; coordinates
//! and heights go through JSON as shortest round-trip decimals, a height not reached
//! (NaN) as `null`.

use crate::pipeline::simulate::{GridRequest, Output, SimulateRequest, SimulateRun};
use crate::pipeline::{Error, Result};
use crate::surface::{MapPoint, PartMap};
use serde::{Deserialize, Serialize};

/// The `kind` of a part-map task and of its result.
pub const MAP_TILES: &str = "map-tiles";

/// One shard of the cells of a part map, with the request that makes the map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapTask {
    /// What the task is: [`MAP_TILES`].
    pub kind: String,
    /// The `crest simulate` request (its grid a part map).
    pub request: SimulateRequest,
    /// This task's shard, 1-based.
    pub shard: usize,
    /// Number of shards.
    pub shards: usize,
}

/// The points of one cell of a part map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapCell {
    /// The cell's index among the map's cells (0-based, in cell order).
    pub cell: usize,
    /// Part points, mm: x, y, z, then the unit normal nx, ny, nz.
    pub points: Vec<[f64; 6]>,
    /// Height along the normal, µm, per point (`null` = not reached).
    pub height_um: Vec<Option<f64>>,
}

/// The outcome of a [`MapTask`]: its cells' points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapResult {
    /// What the task was: [`MAP_TILES`].
    pub kind: String,
    /// The request of the map.
    pub request: SimulateRequest,
    /// The task's shard, 1-based.
    pub shard: usize,
    /// Number of shards.
    pub shards: usize,
    /// Cells of the whole map (those that hold part surface).
    pub cells_total: usize,
    /// This shard's cells, in cell order.
    pub cells: Vec<MapCell>,
}

fn check_map(req: &SimulateRequest) -> Result<()> {
    if !matches!(req.grid, GridRequest::Map { .. }) {
        return Err(Error::Request(
            "only a part map (‹map_mm›) splits into tile tasks; a window or patch is one task"
                .into(),
        ));
    }
    Ok(())
}

/// The `n` tasks of a part-map request (task k: cells k, k+n, …).
pub fn map_tasks(req: &SimulateRequest, n: usize) -> Result<Vec<MapTask>> {
    check_map(req)?;
    if n == 0 {
        return Err(Error::Request("a part map needs at least one task".into()));
    }
    Ok((1..=n)
        .map(|shard| MapTask {
            kind: MAP_TILES.to_string(),
            request: req.clone(),
            shard,
            shards: n,
        })
        .collect())
}

/// Run one task on the current rayon pool, reporting to `progress`: the result, and the
/// run (warnings, resolved cutting data, counts of this shard).
pub fn run_map_task_with(
    task: &MapTask,
    progress: &dyn crate::pipeline::Progress,
) -> Result<(MapResult, SimulateRun)> {
    if task.kind != MAP_TILES {
        return Err(Error::Tasks(format!(
            "unknown task kind '{}' (expected '{MAP_TILES}')",
            task.kind
        )));
    }
    check_map(&task.request)?;
    if task.shard == 0 || task.shard > task.shards {
        return Err(Error::Tasks(format!(
            "task for shard {} of {}: not a shard K/N with 1 ≤ K ≤ N",
            task.shard, task.shards
        )));
    }
    let run = crate::pipeline::simulate::simulate_shard(
        &task.request,
        Some((task.shard, task.shards)),
        progress,
    )?;
    let Output::Map(m) = &run.output else {
        unreachable!("a part-map request makes a part map")
    };
    let mut cells = Vec::with_capacity(m.cells.len());
    let mut at = 0;
    for &(cell, len) in &m.cells {
        let pts = &m.points[at..at + len];
        at += len;
        cells.push(MapCell {
            cell,
            points: pts
                .iter()
                .map(|p| {
                    [
                        p.point.x, p.point.y, p.point.z, p.normal.x, p.normal.y, p.normal.z,
                    ]
                })
                .collect(),
            height_um: pts
                .iter()
                .map(|p| p.height_um.is_finite().then_some(p.height_um))
                .collect(),
        });
    }
    let result = MapResult {
        kind: MAP_TILES.to_string(),
        request: task.request.clone(),
        shard: task.shard,
        shards: task.shards,
        cells_total: m.tiles,
        cells,
    };
    Ok((result, run))
}

/// Run one task (no progress).
pub fn run_map_task(task: &MapTask) -> Result<MapResult> {
    Ok(run_map_task_with(task, &crate::pipeline::Silent)?.0)
}

/// Assemble the results of every task of one part map (any order) into the map of the
/// single process. Fails if the results are of different requests, if a shard is missing
/// or given twice, or if a shard does not hold exactly its cells.
pub fn merge_map(results: Vec<MapResult>) -> Result<PartMap> {
    let first = results
        .first()
        .ok_or_else(|| Error::Tasks("no task results to merge".into()))?;
    if let Some(r) = results.iter().find(|r| r.kind != MAP_TILES) {
        return Err(Error::Tasks(format!(
            "unknown task kind '{}' (expected '{MAP_TILES}')",
            r.kind
        )));
    }
    let (request, shards, total) = (first.request.clone(), first.shards, first.cells_total);
    let file = request.file.display().to_string();
    if let Some(r) = results
        .iter()
        .find(|r| r.request != request || r.shards != shards || r.cells_total != total)
    {
        return Err(Error::Tasks(format!(
            "the results are of different part maps: shard {} of {} is not of the map of shard {} of {shards} ({file})",
            r.shard, r.shards, first.shard
        )));
    }
    super::check_shards(
        &file,
        shards,
        total,
        results
            .iter()
            .map(|r| (r.shard, r.cells.iter().map(|c| c.cell).collect())),
        "cells",
    )?;
    for r in &results {
        if let Some(c) = r.cells.iter().find(|c| c.points.len() != c.height_um.len()) {
            return Err(Error::Tasks(format!(
                "{file}: cell {} has {} points but {} heights",
                c.cell,
                c.points.len(),
                c.height_um.len()
            )));
        }
    }
    let mut cells: Vec<MapCell> = results.into_iter().flat_map(|r| r.cells).collect();
    cells.sort_by_key(|c| c.cell);
    let mut points = Vec::new();
    let mut index = Vec::with_capacity(cells.len());
    let mut nodes_cut = 0;
    for c in cells {
        index.push((c.cell, c.points.len()));
        for (p, h) in c.points.iter().zip(&c.height_um) {
            nodes_cut += usize::from(h.is_some());
            points.push(MapPoint {
                point: crate::math::Point3::new(p[0], p[1], p[2]),
                normal: crate::math::Vec3::new(p[3], p[4], p[5]),
                height_um: h.unwrap_or(f64::NAN),
            });
        }
    }
    Ok(PartMap {
        points,
        tiles: total,
        nodes_cut,
        cells: index,
    })
}
