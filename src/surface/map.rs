//! Part maps: heights over a whole part (or a region of it) at a coarse spacing, as a point
//! cloud of part points with their normals and heights along them.
//!
//! The part is cut into cubic cells of a tile size; every cell that holds part surface gets a
//! patch on the tangent plane at the part point nearest the cell's centre (heights along the
//! part's normals, [`super::GridSpec::Oriented`] with [`super::Reference::Part`]), simulated
//! with only the samples whose tool reaches it; the patch nodes whose part point lies in the
//! cell are kept, so every part point is reported once.

use super::cull::Subset;
use super::{GridFrame, GridSpec, Options, Reference, SurfaceError, simulate_with};
use crate::math::{Frame, Point3, Vec3};
use crate::part::Part;
use crate::resample::Sample;
use crate::tool::Cutter;
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// One point of a part map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapPoint {
    /// The part point, mm.
    pub point: Point3,
    /// The part's unit normal there.
    pub normal: Vec3,
    /// Height along the normal above the design surface, µm (NaN = not reached).
    pub height_um: f64,
}

/// A finished part map.
#[derive(Debug, Clone)]
pub struct PartMap {
    /// The points, cell by cell (cells in x, then y, then z order), nodes row by row.
    pub points: Vec<MapPoint>,
    /// Cells that held part surface.
    pub tiles: usize,
    /// Points with a height.
    pub nodes_cut: usize,
    /// The cells simulated, in order: (index among the `tiles` cells, number of its points,
    /// which follow one another in `points`). Every cell, or one shard's.
    pub cells: Vec<(usize, usize)>,
}

