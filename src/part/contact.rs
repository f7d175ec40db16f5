//! Contact data for centre-line paths: where the cutter touches the surface and the surface
//! normal there, either from the design surface ([`touch`]) or, with no part, from the path
//! itself ([`derive`]).
//!
//! The cutter body is the set of points within the tube radius of its *core*: the ball's
//! centre (radius R), the torus's corner-centre circle (radius rd = R − rc at height rc above
//! the tip, tube rc) or the flat end's bottom disk (tube 0).
//!
//! * **With a part.** The contact is the part point nearest the core (for a ball: nearest
//!   the centre); the clearance is that distance less the tube radius (negative = gouge).
//! * **Without a part.** At a contact with normal n the corner centre `O = CC + rc n` lies on
//!   the surface offset by rc, and `O = tip + rc a + rd w(n)` with `w` the unit radial of −n
//!   (model.md §7; for a ball rd = 0 and O is the centre). The offset points of the
//!   neighbouring postures (other passes included) are fitted with a local quadric, whose
//!   normal gives n; for a torus or flat end w depends on n, so this is iterated from n = a.
//!   Then `CC = O − rc n`. A round insert is a torus here (its insert circle is the
//!   corner). For a profile the contact itself is fitted: `CC = tip + z_s a + r_s w(n)`
//!   with (r_s, z_s) the meridian's point whose outward normal is −n (its support point).
//!
//! [`touch`] knows the cores of the ball, torus, flat end and round insert only; for a
//! profile [`touch_supported`] says no and the caller must not ask.

use super::Part;
use crate::math::{Point3, Vec3, normalize_or_none};
use crate::tool::Cutter;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{SMatrix, SVector};
use std::collections::HashMap;

/// Where a cutter touches the part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Touch {
    /// The part point the cutter is nearest to (the CC point when it touches), mm.
    pub cc: Point3,
    /// The part's unit normal there.
    pub normal: Vec3,
    /// Distance from the cutter body to the part, mm: positive = clearance (air), negative =
    /// penetration (gouge).
    pub clearance_mm: f64,
}

/// The unit radial direction of −n perpendicular to the axis `a` (towards the contact side
/// of the corner circle), or zero when n is along a.
fn radial(n: &Vec3, a: &Vec3) -> Vec3 {
    normalize_or_none(&(-(n - a * n.dot(a))), 1e-9).unwrap_or_else(Vec3::zeros)
}

/// Two unit vectors perpendicular to `a` and each other.
fn basis(a: &Vec3) -> (Vec3, Vec3) {
    let e1 = crate::math::any_perpendicular(a);
    (e1, a.cross(&e1))
}

/// Whether [`touch`] knows the cutter's core (every shape but a profile).
pub fn touch_supported(cutter: &Cutter) -> bool {
    !matches!(cutter.shape, crate::tool::Shape::Profile(_))
}

/// Where `cutter` at tip `tip`, unit axis `axis`, touches `part` (a profile is treated as
/// its corner radius about its end: see [`touch_supported`]).
pub fn touch(part: &Part, cutter: &Cutter, tip: &Point3, axis: &Vec3) -> Touch {
    let r = cutter.radius_mm;
    let rc = cutter.corner_radius_mm();
    let rd = r - rc;
    let centre = tip + axis * rc;
    let at = |p: &Point3| {
        let c = part.closest(p);
        (c.signed_distance - rc, c)
    };
    if rd <= 1e-12 {
        let (clear, c) = at(&centre);
        return Touch {
            cc: c.point,
            normal: c.normal,
            clearance_mm: clear,
        };
    }
    let (e1, e2) = basis(axis);
    // Core points: the corner-centre circle (and, for a flat end, rings of its disk).
    let point = |rho: f64, phi: f64| centre + (e1 * phi.cos() + e2 * phi.sin()) * rho;
    let rings: &[f64] = if rc <= 1e-12 {
        &[0.0, 0.25, 0.5, 0.75, 1.0]
    } else {
        &[1.0]
    };
    const N: usize = 72;
    let mut best = (f64::INFINITY, 1.0, 0.0);
    for &k in rings {
        let n = if k == 0.0 { 1 } else { N };
        for i in 0..n {
            let phi = std::f64::consts::TAU * i as f64 / N as f64;
            let (d, _) = at(&point(k * rd, phi));
            if d < best.0 {
                best = (d, k, phi);
            }
        }
    }
    // Refine the angle (golden section) on the best ring, then the radius for a flat end.
    let (_, k, phi) = best;
    let step = std::f64::consts::TAU / N as f64;
    let f = |phi: f64| at(&point(k * rd, phi)).0;
    let phi = golden(&f, phi - step, phi + step, 40);
    let rho = if rc <= 1e-12 {
        let g = |rho: f64| at(&point(rho, phi)).0;
        golden(&g, 0.0, rd, 40)
    } else {
        k * rd
    };
    let (clear, c) = at(&point(rho, phi));
    let (clear, c) = if clear <= best.0 {
        (clear, c)
    } else {
        at(&point(best.1 * rd, best.2))
    };
    Touch {
        cc: c.point,
        normal: c.normal,
        clearance_mm: clear,
    }
}

