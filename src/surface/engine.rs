//! The simulation driver: poses, ribbon strips, tiles and the widening band.
//!
//! 1. **Strips.** For every ICE step (two consecutive poses) and tooth, the edge levels whose
//!    points can lie below `nominal + band` form one strip (a ribbon of quads between the two
//!    edge polylines). For the dome, every sample and tooth gives strips of 32 angular steps
//!    of its revolved body within the band. Each strip has a bounding box in node space.
//! 2. **Binning.** Strips are listed per tile (tiles of `tile × tile` nodes).
//! 3. **Tiles.** Tiles are rasterised in parallel, in fixed batches; each keeps, per node,
//!    the lowest height of all triangles. A node below `nominal + band` is exact (the
//!    triangle that reaches it lowest was generated); a tile with a node above the band is
//!    recomputed with a 4× wider band, up to the depth of cut.

use super::grid::{GridFrame, Nominal, grid_contacts};
use super::process::{TextureField, apply_pass};
use super::profile::Profile;
use super::profile::scan_candidates;
use super::raster::{Tile, cover, grow, tile_rect};
use super::{GridSpec, HeightMap, Model, Options, Reference, Simulation, SurfaceError};
use crate::math::{Frame, Point3, Vec3, nlerp};
use crate::resample::Sample;
use crate::tool::Cutter;
use nalgebra::Matrix3;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};

mod dome;

/// Largest number of nodes of a grid (3.2 GB of f64 heights).
const MAX_NODES: usize = 400_000_000;
/// Largest number of sub-steps between two samples.
const MAX_SUBSTEPS: f64 = 1.0e6;
/// Angular steps per dome strip.
const DOME_CHUNK: i64 = 32;
/// Nodes per coarse cell of the nominal surface.
const NOMINAL_STRIDE: usize = 32;

/// A tool pose as an affine map from tool-frame points (angle 0) to node space
/// (X = column, Y = row, W = height along the grid normal in mm): `b + m E`.
#[derive(Debug, Clone, Copy)]
struct Pose {
    m: Matrix3<f64>,
    b: Vec3,
}

impl Pose {
    #[inline]
    fn apply(&self, e: &Vec3) -> [f64; 3] {
        let p = self.b + self.m * e;
        [p.x, p.y, p.z]
    }

    /// The same pose turned by spindle angle `theta` (tool-frame rotation, see `profile`).
    fn rotated(&self, theta: f64) -> Pose {
        Pose {
            m: self.m * rot(theta),
            b: self.b,
        }
    }
}

fn rot(theta: f64) -> Matrix3<f64> {
    let (s, c) = theta.sin_cos();
    Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0)
}

/// One ribbon strip: ICE (`k`: first sample of the pair, sub-step `a` of `n`) or dome
/// (`k`: the sample, angles `a..=b` of `n` per turn). Levels `lo..=hi` of tooth `tooth`.
#[derive(Debug, Clone, Copy)]
struct Strip {
    k: u32,
    a: i64,
    b: i64,
    n: u32,
    tooth: u16,
    lo: u16,
    hi: u16,
}

/// Strips between two updates of a tile's cull from its highest node ([`Tile::top`]).
const TOP_EVERY: usize = 32;

struct Setup<'a> {
    samples: &'a [Sample],
    cutter_teeth: usize,
    profile: Profile,
    frame: GridFrame,
    nx: usize,
    ny: usize,
    /// Node spacing, mm.
    d: f64,
    /// Grid-frame coordinates of node (0, 0).
    x0: f64,
    y0: f64,
    nominal: Nominal,
    /// Heights along the local surface normal (a patch, or any grid on a part) rather than
    /// along w.
    along_normal: bool,
    opts: &'a Options,
    /// grid rows (u, v, w) scaled to node space.
    g: Matrix3<f64>,
    /// The texture field, when the process adds one.
    texture: Option<TextureField>,
    /// Dome model: teeth whose revolved body repeats an earlier tooth's (no run-out), which
    /// stamp the same triangles again; skipped unless passes are told apart by tooth.
    dome_repeat: Vec<bool>,
    /// Swept model: the ball's radius, mm.
    ball_mm: f64,
    /// Swept model (empty for the others): per sample, the ball centre in node space and the
    /// last sample of the straight stretch that starts there (`u32::MAX` inside one).
    swept_centre: Vec<Vec3>,
    swept_end: Vec<u32>,
}

