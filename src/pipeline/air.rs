//! Is a patch on the cut? The distance from a point to the surface the cut moves define
//! (their contact points, joined along each pass), and the local stepover there, for
//! `simulate --patch-near`: a point higher above that surface (along its normal) than
//! [`tolerance_mm`] is in the air (on a lead-in or lead-out arc, a rapid, …) and is
//! refused. The height along the normal, not the distance to the nearest contact point:
//! a flat-bottomed cutter's contacts on a floor lie anywhere under its bottom, millimetres
//! to the side of a point on the floor.

use crate::math::{Point3, Vec3};
use crate::toolpath::Program;

/// The smallest distance tolerated between a patch point and the cut surface, mm.
pub const MIN_TOLERANCE_MM: f64 = 0.2;
/// The tolerance in local stepovers.
pub const STEPOVERS: f64 = 1.5;

/// How far a point is from the cut surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nearest {
    /// Distance from the point to the nearest point of the cut surface, mm.
    pub distance_mm: f64,
    /// Height of the point above (or depth below) the cut surface there, along its normal
    /// (the tool axis where the posture has no contact), mm.
    pub height_mm: f64,
    /// That nearest point, mm.
    pub point: Point3,
    /// Distance from the nearest point to the neighbouring pass (the local stepover), mm;
    /// `None` when there is no other pass within reach.
    pub stepover_mm: Option<f64>,
}

/// The tolerance of a patch point: the larger of 0.2 mm and 1.5 local stepovers. A point
/// of the finished surface lies at most half a stepover from the nearest pass (between
/// two passes); 1.5 stepovers leave room for a point read off a drawing and for curvature,
/// while a lead-in arc or a rapid lies millimetres above. Without a neighbouring pass,
/// `fallback_mm` (the tool radius) stands for the stepover.
pub fn tolerance_mm(near: &Nearest, fallback_mm: f64) -> f64 {
    MIN_TOLERANCE_MM.max(STEPOVERS * near.stepover_mm.unwrap_or(fallback_mm))
}

impl Nearest {
    /// How far the point is off the cut surface: its height along the normal, or the whole
    /// distance when the point lies more than `beside_mm` to the side (beyond the cut).
    pub fn off_surface_mm(&self, beside_mm: f64) -> f64 {
        let side = (self.distance_mm.powi(2) - self.height_mm.powi(2))
            .max(0.0)
            .sqrt();
        if side > beside_mm {
            self.distance_mm
        } else {
            self.height_mm
        }
    }
}

/// Closest point of segment a-b to q.
fn on_segment(q: &Point3, a: &Point3, b: &Point3) -> Point3 {
    let ab = b - a;
    let l2 = ab.norm_squared();
    if l2 <= 1e-24 {
        return *a;
    }
    let u = ((q - a).dot(&ab) / l2).clamp(0.0, 1.0);
    a + ab * u
}

/// One polyline piece of the cut surface: its points and their arc length, per pass.
struct Piece {
    pass: usize,
    a: Point3,
    b: Point3,
    n: Vec3,
    s0: f64,
    s1: f64,
}

