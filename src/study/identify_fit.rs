//! The least-squares fit of one feed-direction profile behind the run-out identification:
//! the mark grid's position x0, the level of every tooth's marks, and which teeth cut.
//!
//! Model: the profile is the lower envelope of the tool's feed profile h centred at
//! x0 + pos_j + k·P (tooth j's mark within the revolution's feed P, every revolution k),
//! each raised to the level L_j of tooth j's marks (a deeper tooth has a lower level). For a
//! trial x0 the levels are fitted by alternating least squares: each sample is given to the
//! mark that is lowest there, then each level is the mean of (z − h) over its samples; a
//! tooth that owns no sample keeps its level. x0 is scanned over the span that tells the
//! marks apart (fz for an even pitch, P otherwise) and refined by golden section.
//!
//! A tooth cuts when taking it out of the envelope raises the residual sum of squares by more
//! than [`CUT_CHI2`] times the residual variance (a likelihood-ratio test of one level): a
//! mark that the noise could explain as well without it is not counted. The level of a tooth
//! that does not cut is only bounded: [`bounds`] gives the lowest level at which it still
//! leaves no mark on the envelope of the others.

use crate::tool::FeedProfile;

/// How much a tooth must lower the residual sum of squares, in residual variances, to count
/// as cutting (χ² of one degree of freedom at about 1 in 2000).
pub const CUT_CHI2: f64 = 12.0;

/// Trials of x0 over the span before the golden-section refinement.
const TRIALS: usize = 96;

/// Most teeth for which patterns are searched by swapping a cutting tooth for a silent one.
const SWAP_TEETH: usize = 16;

/// Alternations of ownership and levels per trial.
const ALTERNATIONS: usize = 30;

/// The marks of a tool on a plane at one lead: the feed profile and where each tooth's mark
/// sits within one revolution's feed.
#[derive(Debug, Clone)]
pub struct Marks {
    /// The feed profile of a tooth (its lowest point at 0).
    pub profile: FeedProfile,
    /// Position of tooth j's mark within the revolution's feed, mm, in [0, period).
    pub pos_mm: Vec<f64>,
    /// Feed per revolution Z·fz, mm.
    pub period_mm: f64,
    /// Span of x0 that tells the marks apart: fz for an even pitch, the period otherwise.
    pub span_mm: f64,
}

impl Marks {
    /// Height above its level of tooth j's nearest marks at `x` for the grid at `x0`, mm.
    fn height(&self, j: usize, x0: f64, x: f64) -> f64 {
        let p = self.period_mm;
        let u = (x - x0 - self.pos_mm[j]).rem_euclid(p);
        self.profile.height(u).min(self.profile.height(u - p))
    }

    fn teeth(&self) -> usize {
        self.pos_mm.len()
    }
}

/// One profile's fit.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileFit {
    /// Position of tooth 0's mark grid, mm.
    pub x0_mm: f64,
    /// Level of each tooth's marks, mm: fitted for a tooth that cuts, the bound of
    /// [`bounds`] for one that does not.
    pub levels_mm: Vec<f64>,
    /// Which teeth cut.
    pub cuts: Vec<bool>,
    /// Samples owned by each tooth.
    pub owned: Vec<usize>,
    /// Residual sum of squares, mm².
    pub rss_mm2: f64,
    /// Samples fitted.
    pub samples: usize,
}

impl ProfileFit {
    /// Residual variance per sample (the fitted levels and x0 taken off the degrees of
    /// freedom), mm².
    pub fn variance_mm2(&self) -> f64 {
        let dof = self.samples.saturating_sub(self.teeth_cutting() + 1).max(1);
        self.rss_mm2 / dof as f64
    }

    fn teeth_cutting(&self) -> usize {
        self.cuts.iter().filter(|c| **c).count()
    }
}

/// Heights of every tooth's nearest marks at every sample for the grid at `x0`.
fn heights(marks: &Marks, xs: &[f64], x0: f64) -> Vec<f64> {
    let nt = marks.teeth();
    let mut h = Vec::with_capacity(xs.len() * nt);
    for &x in xs {
        for j in 0..nt {
            h.push(marks.height(j, x0, x));
        }
    }
    h
}

