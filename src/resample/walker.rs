//! The run walker: one cutting run walked move by move on its clock (feed linear in time),
//! the samples placed on the fz or Δθ grid, each with its pose, contact data and frame.

use super::curve::{Curve, above};
use super::sphere::SphereInterp;
use super::{AxisInterpolation, Far, FarRun, Mode, ResampleError, Sample, Stats, Streamed};
use crate::math::{Point3, Vec3, any_perpendicular, normalize_or_none};
use crate::toolpath::Posture;

/// The options a walker needs (everything but the per-posture feeds).
#[derive(Debug, Clone, Copy)]
pub(super) struct Params {
    pub(super) mode: Mode,
    pub(super) fz_mm: f64,
    pub(super) feed_mm_min: Option<f64>,
    pub(super) axis_interpolation: AxisInterpolation,
    pub(super) spline: bool,
    pub(super) posture_feeds: bool,
    /// Build only the samples of moves that may come into this box (lower, upper).
    pub(super) near: Option<(Point3, Point3)>,
}

/// The sample held back until the next one is placed.
#[derive(Debug, Clone)]
enum Pending {
    Built(Sample),
    Far(Far),
}

impl Pending {
    fn s_mm(&self) -> f64 {
        match self {
            Pending::Built(s) => s.s_mm,
            Pending::Far(f) => f.s_mm,
        }
    }

    fn theta_rad(&self) -> f64 {
        match self {
            Pending::Built(s) => s.theta_rad,
            Pending::Far(f) => f.theta_rad,
        }
    }

    fn streamed(&self) -> Streamed<'_> {
        match self {
            Pending::Built(s) => Streamed::Sample(s),
            Pending::Far(f) => Streamed::Far(f),
        }
    }
}

/// A posture held by the resampler, with its per-posture feed.
#[derive(Debug, Clone)]
pub(super) struct Entry {
    pub(super) p: Posture,
    pub(super) feed: Option<f64>,
}

/// The clock of a run: the spindle speed and the nominal feed per tooth.
#[derive(Debug, Clone, Copy)]
pub(super) struct Clock {
    /// Ω, rad/s.
    pub(super) omega: f64,
    pub(super) rpm: f64,
    pub(super) teeth: f64,
    pub(super) fz_mm: f64,
    /// No feed and no spindle speed are known (feed-per-tooth spacing only): the clock
    /// runs at a nominal 1 rpm so that θ follows the arc length (θ = 2π s / (Z fz)),
    /// and the samples carry no time and no feed (NaN).
    pub(super) timeless: bool,
}

/// One cutting move ready for sampling.
#[derive(Debug, Clone, Copy)]
struct Move {
    curve: Curve,
    len: f64,
    axis: SphereInterp,
    contact: Option<(Point3, Point3, SphereInterp)>,
    /// Feeds at the start and end, mm/s.
    va: f64,
    vb: f64,
    /// Duration, s.
    dt: f64,
    /// Run-relative arc length, time and θ at the start.
    s0: f64,
    t0: f64,
    theta0: f64,
}

impl Move {
    /// Time since the start of the move at arc length σ (feed linear in time).
    fn tau_at(&self, sigma: f64) -> f64 {
        if sigma <= 0.0 {
            return 0.0;
        }
        if self.va == self.vb {
            return (sigma / self.va).min(self.dt);
        }
        let a = (self.vb - self.va) / (2.0 * self.dt);
        let disc = (self.va * self.va + 4.0 * a * sigma).max(0.0);
        let den = self.va + disc.sqrt();
        if den > 0.0 {
            (2.0 * sigma / den).min(self.dt)
        } else {
            0.0
        }
    }

    /// Arc length since the start of the move at time τ (model.md §5.3, Eq 6).
    fn sigma_at(&self, tau: f64) -> f64 {
        let s = self.va * tau + (self.vb - self.va) * tau * tau / (2.0 * self.dt);
        s.clamp(0.0, self.len)
    }

