//! The meridian of a cutter of any shape: its profile (r, z) from the tip upward as lines
//! and circular arcs, the queries the other stages ask of it, and the builders of the
//! shapes it describes (round inserts, APT's seven-parameter cutter, any polyline or arc
//! list, the circle-segment families barrel, lens, oval and taper barrel).
//!
//! Coordinates: r from the axis, z along the axis from the tool tip (the CL point, z = 0,
//! the lowest point of the body on the axis plane). An arc is the set of points
//! `centre + ρ (sin t, −cos t)` for t from `t0` to `t1`; the profile runs from the tip
//! upward with the material towards the axis, so an arc with `t1 > t0` is convex (its
//! outward normal is `(sin t, −cos t)`, t the normal's angle from −z towards +r) and one
//! with `t1 < t0` concave. A ball of radius R is the single arc about (0, R) from 0 to π/2.
//!
//! Above its last point the body continues as a cylinder of the last radius when the
//! profile ends going up or outward (the shank); a profile that ends turning inward (a
//! barrel) ends there.

use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::Arc;

mod shapes;

pub use shapes::{apt, barrel, classic, lens, oval, polyline, round_insert, taper_barrel};

/// One piece of a meridian, (r, z) in mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Segment {
    /// A straight piece from `a` to `b`.
    Line {
        /// Start (r, z).
        a: [f64; 2],
        /// End (r, z).
        b: [f64; 2],
    },
    /// A circular arc `centre + radius (sin t, −cos t)`, t from `t0` to `t1`.
    Arc {
        /// Centre (r, z).
        centre: [f64; 2],
        /// Radius ρ > 0.
        radius: f64,
        /// Start angle, rad.
        t0: f64,
        /// End angle, rad (> t0: convex, < t0: concave).
        t1: f64,
    },
}

pub(super) fn arc_point(c: [f64; 2], rho: f64, t: f64) -> [f64; 2] {
    let (s, co) = t.sin_cos();
    [c[0] + rho * s, c[1] - rho * co]
}

/// Whether angle `t` lies in [lo, hi] up to whole turns; returns the representative.
fn in_range(t: f64, lo: f64, hi: f64) -> Option<f64> {
    let k = ((lo - t) / TAU).ceil();
    let t = t + k * TAU;
    (t <= hi + 1e-12).then_some(t.min(hi))
}

impl Segment {
    /// The first point.
    pub fn start(&self) -> [f64; 2] {
        match *self {
            Segment::Line { a, .. } => a,
            Segment::Arc {
                centre, radius, t0, ..
            } => arc_point(centre, radius, t0),
        }
    }

    /// The last point.
    pub fn end(&self) -> [f64; 2] {
        match *self {
            Segment::Line { b, .. } => b,
            Segment::Arc {
                centre, radius, t1, ..
            } => arc_point(centre, radius, t1),
        }
    }

    /// Direction angle of the tangent (atan2(dz, dr)) at the start (`end = false`) or end.
    fn tangent_angle(&self, end: bool) -> f64 {
        match *self {
            Segment::Line { a, b } => (b[1] - a[1]).atan2(b[0] - a[0]),
            Segment::Arc { t0, t1, .. } => {
                let t = if end { t1 } else { t0 };
                if t1 >= t0 { t } else { t + PI }
            }
        }
    }

    /// Signed turning of the tangent along the segment, rad (positive = convex).
    fn turning(&self) -> f64 {
        match *self {
            Segment::Line { .. } => 0.0,
            Segment::Arc { t0, t1, .. } => t1 - t0,
        }
    }

    /// Points of the segment, first excluded, with chord error ≤ `tol` (arcs) and pieces
    /// at most `max_step` long (lines).
    fn sample(&self, tol: f64, max_step: f64, out: &mut Vec<[f64; 2]>) {
        match *self {
            Segment::Line { a, b } => {
                let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
                let n = (len / max_step).ceil().clamp(1.0, 400.0) as usize;
                for i in 1..=n {
                    let f = i as f64 / n as f64;
                    out.push([a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f]);
                }
            }
            Segment::Arc {
                centre,
                radius,
                t0,
                t1,
            } => {
                let dt = (8.0 * tol / radius).sqrt().clamp(1e-4, 2f64.to_radians());
                let n = ((t1 - t0).abs() / dt).ceil().clamp(1.0, 20_000.0) as usize;
                for i in 1..=n {
                    let t = t0 + (t1 - t0) * i as f64 / n as f64;
                    out.push(arc_point(centre, radius, t));
                }
            }
        }
    }

