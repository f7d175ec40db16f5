//! `crest simulate`: a tool-path file read from disk, the cutter, spindle speed and feed
//! resolved (options, then `process.toml`, then the file's SPINDL/FEDRAT), the feed the
//! machine reaches planned when asked, the path resampled for the surface model and the
//! surface simulated on the requested grid.

use super::prepare::{Prepared, prepare};
pub use super::request::{
    CHORD_TOL_UM, Cutting, FeedSource, GridChoice, GridChoiceError, GridRequest, ReferenceSource,
    RequestError, SimulateRequest, default_grid_um, predicted_feed, resolve_cutting,
    resolve_feed_source,
};
use super::select::Selected;
use crate::math::Point3;
use crate::pipeline::{Error, Result};
use crate::resample::Sample;
use crate::surface::cull::Reach;
use crate::surface::{self, GridSpec, PartMap, Reference, Simulation};
use crate::tool::Cutter;
use crate::toolpath::Moves;

/// What was simulated.
#[derive(Debug, Clone)]
pub enum Output {
    /// A height map on a window or patch.
    Grid(Box<Simulation>),
    /// A point cloud over the part.
    Map(PartMap),
}

/// A finished simulation and what it was run with.
#[derive(Debug, Clone)]
pub struct SimulateRun {
    /// The simulated surface.
    pub output: Output,
    /// Nodes in the grid or map.
    pub nodes: usize,
    /// Nodes with a height.
    pub nodes_cut: usize,
    /// Where the tool came from (a file or TLDATA).
    pub tool_source: String,
    /// What the heights are measured from.
    pub reference: ReferenceSource,
    /// Non-fatal findings (tool/TLDATA mismatch, degenerate mesh triangles, …).
    pub warnings: Vec<String>,
    /// Checks that failed (also in `warnings`): the command exits 1.
    pub failed_checks: Vec<String>,
    /// Which moves were simulated.
    pub moves: Moves,
    /// Distance from the `--patch-near` point to the cut surface and its tolerance, mm.
    pub patch_distance_mm: Option<(f64, f64)>,
    /// Samples the path gave before culling.
    pub samples_total: usize,
    /// Grid spacing used, µm (the option, or the default from the feed per tooth).
    pub grid_um: f64,
    /// The cutter.
    pub cutter: Cutter,
    /// Spindle speed and feeds used.
    pub cutting: Cutting,
    /// Depth of cut, mm.
    pub ap_mm: f64,
    /// Whether the feed was predicted on a machine.
    pub predicted: bool,
    /// Samples simulated.
    pub samples: usize,
    /// Cutting time of the resampled runs, s.
    pub cut_time_s: f64,
    /// Feed of the samples, mm/min: min, max, mean.
    pub sample_feed_mm_min: (f64, f64, f64),
}

/// Run a simulation, reporting each phase to `progress` (the simulation itself counts
/// tiles of the grid, or cells of a map, out of a total fixed when it starts). Runs on the
/// current rayon pool.
pub fn simulate(req: &SimulateRequest, progress: &dyn super::Progress) -> Result<SimulateRun> {
    simulate_shard(req, None, progress)
}

/// [`simulate`], for a part map only the cells of shard `k` of `n` (`shard = Some((k, n))`:
/// cells k, k+n, … as [`surface::map_part`] splits them; see [`super::tasks::map`]).
/// Other grids are not split: a shard of one is refused.
pub fn simulate_shard(
    req: &SimulateRequest,
    shard: Option<(usize, usize)>,
    progress: &dyn super::Progress,
) -> Result<SimulateRun> {
    if shard.is_some() && !matches!(req.grid, GridRequest::Map { .. }) {
        return Err(Error::Request(
            "‹shard› splits a part map (‹map_mm›) into its cells; a window or patch is one task"
                .into(),
        ));
    }
    let prepared = prepare(req, progress)?;
    simulate_prepared(req, &prepared, shard, progress)
}

