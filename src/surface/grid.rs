//! Grid frames and the nominal surface.
//!
//! Every simulation runs in a grid frame (origin O, axes u, v, w): nodes sit on the plane
//! w = 0 at `O + i du u + j dv v`, and each node carries a line along w (a "dexel").
//! * A **window** is the WCS xy plane: u = x, v = y, w = z (a z-map, 002 §2.5).
//! * A **patch** is the tangent plane at a contact point of the path: u = f, v = g = n × f,
//!   w = n (the N-buffer "hedgehog" of 001 Fig 1).
//!
//! The nominal surface near the grid is rebuilt from the contact (CC) points and normals
//! of the samples: the points are thinned on a spatial hash, indexed with a kiddo k-d tree,
//! and at every node of a coarse grid a weighted local quadric w = q(u, v) is fitted to the
//! nearest points and to the slopes their normals give. Heights are then bilinear in the
//! coarse grid, which is far below the chord tolerance for any smooth surface.

use super::SurfaceError;
use crate::math::{Point3, Vec3, ceil_fast, floor_fast};
use crate::resample::Sample;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{SMatrix, SVector};
use std::collections::HashSet;

/// An orthonormal grid frame: nodes on the plane through `origin` spanned by `u`, `v`;
/// heights along `w`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridFrame {
    /// Origin (the node at u = v = 0 is `origin + x0 u + y0 v`, see [`super::HeightMap`]).
    pub origin: Point3,
    /// First grid axis (columns).
    pub u: Vec3,
    /// Second grid axis (rows).
    pub v: Vec3,
    /// Height axis, `u × v`.
    pub w: Vec3,
}

impl GridFrame {
    /// The WCS frame: u = x, v = y, w = z.
    pub fn wcs() -> GridFrame {
        GridFrame {
            origin: Point3::origin(),
            u: Vec3::x(),
            v: Vec3::y(),
            w: Vec3::z(),
        }
    }

    /// Coordinates (u, v, w) of a WCS point.
    pub fn local(&self, p: &Point3) -> Vec3 {
        let d = p - self.origin;
        Vec3::new(self.u.dot(&d), self.v.dot(&d), self.w.dot(&d))
    }

    /// Coordinates of a WCS direction.
    pub fn local_dir(&self, d: &Vec3) -> Vec3 {
        Vec3::new(self.u.dot(d), self.v.dot(d), self.w.dot(d))
    }
}

/// The nominal surface over a grid: a local quadric w = q(u, v) fitted at every node of a
/// coarse lattice (every `stride` nodes); between lattice nodes the four surrounding
/// quadrics are evaluated and blended bilinearly, which is exact for quadrics and
/// third-order accurate otherwise.
#[derive(Debug, Clone)]
pub(crate) struct Nominal {
    /// Coarse lattice size.
    cnx: usize,
    cny: usize,
    /// Nodes per coarse cell.
    stride: usize,
    /// Node spacing, mm.
    d: f64,
    /// Quadric coefficients [a, b, c, d, e, f] of w = a + b x + c y + d x² + e x y + f y²
    /// about each lattice node (x, y in mm), row-major.
    quad: Vec<[f64; 6]>,
    /// An upper bound of q over the whole grid, mm.
    pub q_max: f64,
    /// Per lattice node, an upper bound of q over the coarse cells around it, mm.
    bounds: Vec<f64>,
    /// Per lattice node (i, j), the largest of `bounds` over nodes i-1..=i+2, j-1..=j+2
    /// (clamped): what [`Nominal::cell_bound`] returns, computed once (it is asked for
    /// every edge point of every tooth at every sub-step: a third of a part map's time when
    /// it scanned the 16 nodes each time).
    near: Vec<f64>,
}