    /// Feed at time τ, mm/s (Eq 5).
    fn feed_at(&self, tau: f64) -> f64 {
        self.va + (self.vb - self.va) * (tau / self.dt).clamp(0.0, 1.0)
    }
}

/// The walker of one cutting run: its clock, the next grid sample, the held-back sample.
pub(super) struct RunWalker {
    params: Params,
    clock: Clock,
    run_idx: usize,
    s_offset: f64,
    /// Index of the next grid sample of the run.
    k: u64,
    /// Run-relative arc length, time and θ at the end of the last move walked.
    pub(super) s_end: f64,
    pub(super) t_end: f64,
    theta_end: f64,
    last: Option<Move>,
    pending: Option<Pending>,
    pending_is_first: bool,
    prev_feed_dir: Option<Vec3>,
}

fn checked_axis(p: &Posture) -> Result<Vec3, ResampleError> {
    let finite = p.position.coords.iter().all(|c| c.is_finite());
    if !finite {
        return Err(ResampleError::InvalidPosture {
            line: p.line,
            what: "non-finite coordinate",
        });
    }
    if !p.axis.iter().all(|c| c.is_finite()) {
        return Err(ResampleError::InvalidPosture {
            line: p.line,
            what: "non-finite tool axis",
        });
    }
    normalize_or_none(&p.axis, 1e-12).ok_or(ResampleError::InvalidPosture {
        line: p.line,
        what: "zero tool axis",
    })
}

fn checked_feed(line: u32, v: f64) -> Result<f64, ResampleError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(ResampleError::InvalidFeed { line, value: v })
    }
}

/// The unit tangent of the spline at a posture, from the moves into it and out of it
/// (within the run): an adjacent arc's own tangent, else Bessel's (the tangent of the
/// parabola through the neighbours), one-sided at the ends of the run.
fn posture_tangent(
    incoming: Option<(&Posture, &Posture)>,
    outgoing: Option<(&Posture, &Posture)>,
) -> Option<Vec3> {
    let neighbour = |a: &Posture, b: &Posture, out: bool| -> Option<(Vec3, f64, bool)> {
        if let Some(arc) = &b.arc
            && let Some(c) = Curve::arc(a.position, b.position, arc)
        {
            let (t0, t1) = c.end_tangents();
            return Some((if out { t0 } else { t1 }, c.len(), true));
        }
        let d = b.position - a.position;
        let len = d.norm();
        normalize_or_none(&d, 1e-12).map(|d| (d, len, false))
    };
    let incoming = incoming.and_then(|(a, b)| neighbour(a, b, false));
    let outgoing = outgoing.and_then(|(a, b)| neighbour(a, b, true));
    match (incoming, outgoing) {
        (Some((t, _, true)), _) | (_, Some((t, _, true))) => Some(t),
        (Some((din, lin, _)), Some((dout, lout, _))) => {
            normalize_or_none(&(din * lout + dout * lin), 1e-9).or(Some(dout))
        }
        (Some((t, _, _)), None) | (None, Some((t, _, _))) => Some(t),
        (None, None) => None,
    }
}

impl RunWalker {
    pub(super) fn new(params: Params, clock: Clock, run_idx: usize, s_offset: f64) -> RunWalker {
        RunWalker {
            params,
            clock,
            run_idx,
            s_offset,
            k: 0,
            s_end: 0.0,
            t_end: 0.0,
            theta_end: 0.0,
            last: None,
            pending: None,
            pending_is_first: false,
            prev_feed_dir: None,
        }
    }

