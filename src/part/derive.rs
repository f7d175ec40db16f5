//! Contact points and normals derived from a centre-line path alone, with no part, and
//! checked against the cutter: a contact that the path itself contradicts is left out and
//! said why ([`Inconsistency`]).
//!
//! At a contact with normal n the corner centre `O = CC + rc n` lies on the surface offset
//! by rc, and `O = tip + rc a + rd w(n)` with `w` the unit radial of −n perpendicular to the
//! axis a (model.md §7; for a ball rd = 0 and O is the centre). The offset points of the
//! neighbouring postures (other passes included) are fitted with a local quadric, whose
//! normal gives n; for a torus or flat end w depends on n, so this is iterated from n = a
//! until the normals settle. Then `CC = O − rc n`. A round insert is a torus here (its
//! insert circle is the corner). For a profile the contact itself is fitted:
//! `CC = tip + z_s a + r_s w(n)` with (r_s, z_s) the meridian's point whose outward normal
//! is −n (its support point).
//!
//! Where the axis turns, three things keep the fit on the surface the cutter touched:
//! * moves longer than [`DENSE_MM`] get poses between their ends for the fit (the tip on
//!   the line, the axis and the normal interpolated), so a neighbourhood is a few passes
//!   across and not tens of millimetres along one;
//! * a neighbour whose axis differs from the posture's by more than [`AXIS_SPREAD_DEG`] is
//!   left out of its fit (a wall's passes do not define the floor beside it);
//! * the fit of each round starts from the normals of the last;
//! * where the normal is so nearly along the axis that the flat end lies on the surface
//!   (within [`FLAT_END_MM`] across it), the contact is the centre of the end, not a point
//!   of the corner circle picked by a few µrad of noise.
//!
//! A derived contact is then checked: its normal must face the tool (n·a > 0), it must not
//! lie inside a neighbouring posture's cutter by more than [`GOUGE_TOL_MM`] (the surface a
//! path finishes is touched by every pass and cut into by none), and its normal must have
//! settled (turned by less than [`UNSETTLED_DEG`] in the last round). A contact that fails
//! is left out and its [`Inconsistency`] given.

use crate::math::{Point3, Vec3, any_perpendicular, normalize_or_none};
use crate::tool::Cutter;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;
use std::collections::HashMap;

/// Points per neighbourhood.
pub const NEIGHBOURS: usize = 40;
/// Moves longer than this get poses between their ends for the fit, mm.
pub const DENSE_MM: f64 = 1.0;
/// A neighbour whose axis differs by more than this is left out of a posture's fit, degrees.
pub const AXIS_SPREAD_DEG: f64 = 45.0;
/// A derived contact inside a neighbouring posture's cutter by more than this is
/// inconsistent, mm (wrong contacts land millimetres inside; a path's own chord and
/// tolerance errors are a few hundredths).
pub const GOUGE_TOL_MM: f64 = 0.05;
/// A normal that still turned by more than this in the last round has not settled, degrees.
pub const UNSETTLED_DEG: f64 = 0.5;
/// Rounds of the fit for a torus, flat end or profile at most (a ball needs one).
const MAX_ROUNDS: usize = 16;

/// Why a derived contact was left out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Inconsistency {
    /// The fitted normal faces away from the tool.
    FacesAway,
    /// The contact lies inside a neighbouring posture's cutter: the path cuts it away.
    Gouged,
    /// The fit did not settle.
    Unsettled,
}

impl Inconsistency {
    /// What it means, for messages.
    pub fn describe(self) -> &'static str {
        match self {
            Inconsistency::FacesAway => "the fitted normal faces away from the tool",
            Inconsistency::Gouged => "a neighbouring posture's cutter would cut the point away",
            Inconsistency::Unsettled => "the fit of the offset surface did not settle",
        }
    }
}

/// A derived contact: the point and the unit normal, `None` where there is none.
pub type Contact = Option<(Point3, Vec3)>;