    /// The point of the segment farthest along `m` (r, z components), and its value.
    fn support(&self, m: [f64; 2]) -> ([f64; 2], f64) {
        let dot = |p: [f64; 2]| p[0] * m[0] + p[1] * m[1];
        let (s, e) = (self.start(), self.end());
        let mut best = if dot(e) > dot(s) { e } else { s };
        if let Segment::Arc {
            centre,
            radius,
            t0,
            t1,
        } = *self
            && (m[0] != 0.0 || m[1] != 0.0)
            && let Some(t) = in_range(m[0].atan2(-m[1]), t0.min(t1), t0.max(t1))
        {
            let p = arc_point(centre, radius, t);
            if dot(p) > dot(best) {
                best = p;
            }
        }
        (best, dot(best))
    }

    /// Heights z of the segment's points at radius `r`.
    fn heights_at(&self, r: f64, out: &mut Vec<f64>) {
        match *self {
            Segment::Line { a, b } => {
                let (lo, hi) = (a[0].min(b[0]), a[0].max(b[0]));
                if r < lo - 1e-12 || r > hi + 1e-12 {
                    return;
                }
                if (b[0] - a[0]).abs() < 1e-15 {
                    out.push(a[1].min(b[1]));
                } else {
                    let f = ((r - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0);
                    out.push(a[1] + (b[1] - a[1]) * f);
                }
            }
            Segment::Arc {
                centre,
                radius,
                t0,
                t1,
            } => {
                let s = (r - centre[0]) / radius;
                if !(-1.0 - 1e-12..=1.0 + 1e-12).contains(&s) {
                    return;
                }
                let a = s.clamp(-1.0, 1.0).asin();
                let (lo, hi) = (t0.min(t1), t0.max(t1));
                for t in [a, PI - a] {
                    if let Some(t) = in_range(t, lo, hi) {
                        out.push(centre[1] - radius * t.cos());
                    }
                }
            }
        }
    }

    /// Radii r of the segment's points at height `z`.
    fn radii_at(&self, z: f64, out: &mut Vec<f64>) {
        match *self {
            Segment::Line { a, b } => {
                let (lo, hi) = (a[1].min(b[1]), a[1].max(b[1]));
                if z < lo - 1e-12 || z > hi + 1e-12 {
                    return;
                }
                if (b[1] - a[1]).abs() < 1e-15 {
                    out.push(a[0].max(b[0]));
                } else {
                    let f = ((z - a[1]) / (b[1] - a[1])).clamp(0.0, 1.0);
                    out.push(a[0] + (b[0] - a[0]) * f);
                }
            }
            Segment::Arc {
                centre,
                radius,
                t0,
                t1,
            } => {
                let c = (centre[1] - z) / radius;
                if !(-1.0 - 1e-12..=1.0 + 1e-12).contains(&c) {
                    return;
                }
                let a = c.clamp(-1.0, 1.0).acos();
                let (lo, hi) = (t0.min(t1), t0.max(t1));
                for t in [a, -a] {
                    if let Some(t) = in_range(t, lo, hi) {
                        out.push(centre[0] + radius * t.sin());
                    }
                }
            }
        }
    }

    /// The part of the segment with r ≥ 0 (`None` when none of it is).
    pub(super) fn clip_axis(&self) -> Option<Segment> {
        match *self {
            Segment::Line { a, b } => {
                if a[0] >= 0.0 && b[0] >= 0.0 {
                    return Some(*self);
                }
                if a[0] < 0.0 && b[0] < 0.0 {
                    return None;
                }
                let f = a[0] / (a[0] - b[0]);
                let p = [0.0, a[1] + (b[1] - a[1]) * f];
                Some(if a[0] < 0.0 {
                    Segment::Line { a: p, b }
                } else {
                    Segment::Line { a, b: p }
                })
            }
            Segment::Arc {
                centre,
                radius,
                t0,
                t1,
            } => {
                // r(t) = cr + ρ sin t ≥ 0 ⇔ sin t ≥ −cr/ρ.
                let s = -centre[0] / radius;
                if s <= -1.0 {
                    return Some(*self);
                }
                if s > 1.0 {
                    return None;
                }
                let a = s.asin(); // r ≥ 0 on [a, π − a] (mod 2π)
                let (lo, hi) = (t0.min(t1), t0.max(t1));
                let base = a + ((lo - a) / TAU).floor() * TAU;
                let mut best: Option<(f64, f64)> = None;
                for k in 0..3 {
                    let (x0, x1) = (base + k as f64 * TAU, base + k as f64 * TAU + PI - 2.0 * a);
                    let (c0, c1) = (x0.max(lo), x1.min(hi));
                    if c1 - c0 > 1e-12 && best.is_none_or(|b| c1 - c0 > b.1 - b.0) {
                        best = Some((c0, c1));
                    }
                }
                let (c0, c1) = best?;
                Some(if t1 >= t0 {
                    Segment::Arc {
                        centre,
                        radius,
                        t0: c0,
                        t1: c1,
                    }
                } else {
                    Segment::Arc {
                        centre,
                        radius,
                        t0: c1,
                        t1: c0,
                    }
                })
            }
        }
    }

    fn shifted(&self, dr: f64, dz: f64) -> Segment {
        match *self {
            Segment::Line { a, b } => Segment::Line {
                a: [a[0] + dr, a[1] + dz],
                b: [b[0] + dr, b[1] + dz],
            },
            Segment::Arc {
                centre,
                radius,
                t0,
                t1,
            } => Segment::Arc {
                centre: [centre[0] + dr, centre[1] + dz],
                radius,
                t0,
                t1,
            },
        }
    }
}

/// What a meridian was built from (for names and descriptions).
#[derive(Debug, Clone, PartialEq)]
pub enum Family {
    /// A ball, torus, flat end or round insert (built from the classic shapes).
    Classic,
    /// APT's `CUTTER/d,r,e,f,a,b,h` (lengths mm, angles degrees, as written).
    Apt([f64; 7]),
    /// `profile_mm`: a polyline or arc list.
    Polyline,
    /// Barrel: segment radius, height of its widest point, corner radius at the tip.
    Barrel {
        /// Segment radius Rs, mm.
        segment_radius_mm: f64,
        /// Height of the widest point above the tip, mm.
        segment_height_mm: f64,
        /// Corner radius between the end face and the segment, mm.
        corner_radius_mm: f64,
    },
    /// Lens: segment across the end (centre on the axis), corner radius at the periphery.
    Lens {
        /// Segment radius Rs, mm.
        segment_radius_mm: f64,
        /// Corner radius, mm.
        corner_radius_mm: f64,
    },
    /// Oval: tip radius on the axis, segment up to the vertical at R.
    Oval {
        /// Segment radius Rs, mm.
        segment_radius_mm: f64,
        /// Tip radius, mm.
        tip_radius_mm: f64,
    },
    /// Taper barrel: tip radius, segment starting along the taper angle up to R.
    TaperBarrel {
        /// Segment radius Rs, mm.
        segment_radius_mm: f64,
        /// Tip radius, mm.
        tip_radius_mm: f64,
        /// Angle between the axis and the profile where the segment starts, degrees.
        taper_deg: f64,
    },
}

impl Family {
    /// The `shape` name of `tool.toml`.
    pub fn name(&self) -> &'static str {
        match self {
            Family::Classic => "classic",
            Family::Apt(_) => "apt",
            Family::Polyline => "profile",
            Family::Barrel { .. } => "barrel",
            Family::Lens { .. } => "lens",
            Family::Oval { .. } => "oval",
            Family::TaperBarrel { .. } => "taper_barrel",
        }
    }
}