/// [`touch`] for every pose given (tip, unit axis), in parallel; the order is kept.
pub fn touch_all(
    part: &Part,
    cutter: &Cutter,
    poses: &[Option<(Point3, Vec3)>],
) -> Vec<Option<Touch>> {
    use rayon::prelude::*;
    poses
        .par_iter()
        .map(|p| p.map(|(tip, axis)| touch(part, cutter, &tip, &axis)))
        .collect()
}

/// Golden-section minimum of `f` on [a, b].
fn golden(f: &dyn Fn(f64) -> f64, mut a: f64, mut b: f64, iters: usize) -> f64 {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..iters {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    0.5 * (a + b)
}

/// Contact points and normals derived from the path alone (see the module docs): one per
/// pose (tip, unit axis), `None` where the neighbourhood does not span a surface (a lone
/// pass with no neighbour across it). `cell_mm` thins the offset points before fitting
/// (one per cell); neighbourhoods hold `NEIGHBOURS` points.
pub fn derive(
    cutter: &Cutter,
    poses: &[(Point3, Vec3)],
    cell_mm: f64,
) -> Vec<Option<(Point3, Vec3)>> {
    let meridian = match &cutter.shape {
        crate::tool::Shape::Profile(m) => Some(m),
        _ => None,
    };
    // A profile fits its contact points (offset 0); the others their offset surface.
    let rc = if meridian.is_some() {
        0.0
    } else {
        cutter.corner_radius_mm()
    };
    let rd = cutter.radius_mm - rc;
    let mut normals: Vec<Option<Vec3>> = poses.iter().map(|(_, a)| Some(*a)).collect();
    let iterations = if rd <= 1e-12 { 1 } else { 4 };
    let offset = |i: usize, n: &Vec3| {
        let (tip, a) = &poses[i];
        match meridian {
            Some(m) => {
                let w = radial(n, a);
                let m_a = -n.dot(a);
                let m_r = (-n - a * m_a).norm();
                let p = m.support(m_r, m_a);
                tip + a * p[1] + w * p[0]
            }
            None => tip + a * rc + radial(n, a) * rd,
        }
    };
    for _ in 0..iterations {
        let pts: Vec<Option<Point3>> = (0..poses.len())
            .map(|i| normals[i].map(|n| offset(i, &n)))
            .collect();
        let fitted = fit_normals(&pts, &normals, cell_mm);
        normals = fitted;
    }
    (0..poses.len())
        .map(|i| {
            let n = normals[i]?;
            let o = offset(i, &n);
            Some((o - n * rc, n))
        })
        .collect()
}

/// Points per neighbourhood in [`derive`].
pub const NEIGHBOURS: usize = 40;

/// Normals of the surface through `pts` at each point: a weighted quadric fitted in the
/// frame of the point's current normal estimate to its nearest thinned neighbours.
fn fit_normals(pts: &[Option<Point3>], guess: &[Option<Vec3>], cell: f64) -> Vec<Option<Vec3>> {
    // Thin: the first point in each cell (deterministic).
    let mut seen: HashMap<[i64; 3], usize> = HashMap::new();
    let mut reps: Vec<Point3> = Vec::new();
    for p in pts.iter().flatten() {
        let key = [p.x, p.y, p.z].map(|v| (v / cell).floor() as i64);
        seen.entry(key).or_insert_with(|| {
            reps.push(*p);
            reps.len() - 1
        });
    }
    if reps.len() < 6 {
        return vec![None; pts.len()];
    }
    // kiddo cannot split many equal coordinates: a tiny deterministic jitter (≤ 1 nm) for
    // the index only; the fit uses the exact points.
    let jitter = |i: usize, salt: u64| {
        let h = (i as u64 ^ salt).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
        (h as f64 / (1u64 << 24) as f64 - 0.5) * 2e-6
    };
    let coords: Vec<[f64; 3]> = reps
        .iter()
        .enumerate()
        .map(|(i, p)| {
            [
                p.x + jitter(i, 0x51),
                p.y + jitter(i, 0xA7),
                p.z + jitter(i, 0x3D),
            ]
        })
        .collect();
    let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(&coords);
    let k = NEIGHBOURS.min(reps.len());
    pts.iter()
        .zip(guess)
        .map(|(p, g)| {
            let (p, g) = (p.as_ref()?, g.as_ref()?);
            let near = tree.nearest_n::<SquaredEuclidean>(&[p.x, p.y, p.z], k);
            quadric_normal(p, g, near.iter().filter_map(|n| reps.get(n.item as usize)))
        })
        .collect()
}

/// The unit normal at `p` of the quadric `w = q(u, v)` fitted (weighted least squares) to
/// `near` in the frame whose w axis is `guess`; oriented like `guess`. `None` when the points
/// do not span a surface.
fn quadric_normal<'a>(
    p: &Point3,
    guess: &Vec3,
    near: impl Iterator<Item = &'a Point3>,
) -> Option<Vec3> {
    let w = normalize_or_none(guess, 1e-12)?;
    let (u, v) = basis(&w);
    let local: Vec<Vec3> = near
        .map(|q| {
            let d = q - p;
            Vec3::new(d.dot(&u), d.dot(&v), d.dot(&w))
        })
        .collect();
    let scale2 = local
        .iter()
        .map(|d| d.x * d.x + d.y * d.y)
        .fold(0.0f64, f64::max)
        .max(1e-12);
    // The spread across the neighbourhood must be two-dimensional.
    let (mut sxx, mut sxy, mut syy, mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    let mut ata = SMatrix::<f64, 6, 6>::zeros();
    let mut atb = SVector::<f64, 6>::zeros();
    for d in &local {
        let wt = (-(d.x * d.x + d.y * d.y) / scale2).exp();
        let row = SVector::<f64, 6>::from([1.0, d.x, d.y, d.x * d.x, d.x * d.y, d.y * d.y]);
        ata += row * row.transpose() * wt;
        atb += row * d.z * wt;
        sw += wt;
        sx += wt * d.x;
        sy += wt * d.y;
        sxx += wt * d.x * d.x;
        sxy += wt * d.x * d.y;
        syy += wt * d.y * d.y;
    }
    let (mx, my) = (sx / sw, sy / sw);
    let (cxx, cxy, cyy) = (sxx / sw - mx * mx, sxy / sw - mx * my, syy / sw - my * my);
    let det = cxx * cyy - cxy * cxy;
    let tr = cxx + cyy;
    if tr.is_nan() || tr <= 0.0 {
        return None;
    }
    // Smaller principal spread under 2 % of the larger (in length): the points lie along a
    // single pass. The surface is then taken level across the pass: the normal is the
    // guess made perpendicular to the pass direction.
    if det < (0.02f64.powi(2)) * tr * tr * 0.25 {
        let half = 0.5 * (cxx - cyy);
        let lambda = 0.5 * (cxx + cyy) + (half * half + cxy * cxy).sqrt();
        let (tx, ty) = if cxy.abs() > 1e-300 {
            (cxy, lambda - cxx)
        } else if cxx >= cyy {
            (1.0, 0.0)
        } else {
            (0.0, 1.0)
        };
        // The pass direction in 3-D from a line fit of w against the along-pass coordinate.
        let len = (tx * tx + ty * ty).sqrt();
        let (tx, ty) = (tx / len, ty / len);
        let (mut sa, mut sb, mut saa) = (0.0, 0.0, 0.0);
        for d in &local {
            let a = d.x * tx + d.y * ty;
            sa += a;
            sb += d.z;
            saa += a * a;
        }
        let m = local.len() as f64;
        let slope = if saa * m - sa * sa > 1e-300 {
            let sab: f64 = local.iter().map(|d| (d.x * tx + d.y * ty) * d.z).sum();
            (m * sab - sa * sb) / (m * saa - sa * sa)
        } else {
            0.0
        };
        let t = (u * tx + v * ty + w * slope).normalize();
        return normalize_or_none(&(w - t * t.dot(&w)), 1e-9);
    }
    let ridge = 1e-6 * ata.trace().max(1e-12);
    for i in 3..6 {
        ata[(i, i)] += ridge;
    }
    let s = ata.cholesky()?.solve(&atb);
    let n = (w - u * s[1] - v * s[2]).normalize();
    Some(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::Shape;
    use approx::assert_relative_eq;

    /// Poses of a ball or torus over the cylinder of radius `rs` about x (convex, top at
    /// z = 0), axis along the normal (5-axis) or vertical (3-axis); passes along x every
    /// `ds` of arc, points every `dx`.
    fn cylinder_poses(
        cutter: &Cutter,
        rs: f64,
        five_axis: bool,
    ) -> Vec<(Point3, Vec3, Point3, Vec3)> {
        let mut out = Vec::new();
        for j in -6..=6 {
            let phi = j as f64 * 0.4 / rs;
            let n = Vec3::new(0.0, phi.sin(), phi.cos());
            let axis = if five_axis { n } else { Vec3::z() };
            for i in -20..=20 {
                let cc = Point3::new(i as f64 * 0.1, rs * phi.sin(), rs * phi.cos() - rs);
                let tip = crate::synth::tool_tip(cutter, &cc, &n, &axis);
                out.push((tip, axis, cc, n));
            }
        }
        out
    }

    #[test]
    fn derived_contacts_of_a_ball_on_a_cylinder_are_exact() {
        let c = Cutter::new(Shape::Ball, 5.0, 2, 0.0);
        for five in [true, false] {
            let poses = cylinder_poses(&c, 20.0, five);
            let tips: Vec<(Point3, Vec3)> = poses.iter().map(|p| (p.0, p.1)).collect();
            let got = derive(&c, &tips, 0.1);
            // A pose in the middle of the field (pass 0, x = 0).
            let mid = poses.len() / 2;
            let (cc, n) = got[mid].unwrap();
            assert!(
                (cc - poses[mid].2).norm() < 1e-4,
                "{cc:?} vs {:?}",
                poses[mid].2
            );
            assert!(n.angle(&poses[mid].3) < 1e-4);
            // Two passes off the middle.
            let k = mid - 2 * 41;
            let (cc, n) = got[k].unwrap();
            assert!((cc - poses[k].2).norm() < 1e-4);
            assert!(n.angle(&poses[k].3) < 1e-4);
        }
    }

    #[test]
    fn derived_contacts_of_a_torus_converge() {
        let c = Cutter::new(
            Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            2,
            0.0,
        );
        let poses = cylinder_poses(&c, 20.0, false);
        let tips: Vec<(Point3, Vec3)> = poses.iter().map(|p| (p.0, p.1)).collect();
        let got = derive(&c, &tips, 0.1);
        let k = poses.len() / 2 - 41;
        let (cc, n) = got[k].unwrap();
        assert!(
            (cc - poses[k].2).norm() < 1e-3,
            "{cc:?} vs {:?}",
            poses[k].2
        );
        assert!(n.angle(&poses[k].3) < 1e-3);
    }

    #[test]
    fn a_lone_pass_is_taken_level_across() {
        // One pass climbing at 10° along x: the normal is perpendicular to the pass, level
        // across it.
        let c = Cutter::new(Shape::Ball, 5.0, 2, 0.0);
        let slope = 10f64.to_radians();
        let n = Vec3::new(-slope.sin(), 0.0, slope.cos());
        let tips: Vec<(Point3, Vec3)> = (0..100)
            .map(|i| {
                let cc = Point3::new(
                    i as f64 * 0.05 * slope.cos(),
                    0.0,
                    i as f64 * 0.05 * slope.sin(),
                );
                (crate::synth::tool_tip(&c, &cc, &n, &Vec3::z()), Vec3::z())
            })
            .collect();
        let got = derive(&c, &tips, 0.1);
        let (cc, nn) = got[50].unwrap();
        assert!(nn.angle(&n) < 1e-9, "{nn:?}");
        assert!((cc - Point3::new(2.5 * slope.cos(), 0.0, 2.5 * slope.sin())).norm() < 1e-9);
    }

    #[test]
    fn touch_finds_the_contact_and_the_gouge() {
        let part = Part::new(super::super::tests::half_cylinder(20.0, 5.0, 2000)).unwrap();
        let ball = Cutter::new(Shape::Ball, 5.0, 2, 0.0);
        // Convex cylinder of radius 20 about x (top at z = 20); 3-axis ball 2 µm deep.
        let phi = 0.3f64;
        let n = Vec3::new(0.0, -phi.cos(), phi.sin());
        let cc = Point3::new(0.0, -20.0 * phi.cos(), 20.0 * phi.sin());
        let tip = crate::synth::tool_tip(&ball, &cc, &n, &Vec3::z()) - n * 0.002;
        let t = touch(&part, &ball, &tip, &Vec3::z());
        assert_relative_eq!(t.clearance_mm, -0.002, epsilon = 1e-5);
        assert!((t.cc - cc).norm() < 1e-4, "{:?}", t.cc);
        let torus = Cutter::new(
            Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            2,
            0.0,
        );
        let tip = crate::synth::tool_tip(&torus, &cc, &n, &Vec3::z());
        let t = touch(&part, &torus, &tip, &Vec3::z());
        assert!(t.clearance_mm.abs() < 1e-5, "{}", t.clearance_mm);
        assert!((t.cc - cc).norm() < 1e-3, "{:?}", t.cc);
        assert!(t.normal.angle(&n) < 1e-3);
    }
}
