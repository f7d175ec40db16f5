//! `crest atlas`: the roughness atlas of a part (issue 33). Patches are placed every D mm
//! over every finishing region ([`crate::toolpath::regions`]) on the cut surface, and each
//! is simulated by `crest simulate`'s own pipeline ([`super::simulate::simulate`] with
//! `--patch-near`), then measured: Sa, Sq, Sz, the scallop across the feed and the feed
//! marks along it ([`crate::study::atlas`]), their closed forms, the local stepover,
//! curvature, lead and tilt. A patch that is refused (in the air, no cut near it) or that
//! fails a sanity check keeps its row, with the reason in its warnings.
//!
//! Placement (closed form, so that a user can count the patches): in a region of P passes
//! with median stepover s, every k-th pass with k = max(1, round(D / s)), starting at pass
//! ⌊k/2⌋ (the middle pass when the region has fewer than ⌊k/2⌋ + 1); along a chosen pass of
//! length L (of its contact points), n = ⌊L / D⌋ patches D apart, centred on the pass
//! (the first at (L − (n − 1) D) / 2). Patch k of the atlas is row k in this order.

use super::prepare::Prepared;
use super::simulate::{GridRequest, Output, SimulateRequest, SimulateRun};
use crate::math::{Point3, Vec3};
use crate::pipeline::{Error, Result};
use crate::study::atlas::{self, AtlasRow};
use crate::toolpath::{MotionKind, Program};
use serde::{Deserialize, Serialize};

/// Everything `crest atlas` is asked (serde data: an atlas task carries it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AtlasRequest {
    /// The simulation of one patch; its `grid` is replaced by each patch's, and a missing
    /// `grid_um` by [`default_grid_um`].
    pub simulate: SimulateRequest,
    /// Spacing of the patches along and across the passes, mm.
    pub every_mm: f64,
    /// Patch size along and across the feed, mm (default: [`default_patch_mm`]).
    pub patch_mm: Option<(f64, f64)>,
}

/// Where a patch goes.
#[derive(Debug, Clone, PartialEq)]
pub struct Site {
    /// Tool path, 1-based.
    pub path: usize,
    /// Region, 1-based over the whole program (as `crest inspect --regions`).
    pub region: usize,
    /// Pass (cutting run) of the path, 1-based.
    pub pass: usize,
    /// Arc length along the pass, mm.
    pub s_mm: f64,
    /// The point on the cut surface, mm.
    pub point: Point3,
    /// The surface normal there (the tool axis where the posture has no contact).
    pub normal: Vec3,
    /// The tool axis.
    pub axis: Vec3,
    /// The pass's direction there.
    pub feed: Vec3,
    /// The region's median stepover, mm.
    pub region_stepover_mm: Option<f64>,
    /// The normal curvature along the feed, 1/mm.
    pub curvature_along: Option<f64>,
    /// The normal curvature across the feed (to the nearest neighbouring pass), 1/mm.
    pub curvature_across: Option<f64>,
}

/// The default patch: square, twice the region's median stepover (one whole scallop in
/// every profile across the feed wherever the local stepover is up to twice the median), at
/// least 0.5 mm, rounded up to 0.1 mm; 2 mm without a stepover.
pub fn default_patch_mm(stepover_mm: Option<f64>) -> (f64, f64) {
    let l = stepover_mm.map_or(2.0, |s| ((2.0 * s).max(0.5) * 10.0).ceil() / 10.0);
    (l, l)
}

/// The default grid spacing of a patch, µm: the simulation's default (a tenth of the feed
/// per tooth), but no finer than 1/200 of the patch's larger side (at most 200 × 200 nodes
/// a patch), on the 1-2-5 steps of [`super::simulate::default_grid_um`].
pub fn default_grid_um(fz_mm: f64, patch_mm: (f64, f64)) -> f64 {
    let fine = super::simulate::default_grid_um(fz_mm);
    let coarse = patch_mm.0.max(patch_mm.1) * 1e3 / 200.0;
    if fine >= coarse {
        return fine;
    }
    let decade = 10f64.powf(coarse.log10().floor());
    let m = coarse / decade;
    let step = if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
    };
    step * decade
}

