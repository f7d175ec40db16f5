//! Forward and inverse kinematics of a two-rotary-axis chain (kinematics.md §2): AC
//! table–table, 45° nutating axes, table/head splits, with branch choice, unwinding and
//! singularity handling.
//!
//! Joint vectors are `[X, Y, Z, R1, R2]` in mm and rad, in the order of the machine file.
//! The generic inverse (§2.2) reduces every chain to one scalar equation
//! `α cos x + β sin x = γ` for one rotary angle, then finds the other angle as a signed
//! angle about its axis, so 90° and 45° axes on either side need no special cases.

use super::machine::{BranchPreference, Machine, Side};
use crate::math::{Point3, Vec3, wrap_pi};
use std::f64::consts::TAU;

/// Five joint values: three linear (mm), two rotary (rad).
pub type Joints = [f64; 5];

/// Rodrigues rotation of `v` by angle `x` about unit axis `a`.
pub fn rotate(a: &Vec3, x: f64, v: &Vec3) -> Vec3 {
    let (s, c) = x.sin_cos();
    v * c + a.cross(v) * s + a * (a.dot(v) * (1.0 - c))
}

/// Rotation of point `p` by `x` about the line through `c` along `a`.
fn rotate_point(a: &Vec3, c: &Point3, x: f64, p: &Point3) -> Point3 {
    c + rotate(a, x, &(p - c))
}

/// Solutions `x` of `b · R(a, x) v = target` (§2.2 step 2), or `None` when unreachable.
/// When the left side does not depend on `x` (degenerate axis), returns `Some(None)`.
fn solve_dot(a: &Vec3, v: &Vec3, b: &Vec3, target: f64) -> Option<Option<[f64; 2]>> {
    let av = a.dot(v);
    let ab = a.dot(b);
    let alpha = b.dot(v) - av * ab;
    let beta = b.dot(&a.cross(v));
    let gamma = target - av * ab;
    let r = alpha.hypot(beta);
    if r < 1e-12 {
        return if gamma.abs() < 1e-9 { Some(None) } else { None };
    }
    let ratio = gamma / r;
    if ratio.abs() > 1.0 + 1e-9 {
        return None;
    }
    let phi = beta.atan2(alpha);
    let d = ratio.clamp(-1.0, 1.0).acos();
    Some(Some([phi + d, phi - d]))
}

/// Signed angle about unit `a` turning the projection of `from` onto that of `to`, or
/// `None` when either projection vanishes (the axis is undefined: singular posture).
fn signed_angle(a: &Vec3, from: &Vec3, to: &Vec3) -> Option<f64> {
    let f = from - a * a.dot(from);
    let t = to - a * a.dot(to);
    if f.norm() < 1e-9 || t.norm() < 1e-9 {
        return None;
    }
    Some(a.dot(&f.cross(&t)).atan2(f.dot(&t)))
}

/// The LU factors of the linear axes' direction matrix.
pub(crate) type LinearFrame = nalgebra::LU<f64, nalgebra::U3, nalgebra::U3>;

/// Up to two rotary-axis indices, in machine-file order (no heap allocation).
#[derive(Debug, Clone, Copy, Default)]
struct AxisSet {
    idx: [usize; 2],
    n: usize,
}

impl AxisSet {
    fn push(&mut self, i: usize) {
        if self.n < 2 {
            self.idx[self.n] = i;
            self.n += 1;
        }
    }

    fn iter(&self) -> std::slice::Iter<'_, usize> {
        self.idx[..self.n].iter()
    }

    fn len(&self) -> usize {
        self.n
    }
}

/// Up to two rotary solutions (see [`Machine::rotary_solutions`]), without allocation.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Solutions {
    sols: [[Option<f64>; 2]; 2],
    n: usize,
}

impl Solutions {
    fn push(&mut self, s: [Option<f64>; 2]) {
        if self.n < 2 {
            self.sols[self.n] = s;
            self.n += 1;
        }
    }

    fn as_slice(&self) -> &[[Option<f64>; 2]] {
        &self.sols[..self.n]
    }
}

/// A tool posture in the part frame: tip and unit axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Tool tip, part frame, mm.
    pub tip: Point3,
    /// Unit tool axis (tip → holder), part frame.
    pub axis: Vec3,
}

impl Machine {
    /// Rotation angle (radians, right hand about the home axis) of rotary axis `i` at joint
    /// value `q`.
    fn rot(&self, i: usize, q: f64) -> f64 {
        self.rotary[i].sign * q
    }