/// Contacts derived from a path.
#[derive(Debug, Clone, Default)]
pub struct Derived {
    /// Per pose: contact point and unit normal; `None` where the neighbourhood does not
    /// span a surface or the contact is inconsistent.
    pub contacts: Vec<Contact>,
    /// Per pose: why its contact was left out, when it was inconsistent.
    pub flags: Vec<Option<Inconsistency>>,
}

/// A pose of the fit: a posture, or a point of a long move between two postures.
#[derive(Debug, Clone, Copy)]
struct FitPose {
    tip: Point3,
    axis: Vec3,
    /// The postures it lies between and where (a posture is `(i, i, 0)`).
    between: (usize, usize, f64),
}

/// The unit radial direction of −n perpendicular to the axis `a` (towards the contact side
/// of the corner circle), or zero when n is along a.
pub fn radial(n: &Vec3, a: &Vec3) -> Vec3 {
    normalize_or_none(&(-(n - a * n.dot(a))), 1e-9).unwrap_or_else(Vec3::zeros)
}

/// Where the normal is so nearly along the axis that the whole flat end lies on the surface
/// (the heights across it differ by less than this), the contact is the centre of the end,
/// mm: the radial of a normal a few µrad off the axis would pick any point of the corner
/// circle, jumping across the cutter between neighbouring postures.
pub const FLAT_END_MM: f64 = 0.5e-3;

/// [`radial`], or zero where the end of radius `rd` lies flat on the surface (see
/// [`FLAT_END_MM`]).
fn flat_radial(n: &Vec3, a: &Vec3, rd: f64) -> Vec3 {
    if (n - a * n.dot(a)).norm() * rd < FLAT_END_MM {
        Vec3::zeros()
    } else {
        radial(n, a)
    }
}

/// Two unit vectors perpendicular to `a` and each other.
pub(super) fn basis(a: &Vec3) -> (Vec3, Vec3) {
    let e1 = any_perpendicular(a);
    (e1, a.cross(&e1))
}

/// Contact points and normals derived from the path alone (see the module docs): one per
/// pose (tip, axis). `joined[i]` says pose i follows pose i − 1 along one move (the line
/// between them is cut); `cell_mm` thins the offset points before fitting (one per cell).
pub fn derive(cutter: &Cutter, poses: &[(Point3, Vec3)], joined: &[bool], cell_mm: f64) -> Derived {
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
    let poses: Vec<(Point3, Vec3)> = poses
        .iter()
        .map(|(t, a)| (*t, normalize_or_none(a, 1e-12).unwrap_or_else(Vec3::z)))
        .collect();
    let (fit, at) = fit_poses(&poses, joined);
    let offset = |p: &FitPose, n: &Vec3| {
        let a = &p.axis;
        match meridian {
            Some(m) => {
                let w = radial(n, a);
                let m_a = -n.dot(a);
                let m_r = (-n - a * m_a).norm();
                let pt = m.support(m_r, m_a);
                p.tip + a * pt[1] + w * pt[0]
            }
            None => p.tip + a * rc + flat_radial(n, a, rd) * rd,
        }
    };
    let mut normals: Vec<Option<Vec3>> = poses.iter().map(|(_, a)| Some(*a)).collect();
    let rounds = if rd <= 1e-12 { 1 } else { MAX_ROUNDS };
    let mut turned = vec![0.0f64; poses.len()];
    let mut last_tree = None;
    let mut settled = rounds == 1;
    for _ in 0..rounds {
        let fit_normals = spread(&fit, &normals);
        let pts: Vec<Option<Point3>> = fit
            .iter()
            .zip(&fit_normals)
            .map(|(p, n)| n.map(|n| offset(p, &n)))
            .collect();
        let cloud = Cloud::new(&fit, &pts, cell_mm);
        let own: Vec<Option<Point3>> = (0..poses.len())
            .map(|i| normals[i].map(|n| offset(&fit[at[i]], &n)))
            .collect();
        let fitted: Vec<Option<Vec3>> = (0..poses.len())
            .into_par_iter()
            .map(|i| {
                let (p, g) = (own[i]?, normals[i]?);
                cloud.normal(&p, &g, &poses[i].1)
            })
            .collect();
        let mut most = 0.0f64;
        for i in 0..poses.len() {
            turned[i] = match (normals[i], fitted[i]) {
                (Some(a), Some(b)) => a.angle(&b),
                _ => 0.0,
            };
            most = most.max(turned[i]);
        }
        normals = fitted;
        last_tree = Some(cloud);
        if most < 1e-9 {
            settled = true;
            break;
        }
    }
    let mut out = Derived {
        contacts: vec![None; poses.len()],
        flags: vec![None; poses.len()],
    };
    let Some(cloud) = last_tree else {
        return out;
    };
    let checked: Vec<(Contact, Option<Inconsistency>)> = (0..poses.len())
        .into_par_iter()
        .map(|i| {
            let Some(n) = normals[i] else {
                return (None, None);
            };
            let (tip, a) = &poses[i];
            let o = offset(&fit[at[i]], &n);
            let cc = o - n * rc;
            if n.dot(a) <= 0.0 {
                return (None, Some(Inconsistency::FacesAway));
            }
            if meridian.is_none() && cloud.gouged(&cc, tip, cutter) {
                return (None, Some(Inconsistency::Gouged));
            }
            if !settled && turned[i] > UNSETTLED_DEG.to_radians() {
                return (None, Some(Inconsistency::Unsettled));
            }
            (Some((cc, n)), None)
        })
        .collect();
    for (i, (c, f)) in checked.into_iter().enumerate() {
        out.contacts[i] = c;
        out.flags[i] = f;
    }
    out
}