    /// The feeds at the start and end of the move `a → b`, mm/min.
    fn move_feeds(&self, a: &Entry, b: &Entry) -> Result<(f64, f64), ResampleError> {
        if self.params.posture_feeds {
            return Ok((
                checked_feed(a.p.line, a.feed.unwrap_or(f64::NAN))?,
                checked_feed(b.p.line, b.feed.unwrap_or(f64::NAN))?,
            ));
        }
        let v = match (self.params.feed_mm_min, b.p.feed_mm_min) {
            (Some(v), _) | (None, Some(v)) => v,
            (None, None) => self.clock.teeth * self.clock.fz_mm * self.clock.rpm,
        };
        let v = checked_feed(b.p.line, v)?;
        Ok((v, v))
    }

    /// The geometry of the move `a → b` (`before` precedes `a` and `next` follows `b`
    /// in the run), or `None` for a zero-length move.
    fn curve(
        &self,
        before: Option<&Posture>,
        a: &Posture,
        b: &Posture,
        next: Option<&Posture>,
        stats: &mut Stats,
    ) -> Option<Curve> {
        if let Some(arc) = &b.arc {
            stats.arcs += 1;
            if let Some(c) = Curve::arc(a.position, b.position, arc) {
                return Some(c);
            }
            stats.degenerate_arcs += 1;
            return Curve::line(a.position, b.position);
        }
        if self.params.spline {
            let t0 = posture_tangent(before.map(|x| (x, a)), Some((a, b)));
            let t1 = posture_tangent(Some((a, b)), next.map(|n| (b, n)));
            if let (Some(t0), Some(t1)) = (t0, t1) {
                return Curve::hermite(a.position, b.position, t0, t1);
            }
        }
        Curve::line(a.position, b.position)
    }