impl Nominal {
    /// A flat nominal surface w = `level` (no contact data).
    pub fn flat(nx: usize, ny: usize, stride: usize, d: f64, level: f64) -> Nominal {
        let cnx = (nx.saturating_sub(1)).div_ceil(stride) + 1;
        let cny = (ny.saturating_sub(1)).div_ceil(stride) + 1;
        Nominal {
            cnx,
            cny,
            stride,
            d,
            quad: vec![[level, 0.0, 0.0, 0.0, 0.0, 0.0]; cnx * cny],
            q_max: level,
            bounds: vec![level; cnx * cny],
            near: vec![level; cnx * cny],
        }
    }

    /// The 4 × 4 neighbourhood maxima of `bounds` (see `near`): a running maximum along the
    /// rows, then along the columns. `max` is exact, so the values are those of the scan.
    fn dilate(&mut self) {
        let (cnx, cny) = (self.cnx, self.cny);
        let window = |n: usize, k: usize| k.saturating_sub(1)..=(k + 2).min(n - 1);
        let mut rows = vec![f64::NEG_INFINITY; cnx * cny];
        for j in 0..cny {
            for i in 0..cnx {
                rows[j * cnx + i] = window(cnx, i)
                    .map(|ii| self.bounds[j * cnx + ii])
                    .fold(f64::NEG_INFINITY, f64::max);
            }
        }
        for j in 0..cny {
            for i in 0..cnx {
                self.near[j * cnx + i] = window(cny, j)
                    .map(|jj| rows[jj * cnx + i])
                    .fold(f64::NEG_INFINITY, f64::max);
            }
        }
    }

    /// Fit the nominal surface from contact points and normals given in grid coordinates.
    /// Node (i, j) is at (u, v) = (`x0` + i `d`, `y0` + j `d`).
    #[allow(clippy::too_many_arguments)]
    pub fn fit(
        nx: usize,
        ny: usize,
        stride: usize,
        x0: f64,
        y0: f64,
        d: f64,
        contacts: &[(Vec3, Vec3)],
    ) -> Option<Nominal> {
        if contacts.is_empty() {
            return None;
        }
        // kiddo's trees cannot split many points that share a coordinate (a pass along x
        // has one y for all its points): index them with a tiny deterministic jitter
        // (≤ 1 nm); the fit itself uses the exact points.
        let jitter = |i: usize, salt: u64| {
            let h = (i as u64 ^ salt).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
            (h as f64 / (1u64 << 24) as f64 - 0.5) * 2e-6
        };
        let pts: Vec<[f64; 2]> = contacts
            .iter()
            .enumerate()
            .map(|(i, (p, _))| [p.x + jitter(i, 0x51), p.y + jitter(i, 0xA7)])
            .collect();
        let tree: ImmutableKdTree<f64, 2> = ImmutableKdTree::new_from_slice(&pts);
        let mut nominal = Nominal::flat(nx, ny, stride, d, 0.0);
        let k = contacts.len().min(24);
        let h = stride as f64 * d;
        let mut q_max = f64::NEG_INFINITY;
        for cj in 0..nominal.cny {
            for ci in 0..nominal.cnx {
                let u = x0 + (ci * stride) as f64 * d;
                let v = y0 + (cj * stride) as f64 * d;
                let near = tree.nearest_n::<SquaredEuclidean>(&[u, v], k);
                let c = fit_quadric(u, v, &near, contacts);
                let bound = c[0]
                    + (c[1].abs() + c[2].abs()) * h
                    + (c[3].abs() + c[4].abs() + c[5].abs()) * h * h;
                q_max = q_max.max(bound);
                nominal.quad[cj * nominal.cnx + ci] = c;
                nominal.bounds[cj * nominal.cnx + ci] = bound;
            }
        }
        nominal.q_max = q_max;
        nominal.dilate();
        Some(nominal)
    }