/// The lowest active mark at sample i: (its tooth, its height).
fn lowest(h: &[f64], levels: &[f64], active: &[bool], i: usize) -> (usize, f64) {
    let nt = levels.len();
    let mut best = (usize::MAX, f64::INFINITY);
    for j in 0..nt {
        if active[j] {
            let v = h[i * nt + j] + levels[j];
            if v < best.1 {
                best = (j, v);
            }
        }
    }
    best
}

/// Alternating least squares of the levels for the grid heights `h`; returns the residual
/// sum of squares.
fn alternate(h: &[f64], zs: &[f64], levels: &mut [f64], active: &[bool]) -> f64 {
    let nt = levels.len();
    let mut owner = vec![usize::MAX; zs.len()];
    for _ in 0..ALTERNATIONS {
        let mut sum = vec![0.0; nt];
        let mut count = vec![0usize; nt];
        let mut changed = false;
        for (i, z) in zs.iter().enumerate() {
            let (j, _) = lowest(h, levels, active, i);
            if j == usize::MAX {
                continue;
            }
            changed |= owner[i] != j;
            owner[i] = j;
            sum[j] += z - h[i * nt + j];
            count[j] += 1;
        }
        for j in 0..nt {
            if count[j] > 0 {
                levels[j] = sum[j] / count[j] as f64;
            }
        }
        if !changed {
            break;
        }
    }
    rss(h, zs, levels, active)
}

fn rss(h: &[f64], zs: &[f64], levels: &[f64], active: &[bool]) -> f64 {
    zs.iter()
        .enumerate()
        .map(|(i, z)| {
            let (_, v) = lowest(h, levels, active, i);
            if v.is_finite() { (z - v).powi(2) } else { 0.0 }
        })
        .sum()
}

/// The starting levels: for each tooth the median of (z − h) over the samples within a
/// quarter of the nearest mark spacing of its marks' lowest points (its own level when it
/// cuts there; higher when it does not), or the highest sample where it has none.
fn start_levels(marks: &Marks, h: &[f64], xs: &[f64], zs: &[f64], x0: f64) -> Vec<f64> {
    let nt = marks.teeth();
    let p = marks.period_mm;
    let near = 0.25 * marks.span_mm.min(p / nt as f64);
    let top = zs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (0..nt)
        .map(|j| {
            let mut v: Vec<f64> = xs
                .iter()
                .enumerate()
                .filter(|(_, x)| {
                    let u = (*x - x0 - marks.pos_mm[j]).rem_euclid(p);
                    u.min(p - u) <= near
                })
                .map(|(i, _)| zs[i] - h[i * nt + j])
                .filter(|v| v.is_finite())
                .collect();
            if v.is_empty() {
                return top;
            }
            let m = v.len() / 2;
            *v.select_nth_unstable_by(m, f64::total_cmp).1
        })
        .collect()
}

/// The residual sum of squares of the best levels for the grid at `x0` (all teeth active).
fn trial(marks: &Marks, xs: &[f64], zs: &[f64], x0: f64) -> f64 {
    let h = heights(marks, xs, x0);
    let mut levels = start_levels(marks, &h, xs, zs, x0);
    alternate(&h, zs, &mut levels, &vec![true; marks.teeth()])
}