    /// Indices of the table axes (base → part) and head axes (base → spindle). Fixed-size,
    /// no allocation: this runs several times per posture.
    fn sides(&self) -> (AxisSet, AxisSet) {
        let mut t = AxisSet::default();
        let mut h = AxisSet::default();
        for i in 0..2 {
            if self.rotary[i].side == Side::Table {
                t.push(i);
            } else {
                h.push(i);
            }
        }
        (t, h)
    }

    /// Apply the table transform T(θ) = T_outer ∘ T_inner to a point of the table frame.
    fn table_point(&self, q: &Joints, p: &Point3) -> Point3 {
        let (t, _) = self.sides();
        let mut x = *p;
        for &i in t.iter().rev() {
            let r = &self.rotary[i];
            x = rotate_point(&r.axis, &r.point, self.rot(i, q[3 + i]), &x);
        }
        x
    }

    /// Undo the table transform (outermost first).
    fn table_point_inv(&self, q: &Joints, x: &Point3) -> Point3 {
        let (t, _) = self.sides();
        let mut p = *x;
        for &i in t.iter() {
            let r = &self.rotary[i];
            p = rotate_point(&r.axis, &r.point, -self.rot(i, q[3 + i]), &p);
        }
        p
    }

    fn table_dir(&self, q: &Joints, v: &Vec3, inverse: bool) -> Vec3 {
        let (t, _) = self.sides();
        let mut w = *v;
        if inverse {
            for &i in t.iter() {
                w = rotate(&self.rotary[i].axis, -self.rot(i, q[3 + i]), &w);
            }
        } else {
            for &i in t.iter().rev() {
                w = rotate(&self.rotary[i].axis, self.rot(i, q[3 + i]), &w);
            }
        }
        w
    }

    /// Head transform H(φ) = H_outer ∘ H_inner applied to a point.
    fn head_point(&self, q: &Joints, p: &Point3) -> Point3 {
        let (_, h) = self.sides();
        let mut x = *p;
        for &i in h.iter().rev() {
            let r = &self.rotary[i];
            x = rotate_point(&r.axis, &r.point, self.rot(i, q[3 + i]), &x);
        }
        x
    }

    fn head_dir(&self, q: &Joints, v: &Vec3) -> Vec3 {
        let (_, h) = self.sides();
        let mut w = *v;
        for &i in h.iter().rev() {
            w = rotate(&self.rotary[i].axis, self.rot(i, q[3 + i]), &w);
        }
        w
    }

    /// Displacement of the tool relative to the table from the linear joints, machine frame.
    fn linear_disp(&self, q: &Joints) -> Vec3 {
        (0..3)
            .map(|i| self.linear[i].direction * (self.linear[i].sign * q[i]))
            .sum()
    }

    /// Forward kinematics to the part frame (§2.1): tool tip and axis for joints `q`.
    pub fn forward(&self, q: &Joints) -> Pose {
        let tip_m = Point3::from(self.linear_disp(q)) + self.head_point(q, &self.tip_home).coords;
        let axis_m = self.head_dir(q, &self.dir_home);
        let tip_table = self.table_point_inv(q, &tip_m);
        Pose {
            tip: tip_table - self.part_origin,
            axis: self.table_dir(q, &axis_m, true),
        }
    }

    /// Velocity of the tool tip relative to the part (part frame, mm per unit of the
    /// parameter) when the joints move as `dq` from `q`: the exact derivative of
    /// [`Machine::forward`]'s tip, propagated through the chain (a rotation by θ about the
    /// line (c, a) maps a point velocity w to R w + θ̇ a × (x' − c)).
    pub fn tip_velocity(&self, q: &Joints, dq: &Joints) -> Vec3 {
        let (tab, head) = self.sides();
        // Tip in the machine frame: linear displacement plus the head chain.
        let mut x = self.tip_home;
        let mut dx = Vec3::zeros();
        for &i in head.iter().rev() {
            let r = &self.rotary[i];
            let th = self.rot(i, q[3 + i]);
            let dth = r.sign * dq[3 + i];
            x = rotate_point(&r.axis, &r.point, th, &x);
            dx = rotate(&r.axis, th, &dx) + r.axis.cross(&(x - r.point)) * dth;
        }
        let mut p = Point3::from(self.linear_disp(q)) + x.coords;
        let mut dp = dx + self.linear_disp(dq);
        // Undo the table chain (outermost first).
        for &i in tab.iter() {
            let r = &self.rotary[i];
            let th = -self.rot(i, q[3 + i]);
            let dth = -r.sign * dq[3 + i];
            p = rotate_point(&r.axis, &r.point, th, &p);
            dp = rotate(&r.axis, th, &dp) + r.axis.cross(&(p - r.point)) * dth;
        }
        dp
    }