/// Map `part` at `spacing_mm` with the model and depth of `opts` (its grid is ignored),
/// within `region` (lo, hi corners; the part's bounds when `None`), in cells of `tile_mm`.
/// `progress(done, total)` counts cells. With `shard = Some((k, n))` (1 ≤ k ≤ n) only cells
/// k, k+n, k+2n, … (1-based, in cell order) are simulated: a cell's points do not depend on
/// the other cells, so the shards' cells put back in order are the whole map's, bit for bit.
#[allow(clippy::too_many_arguments)]
pub fn map_part(
    samples: &[Sample],
    cutter: &Cutter,
    opts: &Options,
    part: &Part,
    spacing_mm: f64,
    tile_mm: f64,
    region: Option<(Point3, Point3)>,
    shard: Option<(usize, usize)>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<PartMap, SurfaceError> {
    if let Some((k, n)) = shard
        && (k == 0 || k > n)
    {
        return Err(SurfaceError::InvalidOption(format!(
            "shard {k}/{n} is not a shard K/N with 1 ≤ K ≤ N"
        )));
    }
    if !(spacing_mm.is_finite() && spacing_mm > 0.0 && tile_mm.is_finite() && tile_mm >= spacing_mm)
    {
        return Err(SurfaceError::InvalidOption(format!(
            "map spacing {spacing_mm} mm and tile {tile_mm} mm must be positive, the tile at least the spacing"
        )));
    }
    let (plo, phi) = part.bounds();
    let (lo, hi) = match region {
        Some((a, b)) => (
            Point3::new(a.x.max(plo.x), a.y.max(plo.y), a.z.max(plo.z)),
            Point3::new(b.x.min(phi.x), b.y.min(phi.y), b.z.min(phi.z)),
        ),
        None => (plo, phi),
    };
    if (0..3).any(|k| hi[k] < lo[k]) {
        return Err(SurfaceError::InvalidOption(
            "the region does not overlap the part".into(),
        ));
    }
    let n: Vec<usize> = (0..3)
        .map(|k| (((hi[k] - lo[k]) / tile_mm).ceil() as usize).max(1))
        .collect();
    let cells = n[0].saturating_mul(n[1]).saturating_mul(n[2]);
    if cells > 10_000_000 {
        return Err(SurfaceError::InvalidOption(format!(
            "the map needs {cells} cells of {tile_mm} mm; choose a larger tile or a region"
        )));
    }
    // Cells that hold part surface, and their patch centres.
    let mut centres: Vec<(Point3, Point3, crate::part::Closest)> = Vec::new();
    for kz in 0..n[2] {
        for ky in 0..n[1] {
            for kx in 0..n[0] {
                let c_lo = lo + Vec3::new(kx as f64, ky as f64, kz as f64) * tile_mm;
                // Cells end at the region's far side.
                let c_hi = Point3::new(
                    (c_lo.x + tile_mm).min(hi.x),
                    (c_lo.y + tile_mm).min(hi.y),
                    (c_lo.z + tile_mm).min(hi.z),
                );
                if !part.touches_box(&c_lo, &c_hi) {
                    continue;
                }
                let mid = nalgebra::center(&c_lo, &c_hi);
                let c = part.closest(&mid);
                centres.push((c_lo, c_hi, c));
            }
        }
    }
    // An index over the sample tips for culling per cell.
    let tips: Vec<[f64; 3]> = samples
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let j =
                ((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f64 / (1u64 << 24) as f64;
            [
                s.position.x + 1e-7 * j,
                s.position.y - 1e-7 * j,
                s.position.z + 0.5e-7 * j,
            ]
        })
        .collect();
    let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(&tips);
    let reach = cutter.radius_mm + opts.depth_mm + 1.0;
    let mut points = Vec::new();
    let mut nodes_cut = 0;
    let mut cells = Vec::new();
    let mine: Vec<usize> = (0..centres.len())
        .filter(|i| shard.is_none_or(|(k, n)| i % n + 1 == k))
        .collect();
    for (done, &cell) in mine.iter().enumerate() {
        let (c_lo, c_hi, c) = &centres[cell];
        let first = points.len();
        cells.push((cell, 0));
        // A patch large enough to hold the cell's surface seen along any normal.
        let diag = (c_hi - c_lo).norm();
        let side = diag + 2.0 * spacing_mm;
        let r = 0.5 * side * 2f64.sqrt() + reach;
        let mut idx: Vec<usize> = tree
            .within_unsorted::<SquaredEuclidean>(&[c.point.x, c.point.y, c.point.z], r * r)
            .iter()
            .map(|m| m.item as usize)
            .collect();
        idx.sort_unstable();
        progress(done + 1, mine.len());
        if idx.is_empty() {
            continue;
        }
        let mut subset = Subset::default();
        let mut next = 0;
        for (i, s) in samples
            .iter()
            .enumerate()
            .take(idx[idx.len() - 1] + 1)
            .skip(idx[0])
        {
            let keep = next < idx.len() && idx[next] == i;
            if keep {
                next += 1;
            }
            subset.push(s, keep);
        }
        let near = subset.samples;
        let feed = near
            .iter()
            .min_by(|a, b| {
                (a.position - c.point)
                    .norm()
                    .total_cmp(&(b.position - c.point).norm())
            })
            .map_or_else(Vec3::x, |s| s.feed_dir);
        let f = Frame::tool(&c.normal, &feed);
        let frame = GridFrame {
            origin: c.point,
            u: f.x,
            v: f.y,
            w: f.z,
        };
        let mut o = opts.clone();
        o.grid = GridSpec::Oriented {
            frame,
            length_mm: side,
            width_mm: side,
        };
        o.spacing_mm = spacing_mm;
        let sim = match simulate_with(&near, cutter, &o, Reference::Part(part), &|_, _| {}) {
            Ok(s) => s,
            Err(SurfaceError::NoPartSurface) => continue,
            Err(e) => return Err(e),
        };
        for j in 0..sim.map.ny {
            for i in 0..sim.map.nx {
                let (p, nrm) = sim.node_point(i, j);
                // Half-open cells, closed at the region's far side.
                let inside = (0..3).all(|k| {
                    p[k] >= c_lo[k] && (p[k] < c_hi[k] || (c_hi[k] >= hi[k] && p[k] <= hi[k]))
                });
                if !inside {
                    continue;
                }
                let h = sim.map.z_um[j * sim.map.nx + i];
                if h.is_finite() {
                    nodes_cut += 1;
                }
                points.push(MapPoint {
                    point: p,
                    normal: nrm,
                    height_um: h,
                });
            }
        }
        if let Some(last) = cells.last_mut() {
            last.1 = points.len() - first;
        }
    }
    Ok(PartMap {
        points,
        tiles: centres.len(),
        nodes_cut,
        cells,
    })
}
