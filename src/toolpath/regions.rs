//! Finishing regions of a tool path: maximal groups of consecutive cut passes (a pass is
//! a cutting run, [`Toolpath::cutting_runs`]) that lie side by side, with their extents,
//! stepover, tool-axis range, feeds, cutting length and a centre point on the cut.
//!
//! Points are the contact points where the path has contact data, else the CL points
//! (tool tips). Pass k + 1 joins the region of pass k when, seen from points along it, the
//! median distance to one of the region's last three passes is at most the tool diameter
//! (10 mm without TLDATA): the passes lie side by side, or one continues the other.
//! The stepover of a region is the median, over points along its passes, of the distance
//! across the local feed to the nearest other pass of the region (passes k − 2 … k + 2),
//! or to the same pass farther than two tool diameters along it (a zigzag without lifts).

use super::{MotionKind, Toolpath};
use crate::math::{Point3, Vec3};

/// Points sampled along each pass for the stepover and the grouping.
const SAMPLES_PER_PASS: usize = 32;
/// Points sampled along a region of one pass.
const SAMPLES_ONE_PASS: usize = 256;

/// One finishing region.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// Passes (cutting runs).
    pub passes: usize,
    /// Lower corner of the points' bounding box, mm (the file's coordinates).
    pub min: Point3,
    /// Upper corner, mm.
    pub max: Point3,
    /// Median stepover across the feed, mm (`None` without a neighbouring pass).
    pub stepover_mm: Option<f64>,
    /// Smallest and largest angle of the tool axis to the path's mean cutting axis, rad.
    pub axis_rad: (f64, f64),
    /// Distinct programmed feeds of the cut moves, mm/min, in path order.
    pub feeds_mm_min: Vec<f64>,
    /// Length of the cut moves (arcs along the arc), mm.
    pub cut_length_mm: f64,
    /// A point on the cut: half-way along the full pass nearest the region's middle, mm.
    pub centre: Point3,
}

/// One pass as a polyline of points, with the cumulative length along it.
struct Pass {
    points: Vec<Point3>,
    s: Vec<f64>,
    range: std::ops::Range<usize>,
}

impl Pass {
    fn length(&self) -> f64 {
        self.s.last().copied().unwrap_or(0.0)
    }