/// The postures and, on moves longer than [`DENSE_MM`], poses between them; and where each
/// posture is among them.
fn fit_poses(poses: &[(Point3, Vec3)], joined: &[bool]) -> (Vec<FitPose>, Vec<usize>) {
    let mut out = Vec::with_capacity(poses.len());
    let mut at = Vec::with_capacity(poses.len());
    for (i, (tip, axis)) in poses.iter().enumerate() {
        if i > 0 && joined.get(i).copied().unwrap_or(false) {
            let (t0, a0) = &poses[i - 1];
            let len = (tip - t0).norm();
            if len > DENSE_MM && len.is_finite() {
                let k = ((len / DENSE_MM).ceil() as usize).min(100_000);
                for s in 1..k {
                    let t = s as f64 / k as f64;
                    let axis =
                        normalize_or_none(&(a0 * (1.0 - t) + axis * t), 1e-9).unwrap_or(*axis);
                    out.push(FitPose {
                        tip: t0 + (tip - t0) * t,
                        axis,
                        between: (i - 1, i, t),
                    });
                }
            }
        }
        at.push(out.len());
        out.push(FitPose {
            tip: *tip,
            axis: *axis,
            between: (i, i, 0.0),
        });
    }
    (out, at)
}

/// The normals of the fit poses: a posture's own, a pose between two postures the
/// normalised blend of theirs.
fn spread(fit: &[FitPose], normals: &[Option<Vec3>]) -> Vec<Option<Vec3>> {
    fit.iter()
        .map(|p| {
            let (i, j, t) = p.between;
            if i == j {
                return normals[i];
            }
            let (a, b) = (normals[i]?, normals[j]?);
            normalize_or_none(&(a * (1.0 - t) + b * t), 1e-9)
        })
        .collect()
}

/// The thinned offset points of one round, indexed for neighbour queries.
struct Cloud {
    reps: Vec<Point3>,
    /// The fit pose of each point (for its axis and its cutter).
    pose: Vec<FitPose>,
    tree: Option<ImmutableKdTree<f64, 3>>,
}