    /// The rotary solutions (up to two, raw angles in rad) putting the part-frame tool axis
    /// `u` on the tool, or `None` when the orientation is out of reach. A `None` angle
    /// inside a solution means that axis is undefined at this posture (singular).
    pub fn rotary_solutions(&self, u: &Vec3) -> Option<Vec<[Option<f64>; 2]>> {
        self.rotary_solutions_fixed(u)
            .map(|s| s.as_slice().to_vec())
    }

    /// [`Machine::rotary_solutions`] without allocation (the IKT hot path).
    pub(crate) fn rotary_solutions_fixed(&self, u: &Vec3) -> Option<Solutions> {
        let t0 = self.dir_home;
        let (tab, head) = self.sides();
        let [r0, r1] = &self.rotary;
        let mut out = Solutions::default();
        // Each branch first fixes the "first-solved" axis `f`, then the other `o`.
        match (tab.len(), head.len()) {
            (2, 0) => {
                // R1(θ1) R2(θ2) u = t0:  a2·(R1(−θ1) t0) = a2·u.
                let xs = solve_dot(&r0.axis, &t0, &r1.axis, r1.axis.dot(u))?;
                for x in xs.map(|s| s.map(Some)).unwrap_or([None, None]) {
                    let th1 = x.map(|x| -x);
                    let w = rotate(&r0.axis, -th1.unwrap_or(0.0), &t0);
                    let th2 = signed_angle(&r1.axis, u, &w);
                    out.push([th1.map(|a| a * r0.sign), th2.map(|a| a * r1.sign)]);
                }
            }
            (0, 2) => {
                // u = R1(φ1) R2(φ2) t0:  a2·(R1(−φ1) u) = a2·t0.
                let xs = solve_dot(&r0.axis, u, &r1.axis, r1.axis.dot(&t0))?;
                for x in xs.map(|s| s.map(Some)).unwrap_or([None, None]) {
                    let ph1 = x.map(|x| -x);
                    let w = rotate(&r0.axis, -ph1.unwrap_or(0.0), u);
                    let ph2 = signed_angle(&r1.axis, &t0, &w);
                    out.push([ph1.map(|a| a * r0.sign), ph2.map(|a| a * r1.sign)]);
                }
            }
            _ => {
                // One table axis (index 0) and one head axis (index 1):
                // R_T(θ) u = R_H(φ) t0, so a_T·(R_H(φ) t0) = a_T·u.
                let xs = solve_dot(&r1.axis, &t0, &r0.axis, r0.axis.dot(u))?;
                for x in xs.map(|s| s.map(Some)).unwrap_or([None, None]) {
                    let w = rotate(&r1.axis, x.unwrap_or(0.0), &t0);
                    let th = signed_angle(&r0.axis, u, &w);
                    out.push([th.map(|a| a * r0.sign), x.map(|a| a * r1.sign)]);
                }
            }
        }
        Some(out)
    }

    /// Linear joints for tip `p` (part frame) with the rotary joints already in `q`
    /// (§2.2 step 4).
    pub fn linear_joints(&self, q: &mut Joints, p: &Point3) {
        self.linear_joints_with(&self.linear_frame(), q, p);
    }

    /// The linear axes' directions (signed) as columns, factorised for
    /// [`Machine::linear_joints_with`].
    pub(crate) fn linear_frame(&self) -> LinearFrame {
        nalgebra::Matrix3::from_columns(&[
            self.linear[0].direction * self.linear[0].sign,
            self.linear[1].direction * self.linear[1].sign,
            self.linear[2].direction * self.linear[2].sign,
        ])
        .lu()
    }

    /// [`Machine::linear_joints`] with the linear frame factorised once for a whole path.
    pub(crate) fn linear_joints_with(&self, frame: &LinearFrame, q: &mut Joints, p: &Point3) {
        let x = self.table_point(q, &(p + self.part_origin)) - self.head_point(q, &self.tip_home);
        let sol = frame.solve(&x).unwrap_or_else(Vec3::zeros);
        q[0] = sol.x;
        q[1] = sol.y;
        q[2] = sol.z;
    }
}

/// Why a posture has no joint solution.
#[derive(Debug, Clone, PartialEq)]
pub enum IkFailure {
    /// The tool axis cannot be reached by the rotary pair.
    Unreachable,
    /// Every solution violates a rotary travel limit.
    Travel,
}