/// Fit the profile `xs` (mm, ascending), `zs` (mm) with `marks`.
pub fn fit_profile(marks: &Marks, xs: &[f64], zs: &[f64]) -> ProfileFit {
    let nt = marks.teeth();
    let step = marks.span_mm / TRIALS as f64;
    let mut best = (f64::INFINITY, 0.0);
    for i in 0..TRIALS {
        let x0 = i as f64 * step;
        let r = trial(marks, xs, zs, x0);
        if r < best.0 {
            best = (r, x0);
        }
    }
    let (mut lo, mut hi) = (best.1 - step, best.1 + step);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..30 {
        let c = hi - g * (hi - lo);
        let d = lo + g * (hi - lo);
        if trial(marks, xs, zs, c) < trial(marks, xs, zs, d) {
            hi = d;
        } else {
            lo = c;
        }
    }
    let x0 = 0.5 * (lo + hi);
    let x0 = if trial(marks, xs, zs, x0) <= best.0 {
        x0
    } else {
        best.1
    };
    let h = heights(marks, xs, x0);
    let mut levels = start_levels(marks, &h, xs, zs, x0);
    let mut active = vec![true; nt];
    let mut total = alternate(&h, zs, &mut levels, &active);
    // A tooth that owns nothing may still cut by a little: tried just below its bound, it
    // stays when the fit improves.
    for _ in 0..nt {
        let owned = owners(&h, &levels, &active, zs.len());
        let var = variance(total, zs.len(), nt);
        let mut improved = false;
        for j in (0..nt).filter(|&j| owned[j] == 0) {
            let cutting: Vec<bool> = owned.iter().map(|n| *n > 0).collect();
            let b = bounds(marks, &levels, &cutting)[j];
            for depth in [1.0, 4.0, 16.0] {
                let mut trial_levels = levels.clone();
                trial_levels[j] = b - depth * var.sqrt();
                let r = alternate(&h, zs, &mut trial_levels, &active);
                if r < total - CUT_CHI2 * var {
                    levels = trial_levels;
                    total = r;
                    improved = true;
                    break;
                }
            }
        }
        if !improved {
            break;
        }
    }
    // Swap a tooth that cuts for one that does not, when that fits better (two patterns of
    // marks can be close; the alternation keeps the one it started from). Up to
    // [`SWAP_TEETH`] teeth: the search grows with the square of their number.
    for _ in 0..if nt <= SWAP_TEETH { nt } else { 0 } {
        let owned = owners(&h, &levels, &active, zs.len());
        let var = variance(total, zs.len(), nt);
        let top = zs.iter().copied().fold(f64::NEG_INFINITY, f64::max) + 1.0;
        let mut best: Option<(f64, Vec<f64>)> = None;
        for i in (0..nt).filter(|&i| owned[i] > 0) {
            for j in (0..nt).filter(|&j| owned[j] == 0) {
                let mut base = levels.clone();
                base[i] = top;
                let mut cutting: Vec<bool> = owned.iter().map(|n| *n > 0).collect();
                cutting[i] = false;
                if !cutting.iter().any(|c| *c) {
                    continue;
                }
                let b = bounds(marks, &base, &cutting)[j];
                for depth in [1.0, 4.0, 16.0] {
                    let mut trial_levels = base.clone();
                    trial_levels[j] = b - depth * var.sqrt();
                    let r = alternate(&h, zs, &mut trial_levels, &active);
                    if r < total - var && best.as_ref().is_none_or(|(rb, _)| r < *rb) {
                        best = Some((r, trial_levels));
                    }
                }
            }
        }
        match best {
            Some((r, l)) => {
                total = r;
                levels = l;
            }
            None => break,
        }
    }
    // Take out, one at a time, the tooth whose marks explain least.
    loop {
        let owned = owners(&h, &levels, &active, zs.len());
        let left = active.iter().filter(|a| **a).count();
        let var = variance(total, zs.len(), left);
        let gain = |j: usize| -> f64 {
            let mut without = active.clone();
            without[j] = false;
            rss(&h, zs, &levels, &without) - total
        };
        let weakest = (0..nt)
            .filter(|&j| active[j])
            .map(|j| (j, if owned[j] == 0 { 0.0 } else { gain(j) }))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        match weakest {
            Some((j, g)) if left > 1 && g <= CUT_CHI2 * var => {
                active[j] = false;
                total = alternate(&h, zs, &mut levels, &active);
            }
            _ => break,
        }
    }
    let owned = owners(&h, &levels, &active, zs.len());
    let cuts = active.clone();
    let levels = bounds(marks, &levels, &cuts);
    ProfileFit {
        x0_mm: x0,
        levels_mm: levels,
        cuts,
        owned,
        rss_mm2: total,
        samples: zs.len(),
    }
}

/// Smallest residual standard deviation taken for the tests of [`CUT_CHI2`], mm: the model's
/// own approximations (a tooth's arc of radius R where it cuts with R + Δ) leave about a
/// nanometre on a profile without noise, which a tooth trimming the cusps could otherwise
/// "explain".
const SIGMA_FLOOR_MM: f64 = 2e-6;

