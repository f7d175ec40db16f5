//! The resampling step of `crest simulate`: the paths of a [`Prepared`] resampled for the
//! surface model, and the samples that can reach the grid kept. Moves that cannot come
//! near the grid are not built at all ([`crate::resample::Options::near`]): only their
//! clock is counted, so that time follows the patch and the cutting time and feed figures
//! still cover the whole path.

use super::prepare::Prepared;
use super::request::{GridRequest, SimulateRequest};
use crate::math::Point3;
use crate::pipeline::{Error, Result};
use crate::resample::{self, Mode, Streamed};
use crate::surface::cull::{Reach, Subset};
use crate::toolpath::Moves;

/// The samples kept for the grid, and figures of the whole resampling.
#[derive(Debug, Clone)]
pub struct Selected {
    /// The samples that can reach the grid, runs renumbered after every gap.
    pub samples: Vec<resample::Sample>,
    /// Samples of the whole resampling (built or not).
    pub samples_total: usize,
    /// Cutting time of the resampled runs, s.
    pub cut_time_s: f64,
    /// Feed of the samples, mm/min: min, max, mean.
    pub feed_mm_min: (f64, f64, f64),
}

/// Cutting time and the (min, max, mean) sample feed of resampled runs, accumulated.
#[derive(Debug, Default)]
struct FeedFigures {
    n: usize,
    cut_time: f64,
    run_end: f64,
    run: Option<usize>,
    min: f64,
    max: f64,
    sum: f64,
}

impl FeedFigures {
    /// `count` samples of `run` at one feed, the last at `t_s` (times grow along a run):
    /// the same figures as each pushed on its own.
    fn push(&mut self, run: usize, t_s: f64, feed: f64, count: u64) {
        if count == 0 {
            return;
        }
        if self.n == 0 {
            self.min = f64::INFINITY;
            self.max = f64::NEG_INFINITY;
        }
        // t restarts at every run: the cutting time is the sum of the runs' last stamps.
        if self.run != Some(run) {
            self.cut_time += self.run_end;
            self.run_end = 0.0;
            self.run = Some(run);
        }
        self.run_end = self.run_end.max(t_s);
        self.min = self.min.min(feed);
        self.max = self.max.max(feed);
        // One addition per sample: the sum rounds as it always did.
        for _ in 0..count {
            self.sum += feed;
        }
        self.n += count as usize;
    }

    fn finish(&self) -> (f64, (f64, f64, f64)) {
        (
            self.cut_time + self.run_end,
            (self.min, self.max, self.sum / self.n.max(1) as f64),
        )
    }
}