    /// An upper bound of q over the fine nodes within `radius` nodes of (x, y) (node
    /// coordinates, possibly outside the grid).
    pub fn local_max(&self, x: f64, y: f64, radius: f64) -> f64 {
        let s = self.stride as f64;
        let lo = |v: f64, n: usize| (floor_fast((v - radius) / s).max(0.0) as usize).min(n - 1);
        let hi = |v: f64, n: usize| {
            let h = ceil_fast((v + radius) / s);
            if h < 0.0 { 0 } else { (h as usize).min(n - 1) }
        };
        let (i0, i1) = (lo(x, self.cnx), hi(x, self.cnx));
        let (j0, j1) = (lo(y, self.cny), hi(y, self.cny));
        if i0 == 0 && j0 == 0 && i1 + 1 == self.cnx && j1 + 1 == self.cny {
            return self.q_max;
        }
        let mut m = f64::NEG_INFINITY;
        for j in j0..=j1 {
            for i in i0..=i1 {
                m = m.max(self.bounds[j * self.cnx + i]);
            }
        }
        m
    }

    /// An upper bound of q over the coarse cell holding node-space point (x, y) and its
    /// neighbours (clamped to the grid): each lattice node's bound covers the cells around
    /// it, so a triangle with a vertex at (x, y) and any extent up to a cell is covered.
    pub fn cell_bound(&self, x: f64, y: f64) -> f64 {
        let s = self.stride as f64;
        let c = |v: f64, n: usize| (floor_fast(v / s).max(0.0) as usize).min(n - 1);
        let (i, j) = (c(x, self.cnx), c(y, self.cny));
        self.near[j * self.cnx + i]
    }

    /// Nominal height q (mm) and slope factor cos β = 1/√(1 + |∇q|²) at fine node (i, j).
    pub fn q_cos(&self, i: usize, j: usize) -> (f64, f64) {
        let (q, gu, gv) = self.q_grad(i, j);
        (q, 1.0 / (1.0 + gu * gu + gv * gv).sqrt())
    }

    /// Nominal height q (mm) and its gradient (∂q/∂u, ∂q/∂v) at fine node (i, j).
    pub fn q_grad(&self, i: usize, j: usize) -> (f64, f64, f64) {
        let ci = (i / self.stride).min(self.cnx - 1);
        let cj = (j / self.stride).min(self.cny - 1);
        let ci1 = (ci + 1).min(self.cnx - 1);
        let cj1 = (cj + 1).min(self.cny - 1);
        let fx = (i as f64 - (ci * self.stride) as f64) / self.stride as f64;
        let fy = (j as f64 - (cj * self.stride) as f64) / self.stride as f64;
        let mut q = 0.0;
        let mut gu = 0.0;
        let mut gv = 0.0;
        for (cx, cy, wgt) in [
            (ci, cj, (1.0 - fx) * (1.0 - fy)),
            (ci1, cj, fx * (1.0 - fy)),
            (ci, cj1, (1.0 - fx) * fy),
            (ci1, cj1, fx * fy),
        ] {
            if wgt == 0.0 {
                continue;
            }
            let c = &self.quad[cy * self.cnx + cx];
            let x = (i as f64 - (cx * self.stride) as f64) * self.d;
            let y = (j as f64 - (cy * self.stride) as f64) * self.d;
            q += wgt * (c[0] + c[1] * x + c[2] * y + c[3] * x * x + c[4] * x * y + c[5] * y * y);
            gu += wgt * (c[1] + 2.0 * c[3] * x + c[4] * y);
            gv += wgt * (c[2] + c[4] * x + 2.0 * c[5] * y);
        }
        (q, gu, gv)
    }
}