impl Cloud {
    fn new(fit: &[FitPose], pts: &[Option<Point3>], cell: f64) -> Cloud {
        // Thin: the first point in each cell (deterministic).
        let mut seen: HashMap<[i64; 3], ()> = HashMap::new();
        let mut reps = Vec::new();
        let mut pose = Vec::new();
        for (p, f) in pts.iter().zip(fit) {
            let Some(p) = p else { continue };
            let key = [p.x, p.y, p.z].map(|v| (v / cell).floor() as i64);
            if seen.insert(key, ()).is_none() {
                reps.push(*p);
                pose.push(*f);
            }
        }
        if reps.len() < 6 {
            return Cloud {
                reps,
                pose,
                tree: None,
            };
        }
        // kiddo cannot split many equal coordinates: a tiny deterministic jitter (≤ 1 nm)
        // for the index only; the fit uses the exact points.
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
        let tree = ImmutableKdTree::new_from_slice(&coords);
        Cloud {
            reps,
            pose,
            tree: Some(tree),
        }
    }

    /// The indices of the neighbours of `p` whose axis is within [`AXIS_SPREAD_DEG`] of `axis`.
    fn near(&self, p: &Point3, axis: &Vec3) -> Vec<usize> {
        let Some(tree) = &self.tree else {
            return Vec::new();
        };
        let k = NEIGHBOURS.min(self.reps.len());
        let cos = AXIS_SPREAD_DEG.to_radians().cos();
        tree.nearest_n::<SquaredEuclidean>(&[p.x, p.y, p.z], k)
            .iter()
            .map(|n| n.item as usize)
            .filter(|&j| self.pose.get(j).is_some_and(|q| q.axis.dot(axis) >= cos))
            .collect()
    }

    /// The fitted normal at `p` (see [`quadric_normal`]).
    fn normal(&self, p: &Point3, guess: &Vec3, axis: &Vec3) -> Option<Vec3> {
        let near = self.near(p, axis);
        if near.len() < 6 {
            return None;
        }
        quadric_normal(p, guess, near.iter().map(|&j| &self.reps[j]))
    }

    /// Whether `cc` lies inside the cutter of a neighbouring pose by more than
    /// [`GOUGE_TOL_MM`] (the pose at `own_tip` itself excluded).
    fn gouged(&self, cc: &Point3, own_tip: &Point3, cutter: &Cutter) -> bool {
        let Some(tree) = &self.tree else {
            return false;
        };
        let rc = cutter.corner_radius_mm();
        let rd = cutter.radius_mm - rc;
        let k = NEIGHBOURS.min(self.reps.len());
        tree.nearest_n::<SquaredEuclidean>(&[cc.x, cc.y, cc.z], k)
            .iter()
            .filter_map(|n| self.pose.get(n.item as usize))
            .filter(|q| (q.tip - own_tip).norm() > 1e-9)
            .any(|q| core_distance(&q.tip, &q.axis, rc, rd, cc) < rc - GOUGE_TOL_MM)
    }
}

/// Distance from `p` to the core of a cutter (the disk of radius rd at `tip + rc a`,
/// perpendicular to a): the body is where it is at most rc.
fn core_distance(tip: &Point3, a: &Vec3, rc: f64, rd: f64, p: &Point3) -> f64 {
    let d = p - (tip + a * rc);
    let h = d.dot(a);
    let rho = (d.norm_squared() - h * h).max(0.0).sqrt();
    if rho <= rd {
        h.abs()
    } else {
        ((rho - rd).powi(2) + h * h).sqrt()
    }
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

    /// Each pose joined to the one before when it is less than 1 mm away (a pass; passes
    /// are not joined).
    fn joined(tips: &[(Point3, Vec3)]) -> Vec<bool> {
        (0..tips.len())
            .map(|i| i > 0 && (tips[i].0 - tips[i - 1].0).norm() < 1.0)
            .collect()
    }

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
            let got = derive(&c, &tips, &joined(&tips), 0.1).contacts;
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
        let got = derive(&c, &tips, &joined(&tips), 0.1).contacts;
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
        let got = derive(&c, &tips, &joined(&tips), 0.1).contacts;
        let (cc, nn) = got[50].unwrap();
        assert!(nn.angle(&n) < 1e-9, "{nn:?}");
        assert!((cc - Point3::new(2.5 * slope.cos(), 0.0, 2.5 * slope.sin())).norm() < 1e-9);
    }
}