/// Resample the paths of `prep` with `mode` and keep the samples within `margin` of
/// `reach` (every sample without one).
pub fn select(
    req: &SimulateRequest,
    prep: &Prepared,
    mode: Mode,
    reach: Option<&Reach>,
    margin: f64,
    progress: &dyn super::Progress,
) -> Result<Selected> {
    let (cutting, cutter, file) = (&prep.cutting, &prep.cutter, &prep.file);
    let mut ropts =
        resample::Options::new(mode, cutting.fz_mm, cutter.teeth()).with_rpm(cutting.rpm);
    if let Some(f) = cutting.feed_mm_min {
        ropts = ropts.with_feed_mm_min(f);
    }
    if let Some(r) = reach {
        let m = crate::math::Vec3::repeat(margin);
        ropts = ropts.with_near(r.lo - m, r.hi + m);
    }
    let estimated = estimate(prep, mode)?;
    progress.phase("resampling", "poses");
    let mut streamed = 0u64;
    let mut subset = Subset::default();
    let mut all = (0usize, 0.0f64, (f64::INFINITY, f64::NEG_INFINITY, 0.0f64));
    let mut run_base = 0;
    let mut last_run = 0;
    for (&i, feeds) in prep.paths.iter().zip(&prep.posture_feeds) {
        let path = &prep.program.paths[i];
        let mut popts = ropts.clone();
        popts.posture_feed_mm_min = feeds.clone();
        let mut figures = FeedFigures::default();
        resample::resample_streamed(path, &popts, |s| {
            let run = s.run() + run_base;
            last_run = last_run.max(run);
            let count = s.count();
            figures.push(run, s.t_s(), s.feed_mm_min(), count);
            match s {
                Streamed::Sample(s) => {
                    let keep = reach.is_none_or(|r| r.near(&s.position, margin));
                    let mut s = s.clone();
                    s.run = run;
                    subset.push(&s, keep);
                }
                Streamed::Far(_) | Streamed::FarRun(_) => subset.skip(count as usize),
            }
            let before = streamed;
            streamed += count;
            if streamed >> 16 != before >> 16 {
                progress.advance(streamed, (estimated as u64).max(streamed));
            }
        })
        .map_err(|e| {
            Error::within(
                format_args!("{file}: tool path {} ({})", i + 1, path.name),
                e,
            )
        })?;
        run_base = last_run + 1;
        let (cut, (lo, hi, mean)) = figures.finish();
        let n = all.0 + figures.n;
        all.2 = (
            all.2.0.min(lo),
            all.2.1.max(hi),
            if n > 0 {
                (all.2.2 * all.0 as f64 + mean * figures.n as f64) / n as f64
            } else {
                0.0
            },
        );
        all.0 = n;
        all.1 += cut;
    }
    if subset.seen == 0 {
        return Err(Error::Input(format!(
            "{file}: no cutting moves to simulate"
        )));
    }
    if subset.samples.is_empty() {
        return Err(nothing_in_reach(req, prep, margin));
    }
    Ok(Selected {
        samples_total: subset.seen,
        samples: subset.samples,
        cut_time_s: all.1,
        feed_mm_min: all.2,
    })
}

/// The samples the resampling streams (before culling), refused beyond the budget.
fn estimate(prep: &Prepared, mode: Mode) -> Result<f64> {
    let mut extent = crate::resample::PathExtent::default();
    for &i in &prep.paths {
        let p = &prep.program.paths[i];
        extent.cutting_mm += p.stats.cutting_length_mm;
        extent.runs += p.cutting_runs().len();
    }
    let est = crate::resample::estimate_samples(
        &extent,
        mode,
        prep.cutting.fz_mm,
        prep.cutter.teeth(),
        Some(prep.cutting.rpm),
    );
    let cap = crate::math::limits::MAX_SAMPLES as f64;
    if est > cap {
        return Err(Error::Result(format!(
            "{}: {:.1} mm of cutting moves would be resampled into about {est:.3e} poses (more than {cap:.0e}): check the feed per tooth ({} mm) and Δθ",
            prep.file, extent.cutting_mm, prep.cutting.fz_mm
        )));
    }
    Ok(est)
}

/// The error when no sample can reach the grid: for a patch near a point, how far the
/// point is from the cut surface.
fn nothing_in_reach(req: &SimulateRequest, prep: &Prepared, margin: f64) -> Error {
    let file = &prep.file;
    if let GridRequest::PatchNear { point, .. } = req.grid {
        let q = Point3::new(point[0], point[1], point[2]);
        let far = 2.0 * prep.cutter.radius_mm;
        let is_cut = |pi: usize, i: usize| prep.is_cut(pi, i);
        if let Some(n) = super::air::nearest(&prep.program, &prep.paths, &q, far, true, is_cut) {
            return Error::Request(format!(
                "{file}: ‹patch_near› {},{},{} is {:.3} mm from the surface the {} moves define (nearest point {:.4},{:.4},{:.4}): no cutting move comes within reach of the patch; pick a point on a finishing region (`crest inspect ‹regions›` lists them)",
                point[0],
                point[1],
                point[2],
                n.distance_mm,
                if req.moves == Moves::All {
                    "feed"
                } else {
                    "cut"
                },
                n.point.x,
                n.point.y,
                n.point.z
            ));
        }
    }
    Error::Result(format!(
        "{file}: no cutting move comes within reach of the grid (tool radius + depth of cut {margin:.3} mm); check the coordinates and the frame (‹absolute› applies MSYS)"
    ))
}