    pub(super) fn walk_move(
        &mut self,
        before: Option<&Entry>,
        ea: &Entry,
        eb: &Entry,
        next: Option<&Entry>,
        stats: &mut Stats,
        emit: &mut impl FnMut(Streamed<'_>, &Clock, &mut Stats),
    ) -> Result<(), ResampleError> {
        let (a, b) = (&ea.p, &eb.p);
        let axis_a = checked_axis(a)?;
        let axis_b = checked_axis(b)?;
        let Some(curve) = self.curve(before.map(|e| &e.p), a, b, next.map(|e| &e.p), stats) else {
            stats.zero_length_moves += 1;
            return Ok(());
        };
        let len = curve.len();
        let (va, vb) = self.move_feeds(ea, eb)?;
        if !above(va + vb, 0.0) {
            return Err(ResampleError::ZeroFeedMove { line: b.line });
        }
        if va != vb {
            stats.variable_feed_moves += 1;
        }
        let (va, vb) = (va / 60.0, vb / 60.0);
        let dt = 2.0 * len / (va + vb);
        let kind = self.params.axis_interpolation;
        let (axis, flipped) = SphereInterp::new(axis_a, axis_b, kind);
        stats.axis_flips += u64::from(flipped);
        let contact = match (&a.contact, &b.contact) {
            (Some(ca), Some(cb)) => {
                let na = normalize_or_none(&ca.normal, 1e-12);
                let nb = normalize_or_none(&cb.normal, 1e-12);
                match (na, nb) {
                    (Some(na), Some(nb)) => {
                        let (ni, flipped) = SphereInterp::new(na, nb, kind);
                        stats.normal_flips += u64::from(flipped);
                        Some((ca.point, cb.point, ni))
                    }
                    _ => {
                        stats.partial_contact_moves += 1;
                        None
                    }
                }
            }
            (None, None) => None,
            _ => {
                stats.partial_contact_moves += 1;
                None
            }
        };
        let mv = Move {
            curve,
            len,
            axis,
            contact,
            va,
            vb,
            dt,
            s0: self.s_end,
            t0: self.t_end,
            theta0: self.theta_end,
        };
        let s_end = mv.s0 + len;
        let theta_end = mv.theta0 + self.clock.omega * dt;
        // A move that cannot come near the box gets its samples' clock only (the same
        // arc length, time, θ and feed as built ones), not their poses.
        let far = self
            .params
            .near
            .is_some_and(|(lo, hi)| !mv.curve.may_meet(&lo, &hi));
        match self.params.mode {
            Mode::FeedPerTooth if far && mv.va == mv.vb => self.skip_far(&mv, s_end, stats, emit),
            Mode::FeedPerTooth => {
                while (self.k as f64 * self.params.fz_mm) < s_end {
                    self.fz_sample(&mv, far, stats, emit);
                }
            }
            Mode::SpindleStep { dtheta_rad } => loop {
                let theta = self.k as f64 * dtheta_rad;
                if theta >= theta_end {
                    break;
                }
                let tau = ((theta - mv.theta0) / self.clock.omega).max(0.0);
                let sigma = mv.sigma_at(tau);
                self.push(&mv, mv.s0 + sigma, sigma, tau, theta, far, stats, emit);
            },
        }
        self.s_end = s_end;
        self.t_end = mv.t0 + dt;
        self.theta_end = theta_end;
        self.last = Some(mv);
        Ok(())
    }

    /// The samples of a far move at one feed (`mv.va == mv.vb`), every fz up to `s_end`:
    /// what [`RunWalker::push`] would do for each, with the clocks of all but the last
    /// handed on together ([`Streamed::FarRun`]; their times and feeds are the same values
    /// as one by one).
    fn skip_far(
        &mut self,
        mv: &Move,
        s_end: f64,
        stats: &mut Stats,
        emit: &mut impl FnMut(Streamed<'_>, &Clock, &mut Stats),
    ) {
        let step = self.params.fz_mm;
        // The first k at or past the end, as the sample loop finds it (k · fz ≥ s_end).
        let mut end = (s_end / step).ceil().max(0.0) as u64;
        while end > self.k && (end - 1) as f64 * step >= s_end {
            end -= 1;
        }
        while (end as f64 * step) < s_end {
            end += 1;
        }
        if end <= self.k + 1 {
            if end == self.k + 1 {
                self.fz_sample(mv, true, stats, emit);
            }
            return;
        }
        // All but the last: the one held back goes first, then the run of them.
        if let Some(p) = self.pending.take() {
            emit(p.streamed(), &self.clock, stats);
        }
        let last = end - 2;
        let timeless = self.clock.timeless;
        let sigma = (last as f64 * step - mv.s0).max(0.0);
        let batch = FarRun {
            run: self.run_idx,
            count: last + 1 - self.k,
            t_s: if timeless {
                f64::NAN
            } else {
                mv.t0 + mv.tau_at(sigma)
            },
            feed_mm_min: if timeless {
                f64::NAN
            } else {
                mv.feed_at(0.0) * 60.0
            },
        };
        emit(Streamed::FarRun(&batch), &self.clock, stats);
        self.k = end - 1;
        self.fz_sample(mv, true, stats, emit);
    }

    /// [`RunWalker::push`] of sample `k` of the fz grid (built unless `far`).
    fn fz_sample(
        &mut self,
        mv: &Move,
        far: bool,
        stats: &mut Stats,
        emit: &mut impl FnMut(Streamed<'_>, &Clock, &mut Stats),
    ) {
        let s = self.k as f64 * self.params.fz_mm;
        let sigma = (s - mv.s0).max(0.0);
        let tau = mv.tau_at(sigma);
        let theta = mv.theta0 + self.clock.omega * tau;
        self.push(mv, s, sigma, tau, theta, far, stats, emit);
    }

    /// Build the sample at run-relative arc length `s` (σ into the move, τ after its
    /// start, spindle angle θ), or only its clock when the move is `far`, emit the
    /// previous one and hold this one back.
    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        mv: &Move,
        s: f64,
        sigma: f64,
        tau: f64,
        theta: f64,
        far: bool,
        stats: &mut Stats,
        emit: &mut impl FnMut(Streamed<'_>, &Clock, &mut Stats),
    ) {
        let sample = if far {
            let timeless = self.clock.timeless;
            Pending::Far(Far {
                run: self.run_idx,
                s_mm: self.s_offset + s,
                t_s: if timeless { f64::NAN } else { mv.t0 + tau },
                theta_rad: theta,
                feed_mm_min: if timeless {
                    f64::NAN
                } else {
                    mv.feed_at(tau) * 60.0
                },
            })
        } else {
            Pending::Built(self.sample(mv, s, sigma, tau, theta, stats))
        };
        if let Some(p) = self.pending.take() {
            emit(p.streamed(), &self.clock, stats);
        }
        self.pending_is_first = self.k == 0;
        self.pending = Some(sample);
        self.k += 1;
    }

    fn sample(
        &mut self,
        mv: &Move,
        s: f64,
        sigma: f64,
        tau: f64,
        theta: f64,
        stats: &mut Stats,
    ) -> Sample {
        let u = mv.curve.param(sigma);
        let (position, tangent) = mv.curve.eval(u);
        let axis = mv.axis.eval(u);
        let (contact, normal) = match &mv.contact {
            Some((c0, c1, ni)) => (Some(c0 + (c1 - c0) * u), Some(ni.eval(u))),
            None => (None, None),
        };
        let feed_dir = self.feed_direction(&tangent, &axis, normal.as_ref(), stats);
        let timeless = self.clock.timeless;
        Sample {
            run: self.run_idx,
            s_mm: self.s_offset + s,
            t_s: if timeless { f64::NAN } else { mv.t0 + tau },
            theta_rad: theta,
            position,
            axis,
            contact,
            normal,
            feed_dir,
            feed_mm_min: if timeless {
                f64::NAN
            } else {
                mv.feed_at(tau) * 60.0
            },
        }
    }

    /// f: the tangent projected on the plane normal to `n` (or to the axis without
    /// contact data); the degenerate cases are counted and fall back as documented.
    fn feed_direction(
        &mut self,
        tangent: &Vec3,
        axis: &Vec3,
        normal: Option<&Vec3>,
        stats: &mut Stats,
    ) -> Vec3 {
        let plane = normal.unwrap_or(axis);
        let project = |v: &Vec3| normalize_or_none(&(v - plane * v.dot(plane)), 1e-9);
        let f = match project(tangent) {
            Some(f) => f,
            None => {
                let from_axis = match normal {
                    Some(n) => {
                        stats.normal_parallel_to_feed += 1;
                        // The paper's own rule for a lone point: g = n × axis, f = g × n.
                        normalize_or_none(&n.cross(axis), 1e-9).map(|g| g.cross(n))
                    }
                    None => {
                        stats.feed_parallel_to_axis += 1;
                        None
                    }
                };
                from_axis
                    .or_else(|| self.prev_feed_dir.as_ref().and_then(project))
                    .unwrap_or_else(|| any_perpendicular(plane))
            }
        };
        self.prev_feed_dir = Some(f);
        f
    }

    /// Emit the held-back sample and the exact end of the run; false for a run of zero
    /// length (nothing emitted).
    pub(super) fn finish(
        &mut self,
        stats: &mut Stats,
        emit: &mut impl FnMut(Streamed<'_>, &Clock, &mut Stats),
    ) -> bool {
        let Some(mv) = self.last else {
            return false;
        };
        let end = self.sample(&mv, self.s_end, mv.len, mv.dt, self.theta_end, stats);
        if let Some(p) = self.pending.take() {
            // A grid sample within 1e-6 step of the end is the end itself.
            let at_end = match self.params.mode {
                Mode::FeedPerTooth => p.s_mm() >= end.s_mm - 1e-6 * self.params.fz_mm,
                Mode::SpindleStep { dtheta_rad } => {
                    p.theta_rad() >= end.theta_rad - 1e-6 * dtheta_rad
                }
            };
            if !at_end || self.pending_is_first {
                emit(p.streamed(), &self.clock, stats);
            }
        }
        emit(Streamed::Sample(&end), &self.clock, stats);
        true
    }
}