/// The grid of a request and the box the tool must reach (none: every sample).
fn grid_and_reach(req: &SimulateRequest, prep: &Prepared) -> (Option<GridSpec>, Option<Reach>) {
    match req.grid {
        GridRequest::Window {
            x0_mm,
            y0_mm,
            x1_mm,
            y1_mm,
        } => (
            Some(GridSpec::Window {
                x0_mm,
                y0_mm,
                x1_mm,
                y1_mm,
            }),
            Some(Reach {
                lo: Point3::new(x0_mm, y0_mm, f64::NEG_INFINITY),
                hi: Point3::new(x1_mm, y1_mm, f64::INFINITY),
            }),
        ),
        GridRequest::PatchAt {
            s_mm,
            length_mm,
            width_mm,
        } => (
            Some(GridSpec::Patch {
                s_mm,
                length_mm,
                width_mm,
            }),
            None,
        ),
        GridRequest::PatchNear {
            point,
            length_mm,
            width_mm,
        } => {
            let q = Point3::new(point[0], point[1], point[2]);
            let half = 0.5 * (length_mm * length_mm + width_mm * width_mm).sqrt();
            (None, Some(Reach::around(&q, half + 2.0)))
        }
        GridRequest::Map { region, .. } => (
            None,
            match region {
                Some(r) => Some(Reach {
                    lo: Point3::new(r[0], r[1], r[2]),
                    hi: Point3::new(r[3], r[4], r[5]),
                }),
                None => prep.part.as_ref().map(|p| {
                    let (lo, hi) = p.bounds();
                    Reach { lo, hi }
                }),
            },
        ),
    }
}

/// The surface-model options of a request on `grid`.
fn surface_options(
    req: &SimulateRequest,
    prep: &Prepared,
    model: surface::Model,
    grid: Option<GridSpec>,
) -> surface::Options {
    let mut sopts = surface::Options::new(
        model,
        grid.unwrap_or(GridSpec::Window {
            x0_mm: 0.0,
            y0_mm: 0.0,
            x1_mm: 0.0,
            y1_mm: 0.0,
        }),
        prep.grid_um(req) * 1e-3,
    );
    sopts.depth_mm = prep.ap_mm;
    if let Some(t) = req.chord_tol_um {
        sopts.chord_tol_mm = t * 1e-3;
    }
    if let Some(b) = req.band_um {
        sopts.band_mm = (b * 1e-3).min(prep.ap_mm);
    }
    sopts.process = prep.process.effects(prep.min_chip_mm);
    sopts
}

/// Simulate `req`'s grid from what [`prepare`] made of `req` (a request that differs from
/// the prepared one only in `grid` and `grid_um`, as the atlas's patches do).
pub fn simulate_prepared(
    req: &SimulateRequest,
    prep: &Prepared,
    shard: Option<(usize, usize)>,
    progress: &dyn super::Progress,
) -> Result<SimulateRun> {
    let tiles = |done: usize, total: usize| progress.advance(done as u64, total as u64);
    let tiles: &(dyn Fn(usize, usize) + Sync) = &tiles;
    let (file, cutter) = (&prep.file, &prep.cutter);
    let mut warnings = prep.warnings.clone();
    let mut failed_checks = Vec::new();
    // The region the tool must reach, for culling.
    let margin = cutter.radius_mm + prep.ap_mm + 1.0;
    let (grid, reach) = grid_and_reach(req, prep);
    let (model, mode) = req.model.with_resampling(
        req.dtheta_deg.to_radians(),
        prep.cutting.fz_mm,
        cutter.teeth(),
    );
    let selected = super::select::select(req, prep, mode, reach.as_ref(), margin, progress)?;
    let samples = &selected.samples;
    let mut sopts = surface_options(req, prep, model, grid);
    let reference = match (&prep.part, prep.reference) {
        (Some(p), ReferenceSource::Part) => Reference::Part(p),
        _ => Reference::Contacts,
    };
    let mut patch_distance = None;
    let simulated = match req.grid {
        GridRequest::Map { spacing_mm, .. } => {
            let Some(p) = &prep.part else {
                unreachable!("prepare refuses a map without a part")
            };
            let tile = (128.0 * spacing_mm).clamp(0.5, 10.0).max(spacing_mm);
            sopts.spacing_mm = spacing_mm;
            let region = reach.map(|r| (r.lo, r.hi));
            progress.phase("simulating the part map", "cells");
            let m = surface::map_part(
                samples, cutter, &sopts, p, spacing_mm, tile, region, shard, tiles,
            )
            .map_err(|e| Error::within(file, e))?;
            return finish(
                req,
                prep,
                Output::Map(m),
                &selected,
                None,
                warnings,
                failed_checks,
            );
        }
        GridRequest::PatchNear {
            point,
            length_mm,
            width_mm,
        } => {
            let placed = super::patch::place(prep, req.moves, samples, point, length_mm, width_mm)?;
            sopts.grid = placed.grid;
            patch_distance = placed.distance_mm;
            if let Some(w) = placed.failed {
                warnings.push(w.clone());
                failed_checks.push(w);
            }
            progress.phase("simulating", "tiles");
            surface::simulate_with(samples, cutter, &sopts, reference, tiles)
        }
        GridRequest::PatchAt { s_mm, .. } => {
            let last = samples.last().map_or(0.0, |s| s.s_mm);
            if !(0.0..=last + 1e-9).contains(&s_mm) {
                return Err(Error::field(
                    "patch_at",
                    format!("{s_mm}: the path has {last:.3} mm of cutting moves (0 to {last:.3})"),
                ));
            }
            progress.phase("simulating", "tiles");
            surface::simulate_with(samples, cutter, &sopts, reference, tiles)
        }
        GridRequest::Window { .. } => {
            progress.phase("simulating", "tiles");
            surface::simulate_with(samples, cutter, &sopts, reference, tiles)
        }
    };
    let sim = simulated.map_err(|e| Error::within(file, e))?;
    // Derived contacts left out as inconsistent fail the run where their cutter touches it.
    if let Some(w) = prep
        .derived
        .as_ref()
        .and_then(|d| d.reaching(&sim, &prep.program, &prep.paths, cutter))
    {
        warnings.push(w.clone());
        failed_checks.push(w);
    }
    // The sanity checks (README "Sanity checks"): each finding fails the run.
    let sane = checks(req, prep, &sim, samples, sopts.chord_tol_mm * 1e3);
    warnings.extend(sane.iter().cloned());
    failed_checks.extend(sane);
    let output = Output::Grid(Box::new(sim));
    finish(
        req,
        prep,
        output,
        &selected,
        patch_distance,
        warnings,
        failed_checks,
    )
}