#[derive(Debug, PartialEq)]
struct Data {
    segments: Vec<Segment>,
    family: Family,
    r_max: f64,
    r_min: f64,
    z_end: f64,
    end_height: f64,
    convex: bool,
    extends: bool,
}

/// A cutter's meridian (cheap to clone).
#[derive(Debug, Clone, PartialEq)]
pub struct Meridian(Arc<Data>);

/// Why a profile describes no cutter.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ProfileError(pub String);

pub(super) fn err<T>(msg: impl Into<String>) -> Result<T, ProfileError> {
    Err(ProfileError(msg.into()))
}

/// Join tolerance between consecutive segments, mm.
const JOIN_TOL: f64 = 1e-6;

impl Meridian {
    /// A meridian from its segments (checked: finite, continuous, r ≥ 0, lowest z = 0).
    pub fn new(segments: Vec<Segment>, family: Family) -> Result<Meridian, ProfileError> {
        let segments: Vec<Segment> = segments
            .into_iter()
            .filter(|s| match *s {
                Segment::Line { a, b } => (a[0] - b[0]).abs() + (a[1] - b[1]).abs() > 1e-12,
                Segment::Arc { t0, t1, radius, .. } => (t1 - t0).abs() * radius > 1e-12,
            })
            .collect();
        if segments.is_empty() {
            return err("the profile has no length");
        }
        for s in &segments {
            let ok = match *s {
                Segment::Line { a, b } => a.iter().chain(&b).all(|v| v.is_finite()),
                Segment::Arc {
                    centre,
                    radius,
                    t0,
                    t1,
                } => {
                    centre.iter().all(|v| v.is_finite())
                        && radius.is_finite()
                        && radius > 0.0
                        && t0.is_finite()
                        && t1.is_finite()
                }
            };
            if !ok {
                return err("the profile has a non-finite or non-positive value");
            }
        }
        for w in segments.windows(2) {
            let (e, s) = (w[0].end(), w[1].start());
            if (e[0] - s[0]).abs() > JOIN_TOL || (e[1] - s[1]).abs() > JOIN_TOL {
                return err(format!(
                    "the profile is not continuous at r = {:.6}, z = {:.6} mm",
                    e[0], e[1]
                ));
            }
        }
        let extreme = |m: [f64; 2]| {
            segments
                .iter()
                .map(|s| s.support(m).1)
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let r_min = -extreme([-1.0, 0.0]);
        let z_min = -extreme([0.0, -1.0]);
        if r_min < -1e-9 {
            return err("the profile crosses the axis (r < 0)");
        }
        if z_min.abs() > 1e-6 {
            return err(format!(
                "the lowest point of the profile must be at z = 0 (the tool tip), found z = {z_min:.6} mm"
            ));
        }
        let r_max = segments
            .iter()
            .map(|s| s.support([1.0, 0.0]).1)
            .fold(0.0f64, f64::max);
        if r_max <= 0.0 {
            return err("the profile has no radius");
        }
        // Convex: every arc convex, no right turn at a joint, total turning below π.
        let mut convex = segments.iter().all(|s| s.turning() >= 0.0);
        let mut total = 0.0;
        for (i, s) in segments.iter().enumerate() {
            total += s.turning();
            if i > 0 {
                let mut turn = s.tangent_angle(false) - segments[i - 1].tangent_angle(true);
                turn = (turn + PI).rem_euclid(TAU) - PI;
                if turn < -1e-9 {
                    convex = false;
                }
                total += turn;
            }
        }
        if total > PI + 1e-9 {
            convex = false;
        }
        let last = *segments.last().expect("not empty");
        let end = last.end();
        let end_angle = last.tangent_angle(true);
        // The shank continues when the profile ends going up (not turning back inward).
        let extends = (-1e-9..=FRAC_PI_2 + 1e-9).contains(&end_angle);
        let end_height = match last {
            Segment::Line { a, b } if segments.len() > 1 && b[1] > a[1] => a[1],
            _ => end[1],
        };
        Ok(Meridian(Arc::new(Data {
            segments,
            family,
            r_max,
            r_min: r_min.max(0.0),
            z_end: end[1],
            end_height: end_height.max(0.0),
            convex,
            extends,
        })))
    }

    /// The segments, from the tip upward.
    pub fn segments(&self) -> &[Segment] {
        &self.0.segments
    }

    /// What the meridian was built from.
    pub fn family(&self) -> &Family {
        &self.0.family
    }

    /// The largest radius, mm.
    pub fn r_max(&self) -> f64 {
        self.0.r_max
    }

    /// The smallest radius of the profile (0 when it starts on the axis), mm.
    pub fn r_min(&self) -> f64 {
        self.0.r_min
    }

    /// Height of the end: where the final straight side starts, else the top, mm.
    pub fn end_height(&self) -> f64 {
        self.0.end_height
    }

    /// Whether the profile (with its mirror image) bounds a convex body.
    pub fn is_convex(&self) -> bool {
        self.0.convex
    }

    /// The first and last points.
    pub fn ends(&self) -> ([f64; 2], [f64; 2]) {
        let s = &self.0.segments;
        (s[0].start(), s[s.len() - 1].end())
    }

    /// Whether a cylinder of the last radius continues above the last point.
    pub fn extends(&self) -> bool {
        self.0.extends
    }

    /// The same profile moved outward by `dr` (a flat end from the axis is kept joined to
    /// the axis; parts that would cross the axis are cut off).
    pub fn shifted_radially(&self, dr: f64) -> Result<Meridian, ProfileError> {
        let mut segs: Vec<Segment> = Vec::new();
        let (start, _) = self.ends();
        if dr > 0.0 && start[0] <= 1e-12 {
            segs.push(Segment::Line {
                a: [0.0, start[1]],
                b: [dr, start[1]],
            });
        }
        segs.extend(
            self.0
                .segments
                .iter()
                .filter_map(|s| s.shifted(dr, 0.0).clip_axis()),
        );
        Meridian::new(segs, self.0.family.clone())
    }

    /// The meridian polyline up to `end_height + side_mm` (with the shank's cylinder when the
    /// profile ends below), arcs within chord error `tol`, lines in pieces ≤ 0.05 mm.
    pub fn polyline(&self, tol: f64, side_mm: f64) -> Vec<[f64; 2]> {
        let z_lim = self.0.end_height + side_mm.max(0.0);
        let mut raw = vec![self.0.segments[0].start()];
        for s in &self.0.segments {
            s.sample(tol, 0.05, &mut raw);
        }
        let mut out: Vec<[f64; 2]> = Vec::with_capacity(raw.len());
        for p in raw {
            if p[1] > z_lim + 1e-12 {
                if let Some(q) = out.last().copied()
                    && q[1] < z_lim
                    && p[1] > q[1]
                {
                    let f = (z_lim - q[1]) / (p[1] - q[1]);
                    out.push([q[0] + (p[0] - q[0]) * f, z_lim]);
                }
                return out;
            }
            out.push(p);
        }
        if self.0.extends {
            let last = *out.last().expect("not empty");
            let ext = z_lim - last[1];
            if ext > 1e-9 {
                let n = (ext / 0.05).ceil().clamp(1.0, 200.0) as usize;
                for i in 1..=n {
                    out.push([last[0], last[1] + ext * i as f64 / n as f64]);
                }
            }
        }
        out
    }

    /// Lowest height of the body at radius `r` (`None` where the profile has no point).
    pub fn height_at(&self, r: f64) -> Option<f64> {
        let mut zs = Vec::new();
        for s in &self.0.segments {
            s.heights_at(r, &mut zs);
        }
        zs.into_iter().reduce(f64::min)
    }

    /// The outermost radius at height `z` (the last radius above the profile, the radius
    /// of the lowest point below it).
    pub fn radius_at(&self, z: f64) -> f64 {
        let (_, end) = self.ends();
        if z >= self.0.z_end {
            return end[0];
        }
        let mut rs = Vec::new();
        for s in &self.0.segments {
            s.radii_at(z.max(0.0), &mut rs);
        }
        rs.into_iter().reduce(f64::max).unwrap_or(end[0])
    }

    /// The point (r, z) of the profile farthest along the direction (m_r, m_z), m_r ≥ 0
    /// (the cutter's point whose outward normal is that direction when it is convex).
    pub fn support(&self, m_r: f64, m_z: f64) -> [f64; 2] {
        let mut best = ([0.0, 0.0], f64::NEG_INFINITY);
        for s in &self.0.segments {
            let (p, v) = s.support([m_r, m_z]);
            if v > best.1 + 1e-15 {
                best = (p, v);
            }
        }
        best.0
    }
}

// ---------------------------------------------------------------------------------------
// The feed-direction section.

/// The lower boundary of the section of the body by the plane through its axis and the
/// feed direction, with the axis leaning by the lead β into the feed (u along the feed, v
/// along the surface normal), relative to its lowest point.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    segs: Vec<Segment>,
    low: [f64; 2],
}