/// Simulate the surface that `cutter` leaves along `samples`.
///
/// `samples` are resampled postures (`resample::resample`): for the dome model one per
/// feed per tooth, for ICE any spacing (steps longer than Δθ are subdivided linearly).
/// Consecutive samples of the same `run` are joined. `progress(done, total)` is called
/// after each batch of tiles (from the calling thread).
pub fn simulate(
    samples: &[Sample],
    cutter: &Cutter,
    opts: &Options,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Simulation, SurfaceError> {
    simulate_with(samples, cutter, opts, Reference::Contacts, progress)
}

/// [`simulate`] with heights measured from `reference` (the contact data, or the design
/// surface of a part).
pub fn simulate_with(
    samples: &[Sample],
    cutter: &Cutter,
    opts: &Options,
    reference: Reference<'_>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Simulation, SurfaceError> {
    check_options(opts, cutter)?;
    if samples.is_empty() {
        return Err(SurfaceError::NoSamples);
    }
    for (i, s) in samples.iter().enumerate() {
        let ok = s.position.coords.iter().all(|v| v.is_finite())
            && s.axis.iter().all(|v| v.is_finite())
            && s.axis.norm() > 1e-9
            && s.feed_dir.iter().all(|v| v.is_finite())
            && s.theta_rad.is_finite();
        if !ok {
            return Err(SurfaceError::BadSample(i));
        }
    }
    let d = opts.spacing_mm;
    let (frame, nx, ny, x0, y0, patch) = match opts.grid {
        GridSpec::Window {
            x0_mm,
            y0_mm,
            x1_mm,
            y1_mm,
        } => {
            let nx = count(x0_mm, x1_mm, d);
            let ny = count(y0_mm, y1_mm, d);
            (GridFrame::wcs(), nx, ny, x0_mm, y0_mm, false)
        }
        GridSpec::Patch {
            s_mm,
            length_mm,
            width_mm,
        } => {
            let frame = GridFrame::patch(samples, s_mm)?;
            let nx = count(0.0, length_mm, d);
            let ny = count(0.0, width_mm, d);
            (frame, nx, ny, -0.5 * length_mm, -0.5 * width_mm, true)
        }
        GridSpec::Oriented {
            frame,
            length_mm,
            width_mm,
        } => {
            let nx = count(0.0, length_mm, d);
            let ny = count(0.0, width_mm, d);
            (frame, nx, ny, -0.5 * length_mm, -0.5 * width_mm, true)
        }
    };
    if nx == 0 || ny == 0 || nx.saturating_mul(ny) > MAX_NODES {
        return Err(SurfaceError::BadGrid { nx, ny });
    }
    let uv_box = [x0, y0, x0 + (nx - 1) as f64 * d, y0 + (ny - 1) as f64 * d];
    let diag = ((uv_box[2] - uv_box[0]).powi(2) + (uv_box[3] - uv_box[1]).powi(2)).sqrt();
    // Lattice of the nominal surface: every 32 nodes, at most 0.25 mm apart.
    let stride = ((0.25 / d).floor() as usize).clamp(1, NOMINAL_STRIDE);
    let contacts = match reference {
        Reference::Contacts => grid_contacts(samples, &frame, uv_box, (0.5 * diag).max(2.0), 0.05),
        Reference::Part(part) => {
            let c = part_contacts(part, &frame, uv_box, patch, 0.5 * stride as f64 * d);
            if c.is_empty() {
                return Err(SurfaceError::NoPartSurface);
            }
            c
        }
    };
    let along_normal = patch || matches!(reference, Reference::Part(_));
    let (nominal, from_contacts) = match Nominal::fit(nx, ny, stride, x0, y0, d, &contacts) {
        Some(n) => (n, true),
        None if patch => return Err(SurfaceError::NoContactData),
        None => (Nominal::flat(nx, ny, stride, d, 0.0), false),
    };
    let side = opts.depth_mm.min(cutter.radius_mm);
    let profile = Profile::new(cutter, opts.chord_tol_mm, side)
        .map_err(|e| SurfaceError::InvalidOption(format!("the cutter: {e}")))?;
    let s = Matrix3::from_diagonal(&Vec3::new(1.0 / d, 1.0 / d, 1.0));
    let g = s * Matrix3::from_rows(&[
        frame.u.transpose(),
        frame.v.transpose(),
        frame.w.transpose(),
    ]);
    let dome_repeat = (0..cutter.teeth())
        .map(|j| !opts.process.ploughs() && profile.body[..j].contains(&profile.body[j]))
        .collect();
    let setup = Setup {
        samples,
        cutter_teeth: cutter.teeth(),
        profile,
        frame,
        nx,
        ny,
        d,
        x0,
        y0,
        nominal,
        along_normal,
        opts,
        g,
        texture: opts
            .process
            .texture
            .filter(|t| t.sq_mm > 0.0)
            .map(|t| TextureField::new(&t)),
        dome_repeat,
        ball_mm: cutter.radius_mm,
        swept_centre: Vec::new(),
        swept_end: Vec::new(),
    };
    let setup = if opts.model == Model::Swept {
        let shift = Vec3::new(x0 / d, y0 / d, 0.0);
        let (g, f) = (&setup.g, &setup.frame);
        let (centre, end) = super::swept::plan(samples, cutter.radius_mm, g, f, shift, d);
        Setup {
            swept_centre: centre,
            swept_end: end,
            ..setup
        }
    } else {
        setup
    };
    let mut map = HeightMap::new_nan(nx, ny, d * 1e3, d * 1e3);
    map.x0_mm = x0;
    map.y0_mm = y0;

    let t = opts.tile.max(8);
    let ntx = nx.div_ceil(t);
    let nty = ny.div_ceil(t);
    let mut pending: Vec<usize> = (0..ntx * nty).collect();
    let mut band = if opts.process.ploughs() {
        opts.band_mm.max(4.0 * opts.process.min_chip_mm)
    } else {
        opts.band_mm
    }
    .min(opts.depth_mm);
    let mut strips_total = 0;
    let mut widened = 0;
    // Tiles finished (certain, or computed with the full depth) out of all tiles: the
    // total is fixed up front; a tile widened for a second pass is finished only then.
    let mut finished = 0;
    let total = pending.len();
    loop {
        let last = band >= opts.depth_mm;
        let strips = setup.strips(band);
        strips_total += strips.0.len();
        let bins = setup.bin(&strips.0, &strips.1, t, ntx, nty, &pending);
        let mut uncertain = Vec::new();
        // Tiles go straight into the map as they finish (no batch of results is held), so
        // a batch can be long enough to keep every thread busy to its end.
        let batch = (16 * rayon::current_num_threads()).max(32);
        for chunk in pending.chunks(batch) {
            let sink = std::sync::Mutex::new((&mut map.z_um, &mut uncertain, &mut finished));
            chunk.par_iter().for_each(|&tid| {
                let (h, unc) = setup.run_tile(tid, t, ntx, &strips.0, &bins[tid], band, last);
                let (i0, j0, w, hgt) = tile_rect(tid, t, ntx, nx, ny);
                let mut g = sink.lock().unwrap_or_else(|e| e.into_inner());
                let (z, uncertain, finished) = &mut *g;
                for r in 0..hgt {
                    let dst = (j0 + r) * nx + i0;
                    z[dst..dst + w].copy_from_slice(&h[r * w..(r + 1) * w]);
                }
                if unc && !last {
                    uncertain.push(tid);
                } else {
                    **finished += 1;
                }
            });
            progress(finished, total);
        }
        uncertain.sort_unstable();
        if uncertain.is_empty() || last {
            break;
        }
        widened += uncertain.len();
        pending = uncertain;
        band = (band * 4.0).min(opts.depth_mm);
    }
    let nodes_cut = map.known();
    Ok(Simulation {
        map,
        frame: setup.frame,
        nodes_cut,
        strips: strips_total,
        tiles_widened: widened,
        nominal_from_contacts: from_contacts,
        nominal: setup.nominal,
    })
}

fn check_options(opts: &Options, cutter: &Cutter) -> Result<(), SurfaceError> {
    let positive = |v: f64, name: &str| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(SurfaceError::InvalidOption(format!(
                "{name} must be positive, got {}",
                crate::math::limits::shown(v)
            )))
        }
    };
    positive(opts.spacing_mm, "grid spacing")?;
    positive(opts.depth_mm, "depth of cut")?;
    positive(opts.band_mm, "band")?;
    positive(opts.chord_tol_mm, "chord tolerance")?;
    positive(cutter.radius_mm, "tool radius")?;
    opts.process
        .check()
        .map_err(|e| SurfaceError::InvalidOption(e.to_string()))?;
    if cutter.teeth() == 0 || cutter.teeth() > u16::MAX as usize {
        return Err(SurfaceError::InvalidOption(format!(
            "the cutter has {} teeth",
            cutter.teeth()
        )));
    }
    if let Model::Ice { dtheta_rad } = opts.model {
        positive(dtheta_rad, "spindle step Δθ")?;
    }
    if opts.model == Model::Swept {
        if !matches!(cutter.shape, crate::tool::Shape::Ball) {
            return Err(SurfaceError::InvalidOption(format!(
                "the swept model sweeps a ball; the cutter is a {} end (use dome or ice)",
                cutter.shape.name()
            )));
        }
        if opts.process.ploughs() {
            return Err(SurfaceError::InvalidOption(
                "the swept model has no teeth, so no chip and no ploughing (use dome or ice)"
                    .to_string(),
            ));
        }
    }
    match opts.grid {
        GridSpec::Window {
            x0_mm,
            y0_mm,
            x1_mm,
            y1_mm,
        } => {
            let ok = [x0_mm, y0_mm, x1_mm, y1_mm].iter().all(|v| v.is_finite())
                && x1_mm >= x0_mm
                && y1_mm >= y0_mm;
            if !ok {
                return Err(SurfaceError::InvalidOption(format!(
                    "window {x0_mm},{y0_mm},{x1_mm},{y1_mm} needs X0 ≤ X1 and Y0 ≤ Y1"
                )));
            }
        }
        GridSpec::Oriented {
            frame,
            length_mm,
            width_mm,
        } => {
            let finite = [frame.origin.coords, frame.u, frame.v, frame.w]
                .iter()
                .all(|v| v.iter().all(|c| c.is_finite()));
            if !finite {
                return Err(SurfaceError::InvalidOption(
                    "patch frame is not finite".into(),
                ));
            }
            positive(length_mm, "patch length")?;
            positive(width_mm, "patch width")?;
        }
        GridSpec::Patch {
            s_mm,
            length_mm,
            width_mm,
        } => {
            if !s_mm.is_finite() {
                return Err(SurfaceError::InvalidOption(
                    "patch arc length is not finite".into(),
                ));
            }
            positive(length_mm, "patch length")?;
            positive(width_mm, "patch width")?;
        }
    }
    Ok(())
}