/// One pass's points on the cut surface, with normals, axes and arc length.
struct Pass {
    points: Vec<Point3>,
    normals: Vec<Vec3>,
    axes: Vec<Vec3>,
    s: Vec<f64>,
}

impl Pass {
    fn of(program: &Program, path: usize, run: std::ops::Range<usize>) -> Pass {
        let ps = &program.paths[path].postures;
        let mut pass = Pass {
            points: Vec::new(),
            normals: Vec::new(),
            axes: Vec::new(),
            s: Vec::new(),
        };
        // Where the pass has contact points, only those; the first posture of a run (where
        // the first cut leaves, often the end of a lead-in arc, without a contact) is its CL
        // point carried by the next posture's contact offset, kept when the first cut runs
        // along the surface (within 30° of its tangent plane), not when it plunges.
        let with_contacts = run.clone().any(|i| ps[i].contact.is_some());
        let first = run.start;
        for i in run {
            let p = &ps[i];
            let (q, n) =
                match (&p.contact, with_contacts) {
                    (Some(c), _) => (c.point, c.normal),
                    (None, false) => (p.position, p.axis),
                    (None, true) => {
                        let Some(c) = ps.get(i + 1).filter(|_| i == first).and_then(|x| {
                            x.contact.as_ref().map(|c| (c.point, c.normal, x.position))
                        }) else {
                            continue;
                        };
                        let q = p.position + (c.0 - c.2);
                        let d = c.0 - q;
                        if d.norm() == 0.0 || d.dot(&c.1).abs() > 0.5 * d.norm() {
                            continue;
                        }
                        (q, c.1)
                    }
                };
            let s = pass.points.last().map_or(0.0, |l| {
                pass.s.last().copied().unwrap_or(0.0) + (q - l).norm()
            });
            pass.points.push(q);
            pass.normals.push(n);
            pass.axes.push(p.axis);
            pass.s.push(s);
        }
        pass
    }

    fn length(&self) -> f64 {
        self.s.last().copied().unwrap_or(0.0)
    }