/// Weighted least-squares quadric w = a + b x + c y + d x² + e x y + f y² about (u, v)
/// through the given neighbours (positions and normal slopes). Returns q(u, v) and ∇q.
fn fit_quadric(
    u: f64,
    v: f64,
    near: &[kiddo::NearestNeighbour<f64, u64>],
    contacts: &[(Vec3, Vec3)],
) -> [f64; 6] {
    let scale2 = near
        .iter()
        .map(|n| n.distance)
        .fold(0.0f64, f64::max)
        .max(1e-6);
    let mut ata = SMatrix::<f64, 6, 6>::zeros();
    let mut atb = SVector::<f64, 6>::zeros();
    let mut add = |row: [f64; 6], rhs: f64, weight: f64| {
        let r = SVector::<f64, 6>::from(row);
        ata += r * r.transpose() * weight;
        atb += r * rhs * weight;
    };
    for n in near {
        let Some((p, nrm)) = usize::try_from(n.item).ok().and_then(|i| contacts.get(i)) else {
            continue;
        };
        let x = p.x - u;
        let y = p.y - v;
        let wt = (-n.distance / scale2).exp();
        add([1.0, x, y, x * x, x * y, y * y], p.z, wt);
        if nrm.z > 0.2 {
            // Slopes from the normal: ∂w/∂u = −n_u/n_w, ∂w/∂v = −n_v/n_w.
            let su = -nrm.x / nrm.z;
            let sv = -nrm.y / nrm.z;
            let lw = wt * scale2; // slopes carry a length scale, balance them with positions
            add([0.0, 1.0, 0.0, 2.0 * x, y, 0.0], su, lw);
            add([0.0, 0.0, 1.0, 0.0, x, 2.0 * y], sv, lw);
        }
    }
    // A small ridge on the curvature terms keeps under-determined directions flat.
    let ridge = 1e-6 * ata.trace().max(1e-12);
    for i in 3..6 {
        ata[(i, i)] += ridge;
    }
    for i in 0..3 {
        ata[(i, i)] += 1e-12 * ata.trace().max(1e-12);
    }
    match ata.cholesky() {
        Some(ch) => {
            let s = ch.solve(&atb);
            [s[0], s[1], s[2], s[3], s[4], s[5]]
        }
        None => {
            let z = near
                .first()
                .and_then(|n| usize::try_from(n.item).ok())
                .and_then(|i| contacts.get(i))
                .map_or(0.0, |(p, _)| p.z);
            [z, 0.0, 0.0, 0.0, 0.0, 0.0]
        }
    }
}

/// Contact points and normals of the samples in grid coordinates, thinned to one per
/// `cell` × `cell` × `cell` cube, keeping only points near the grid (within `reach` of
/// the plane w = 0 region's bounding box, given in (u, v)) whose normal faces +w.
pub(crate) fn grid_contacts(
    samples: &[Sample],
    frame: &GridFrame,
    uv_box: [f64; 4],
    reach: f64,
    cell: f64,
) -> Vec<(Vec3, Vec3)> {
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for s in samples {
        let (Some(c), Some(n)) = (s.contact, s.normal) else {
            continue;
        };
        let p = frame.local(&c);
        let nl = frame.local_dir(&n);
        if !(p.x >= uv_box[0] - reach
            && p.x <= uv_box[2] + reach
            && p.y >= uv_box[1] - reach
            && p.y <= uv_box[3] + reach
            && p.z.abs() <= reach
            && nl.z > 0.3)
        {
            continue;
        }
        let key = (
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            (p.z / cell).floor() as i64,
        );
        if seen.insert(key) {
            out.push((p, nl));
        }
    }
    out
}