/// Inverse kinematics along a path, keeping the branch continuous (§2.3).
#[derive(Debug, Clone)]
pub struct IkTracker<'m> {
    machine: &'m Machine,
    prev: Option<Joints>,
    prev_branch: usize,
    /// Number of branch switches so far.
    pub switches: usize,
}

/// One solved posture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solved {
    /// Joints, mm and rad (rotaries unwound).
    pub joints: Joints,
    /// Index of the IKT branch (0 or 1) taken.
    pub branch: usize,
    /// True when the branch differs from the previous posture's (a configuration change).
    pub switched: bool,
    /// True when an axis was undefined here and kept its previous value.
    pub singular: bool,
}

impl<'m> IkTracker<'m> {
    /// A tracker with no previous posture.
    pub fn new(machine: &'m Machine) -> Self {
        IkTracker {
            machine,
            prev: None,
            prev_branch: 0,
            switches: 0,
        }
    }

    /// Unwind `x` to the representative closest to `reference` within the travel limits.
    fn unwind(&self, i: usize, x: f64, reference: f64) -> Option<f64> {
        let r = &self.machine.rotary[i];
        let base = reference + wrap_pi(x - reference);
        match r.travel {
            None => Some(base),
            Some((lo, hi)) => {
                let eps = 1e-9;
                [
                    base,
                    base - TAU,
                    base + TAU,
                    base - 2.0 * TAU,
                    base + 2.0 * TAU,
                ]
                .into_iter()
                .filter(|v| *v >= lo - eps && *v <= hi + eps)
                .min_by(|a, b| (a - reference).abs().total_cmp(&(b - reference).abs()))
            }
        }
    }

    /// Solve the next posture (tip `p`, unit axis `u`, part frame).
    pub fn solve(&mut self, p: &Point3, u: &Vec3) -> Result<Solved, IkFailure> {
        let mut solved = self.solve_rotaries(self.machine.rotary_solutions_fixed(u))?;
        self.machine.linear_joints(&mut solved.joints, p);
        Ok(solved)
    }