/// Points and normals of the part's surface facing +w over the grid, in grid coordinates:
/// the first hit of a ray along −w from above at every `step` of the (u, v) box widened by
/// two steps. For a patch the rays start a little above the patch plane (the local surface);
/// for a window above the whole part (the top surface).
fn part_contacts(
    part: &crate::part::Part,
    frame: &GridFrame,
    uv_box: [f64; 4],
    patch: bool,
    step: f64,
) -> Vec<(Vec3, Vec3)> {
    let (lo, hi) = part.bounds();
    let diag = (hi - lo).norm();
    let span = ((uv_box[2] - uv_box[0]).powi(2) + (uv_box[3] - uv_box[1]).powi(2)).sqrt();
    let top = if patch {
        0.5 * span + 1.0
    } else {
        // Above every vertex along w.
        let c = nalgebra::center(&lo, &hi);
        frame.w.dot(&(c - frame.origin)) + diag
    };
    let reach = top + diag + 1.0;
    let n_u = (((uv_box[2] - uv_box[0]) / step).ceil() as i64 + 4).clamp(2, 4096);
    let n_v = (((uv_box[3] - uv_box[1]) / step).ceil() as i64 + 4).clamp(2, 4096);
    let mut out = Vec::new();
    for b in 0..=n_v {
        for a in 0..=n_u {
            let u = uv_box[0] - 2.0 * step + a as f64 * step;
            let v = uv_box[1] - 2.0 * step + b as f64 * step;
            let from = frame.origin + frame.u * u + frame.v * v + frame.w * top;
            if let Some((_, p, n)) = part.ray(&from, &-frame.w, reach) {
                let nl = frame.local_dir(&n);
                if nl.z > 0.2 {
                    out.push((frame.local(&p), nl));
                }
            }
        }
    }
    out
}

