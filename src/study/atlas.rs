//! One row of a roughness atlas (`crest atlas`, issue 33): a patch's place on the part and
//! its numbers (Sa, Sq, Sz, the scallop across the feed and the feed marks along it, their
//! closed forms, the local stepover and curvature, lead and tilt, warnings), and the
//! measures taken from a patch's height map and from the path at the patch, and the
//! patches run side by side ([`each_patch`]). Plain data otherwise:
//! `pipeline::atlas` places and simulates the patches, `io::atlas` writes the rows.

use crate::math::{Point3, Vec3};
use crate::surface::HeightMap;
use serde::{Deserialize, Serialize};

/// One patch of the atlas. Numbers are `None` where the patch produced none (it was
/// refused: `warnings` says why).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AtlasRow {
    /// Patch number, 1-based, in placement order (path, region, pass, along the pass).
    pub patch: usize,
    /// Tool path, 1-based.
    pub path: usize,
    /// Finishing region of the path, 1-based (as `crest inspect --regions` numbers them).
    pub region: usize,
    /// Pass (cutting run) of the path, 1-based.
    pub pass: usize,
    /// Arc length along the pass to the patch centre, mm.
    pub s_mm: f64,
    /// Patch centre on the cut surface, mm (the simulated patch's centre when it ran).
    pub point: [f64; 3],
    /// Unit surface normal there.
    pub normal: [f64; 3],
    /// Areal arithmetic mean height Sa, µm.
    pub sa_um: Option<f64>,
    /// Root-mean-square height Sq, µm.
    pub sq_um: Option<f64>,
    /// Maximum height Sz, µm.
    pub sz_um: Option<f64>,
    /// Scallop height across the feed: the median over the profiles across the feed of
    /// their peak-to-valley height, µm.
    pub scallop_um: Option<f64>,
    /// Feed-mark height along the feed: the peak-to-valley height of the profiles along the
    /// feed at the bottom of the pass (the rows of lowest mean), a line removed, µm.
    pub feed_mark_um: Option<f64>,
    /// Closed-form scallop of the local stepover with the corner radius, R − √(R² − s²/4), µm.
    pub scallop_closed_um: Option<f64>,
    /// Closed-form feed-mark height fz² / (8 R) with the corner radius, µm.
    pub feed_mark_closed_um: Option<f64>,
    /// Local stepover (distance to the neighbouring pass), mm.
    pub stepover_mm: Option<f64>,
    /// Normal curvature of the cut surface along the feed, 1/mm (positive: convex).
    pub curvature_along_per_mm: Option<f64>,
    /// Normal curvature across the feed, 1/mm (positive: convex).
    pub curvature_across_per_mm: Option<f64>,
    /// Lead: the tool axis leaning along the feed from the normal, degrees.
    pub lead_deg: Option<f64>,
    /// Tilt: the tool axis leaning across the feed (towards n × f), degrees.
    pub tilt_deg: Option<f64>,
    /// Nodes of the patch grid.
    pub nodes: usize,
    /// Nodes with a height.
    pub nodes_cut: usize,
    /// Why the patch has no numbers, or checks it failed (one sentence each).
    pub warnings: Vec<String>,
}

/// The numeric columns of an atlas, in order, with how to read them from a row (the
/// table's and the point cloud's columns after `patch … z`, normals and before `warnings`).
pub const NUMBER_COLUMNS: [&str; 14] = [
    "Sa_um",
    "Sq_um",
    "Sz_um",
    "scallop_um",
    "feed_mark_um",
    "scallop_closed_um",
    "feed_mark_closed_um",
    "stepover_mm",
    "curvature_along_per_mm",
    "curvature_across_per_mm",
    "lead_deg",
    "tilt_deg",
    "nodes",
    "nodes_cut",
];

impl AtlasRow {
    /// The values of [`NUMBER_COLUMNS`] (NaN where `None`).
    pub fn numbers(&self) -> [f64; 14] {
        let v = |o: Option<f64>| o.unwrap_or(f64::NAN);
        [
            v(self.sa_um),
            v(self.sq_um),
            v(self.sz_um),
            v(self.scallop_um),
            v(self.feed_mark_um),
            v(self.scallop_closed_um),
            v(self.feed_mark_closed_um),
            v(self.stepover_mm),
            v(self.curvature_along_per_mm),
            v(self.curvature_across_per_mm),
            v(self.lead_deg),
            v(self.tilt_deg),
            self.nodes as f64,
            self.nodes_cut as f64,
        ]
    }

    /// Whether the patch produced numbers.
    pub fn has_numbers(&self) -> bool {
        self.sa_um.is_some()
    }
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

/// Peak-to-valley of the finite values (at least 3).
fn peak_to_valley(v: impl Iterator<Item = f64>) -> Option<f64> {
    let (mut lo, mut hi, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0usize);
    for z in v.filter(|z| z.is_finite()) {
        lo = lo.min(z);
        hi = hi.max(z);
        n += 1;
    }
    (n >= 3).then_some(hi - lo)
}

/// Peak-to-valley of the finite values of a profile after removing its least-squares line.
fn detrended_peak_to_valley(v: &[f64]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = v
        .iter()
        .enumerate()
        .filter(|(_, z)| z.is_finite())
        .map(|(i, z)| (i as f64, *z))
        .collect();
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let mz = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxz: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - mz)).sum();
    let b = if sxx > 0.0 { sxz / sxx } else { 0.0 };
    peak_to_valley(pts.iter().map(|p| p.1 - mz - b * (p.0 - mx)))
}