    /// Point, normal, axis and direction at arc length `t`.
    fn at(&self, t: f64) -> (Point3, Vec3, Vec3, Vec3) {
        let n = self.points.len();
        if n < 2 {
            return (self.points[0], self.normals[0], self.axes[0], Vec3::x());
        }
        let k = self.s.partition_point(|v| *v < t).clamp(1, n - 1);
        let l = self.s[k] - self.s[k - 1];
        let u = if l > 0.0 {
            ((t - self.s[k - 1]) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (a, b) = (self.points[k - 1], self.points[k]);
        let dir = crate::math::normalize_or_none(&(b - a), 1e-12).unwrap_or_else(Vec3::x);
        (
            a + (b - a) * u,
            crate::math::nlerp(&self.normals[k - 1], &self.normals[k], u),
            crate::math::nlerp(&self.axes[k - 1], &self.axes[k], u),
            dir,
        )
    }

    /// The vertex nearest `q`, with its normal.
    fn nearest(&self, q: &Point3) -> Option<(Point3, Vec3)> {
        self.points
            .iter()
            .zip(&self.normals)
            .min_by(|a, b| (a.0 - q).norm().total_cmp(&(b.0 - q).norm()))
            .map(|(p, n)| (*p, *n))
    }
}

/// The patch sites of `program` (contacts derived where it has none): every finishing
/// region of every path in `paths` (all when empty), `every_mm` apart (see the module
/// text). `regions` are the regions of each path as `crest inspect --regions` finds them,
/// with their passes.
pub fn place(
    program: &Program,
    regions: &[Vec<(crate::toolpath::regions::Region, std::ops::Range<usize>)>],
    every_mm: f64,
) -> Vec<Site> {
    let mut sites = Vec::new();
    let mut region_id = 0;
    for (pi, path_regions) in regions.iter().enumerate() {
        let runs = program.paths[pi].cutting_runs();
        for (region, passes) in path_regions {
            region_id += 1;
            let k = region
                .stepover_mm
                .map_or(1, |s| ((every_mm / s).round() as usize).max(1));
            let count = passes.len();
            let first = if count > k / 2 { k / 2 } else { count / 2 };
            let built: Vec<Pass> = passes
                .clone()
                .map(|r| Pass::of(program, pi, runs[r].clone()))
                .collect();
            for local in (first..count).step_by(k) {
                let pass = &built[local];
                let len = pass.length();
                let n = (len / every_mm + 1e-9).floor() as usize;
                let start = 0.5 * (len - (n.max(1) - 1) as f64 * every_mm);
                for j in 0..n {
                    let t = start + j as f64 * every_mm;
                    let (point, normal, axis, feed) = pass.at(t);
                    let h = (0.5 * every_mm).min(1.0).min(0.5 * len);
                    let along = {
                        let (pa, na, _, _) = pass.at((t - h).max(0.0));
                        let (pb, nb, _, _) = pass.at((t + h).min(len));
                        atlas::curvature(&pa, &na, &pb, &nb)
                    };
                    let neighbour = [local + 1, local.wrapping_sub(1)]
                        .into_iter()
                        .filter(|&o| o < count)
                        .filter_map(|o| built[o].nearest(&point))
                        .min_by(|a, b| (a.0 - point).norm().total_cmp(&(b.0 - point).norm()));
                    let across = neighbour.and_then(|(pb, nb)| {
                        // Only the component across the feed: the neighbour's nearest vertex
                        // may lie a little ahead or behind.
                        let d = pb - point;
                        let pb = point + (d - feed * d.dot(&feed));
                        atlas::curvature(&point, &normal, &pb, &nb)
                    });
                    sites.push(Site {
                        path: pi + 1,
                        region: region_id,
                        pass: passes.start + local + 1,
                        s_mm: t,
                        point,
                        normal,
                        axis,
                        feed,
                        region_stepover_mm: region.stepover_mm,
                        curvature_along: along,
                        curvature_across: across,
                    });
                }
            }
        }
    }
    sites
}

/// The program of an atlas request read, its regions found (on the path as read, as
/// `crest inspect --regions`) and its contacts derived where it has none, and the sites.
pub struct Placement {
    /// The program (cut moves as `--moves` says, contacts derived).
    pub program: Program,
    /// The patch sites in atlas order.
    pub sites: Vec<Site>,
    /// Finishing regions in the paths simulated.
    pub regions: usize,
    /// The feed per tooth the patches run at, mm.
    pub fz_mm: f64,
    /// The corner radius of the cutter (R for a ball), mm.
    pub corner_radius_mm: f64,
}

/// The request of the simulation every patch shares (its grid a patch at the origin).
fn shared_request(req: &AtlasRequest) -> SimulateRequest {
    let (length_mm, width_mm) = req.patch_mm.unwrap_or((1.0, 1.0));
    let mut sim = req.simulate.clone();
    sim.grid = GridRequest::PatchNear {
        point: [0.0; 3],
        length_mm,
        width_mm,
    };
    sim
}

/// Check the request and place its patches on the path `prep` read.
pub fn placement(req: &AtlasRequest, prep: &Prepared) -> Result<Placement> {
    let d = req.every_mm;
    if !(d.is_finite() && d > 0.0) {
        return Err(Error::field(
            "every_mm",
            format!("must be positive, got {}", crate::math::limits::shown(d)),
        ));
    }
    if let Some((l, w)) = req.patch_mm
        && !(l.is_finite() && l > 0.0 && w.is_finite() && w > 0.0)
    {
        return Err(Error::field(
            "patch_mm",
            format!("must be positive, got {l},{w}"),
        ));
    }
    let sim = &req.simulate;
    // Regions from the path as read (contacts derived for the simulation taken off again).
    let mut program = prep.program.clone();
    for &(pi, i) in prep.derived.iter().flat_map(|d| &d.given) {
        program.paths[pi].postures[i].contact = None;
    }
    let mut regions: Vec<Vec<_>> = program
        .paths
        .iter()
        .map(crate::toolpath::regions::regions_with_passes)
        .collect();
    let file = sim.file.display();
    let selected = super::inputs::select_paths(&sim.file, sim.path, program.paths.len())?;
    for (i, r) in regions.iter_mut().enumerate() {
        if !selected.contains(&i) {
            r.clear();
        }
    }
    let count = regions.iter().map(Vec::len).sum();
    if count == 0 {
        return Err(Error::Input(format!(
            "{file}: no finishing region (no cut moves) to place patches on"
        )));
    }
    let has_contacts = program
        .paths
        .iter()
        .flat_map(|p| p.postures.iter())
        .any(|p| p.motion == MotionKind::Cut && p.contact.is_some());
    // The contacts: the file's, those derived for the simulation, else derived here.
    if !has_contacts {
        match &prep.derived {
            Some(d) => {
                for &(pi, i) in &d.given {
                    program.paths[pi].postures[i].contact =
                        prep.program.paths[pi].postures[i].contact.clone();
                }
            }
            None => {
                super::contact::derive_contacts(&mut program, &prep.cutter);
            }
        }
    }
    let sites = place(&program, &regions, d);
    Ok(Placement {
        program,
        sites,
        regions: count,
        fz_mm: prep.cutting.fz_mm,
        corner_radius_mm: prep.cutter.corner_radius_mm(),
    })
}

/// The band a patch starts with, over its closed-form scallop and feed mark.
const BAND_OVER_SCALLOP: f64 = 1.5;

/// The smallest starting band, µm (the simulation's own default).
const BAND_MIN_UM: f64 = 5.0;

/// A patch's default chord tolerance over its closed-form scallop.
const CHORD_OVER_SCALLOP: f64 = 0.01;

/// The default chord tolerance's bounds, µm (the lower one is the simulation's default).
const CHORD_MIN_UM: f64 = 0.01;
const CHORD_MAX_UM: f64 = 1.0;

/// Whether nodes `grid_um` apart resolve feed marks `fz_mm` apart: at least two nodes a
/// mark (grid ≤ fz / 2).
pub fn marks_resolved(grid_um: f64, fz_mm: f64) -> bool {
    grid_um <= 0.5 * fz_mm * 1e3
}

/// `v` to four decimals, printed without trailing zeros.
fn round4(v: f64) -> f64 {
    (v * 1e4).round() / 1e4
}

/// The note of a run whose grid does not resolve the feed marks, or `None`.
fn marks_note(grid_um: f64, fz_mm: f64) -> Option<String> {
    (!marks_resolved(grid_um, fz_mm)).then(|| {
        format!(
            "the feed marks are not resolved: the grid is {grid_um} µm, the feed per tooth {} µm (at most {} µm resolves them, ‹grid_um›); feed_mark_um is left empty, feed_mark_closed_um is the closed form",
            round4(fz_mm * 1e3),
            round4(0.5 * fz_mm * 1e3)
        )
    })
}

/// The size (along, across the feed, mm) and grid spacing (µm) of the patch at `site`.
fn patch_grid(req: &AtlasRequest, placed: &Placement, site: &Site) -> ((f64, f64), f64) {
    let size = req
        .patch_mm
        .unwrap_or_else(|| default_patch_mm(site.region_stepover_mm));
    let grid = req
        .simulate
        .grid_um
        .unwrap_or_else(|| default_grid_um(placed.fz_mm, size));
    (size, grid)
}

/// Simulate and measure the patch at `site` (patch number `patch`, 1-based).
pub fn run_patch(
    req: &AtlasRequest,
    prep: &Prepared,
    placed: &Placement,
    patch: usize,
    site: &Site,
) -> (AtlasRow, Option<SimulateRun>) {
    let ((length, width), grid_um) = patch_grid(req, placed, site);
    let mut sim = req.simulate.clone();
    sim.grid = GridRequest::PatchNear {
        point: [site.point.x, site.point.y, site.point.z],
        length_mm: length,
        width_mm: width,
    };
    sim.grid_um = Some(grid_um);
    let paths = [site.path - 1];
    let is_cut =
        |pi: usize, i: usize| placed.program.paths[pi].postures[i].motion == MotionKind::Cut;
    let r = placed.corner_radius_mm;
    let stepover = super::air::nearest(
        &placed.program,
        &paths,
        &site.point,
        2.0 * r.max(1.0),
        true,
        is_cut,
    )
    .and_then(|n| n.stepover_mm);
    let lt = atlas::lead_tilt(&site.axis, &site.normal, &site.feed);
    let closed = |v: f64| (r > 0.0).then_some(v);
    let scallop_um = |s: f64| closed(super::sanity::scallop_mm(s, r) * 1e3);
    let scallop_closed_um = stepover.and_then(scallop_um);
    let feed_mark_closed_um = closed(placed.fz_mm * placed.fz_mm / (8.0 * r) * 1e3);
    // The defaults below take the larger of the local and the region's scallop: a patch is
    // two of the region's stepovers wide, so it holds the region's scallops even where its
    // own pass runs close to the next (a local stepover of 0.65 mm in a region of 14.6 mm
    // gave a chord of 0.035 µm and a patch of more than 4 minutes), and a patch without a
    // neighbouring pass of its own (a region's edge) still has defaults.
    let scallop_for_defaults = scallop_closed_um
        .into_iter()
        .chain(site.region_stepover_mm.and_then(scallop_um))
        .reduce(f64::max);
    if sim.chord_tol_um.is_none()
        && let Some(s) = scallop_for_defaults
    {
        // The meshes' chord error is the heights' error: a hundredth of this patch's
        // scallop, within the simulation's default 0.01 µm and 1 µm.
        sim.chord_tol_um = Some((CHORD_OVER_SCALLOP * s).clamp(CHORD_MIN_UM, CHORD_MAX_UM));
    }
    if sim.band_um.is_none()
        && let Some(s) = scallop_for_defaults
    {
        // The band is for speed only (a tile with a node above it is recomputed wider, the
        // heights are the same): start it above the heights this patch can have, so that
        // a coarse finish (scallops of hundreds of µm) is rasterised once, not five times.
        sim.band_um =
            Some((BAND_OVER_SCALLOP * (s + feed_mark_closed_um.unwrap_or(0.0))).max(BAND_MIN_UM));
    }
    let mut row = AtlasRow {
        patch,
        path: site.path,
        region: site.region,
        pass: site.pass,
        s_mm: site.s_mm,
        point: [site.point.x, site.point.y, site.point.z],
        normal: [site.normal.x, site.normal.y, site.normal.z],
        sa_um: None,
        sq_um: None,
        sz_um: None,
        scallop_um: None,
        feed_mark_um: None,
        scallop_closed_um,
        feed_mark_closed_um,
        stepover_mm: stepover,
        curvature_along_per_mm: site.curvature_along,
        curvature_across_per_mm: site.curvature_across,
        lead_deg: lt.map(|v| v.0.to_degrees()),
        tilt_deg: lt.map(|v| v.1.to_degrees()),
        nodes: 0,
        nodes_cut: 0,
        warnings: Vec::new(),
    };
    match super::simulate::simulate_prepared(&sim, prep, None, &super::Silent) {
        Err(e) => {
            row.warnings.push(e.to_string());
            (row, None)
        }
        Ok(run) => {
            if let Output::Grid(g) = &run.output {
                let (c, n) = g.node_point(g.map.nx / 2, g.map.ny / 2);
                row.point = [c.x, c.y, c.z];
                row.normal = [n.x, n.y, n.z];
                if let Some(st) = crate::metrics::height_stats(&g.map.z_um) {
                    row.sa_um = Some(st.sa);
                    row.sq_um = Some(st.sq);
                    row.sz_um = Some(st.sz());
                }
                let (s, m) = atlas::scallop_and_feed_marks(&g.map);
                row.scallop_um = s;
                // Marks fz apart are not seen by nodes more than fz / 2 apart (the sampling
                // theorem): what such nodes show is aliasing and mesh error, not marks.
                row.feed_mark_um = m.filter(|_| marks_resolved(grid_um, placed.fz_mm));
            }
            row.nodes = run.nodes;
            row.nodes_cut = run.nodes_cut;
            row.warnings.extend(run.failed_checks.iter().cloned());
            if row.sa_um.is_none() {
                row.warnings
                    .push("no node of the patch was reached by the tool".to_string());
            }
            (row, Some(run))
        }
    }
}

/// A finished atlas (or one shard of it).
#[derive(Debug, Clone)]
pub struct Atlas {
    /// The tool-path file, as given.
    pub file: String,
    /// Spacing of the patches, mm.
    pub every_mm: f64,
    /// Rows in patch order.
    pub rows: Vec<AtlasRow>,
    /// Patches of the whole atlas.
    pub patches_total: usize,
    /// Finishing regions.
    pub regions: usize,
    /// Warnings common to the run (the tool from TLDATA, …), once each.
    pub warnings: Vec<String>,
}

/// Run the atlas, or shard `k` of `n` of its patches (patches k, k + n, …), reporting
/// each patch to `progress`. Fails only when the request is wrong; patches that are
/// refused keep their rows (see [`check_numbers`]).
pub fn run(
    req: &AtlasRequest,
    shard: Option<(usize, usize)>,
    progress: &dyn super::Progress,
) -> Result<Atlas> {
    let prep = super::prepare::prepare(&shared_request(req), progress)?;
    let placed = placement(req, &prep)?;
    let total = placed.sites.len();
    if total == 0 {
        return Err(Error::Request(format!(
            "{}: no pass of any finishing region is {} mm long: no patch placed; give a smaller ‹every_mm›",
            req.simulate.file.display(),
            req.every_mm
        )));
    }
    let (k, n) = shard.unwrap_or((1, 1));
    if k == 0 || k > n {
        return Err(Error::Tasks(format!(
            "shard {k} of {n}: not a shard K/N with 1 ≤ K ≤ N"
        )));
    }
    let mine: Vec<usize> = (k - 1..total).step_by(n).collect();
    progress.phase("simulating patches", "patches");
    let mut rows = Vec::with_capacity(mine.len());
    let mut warnings: Vec<String> = Vec::new();
    let done = std::sync::atomic::AtomicU64::new(0);
    // Patches side by side (a small patch has too few tiles to keep the cores busy).
    let runs = atlas::each_patch(&mine, |i| {
        let (row, run) = run_patch(req, &prep, &placed, i + 1, &placed.sites[i]);
        let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        progress.advance(n, mine.len() as u64);
        (row, run.map(|r| (r.warnings, r.failed_checks)))
    });
    for (row, run) in runs {
        let grid_um = patch_grid(req, &placed, &placed.sites[row.patch - 1]).1;
        if let Some(note) = marks_note(grid_um, placed.fz_mm).filter(|n| !warnings.contains(n)) {
            warnings.push(note);
        }
        if let Some((run_warnings, failed)) = run {
            for w in run_warnings {
                if !failed.contains(&w) && !warnings.contains(&w) {
                    warnings.push(w);
                }
            }
        }
        rows.push(row);
    }
    Ok(Atlas {
        file: req.simulate.file.display().to_string(),
        every_mm: req.every_mm,
        rows,
        patches_total: total,
        regions: placed.regions,
        warnings,
    })
}

/// An error when no row of a whole atlas has numbers, naming the first reasons.
pub fn check_numbers(file: &str, rows: &[AtlasRow]) -> Result<()> {
    if rows.iter().any(AtlasRow::has_numbers) {
        return Ok(());
    }
    let mut why: Vec<&str> = Vec::new();
    for r in rows {
        for w in &r.warnings {
            if !why.contains(&w.as_str()) && why.len() < 3 {
                why.push(w);
            }
        }
    }
    Err(Error::Result(format!(
        "{file}: none of the {} patches produced numbers; {}",
        rows.len(),
        if why.is_empty() {
            "no reason given".to_string()
        } else {
            format!("first reasons: {}", why.join(" | "))
        }
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marks_need_two_nodes_a_feed_per_tooth() {
        assert!(marks_resolved(7.8125, 0.015625));
        assert!(!marks_resolved(7.9, 0.015625));
        assert!(marks_note(20.0, 0.015625).is_some_and(|n| n.contains("7.8125 µm")));
        assert!(marks_note(5.0, 0.015625).is_none());
    }

    #[test]
    fn default_patch_and_grid() {
        assert_eq!(default_patch_mm(Some(0.5)), (1.0, 1.0));
        assert_eq!(default_patch_mm(Some(1.98)), (4.0, 4.0));
        assert_eq!(default_patch_mm(None), (2.0, 2.0));
        // fz 0.1 mm → 10 µm; a 4 mm patch → 20 µm.
        assert_eq!(default_grid_um(0.1, (1.0, 1.0)), 10.0);
        assert_eq!(default_grid_um(0.015625, (4.0, 4.0)), 20.0);
        assert_eq!(default_grid_um(0.015625, (1.0, 1.0)), 5.0);
    }
}