/// The residual variance of a fit with `levels` free levels, never below the floor.
fn variance(rss: f64, n: usize, levels: usize) -> f64 {
    (rss / n.saturating_sub(levels + 1).max(1) as f64).max(SIGMA_FLOOR_MM * SIGMA_FLOOR_MM)
}

fn owners(h: &[f64], levels: &[f64], active: &[bool], n: usize) -> Vec<usize> {
    let mut owned = vec![0usize; levels.len()];
    for i in 0..n {
        let (j, _) = lowest(h, levels, active, i);
        if j < owned.len() {
            owned[j] += 1;
        }
    }
    owned
}

/// Points per revolution's feed on which [`bounds`] evaluates the envelope.
const BOUND_POINTS: usize = 20_000;

/// The levels with every tooth that does not cut raised or lowered to its bound: the lowest
/// level at which it leaves no mark below the envelope of the teeth that cut (it touches the
/// envelope there, and any higher level gives the same profile), mm. The teeth that cut keep
/// their levels.
pub fn bounds(marks: &Marks, levels: &[f64], cuts: &[bool]) -> Vec<f64> {
    let nt = marks.teeth();
    let p = marks.period_mm;
    let dx = p / BOUND_POINTS as f64;
    let mut out = levels.to_vec();
    let mut worst = vec![f64::NEG_INFINITY; nt];
    for i in 0..BOUND_POINTS {
        let x = i as f64 * dx;
        let env = (0..nt)
            .filter(|&j| cuts[j])
            .map(|j| marks.height(j, 0.0, x) + levels[j])
            .fold(f64::INFINITY, f64::min);
        for j in 0..nt {
            if !cuts[j] {
                worst[j] = worst[j].max(env - marks.height(j, 0.0, x));
            }
        }
    }
    for j in 0..nt {
        if !cuts[j] && worst[j].is_finite() {
            out[j] = worst[j];
        }
    }
    out
}

/// How far a tooth's level may move before it changes from cutting to not (or back), mm:
/// for a tooth that cuts, how far its marks reach below the envelope of the others; for one
/// that does not, how far its level lies above its bound. `None` when only one tooth cuts
/// and the question is that tooth's.
pub fn margins(marks: &Marks, levels: &[f64], cuts: &[bool]) -> Vec<Option<f64>> {
    let nt = marks.teeth();
    (0..nt)
        .map(|j| {
            let mut others = cuts.to_vec();
            others[j] = false;
            if !others.iter().any(|c| *c) {
                return None;
            }
            let b = bounds(marks, levels, &others)[j];
            Some((b - levels[j]).abs())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle_marks(nt: usize, fz: f64) -> Marks {
        Marks {
            profile: FeedProfile::Circle { radius_mm: 5.0 },
            pos_mm: (0..nt).map(|j| j as f64 * fz).collect(),
            period_mm: nt as f64 * fz,
            span_mm: fz,
        }
    }

    #[test]
    fn one_deep_tooth_is_found_and_the_others_are_set_at_their_bounds() {
        let m = circle_marks(4, 0.05);
        let truth = [0.0, 0.003, 0.004, 0.003];
        let xs: Vec<f64> = (0..2000).map(|i| i as f64 * 0.0008).collect();
        let zs: Vec<f64> = xs
            .iter()
            .map(|&x| {
                (0..4)
                    .map(|j| m.height(j, 0.013, x) + truth[j])
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let fit = fit_profile(&m, &xs, &zs);
        assert_eq!(fit.cuts.iter().filter(|c| **c).count(), 1, "{fit:?}");
        let j = fit.cuts.iter().position(|c| *c).unwrap();
        assert!(fit.levels_mm[j].abs() < 1e-7, "{fit:?}");
        // Tooth j + 2 sits under the cusp: its bound is the cusp, 1 µm.
        let b = fit.levels_mm[(j + 2) % 4];
        assert!((b - 0.2f64.powi(2) / 40.0).abs() < 2e-5, "{b}");
    }
}