/// Nodes from `a` to `b` at spacing `d` (both ends included when they fall on the grid).
fn count(a: f64, b: f64, d: f64) -> usize {
    let n = ((b - a) / d + 1e-9).floor();
    if (0.0..1e9).contains(&n) {
        n as usize + 1
    } else {
        0
    }
}

impl Setup<'_> {
    /// The pose at fraction `u` from sample `k` towards `k + 1` (angle included for ICE).
    fn pose(&self, k: usize, u: f64, with_angle: bool) -> Pose {
        let a = &self.samples[k];
        let (p, axis, feed, theta): (Point3, Vec3, Vec3, f64) =
            if u > 0.0 && k + 1 < self.samples.len() {
                let b = &self.samples[k + 1];
                (
                    a.position + (b.position - a.position) * u,
                    nlerp(&a.axis, &b.axis, u),
                    a.feed_dir * (1.0 - u) + b.feed_dir * u,
                    a.theta_rad + (b.theta_rad - a.theta_rad) * u,
                )
            } else {
                (a.position, a.axis, a.feed_dir, a.theta_rad)
            };
        let tf = Frame::tool(&axis, &feed);
        let r = Matrix3::from_columns(&[tf.x, tf.y, tf.z]);
        let mut m = self.g * r;
        if with_angle {
            m *= rot(theta);
        }
        let b =
            self.g * (p - self.frame.origin) - Vec3::new(self.x0 / self.d, self.y0 / self.d, 0.0);
        Pose { m, b }
    }

    /// Levels whose nominal circle (widened by the run-out bound) can dip to `thr`,
    /// extended by one level on each side.
    fn candidates(&self, p: &Pose, thr: f64) -> Option<(usize, usize)> {
        self.candidates_at(p, &[thr])[0]
    }

    /// [`Self::candidates`] for several thresholds of one pose (one search of the lowest
    /// circle).
    fn candidates_at<const N: usize>(
        &self,
        p: &Pose,
        thr: &[f64; N],
    ) -> [Option<(usize, usize)>; N] {
        let amp = (p.m[(2, 0)].powi(2) + p.m[(2, 1)].powi(2)).sqrt();
        let m22 = p.m[(2, 2)];
        let rb = self.profile.runout_bound;
        let levels = &self.profile.levels;
        let f = |i: usize| p.b.z + levels[i].z * m22 - levels[i].r * amp;
        if !self.profile.convex {
            return thr.map(|t| scan_candidates(&f, levels.len(), t + rb));
        }
        // The lowest circle: f is a linear function along the convex meridian, so it is
        // unimodal and its sublevel sets are intervals. Coarse scan, then refine.
        const S: usize = 8;
        let n = levels.len();
        let mut best = 0;
        let mut best_f = f64::INFINITY;
        let mut i = 0;
        while i < n {
            let v = f(i);
            if v < best_f {
                best_f = v;
                best = i;
            }
            i += S;
        }
        let last = f(n - 1);
        if last < best_f {
            best_f = last;
            best = n - 1;
        }
        for i in best.saturating_sub(S)..(best + S + 1).min(n) {
            let v = f(i);
            if v < best_f {
                best_f = v;
                best = i;
            }
        }
        thr.map(|t| {
            let lim = t + rb;
            if best_f > lim {
                return None;
            }
            let mut lo = best;
            while lo > 0 && f(lo - 1) <= lim {
                lo -= 1;
            }
            let mut hi = best;
            while hi + 1 < n && f(hi + 1) <= lim {
                hi += 1;
            }
            Some((lo.saturating_sub(1), (hi + 1).min(n - 1)))
        })
    }

    /// The threshold of sample `k`: the band above the highest nominal the tool can reach
    /// from there (the nominal's bound over the nodes within the tool's reach of its tip).
    fn threshold(&self, k: usize, band: f64) -> f64 {
        let p = self.pose(k, 0.0, false);
        let top = self.profile.reach[self.profile.reach.len() - 1];
        let reach = (top + self.profile.runout_bound) / self.d;
        // Tips farther than the step to the next sample lie within its reach too.
        let step = if k + 1 < self.samples.len() {
            (self.samples[k + 1].position - self.samples[k].position).norm() / self.d
        } else {
            0.0
        };
        self.nominal.local_max(p.b.x, p.b.y, reach + step + 1.0) + band
    }

    /// All strips within the band above the nominal, with their node-space bounding boxes.
    fn strips(&self, band: f64) -> (Vec<Strip>, Vec<[f64; 4]>) {
        let n = self.samples.len();
        let chunks: Vec<(Vec<Strip>, Vec<[f64; 4]>)> = (0..n)
            .into_par_iter()
            .with_min_len(64)
            .map(|k| match self.opts.model {
                Model::Ice { dtheta_rad } => {
                    self.ice_strips(k, dtheta_rad, self.threshold(k, band), band)
                }
                Model::Dome => self.dome_strips(k, self.threshold(k, band)),
                Model::Swept => self.swept_strips(k, band),
            })
            .collect();
        let mut strips = Vec::new();
        let mut boxes = Vec::new();
        for (s, b) in chunks {
            strips.extend(s);
            boxes.extend(b);
        }
        (strips, boxes)
    }

    /// The ICE strips of the pair of samples `k`, `k + 1`: `thr` bounds the whole pair
    /// (quick rejection and candidate levels), `band` the edge points, each against the
    /// nominal's bound under it.
    fn ice_strips(
        &self,
        k: usize,
        dtheta: f64,
        thr: f64,
        band: f64,
    ) -> (Vec<Strip>, Vec<[f64; 4]>) {
        let mut strips = Vec::new();
        let mut boxes = Vec::new();
        if k + 1 >= self.samples.len() || self.samples[k + 1].run != self.samples[k].run {
            return (strips, boxes);
        }
        // Quick rejection of the whole pair: no level near the band at either end, or the
        // tip too far from the grid for the candidate levels to reach it.
        let mut pa = self.pose(k, 0.0, true);
        let p1 = self.pose(k, 1.0, true);
        let step = (self.samples[k + 1].position - self.samples[k].position).norm();
        // Candidates with the step's allowance (whole pair) and without (sub-steps).
        let [c0, ca0] = self.candidates_at(&pa, &[thr + step, thr]);
        let [c1, c1b] = self.candidates_at(&p1, &[thr + step, thr]);
        let Some(hi) = c0.map(|c| c.1).max(c1.map(|c| c.1)) else {
            return (strips, boxes);
        };
        let reach = (self.profile.reach[hi] + self.profile.runout_bound + step) / self.d;
        let (xa, xb) = (pa.b.x.min(p1.b.x) - reach, pa.b.x.max(p1.b.x) + reach);
        let (ya, yb) = (pa.b.y.min(p1.b.y) - reach, pa.b.y.max(p1.b.y) + reach);
        if xb < 0.0 || ya > (self.ny - 1) as f64 || yb < 0.0 || xa > (self.nx - 1) as f64 {
            return (strips, boxes);
        }
        let dth = (self.samples[k + 1].theta_rad - self.samples[k].theta_rad).abs();
        let nsub = (dth / dtheta - 1e-9).ceil().clamp(1.0, MAX_SUBSTEPS) as usize;
        let mut ca = ca0;
        let mut wa: Vec<[f64; 3]> = Vec::new();
        let mut wb: Vec<[f64; 3]> = Vec::new();
        for sub in 0..nsub {
            // The last sub-step ends at the pair's end pose, already known.
            let (pb, cb) = if sub + 1 == nsub {
                (p1, c1b)
            } else {
                let pb = self.pose(k, (sub + 1) as f64 / nsub as f64, true);
                (pb, self.candidates(&pb, thr))
            };
            let range = match (ca, cb) {
                (Some(a), Some(b)) => Some((a.0.min(b.0), a.1.max(b.1))),
                (a, b) => a.or(b),
            };
            if let Some((clo, chi)) = range {
                for j in 0..self.cutter_teeth {
                    let edge = &self.profile.edge[j][clo..=chi];
                    wa.clear();
                    wb.clear();
                    wa.extend(edge.iter().map(|e| pa.apply(e)));
                    wb.extend(edge.iter().map(|e| pb.apply(e)));
                    let mut lo = usize::MAX;
                    let mut hi = 0;
                    for i in 0..wa.len() {
                        let low = |p: &[f64; 3]| {
                            p[2] <= thr && p[2] <= self.nominal.cell_bound(p[0], p[1]) + band
                        };
                        if low(&wa[i]) || low(&wb[i]) {
                            lo = lo.min(i);
                            hi = i;
                        }
                    }
                    if lo == usize::MAX {
                        continue;
                    }
                    let lo = lo.saturating_sub(1);
                    let hi = (hi + 1).min(wa.len() - 1);
                    let mut bb = [
                        f64::INFINITY,
                        f64::INFINITY,
                        f64::NEG_INFINITY,
                        f64::NEG_INFINITY,
                    ];
                    for p in wa[lo..=hi].iter().chain(wb[lo..=hi].iter()) {
                        grow(&mut bb, p);
                    }
                    strips.push(Strip {
                        k: k as u32,
                        a: sub as i64,
                        b: sub as i64 + 1,
                        n: nsub as u32,
                        tooth: j as u16,
                        lo: (clo + lo) as u16,
                        hi: (clo + hi) as u16,
                    });
                    boxes.push(bb);
                }
            }
            pa = pb;
            ca = cb;
        }
        (strips, boxes)
    }

    /// The swept model's strip of sample `k` when a straight stretch of its run starts
    /// there ([`straight_stretches`]; a lone sample is a stretch of length 0), with the
    /// node-space box within which the ball can come below the band over the nominal.
    fn swept_strips(&self, k: usize, band: f64) -> (Vec<Strip>, Vec<[f64; 4]>) {
        let end = self.swept_end[k];
        if end == u32::MAX {
            return (Vec::new(), Vec::new());
        }
        let (c0, c1) = (self.swept_centre[k], self.swept_centre[end as usize]);
        let mid = (c0 + c1) * 0.5;
        let half = 0.5 * (c1.xy() - c0.xy()).norm();
        let r = self.ball_mm / self.d;
        let thr = self.nominal.local_max(mid.x, mid.y, r + half + 1.0) + band;
        let bottom = c0.z.min(c1.z) - self.ball_mm;
        if bottom > thr {
            return (Vec::new(), Vec::new());
        }
        let h = thr - bottom;
        let reach = if h >= self.ball_mm {
            self.ball_mm
        } else {
            (h * (2.0 * self.ball_mm - h)).sqrt()
        } / self.d;
        let bb = [
            c0.x.min(c1.x) - reach,
            c0.y.min(c1.y) - reach,
            c0.x.max(c1.x) + reach,
            c0.y.max(c1.y) + reach,
        ];
        let strip = Strip {
            k: k as u32,
            a: 0,
            b: i64::from(end) - k as i64,
            n: 1,
            tooth: 0,
            lo: 0,
            hi: 0,
        };
        (vec![strip], vec![bb])
    }

    /// Lower `tile` to the ball swept along strip `s` (nodes the ball can bring below
    /// `cull`).
    fn sweep_ball(&self, s: &Strip, tile: &mut Tile, cull: f64) {
        let k = s.k as usize;
        let (c0, c1) = (self.swept_centre[k], self.swept_centre[k + s.b as usize]);
        super::swept::lower_tile(tile, c0, c1, self.ball_mm, self.d, cull);
    }

    /// Strip indices per tile, for the tiles in `pending`.
    fn bin(
        &self,
        strips: &[Strip],
        boxes: &[[f64; 4]],
        t: usize,
        ntx: usize,
        nty: usize,
        pending: &[usize],
    ) -> Vec<Vec<u32>> {
        let mut wanted = vec![false; ntx * nty];
        for &p in pending {
            wanted[p] = true;
        }
        let mut bins = vec![Vec::new(); ntx * nty];
        let tf = t as f64;
        for (si, bb) in boxes.iter().enumerate().take(strips.len()) {
            if bb[2] < -1e-9
                || bb[3] < -1e-9
                || bb[0] > (self.nx - 1) as f64 + 1e-9
                || bb[1] > (self.ny - 1) as f64 + 1e-9
            {
                continue;
            }
            let tx0 = ((bb[0] - 1e-9) / tf).floor().max(0.0) as usize;
            let ty0 = ((bb[1] - 1e-9) / tf).floor().max(0.0) as usize;
            let tx1 = (((bb[2] + 1e-9) / tf).floor() as usize).min(ntx - 1);
            let ty1 = (((bb[3] + 1e-9) / tf).floor() as usize).min(nty - 1);
            for ty in ty0..=ty1 {
                for tx in tx0..=tx1 {
                    let tid = ty * ntx + tx;
                    if wanted[tid] {
                        bins[tid].push(si as u32);
                    }
                }
            }
        }
        bins
    }

    /// Rasterise one tile; returns its heights (µm, NaN = not reached) and whether a node
    /// lies above the band (so that a wider band could still lower it).
    #[allow(clippy::too_many_arguments)]
    fn run_tile(
        &self,
        tid: usize,
        t: usize,
        ntx: usize,
        strips: &[Strip],
        list: &[u32],
        band: f64,
        last: bool,
    ) -> (Vec<f64>, bool) {
        let (i0, j0, w, h) = tile_rect(tid, t, ntx, self.nx, self.ny);
        let mut tile = Tile::new(i0, j0, w, h);
        let qc = self.tile_nominal(i0, j0, w, h);
        let cull = qc.iter().fold(f64::NEG_INFINITY, |m, q| m.max(q.0)) + band;
        let mut cols = Scratch::default();
        let slack = if matches!(self.opts.model, Model::Swept) {
            for &si in list {
                self.sweep_ball(&strips[si as usize], &mut tile, cull);
            }
            0.0
        } else if self.opts.process.ploughs() {
            self.plough_tile(&mut tile, strips, list, cull, &mut cols);
            self.opts.process.min_chip_mm
        } else {
            // Dome strips nearest first, so that later ones meet low bounds (the same minimum).
            let mut order = list.to_vec();
            if self.opts.model == Model::Dome {
                let (cx, cy) = ((i0 + w / 2) as f64, (j0 + h / 2) as f64);
                let key = |si: &u32| self.strip_key(&strips[*si as usize], cx, cy);
                // (A distance ≥ 0: its bits order as its value.)
                order.sort_by_cached_key(|si| (key(si).to_bits(), *si));
            }
            // Once every node is reached, nothing above the highest of them can lower one:
            // the cull comes down to it (and a node tolerance's worth of extrapolation
            // along the steepest triangle, 1 nm), so later strips mesh less or nothing.
            let mut cull_now = cull;
            for (n, si) in order.into_iter().enumerate() {
                if n % TOP_EVERY == TOP_EVERY - 1
                    && let Some(top) = tile.top()
                {
                    cull_now = cull.min(top + 1e-6);
                }
                self.raster_strip(&strips[si as usize], &mut tile, cull_now, &mut cols);
            }
            0.0
        };
        let mut out = vec![f64::NAN; w * h];
        let mut uncertain = false;
        let depth = self.opts.depth_mm;
        for r in 0..h {
            for c in 0..w {
                let z = tile.z[r * w + c];
                let (q, cos_beta) = qc[r * w + c];
                let above = z - q;
                if above.is_nan() || above + slack > band {
                    uncertain = true;
                }
                if above <= depth {
                    let f = if self.along_normal { cos_beta } else { 1.0 };
                    out[r * w + c] = above * f * 1e3;
                }
            }
        }
        if let Some(tex) = &self.texture {
            for r in 0..h {
                let y = self.y0 + (j0 + r) as f64 * self.d;
                for c in 0..w {
                    let v = &mut out[r * w + c];
                    if v.is_finite() {
                        *v += tex.value(self.x0 + (i0 + c) as f64 * self.d, y) * 1e3;
                    }
                }
            }
        }
        (out, uncertain && !last)
    }

    /// The tile's strips applied pass by pass with the chip rule ([`super::process`]).
    /// Strips arrive in cutting order (samples, sub-steps, teeth). A tooth's pass over a
    /// node is the run of its touches there with no gap longer than a quarter turn (ICE) or
    /// one sample (dome); a pass is applied when it has ended, passes in the order they
    /// began, each with its own lowest height at the node.
    fn plough_tile(
        &self,
        tile: &mut Tile,
        strips: &[Strip],
        list: &[u32],
        cull: f64,
        cols: &mut Scratch,
    ) {
        let nt = self.cutter_teeth;
        let n = tile.w * tile.h;
        let p = self.opts.process;
        let (h_min, rec) = (p.min_chip_mm, p.recovery);
        // Per node and tooth: lowest height of the open pass (+∞ = none), start, last touch.
        let mut open = vec![[f64::INFINITY, 0.0, 0.0]; n * nt];
        let gap = match self.opts.model {
            Model::Ice { .. } => 0.5 * PI,
            Model::Dome | Model::Swept => 0.5,
        };
        let rect = (tile.i0, tile.j0, tile.w, tile.h);
        let z = &mut tile.z;
        // Apply, in start order, the passes at node `i` that ended before time `t`.
        let close = |z: &mut [f64], open: &mut [[f64; 3]], i: usize, t: f64| loop {
            let mut best: Option<usize> = None;
            for q in 0..nt {
                let st = open[i * nt + q];
                if st[0] < f64::INFINITY
                    && (t - st[2]).abs() > gap
                    && best.is_none_or(|b| st[1] < open[i * nt + b][1])
                {
                    best = Some(q);
                }
            }
            let Some(q) = best else { break };
            let st = &mut open[i * nt + q];
            z[i] = apply_pass(z[i], st[0], h_min, rec);
            st[0] = f64::INFINITY;
        };
        for &si in list {
            let s = &strips[si as usize];
            let k = s.k as usize;
            let t = match self.opts.model {
                Model::Ice { .. } => {
                    let a = self.samples[k].theta_rad;
                    let b = self.samples.get(k + 1).map_or(a, |x| x.theta_rad);
                    a + (b - a) * s.a as f64 / s.n as f64
                }
                Model::Dome | Model::Swept => k as f64,
            };
            let j = s.tooth as usize;
            self.strip_triangles(s, cols, |a, b, c| {
                cover(rect, a, b, c, cull, |i, wv| {
                    close(z, &mut open, i, t);
                    let st = &mut open[i * nt + j];
                    if st[0] == f64::INFINITY {
                        *st = [wv, t, t];
                    } else {
                        st[0] = st[0].min(wv);
                        st[2] = t;
                    }
                })
            });
        }
        for i in 0..n {
            close(z, &mut open, i, f64::INFINITY);
        }
    }

    /// Nominal height and cos β at every node of a tile: exact on a global sub-lattice
    /// every K nodes, bilinear in between, K ≤ 8 and K·d ≤ 20 µm (the error is κ (K d)²/8:
    /// 4·10⁻⁷ mm for a 20 mm radius at 1 µm, 2.5·10⁻⁶ mm at most). The sub-lattice is
    /// global so the result does not depend on the tiling.
    fn tile_nominal(&self, i0: usize, j0: usize, w: usize, h: usize) -> Vec<(f64, f64)> {
        let k = ((0.02 / self.d + 1e-9).floor() as usize).clamp(1, 8);
        let (nx, ny) = (self.nx, self.ny);
        let gi0 = i0 / k;
        let gj0 = j0 / k;
        let gi1 = (i0 + w - 1).div_ceil(k);
        let gj1 = (j0 + h - 1).div_ceil(k);
        let sw = gi1 - gi0 + 1;
        let mut sub = Vec::with_capacity(sw * (gj1 - gj0 + 1));
        for gj in gj0..=gj1 {
            for gi in gi0..=gi1 {
                sub.push(
                    self.nominal
                        .q_cos((gi * k).min(nx - 1), (gj * k).min(ny - 1)),
                );
            }
        }
        let lerp = |p: f64, q: f64, t: f64| p + (q - p) * t;
        let frac = |x: usize, n: usize| {
            let g = x / k;
            let a = (g * k).min(n - 1);
            let b = ((g + 1) * k).min(n - 1);
            (
                g,
                if b > a {
                    (x - a) as f64 / (b - a) as f64
                } else {
                    0.0
                },
            )
        };
        let mut out = Vec::with_capacity(w * h);
        for r in 0..h {
            let (gj, fy) = frac(j0 + r, ny);
            let row0 = (gj - gj0) * sw;
            let row1 = ((gj + 1).min(gj1) - gj0) * sw;
            for c in 0..w {
                let (gi, fx) = frac(i0 + c, nx);
                let c0 = gi - gi0;
                let c1 = (gi + 1).min(gi1) - gi0;
                let (a, b, cc, d) = (
                    sub[row0 + c0],
                    sub[row0 + c1],
                    sub[row1 + c0],
                    sub[row1 + c1],
                );
                out.push((
                    lerp(lerp(a.0, b.0, fx), lerp(cc.0, d.0, fx), fy),
                    lerp(lerp(a.1, b.1, fx), lerp(cc.1, d.1, fx), fy),
                ));
            }
        }
        out
    }

    /// How far (squared, nodes) the lowest point of strip `s`'s body or edge lies from (cx, cy).
    fn strip_key(&self, s: &Strip, cx: f64, cy: f64) -> f64 {
        let p = self.pose(s.k as usize, 0.0, false);
        let body = self.profile.body[s.tooth as usize].get(s.lo as usize..=s.hi as usize);
        let [x, y] = super::envelope::lowest_xy(&p.m, &p.b, body.unwrap_or_default());
        (x - cx).powi(2) + (y - cy).powi(2)
    }

    fn raster_strip(&self, s: &Strip, tile: &mut Tile, cull: f64, cols: &mut Scratch) {
        let mut s = *s;
        if self.opts.model == Model::Dome && !self.dome_narrow(&mut s, tile, cull, &mut cols.levels)
        {
            return;
        }
        let (ncols, nl) = self.strip_points(&s, cols);

        tile.quads(&cols.pts, ncols, nl, cull);
    }

    /// The triangles of strip `s`, in order (`scratch`: space for the points and the last
    /// poses, which the strips of the other teeth at the same step share).
    fn strip_triangles(
        &self,
        s: &Strip,
        scratch: &mut Scratch,
        mut tri: impl FnMut([f64; 3], [f64; 3], [f64; 3]),
    ) {
        let (ncols, nl) = self.strip_points(s, scratch);
        let cols = &scratch.pts;
        for c in 0..ncols - 1 {
            let a = &cols[c * nl..(c + 1) * nl];
            let b = &cols[(c + 1) * nl..(c + 2) * nl];
            for i in 0..nl - 1 {
                tri(a[i], a[i + 1], b[i + 1]);
                tri(a[i], b[i + 1], b[i]);
            }
        }
    }

    /// The points of strip `s` into `scratch.pts`, column by column (a pose or angle per
    /// column, `nl` levels each); returns (columns, levels).
    fn strip_points(&self, s: &Strip, scratch: &mut Scratch) -> (usize, usize) {
        let k = s.k as usize;
        let (lo, hi) = (s.lo as usize, s.hi as usize);
        let j = s.tooth as usize;
        let Scratch {
            pts: cols,
            poses,
            levels,
        } = scratch;
        cols.clear();
        let mut pose = |c: i64, n: u32, with_angle: bool| {
            let key = (s.k, c, n, with_angle);
            if let Some((_, p)) = poses.iter().find(|(q, _)| *q == key) {
                return *p;
            }
            let p = self.pose(k, c as f64 / n as f64, with_angle);
            poses.rotate_right(1);
            poses[0] = (key, p);
            p
        };
        match self.opts.model {
            Model::Ice { .. } => {
                let edge = &self.profile.edge[j][lo..=hi];
                for c in [s.a, s.b] {
                    let p = pose(c, s.n, true);
                    cols.extend(edge.iter().map(|e| p.apply(e)));
                }
                (2, hi - lo + 1)
            }
            Model::Dome => {
                // The end face's levels strictly between the stretch's ends lie on the
                // segment between them: the quads they make are one plane's fan.
                let body = &self.profile.body[j];
                levels.clear();
                levels.extend(self.profile.dome_levels(lo, hi).map(|i| body[i]));
                let base = pose(0, 1, false);
                let step = TAU / s.n as f64;
                for m in s.a..=s.b {
                    let p = base.rotated(m as f64 * step);
                    cols.extend(levels.iter().map(|e| p.apply(e)));
                }
                ((s.b - s.a + 1) as usize, levels.len())
            }
            Model::Swept => unreachable!("the swept model has no triangles"),
        }
    }
}

/// Scratch space of [`Setup::strip_triangles`]: strip points and the last poses used.
struct Scratch {
    pts: Vec<[f64; 3]>,
    /// The body points a dome strip meshes (its kept levels).
    levels: Vec<Vec3>,
    /// (sample, step, steps, with angle) and the pose, most recent first.
    poses: [((u32, i64, u32, bool), Pose); 2],
}

impl Default for Scratch {
    fn default() -> Scratch {
        let none = Pose {
            m: Matrix3::zeros(),
            b: Vec3::zeros(),
        };
        Scratch {
            pts: Vec::new(),
            levels: Vec::new(),
            poses: [((u32::MAX, 0, 0, false), none); 2],
        }
    }
}