    /// The sequential part of [`IkTracker::solve`]: branch choice and unwinding from the
    /// rotary solutions of the next posture's axis (`None`: unreachable). The linear joints
    /// of the result are left for [`Machine::linear_joints`]; they do not depend on the
    /// path before, so a caller can solve them, and the rotary solutions, in parallel.
    pub(crate) fn solve_rotaries(&mut self, fixed: Option<Solutions>) -> Result<Solved, IkFailure> {
        let fixed = fixed.ok_or(IkFailure::Unreachable)?;
        let sols = fixed.as_slice();
        let prev = self.prev.unwrap_or([0.0; 5]);
        let mut best: Option<(f64, Joints, usize, bool)> = None;
        for (b, s) in sols.iter().enumerate() {
            let mut q = prev;
            let mut singular = false;
            let mut ok = true;
            for i in 0..2 {
                let raw = match s[i] {
                    Some(x) => x,
                    None => {
                        singular = true;
                        prev[3 + i]
                    }
                };
                // The first posture: reference 0 so the angles come out near home.
                let reference = if self.prev.is_some() {
                    prev[3 + i]
                } else {
                    0.0
                };
                match self.unwind(i, raw, reference) {
                    Some(v) => q[3 + i] = v,
                    None => ok = false,
                }
            }
            if !ok {
                continue;
            }
            let cost = if self.prev.is_some() {
                // Keep the configuration (branch) as the NC does; take the other one only
                // when the current branch is out of travel.
                let penalty = if b == self.prev_branch { 0.0 } else { 1e6 };
                penalty + (q[3] - prev[3]).abs().max((q[4] - prev[4]).abs())
            } else {
                // Preference on the first rotary's sign, then small angles.
                let want_pos = self.machine.branch == BranchPreference::FirstPositive;
                let wrong = if want_pos {
                    q[3] < -1e-12
                } else {
                    q[3] > 1e-12
                };
                (if wrong { 1e3 } else { 0.0 }) + q[3].abs() + q[4].abs()
            };
            if best.as_ref().is_none_or(|(c, ..)| cost < *c - 1e-12) {
                best = Some((cost, q, b, singular));
            }
        }
        let (_, q, branch, singular) = best.ok_or(IkFailure::Travel)?;
        // A switch only counts when the two solutions really differ.
        let distinct = sols.len() == 2
            && match (sols[0][0], sols[1][0]) {
                (Some(a), Some(b)) => wrap_pi(a - b).abs() > 1e-9,
                _ => false,
            };
        let switched = self.prev.is_some() && distinct && branch != self.prev_branch;
        if switched {
            self.switches += 1;
        }
        if distinct || self.prev.is_none() {
            self.prev_branch = branch;
        }
        self.prev = Some(q);
        Ok(Solved {
            joints: q,
            branch,
            switched,
            singular,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::machine::TABLE_I_AC_TOML;
    use approx::assert_relative_eq;

    fn ac() -> Machine {
        Machine::from_toml_str(TABLE_I_AC_TOML).unwrap()
    }

    fn dir(tilt_deg: f64, az_deg: f64) -> Vec3 {
        let (t, a) = (tilt_deg.to_radians(), az_deg.to_radians());
        Vec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos())
    }

    #[test]
    fn ac_solutions_match_k6_example() {
        // kinematics.md §8 K6: AC tilt 30 / az 120 → (A, C) = (30, −30) or (−30, 150).
        let m = ac();
        let sols = m.rotary_solutions(&dir(30.0, 120.0)).unwrap();
        let mut got: Vec<(f64, f64)> = sols
            .iter()
            .map(|s| {
                (
                    s[0].unwrap().to_degrees(),
                    wrap_pi(s[1].unwrap()).to_degrees(),
                )
            })
            .collect();
        got.sort_by(|a, b| b.0.total_cmp(&a.0));
        assert_relative_eq!(got[0].0, 30.0, epsilon = 1e-9);
        assert_relative_eq!(got[0].1, -30.0, epsilon = 1e-9);
        assert_relative_eq!(got[1].0, -30.0, epsilon = 1e-9);
        assert_relative_eq!(got[1].1, 150.0, epsilon = 1e-9);
    }

    #[test]
    fn tip_velocity_is_the_derivative_of_forward() {
        // Table–table AC, the 45° nutating variant, and a head/table split (A on the head).
        let nut = include_str!("../../samples/machines/table1_nutating45.toml");
        let cut = TABLE_I_AC_TOML.rfind("side = \"table\"").unwrap();
        let split = format!(
            "{}side = \"head\"{}",
            &TABLE_I_AC_TOML[..cut],
            &TABLE_I_AC_TOML[cut + "side = \"table\"".len()..]
        );
        for text in [TABLE_I_AC_TOML, nut, split.as_str()] {
            let m = Machine::from_toml_str(text).unwrap();
            for k in 0..20 {
                let f = k as f64;
                let q = [
                    3.0 * f.sin(),
                    -20.0 + f,
                    5.0 * f.cos(),
                    0.3 * (0.7 * f).sin(),
                    1.3 * f,
                ];
                let dq = [0.2 * f.cos(), 0.9, -0.1 * f, 0.05 * f.sin(), 0.3 - 0.02 * f];
                let h = 1e-5;
                let (mut qp, mut qm) = (q, q);
                for i in 0..5 {
                    qp[i] += dq[i] * h;
                    qm[i] -= dq[i] * h;
                }
                let fd = (m.forward(&qp).tip - m.forward(&qm).tip) / (2.0 * h);
                let an = m.tip_velocity(&q, &dq);
                assert!((fd - an).norm() < 1e-6 * (1.0 + an.norm()), "{fd} vs {an}");
            }
        }
    }

    #[test]
    fn pole_keeps_previous_c_and_is_flagged() {
        let m = ac();
        let mut ik = IkTracker::new(&m);
        let a = ik.solve(&Point3::origin(), &dir(10.0, 40.0)).unwrap();
        let b = ik.solve(&Point3::origin(), &Vec3::z()).unwrap();
        assert!(b.singular);
        assert_relative_eq!(b.joints[4], a.joints[4]);
        assert_relative_eq!(b.joints[3], 0.0, epsilon = 1e-12);
    }

    #[test]
    fn c_unwinds_through_180() {
        let m = ac();
        let mut ik = IkTracker::new(&m);
        let mut last = ik.solve(&Point3::origin(), &dir(30.0, 0.0)).unwrap().joints;
        for k in 1..=100 {
            let q = ik
                .solve(&Point3::origin(), &dir(30.0, 10.0 * k as f64))
                .unwrap()
                .joints;
            assert!((q[4] - last[4]).abs() < 11f64.to_radians());
            last = q;
        }
        assert_eq!(ik.switches, 0);
        // C = 90° − azimuth, unwound over 1000° of azimuth: no wrap.
        assert_relative_eq!(last[4].to_degrees(), 90.0 - 1000.0, epsilon = 1e-9);
    }
}