impl GridFrame {
    /// The patch frame at the contact point of the sample nearest `s_mm`: origin C, u = f on
    /// the tangent plane, v = n × f, w = n.
    pub(crate) fn patch(samples: &[Sample], s_mm: f64) -> Result<GridFrame, SurfaceError> {
        let best = samples
            .iter()
            .filter(|s| s.contact.is_some() && s.normal.is_some())
            .min_by(|a, b| (a.s_mm - s_mm).abs().total_cmp(&(b.s_mm - s_mm).abs()))
            .ok_or(SurfaceError::NoContactData)?;
        let (Some(c), Some(n)) = (best.contact, best.normal) else {
            return Err(SurfaceError::NoContactData);
        };
        let w = crate::math::normalize_or_none(&n, 1e-12).ok_or(SurfaceError::NoContactData)?;
        let f = crate::math::Frame::tool(&w, &best.feed_dir);
        Ok(GridFrame {
            origin: c,
            u: f.x,
            v: f.y,
            w: f.z,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn collinear_contacts_fit_a_plane() {
        // One pass along u: every point has v = 0.
        let contacts: Vec<(Vec3, Vec3)> = (0..500)
            .map(|i| (Vec3::new(i as f64 * 0.01, 0.0, 0.3), Vec3::z()))
            .collect();
        let nominal = Nominal::fit(5, 5, 2, 0.0, 0.0, 0.1, &contacts).unwrap();
        assert_relative_eq!(nominal.q_cos(4, 4).0, 0.3, epsilon = 1e-7);
    }

    #[test]
    fn quadric_fit_recovers_a_sphere_cap() {
        // Points on a sphere of radius 50 mm with top at w = 1, normals outwards.
        let r = 50.0;
        let mut contacts = Vec::new();
        for i in -5..=5 {
            for j in -5..=5 {
                let (x, y) = (i as f64 * 0.2, j as f64 * 0.2);
                let z = 1.0 - r + (r * r - x * x - y * y).sqrt();
                let n = Vec3::new(x, y, z - (1.0 - r)).normalize();
                contacts.push((Vec3::new(x, y, z), n));
            }
        }
        let nominal = Nominal::fit(11, 11, 5, -0.5, -0.5, 0.1, &contacts).unwrap();
        // Node (0, 0) is at (-0.5, -0.5); node (2, 3) at (-0.3, -0.2), between lattice nodes.
        for (i, j) in [(0, 0), (2, 3)] {
            let (x, y) = (-0.5 + 0.1 * i as f64, -0.5 + 0.1 * j as f64);
            let exact = 1.0 - r + (r * r - x * x - y * y).sqrt();
            let (q, cos) = nominal.q_cos(i, j);
            assert_relative_eq!(q, exact, epsilon = 2e-6);
            let slope2 = (x * x + y * y) / (r * r - x * x - y * y);
            assert_relative_eq!(cos, 1.0 / (1.0 + slope2).sqrt(), epsilon = 1e-6);
        }
        assert!(nominal.q_max >= 1.0);
    }

    #[test]
    fn cell_bound_is_the_maximum_over_the_sixteen_lattice_nodes_around() {
        // Bounds that differ from node to node: a tilted, curved nominal on a 7 × 5 lattice.
        let contacts: Vec<(Vec3, Vec3)> = (0..400)
            .map(|k| {
                let (x, y) = ((k % 20) as f64 * 0.07, (k / 20) as f64 * 0.05);
                (Vec3::new(x, y, 0.1 * x - 0.2 * y + 0.05 * x * x), Vec3::z())
            })
            .collect();
        let n = Nominal::fit(25, 17, 4, 0.0, 0.0, 0.05, &contacts).unwrap();
        assert_eq!((n.cnx, n.cny), (7, 5));
        let scan = |x: f64, y: f64| {
            let s = n.stride as f64;
            let c = |v: f64, m: usize| ((v / s).floor().max(0.0) as usize).min(m - 1);
            let (i, j) = (c(x, n.cnx), c(y, n.cny));
            let mut m = f64::NEG_INFINITY;
            for jj in j.saturating_sub(1)..=(j + 2).min(n.cny - 1) {
                for ii in i.saturating_sub(1)..=(i + 2).min(n.cnx - 1) {
                    m = m.max(n.bounds[jj * n.cnx + ii]);
                }
            }
            m
        };
        let distinct: std::collections::BTreeSet<u64> =
            n.bounds.iter().map(|b| b.to_bits()).collect();
        assert!(distinct.len() > 20, "bounds must differ: {distinct:?}");
        for y in -6..=24 {
            for x in -6..=32 {
                let (x, y) = (x as f64 + 0.37, y as f64 - 0.21);
                assert_eq!(
                    n.cell_bound(x, y).to_bits(),
                    scan(x, y).to_bits(),
                    "at ({x}, {y})"
                );
            }
        }
    }
}