    /// The point at arc length `t`.
    fn at(&self, t: f64) -> Point3 {
        let k = self
            .s
            .partition_point(|v| *v < t)
            .clamp(1, self.points.len().max(2) - 1);
        if self.points.len() < 2 {
            return self.points[0];
        }
        let (a, b) = (self.points[k - 1], self.points[k]);
        let l = self.s[k] - self.s[k - 1];
        let u = if l > 0.0 {
            ((t - self.s[k - 1]) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        a + (b - a) * u
    }

    /// `n` points evenly along the pass, with their arc lengths.
    fn samples(&self, n: usize) -> Vec<(Point3, f64)> {
        let len = self.length();
        (0..n)
            .map(|i| {
                let t = len * (i as f64 + 0.5) / n as f64;
                (self.at(t), t)
            })
            .collect()
    }
}

/// Distance from `q` to pass `p` across the feed, looking only at segments whose arc
/// length lies outside `skip`: `(distance across, distance, beside)` where `beside` = the
/// nearest point is inside a segment or at a vertex between two.
fn across(q: &Point3, p: &Pass, skip: Option<(f64, f64)>) -> Option<(f64, f64, bool)> {
    let mut best: Option<(f64, f64, bool)> = None; // (full distance, across, beside)
    for k in 1..p.points.len() {
        if let Some((lo, hi)) = skip
            && p.s[k] > lo
            && p.s[k - 1] < hi
        {
            continue;
        }
        let (a, b) = (p.points[k - 1], p.points[k]);
        let ab = b - a;
        let l2 = ab.norm_squared();
        if l2 <= 1e-18 {
            continue;
        }
        let u = (q - a).dot(&ab) / l2;
        let uc = u.clamp(0.0, 1.0);
        let d = q - (a + ab * uc);
        let full = d.norm();
        if best.is_none_or(|b| full < b.0) {
            let t: Vec3 = ab / l2.sqrt();
            let w = q - a;
            let perp = (w - t * w.dot(&t)).norm();
            let vertex = (u < 0.0 && k > 1) || (u > 1.0 && k + 1 < p.points.len());
            let beside = (0.0..=1.0).contains(&u) || vertex;
            best = Some((full, perp, beside));
        }
    }
    best.map(|(full, perp, beside)| (perp, full, beside))
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// The finishing regions of `path` (its cut moves, `MotionKind::Cut`), in path order.
pub fn regions(path: &Toolpath) -> Vec<Region> {
    regions_with_passes(path)
        .into_iter()
        .map(|(r, _)| r)
        .collect()
}

/// [`regions`], each with the indices of its passes among [`Toolpath::cutting_runs`]
/// (consecutive: a region is a range of passes).
pub fn regions_with_passes(path: &Toolpath) -> Vec<(Region, std::ops::Range<usize>)> {
    let ps = &path.postures;
    let point = |i: usize| ps[i].contact.as_ref().map_or(ps[i].position, |c| c.point);
    let passes: Vec<Pass> = path
        .cutting_runs()
        .into_iter()
        .map(|r| {
            let points: Vec<Point3> = r.clone().map(point).collect();
            let mut s = Vec::with_capacity(points.len());
            let mut acc = 0.0;
            for (k, q) in points.iter().enumerate() {
                if k > 0 {
                    acc += (q - points[k - 1]).norm();
                }
                s.push(acc);
            }
            Pass {
                points,
                s,
                range: r,
            }
        })
        .collect();
    if passes.is_empty() {
        return Vec::new();
    }
    let diameter = path
        .tool
        .as_ref()
        .map(|t| t.diameter_mm)
        .filter(|d| *d > 0.0)
        .unwrap_or(10.0);
    // Group consecutive passes that lie side by side.
    let mut groups: Vec<std::ops::Range<usize>> = Vec::new();
    let mut start = 0;
    for k in 1..passes.len() {
        // Against each of the last three passes of the region: a short piece between two
        // passes (a corner, a fragment) does not split the region.
        let samples = passes[k].samples(SAMPLES_PER_PASS);
        let joins = (k.saturating_sub(3).max(start)..k).any(|j| {
            let seen: Vec<f64> = samples
                .iter()
                .filter_map(|(q, _)| across(q, &passes[j], None).map(|a| a.1))
                .collect();
            median(seen).is_some_and(|d| d <= diameter)
        });
        if !joins {
            groups.push(start..k);
            start = k;
        }
    }
    groups.push(start..passes.len());
    // The path's mean cutting axis.
    let mean = ps
        .iter()
        .filter(|p| p.motion == MotionKind::Cut)
        .fold(Vec3::zeros(), |a, p| a + p.axis);
    let mean = crate::math::normalize_or_none(&mean, 1e-12).unwrap_or_else(Vec3::z);
    groups
        .into_iter()
        .map(|g| (region(path, &passes, g.clone(), diameter, &mean), g))
        .collect()
}

fn region(
    path: &Toolpath,
    passes: &[Pass],
    g: std::ops::Range<usize>,
    diameter: f64,
    mean: &Vec3,
) -> Region {
    let ps = &path.postures;
    let mut min = Point3::from(Vec3::repeat(f64::INFINITY));
    let mut max = Point3::from(Vec3::repeat(f64::NEG_INFINITY));
    let mut axis = (f64::INFINITY, 0.0f64);
    let mut feeds: Vec<f64> = Vec::new();
    let mut length = 0.0;
    for pass in &passes[g.clone()] {
        for q in &pass.points {
            min = min.inf(q);
            max = max.sup(q);
        }
        for i in pass.range.clone() {
            let p = &ps[i];
            let a = p.axis.dot(mean).clamp(-1.0, 1.0).acos();
            axis = (axis.0.min(a), axis.1.max(a));
            if i > pass.range.start && p.motion == MotionKind::Cut {
                let s = ps[i - 1].position;
                length += match &p.arc {
                    Some(arc) => arc.length_mm(&s, &p.position),
                    None => (p.position - s).norm(),
                };
                if let Some(f) = p.feed_mm_min
                    && !feeds.contains(&f)
                {
                    feeds.push(f);
                }
            }
        }
    }
    // Stepover: across the feed to the nearest other pass (or the same pass, far along).
    let one = g.len() == 1;
    let mut across_d = Vec::new();
    for k in g.clone() {
        let n = if one {
            SAMPLES_ONE_PASS
        } else {
            SAMPLES_PER_PASS
        };
        for (q, t) in passes[k].samples(n) {
            let mut best: Option<f64> = None;
            let lo = k.saturating_sub(2).max(g.start);
            let hi = (k + 3).min(g.end);
            for (j, pass) in passes.iter().enumerate().take(hi).skip(lo) {
                let skip = (j == k).then_some((t - 2.0 * diameter, t + 2.0 * diameter));
                if let Some((d, _, true)) = across(&q, pass, skip)
                    && d > 1e-9
                    && best.is_none_or(|b| d < b)
                {
                    best = Some(d);
                }
            }
            if let Some(b) = best {
                across_d.push(b);
            }
        }
    }
    // The centre: on the pass nearest the middle of the region among its full passes (at
    // least half the median length; a short piece in a corner is no centre).
    let lengths: Vec<f64> = passes[g.clone()].iter().map(Pass::length).collect();
    let full = 0.5 * median(lengths.clone()).unwrap_or(0.0);
    let middle = g.start + g.len() / 2;
    let mid = g
        .clone()
        .filter(|&k| passes[k].length() >= full)
        .min_by_key(|&k| k.abs_diff(middle))
        .map_or(&passes[middle], |k| &passes[k]);
    Region {
        passes: g.len(),
        min,
        max,
        stepover_mm: median(across_d).filter(|d| *d <= diameter),
        axis_rad: if axis.0.is_finite() { axis } else { (0.0, 0.0) },
        feeds_mm_min: feeds,
        cut_length_mm: length,
        centre: mid.at(0.5 * mid.length()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::toolpath::Posture;

    fn at(x: f64, y: f64, motion: MotionKind) -> Posture {
        Posture {
            position: Point3::new(x, y, 0.0),
            axis: Vec3::z(),
            motion,
            arc: None,
            contact: None,
            feed_mm_min: Some(1000.0),
            spindle_rpm: None,
            line: 0,
        }
    }

    #[test]
    fn parallel_passes_make_one_region_with_their_stepover() {
        use MotionKind::*;
        let mut ps = Vec::new();
        // Five passes 0.4 mm apart along x, then one far away.
        for k in 0..5 {
            let y = 0.4 * f64::from(k);
            ps.push(at(0.0, y, Approach));
            ps.push(at(10.0, y, Cut));
        }
        ps.push(at(100.0, 0.0, Rapid));
        ps.push(at(110.0, 0.0, Cut));
        let path = Toolpath {
            postures: ps,
            ..Default::default()
        };
        let r = regions(&path);
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].passes, 5);
        assert!((r[0].stepover_mm.unwrap_or(0.0) - 0.4).abs() < 1e-9);
        assert!((r[0].cut_length_mm - 50.0).abs() < 1e-9);
        assert_eq!(r[0].max, Point3::new(10.0, 1.6, 0.0));
        assert_eq!(r[0].centre, Point3::new(5.0, 0.8, 0.0));
        assert_eq!((r[1].passes, r[1].stepover_mm), (1, None));
    }
}