/// `f` of every patch in `patches`, on the current rayon pool, in the order given (each
/// patch is independent of the others: the results do not depend on the thread count).
pub fn each_patch<T: Send>(patches: &[usize], f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    use rayon::prelude::*;
    patches.par_iter().with_max_len(1).map(|&i| f(i)).collect()
}

/// The scallop across the feed and the feed-mark height along it of a patch's height map
/// whose columns run along the feed (x) and rows across (y), µm:
/// - scallop: the median over columns of each column's peak-to-valley height (a patch at
///   least one stepover wide holds a whole scallop in every column);
/// - feed marks: the rows of lowest mean height (the bottom of a pass, where the tool's
///   feed marks are those of its tip or corner), the row of least mean and its two
///   neighbours, each with its least-squares line removed, the median of their
///   peak-to-valley heights.
pub fn scallop_and_feed_marks(map: &HeightMap) -> (Option<f64>, Option<f64>) {
    let (nx, ny) = (map.nx, map.ny);
    let z = |i: usize, j: usize| map.z_um[j * nx + i];
    let scallop = median(
        (0..nx)
            .filter_map(|i| peak_to_valley((0..ny).map(|j| z(i, j))))
            .collect(),
    );
    let mean_of = |j: usize| {
        let v: Vec<f64> = (0..nx).map(|i| z(i, j)).filter(|v| v.is_finite()).collect();
        (v.len() >= 3).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    let low = (0..ny)
        .filter_map(|j| mean_of(j).map(|m| (j, m)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(j, _)| j);
    let marks = low.and_then(|j| {
        median(
            (j.saturating_sub(1)..(j + 2).min(ny))
                .filter_map(|r| detrended_peak_to_valley(&map.z_um[r * nx..(r + 1) * nx]))
                .collect(),
        )
    });
    (scallop, marks)
}

/// Lead and tilt of tool axis `axis` at a point of normal `normal` with feed direction
/// `feed` (projected on the tangent plane), radians: lead = atan2(a·f, a·n), tilt =
/// atan2(a·g, a·n) with g = n × f (model.md §1.2: a lead β leans the axis into the feed).
pub fn lead_tilt(axis: &Vec3, normal: &Vec3, feed: &Vec3) -> Option<(f64, f64)> {
    let n = crate::math::normalize_or_none(normal, 1e-12)?;
    let f = crate::math::normalize_or_none(&(feed - n * feed.dot(&n)), 1e-12)?;
    let g = n.cross(&f);
    let an = axis.dot(&n);
    Some((axis.dot(&f).atan2(an), axis.dot(&g).atan2(an)))
}

/// Normal curvature of a surface between two of its points with their unit normals, 1/mm:
/// (n_b − n_a)·(p_b − p_a) / |p_b − p_a|² (exact on a sphere or a cylinder across its axis;
/// positive where the normals spread: convex).
pub fn curvature(pa: &Point3, na: &Vec3, pb: &Point3, nb: &Vec3) -> Option<f64> {
    let d = pb - pa;
    let l2 = d.norm_squared();
    (l2 > 1e-18).then(|| (nb - na).dot(&d) / l2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scallop_and_marks_of_a_made_map() {
        // Across (rows, y): a parabola of 10 µm peak-to-valley; along (x): a sawtooth of 1 µm
        // on every row, plus a slope along x that the feed-mark measure removes.
        let (nx, ny) = (40, 21);
        let mut map = HeightMap::new_nan(nx, ny, 1.0, 1.0);
        for j in 0..ny {
            for i in 0..nx {
                let y = (j as f64 - 10.0) / 10.0;
                map.z_um[j * nx + i] = 10.0 * y * y + (i % 4) as f64 / 3.0 + 0.01 * i as f64;
            }
        }
        let (s, m) = scallop_and_feed_marks(&map);
        let s = s.unwrap_or(f64::NAN);
        assert!((s - 10.0).abs() < 1e-9, "{s}");
        // The sawtooth's own least-squares line is not quite flat over ten teeth: its
        // removal leaves 1.10 µm peak-to-valley.
        let m = m.unwrap_or(f64::NAN);
        assert!((m - 1.0).abs() < 0.15, "{m}");
    }

    #[test]
    fn lead_tilt_and_curvature_closed_forms() {
        let (lead, tilt) = (10f64.to_radians(), 5f64.to_radians());
        let a = Vec3::new(lead.tan(), tilt.tan(), 1.0).normalize();
        let (l, t) = lead_tilt(&a, &Vec3::z(), &Vec3::x()).unwrap_or((0.0, 0.0));
        assert!((l - lead).abs() < 1e-12 && (t - tilt).abs() < 1e-12);
        // A sphere of radius 20: curvature 1/20 between any two points.
        let c = Point3::new(0.0, 0.0, -20.0);
        let p = |u: f64| Point3::new(20.0 * u.sin(), 0.0, -20.0 + 20.0 * u.cos());
        let n = |q: &Point3| (q - c).normalize();
        let (a, b) = (p(0.0), p(0.1));
        let k = curvature(&a, &n(&a), &b, &n(&b)).unwrap_or(0.0);
        assert!((k - 0.05).abs() < 1e-12, "{k}");
    }
}