/// The sanity checks of a simulated grid (README "Sanity checks").
fn checks(
    req: &SimulateRequest,
    prep: &Prepared,
    sim: &Simulation,
    samples: &[Sample],
    chord_tol_um: f64,
) -> Vec<String> {
    let mut sane = super::sanity::unit_findings(&prep.program);
    let (centre, normal) = sim.node_point(sim.map.nx / 2, sim.map.ny / 2);
    let is_cut = |pi: usize, i: usize| prep.is_cut(pi, i);
    let far = 2.0 * prep.cutter.radius_mm;
    let facts = super::sanity::Facts {
        cutter: &prep.cutter,
        model: req.model,
        fz_mm: prep.cutting.fz_mm,
        chord_tol_um,
        stepover_mm: super::air::nearest(&prep.program, &prep.paths, &centre, far, true, is_cut)
            .and_then(|n| n.stepover_mm),
        ap_mm: prep.ap_mm,
        heights_um: &sim.map.z_um,
        patch_mm: match req.grid {
            GridRequest::PatchNear {
                length_mm,
                width_mm,
                ..
            }
            | GridRequest::PatchAt {
                length_mm,
                width_mm,
                ..
            } => Some((length_mm, width_mm)),
            _ => None,
        },
        axis_normal_cos: samples
            .iter()
            .min_by(|a, b| {
                (a.position - centre)
                    .norm()
                    .total_cmp(&(b.position - centre).norm())
            })
            .map(|s| s.axis.dot(&normal).abs()),
    };
    sane.extend(super::sanity::check(&facts));
    sane
}

/// The finished run.
fn finish(
    req: &SimulateRequest,
    prep: &Prepared,
    output: Output,
    selected: &Selected,
    patch_distance_mm: Option<(f64, f64)>,
    warnings: Vec<String>,
    failed_checks: Vec<String>,
) -> Result<SimulateRun> {
    let (nodes, nodes_cut) = match &output {
        Output::Grid(sim) => (sim.map.nx * sim.map.ny, sim.nodes_cut),
        Output::Map(m) => (m.points.len(), m.nodes_cut),
    };
    Ok(SimulateRun {
        output,
        nodes,
        nodes_cut,
        tool_source: prep.tool_source.clone(),
        reference: prep.reference,
        warnings,
        failed_checks,
        moves: req.moves,
        patch_distance_mm,
        samples_total: selected.samples_total,
        grid_um: prep.grid_um(req),
        cutter: prep.cutter.clone(),
        cutting: prep.cutting,
        ap_mm: prep.ap_mm,
        predicted: prep.machine.is_some(),
        samples: selected.samples.len(),
        cut_time_s: selected.cut_time_s,
        sample_feed_mm_min: selected.feed_mm_min,
    })
}