impl Section {
    /// The section of `m` at lead `lead_rad`.
    pub fn new(m: &Meridian, lead_rad: f64) -> Section {
        let (sb, cb) = lead_rad.sin_cos();
        let rot = |p: [f64; 2]| [p[0] * cb + p[1] * sb, -p[0] * sb + p[1] * cb];
        let mut base: Vec<Segment> = m.segments().to_vec();
        let (_, end) = m.ends();
        if m.extends() {
            base.push(Segment::Line {
                a: end,
                b: [end[0], end[1] + 4.0 * m.r_max() + 10.0],
            });
        }
        let mut segs = Vec::with_capacity(2 * base.len());
        for mirror in [false, true] {
            for s in &base {
                let s = match *s {
                    Segment::Line { a, b } => {
                        let f = |p: [f64; 2]| if mirror { [-p[0], p[1]] } else { p };
                        Segment::Line {
                            a: rot(f(a)),
                            b: rot(f(b)),
                        }
                    }
                    Segment::Arc {
                        centre,
                        radius,
                        t0,
                        t1,
                    } => {
                        let c = if mirror {
                            [-centre[0], centre[1]]
                        } else {
                            centre
                        };
                        let (t0, t1) = if mirror { (-t0, -t1) } else { (t0, t1) };
                        Segment::Arc {
                            centre: rot(c),
                            radius,
                            t0: t0 - lead_rad,
                            t1: t1 - lead_rad,
                        }
                    }
                };
                segs.push(s);
            }
        }
        // Lowest point: the frontmost of the lowest.
        let mut low = [f64::NEG_INFINITY, f64::INFINITY];
        for s in &segs {
            let (p, v) = s.support([0.0, -1.0]);
            let z = -v;
            if z < low[1] - 1e-12 || (z <= low[1] + 1e-12 && p[0] > low[0]) {
                low = [p[0], z.min(low[1])];
            }
        }
        Section { segs, low }
    }