/// The nearest point to `q` of the surface of the postures `selected(path, index)` picks
/// (a move into a picked posture cuts), among `paths` of `program`: contact points where
/// the posture has one (else its CL point when `cl_fallback`), joined along each pass. The
/// stepover is the distance from that point to the nearest other pass, or to the same pass
/// farther than `far_mm` along it. `None` when nothing is picked.
pub fn nearest(
    program: &Program,
    paths: &[usize],
    q: &Point3,
    far_mm: f64,
    cl_fallback: bool,
    selected: impl Fn(usize, usize) -> bool,
) -> Option<Nearest> {
    let mut pieces = Vec::new();
    let mut pass = 0usize;
    for &pi in paths {
        let Some(path) = program.paths.get(pi) else {
            continue;
        };
        let mut prev: Option<(Point3, f64)> = None;
        let mut prev_cl: Option<Point3> = None;
        for (i, p) in path.postures.iter().enumerate() {
            let point = match (&p.contact, cl_fallback) {
                (Some(c), _) => Some(c.point),
                (None, true) => Some(p.position),
                (None, false) => None,
            };
            let n = p.contact.as_ref().map_or(p.axis, |c| c.normal);
            let picked = selected(pi, i);
            match (picked, point, prev) {
                (true, Some(b), Some((a, s))) => {
                    let s1 = s + (b - a).norm();
                    pieces.push(Piece {
                        pass,
                        a,
                        b,
                        n,
                        s0: s,
                        s1,
                    });
                    prev = Some((b, s1));
                }
                (true, Some(b), None) => {
                    // The first cut of a pass leaves from a posture without a contact:
                    // its CL point carried by this posture's contact offset.
                    let a = prev_cl.map_or(b, |c| c + (b - p.position));
                    let s1 = (b - a).norm();
                    pieces.push(Piece {
                        pass,
                        a,
                        b,
                        n,
                        s0: 0.0,
                        s1,
                    });
                    prev = Some((b, s1));
                }
                _ => {
                    // A move that does not cut ends the pass.
                    if prev.is_some() {
                        pass += 1;
                    }
                    prev = None;
                }
            }
            prev_cl = Some(p.position);
        }
        pass += 1;
    }
    let (best, c0) = pieces
        .iter()
        .map(|k| (k, on_segment(q, &k.a, &k.b)))
        .min_by(|x, y| (x.1 - q).norm().total_cmp(&(y.1 - q).norm()))?;
    let l = (best.b - best.a).norm();
    let s0 = if l > 0.0 {
        best.s0 + (best.s1 - best.s0) * ((c0 - best.a).norm() / l)
    } else {
        best.s0
    };
    let stepover = pieces
        .iter()
        .filter(|k| k.pass != best.pass || k.s1 < s0 - far_mm || k.s0 > s0 + far_mm)
        .map(|k| (on_segment(&c0, &k.a, &k.b) - c0).norm())
        .filter(|d| *d > 1e-9)
        .min_by(f64::total_cmp);
    Some(Nearest {
        distance_mm: (c0 - q).norm(),
        height_mm: (q - c0).dot(&best.n).abs(),
        point: c0,
        stepover_mm: stepover,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::toolpath::{Contact, MotionKind, Posture, Toolpath};

    fn at(x: f64, y: f64, motion: MotionKind) -> Posture {
        Posture {
            position: Point3::new(x, y, 1.0),
            axis: Vec3::z(),
            motion,
            arc: None,
            contact: Some(Contact {
                point: Point3::new(x, y, 0.0),
                normal: Vec3::z(),
                normal_derived: true,
            }),
            feed_mm_min: Some(1000.0),
            spindle_rpm: None,
            line: 0,
        }
    }

    #[test]
    fn distance_and_stepover_of_two_passes() {
        use MotionKind::*;
        let path = Toolpath {
            postures: vec![
                at(0.0, 0.0, Engage),
                at(10.0, 0.0, Cut),
                at(10.0, 0.5, Retract),
                at(0.0, 0.5, Approach),
                at(0.0, 0.5, Engage),
                at(10.0, 0.5, Cut),
            ],
            ..Default::default()
        };
        let program = Program {
            paths: vec![path],
            warnings: Vec::new(),
        };
        let cut = |pi: usize, i: usize| program.paths[pi].postures[i].motion == Cut;
        let n = nearest(
            &program,
            &[0],
            &Point3::new(4.0, 0.1, 3.0),
            10.0,
            false,
            cut,
        );
        let n = n.unwrap_or_else(|| panic!("nearest"));
        assert!((n.distance_mm - (0.01f64 + 9.0).sqrt()).abs() < 1e-12);
        assert!((n.height_mm - 3.0).abs() < 1e-12 && (n.off_surface_mm(1.0) - 3.0).abs() < 1e-12);
        assert!((n.stepover_mm.unwrap_or(0.0) - 0.5).abs() < 1e-12);
        assert!((tolerance_mm(&n, 5.0) - 0.75).abs() < 1e-12);
    }
}