    /// Height above the lowest point at feed position `u` from it, mm (+∞ where the tool
    /// does not reach).
    pub fn height(&self, u: f64) -> f64 {
        let x = u + self.low[0];
        let mut zs = Vec::new();
        for s in &self.segs {
            s.heights_at(x, &mut zs);
        }
        zs.into_iter()
            .reduce(f64::min)
            .map_or(f64::INFINITY, |z| (z - self.low[1]).max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn classic_profiles() {
        let b = classic(5.0, 5.0).unwrap();
        assert_relative_eq!(b.r_max(), 5.0);
        assert!(b.is_convex());
        assert_relative_eq!(b.height_at(3.0).unwrap(), 1.0, epsilon = 1e-12);
        assert_relative_eq!(b.radius_at(1.0), 3.0, epsilon = 1e-12);
        let t = classic(5.0, 1.5).unwrap();
        assert_relative_eq!(t.height_at(2.0).unwrap(), 0.0);
        assert_relative_eq!(t.end_height(), 1.5);
        let p = t.support(30f64.to_radians().sin(), -30f64.to_radians().cos());
        assert_relative_eq!(
            p[1],
            1.5 * (1.0 - 30f64.to_radians().cos()),
            epsilon = 1e-12
        );
        let pl = t.polyline(1e-4, 0.5);
        assert_relative_eq!(pl.last().unwrap()[1], 2.0, epsilon = 1e-12);
        assert_relative_eq!(pl.last().unwrap()[0], 5.0, epsilon = 1e-12);
    }

    #[test]
    fn round_insert_has_both_flanks() {
        let m = round_insert(10.0, 3.0).unwrap();
        let (s, e) = m.ends();
        assert_relative_eq!(s[0], 4.0, epsilon = 1e-12);
        assert_relative_eq!(s[1], 3.0, epsilon = 1e-12);
        assert_relative_eq!(e[0], 10.0, epsilon = 1e-12);
        assert_relative_eq!(m.height_at(7.0).unwrap(), 0.0, epsilon = 1e-12);
        assert_relative_eq!(m.height_at(5.5).unwrap(), 3.0 - (9.0f64 - 2.25).sqrt());
        assert!(m.height_at(3.0).is_none());
        assert_relative_eq!(m.r_min(), 4.0, epsilon = 1e-12);
        assert!(m.is_convex());
        // Insert larger than the ring: cut at the axis.
        let m = round_insert(5.0, 4.0).unwrap();
        assert_relative_eq!(m.ends().0[0], 0.0, epsilon = 1e-12);
    }

    #[test]
    fn apt_matches_the_classic_shapes() {
        let (b, w) = apt([10.0, 5.0, 0.0, 5.0, 0.0, 0.0, 50.0]).unwrap();
        assert!(w.is_none());
        assert_relative_eq!(b.height_at(3.0).unwrap(), 1.0, epsilon = 1e-12);
        let (t, w) = apt([10.0, 1.0, 4.0, 1.0, 0.0, 0.0, 50.0]).unwrap();
        assert!(w.is_none());
        assert_relative_eq!(t.height_at(2.0).unwrap(), 0.0);
        assert_relative_eq!(t.radius_at(1.0), 5.0, epsilon = 1e-12);
        // Lazy e = f = 0: the two-parameter form.
        let (t2, _) = apt([10.0, 1.0, 0.0, 0.0, 0.0, 0.0, 50.0]).unwrap();
        assert_relative_eq!(t2.height_at(4.5).unwrap(), t.height_at(4.5).unwrap());
        // Cone: a V tip of 60° per side ending at d/2.
        let a = 30.0f64;
        let (c, w) = apt([10.0, 0.0, 5.0, 5.0 * a.to_radians().tan(), a, 0.0, 20.0]).unwrap();
        assert!(w.is_none(), "{w:?}");
        assert_relative_eq!(
            c.height_at(2.0).unwrap(),
            2.0 * a.to_radians().tan(),
            epsilon = 1e-12
        );
        // Taper with a corner: the side widens upward.
        let (tp, _) = apt([10.0, 1.0, 4.0, 1.0, 0.0, 5.0, 20.0]).unwrap();
        assert!(tp.r_max() > 5.0);
        assert!(tp.is_convex());
        // Inconsistent tip.
        assert!(apt([10.0, 1.0, 4.0, 3.0, 0.0, 0.0, 20.0]).is_err());
    }

    #[test]
    fn polyline_arcs() {
        // A ball as an arc list.
        let m = polyline(&[[0.0, 0.0, 0.0], [5.0, 5.0, 5.0], [5.0, 8.0, 0.0]]).unwrap();
        assert_relative_eq!(m.height_at(3.0).unwrap(), 1.0, epsilon = 1e-12);
        assert!(m.is_convex());
        // A concave chamfer is not convex.
        let m = polyline(&[
            [0.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [5.0, 2.0, -3.0],
            [5.0, 4.0, 0.0],
        ])
        .unwrap();
        assert!(!m.is_convex());
        assert!(polyline(&[[0.0, 1.0, 0.0], [2.0, 1.0, 0.0]]).is_err());
    }

    #[test]
    fn families_join_tangentially() {
        let b = barrel(8.0, 250.0, 10.0, 1.0).unwrap();
        assert_relative_eq!(b.r_max(), 8.0, epsilon = 1e-9);
        assert!(b.is_convex());
        assert!(!b.extends());
        let l = lens(5.0, 50.0, 1.0).unwrap();
        assert_relative_eq!(l.r_max(), 5.0, epsilon = 1e-9);
        assert!(l.is_convex() && l.extends());
        let o = oval(5.0, 20.0, 2.0).unwrap();
        assert_relative_eq!(o.r_max(), 5.0, epsilon = 1e-9);
        assert!(o.is_convex());
        let t = taper_barrel(3.0, 250.0, 1.0, 10.0).unwrap();
        assert_relative_eq!(t.ends().1[0], 3.0, epsilon = 1e-9);
        assert!(taper_barrel(5.0, 100.0, 1.0, 10.0).is_err());
        assert!(t.is_convex());
        for m in [&b, &l, &o, &t] {
            for w in m.segments().windows(2) {
                let turn = w[1].tangent_angle(false) - w[0].tangent_angle(true);
                assert!(turn.abs() < 1e-9, "{:?}: kink {turn}", m.family());
            }
        }
    }

    #[test]
    fn section_of_a_ball_is_its_circle() {
        let m = classic(5.0, 5.0).unwrap();
        let s = Section::new(&m, 0.3);
        for u in [-2.0, -0.5, 0.0, 0.4, 1.7] {
            let want = 5.0 - (25.0f64 - u * u).sqrt();
            assert_relative_eq!(s.height(u), want, epsilon = 1e-12);
        }
    }
}
