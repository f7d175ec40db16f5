//! The geometry of one move between two postures, parameterised by its own arc length σ.
//!
//! A move is a straight line, an arc ([`ArcMove`]: clockwise about its axis, with extra
//! turns, helical when the end lies higher along the axis), or, with the spline option, a
//! cubic Hermite curve whose end tangents come from the neighbouring postures. Every curve
//! gives its length, the point at σ, the unit tangent at σ and the interpolation parameter
//! u ∈ [0, 1] (used for the tool axis, CC point and normal) at σ.

use crate::math::{Point3, Vec3, normalize_or_none};
use crate::toolpath::ArcMove;
use std::f64::consts::TAU;

/// Below this length (mm) a move is treated as a zero-length move.
pub(crate) const ZERO_LENGTH_MM: f64 = 1e-12;

/// `x > limit`, false for NaN (reads better negated than `!(x > limit)`).
pub(crate) fn above(x: f64, limit: f64) -> bool {
    x > limit
}

/// Number of sub-intervals of the arc-length table of a Hermite segment.
const HERMITE_TABLE: usize = 16;

/// One move's geometry.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Curve {
    /// Straight line from `p0` along the unit direction `dir`.
    Line { p0: Point3, dir: Vec3, len: f64 },
    /// Arc or helix about `centre` and the unit `axis`: the point at angle φ (clockwise
    /// about the axis) is `centre + axis·(h0 + dh·φ) + (r0 + dr·φ)(e1 cos φ + e2 sin φ)`.
    Arc {
        centre: Point3,
        axis: Vec3,
        e1: Vec3,
        e2: Vec3,
        r0: f64,
        dr: f64,
        h0: f64,
        dh: f64,
        sweep: f64,
        len: f64,
    },
    /// Cubic Hermite curve from `p0` to `p1` with end derivatives `m0`, `m1` (per unit u),
    /// with a table of the arc length at u = j/16.
    Hermite {
        p0: Point3,
        p1: Point3,
        m0: Vec3,
        m1: Vec3,
        table: [f64; HERMITE_TABLE + 1],
    },
}

impl Curve {
    /// A straight move; `None` when it is shorter than [`ZERO_LENGTH_MM`].
    pub(crate) fn line(p0: Point3, p1: Point3) -> Option<Curve> {
        let d = p1 - p0;
        let len = d.norm();
        if !above(len, ZERO_LENGTH_MM) {
            return None;
        }
        Some(Curve::Line {
            p0,
            dir: d / len,
            len,
        })
    }

    /// An arc from `p0` to `p1`; `None` when the arc is degenerate (zero axis, an end on
    /// the axis), in which case the caller falls back to a line.
    pub(crate) fn arc(p0: Point3, p1: Point3, arc: &ArcMove) -> Option<Curve> {
        let axis = normalize_or_none(&arc.axis, 1e-12)?;
        let c = arc.centre;
        let w0 = p0 - c;
        let w1 = p1 - c;
        let h0 = w0.dot(&axis);
        let h1 = w1.dot(&axis);
        let v0 = w0 - axis * h0;
        let v1 = w1 - axis * h1;
        let r0 = v0.norm();
        let r1 = v1.norm();
        let scale = arc.radius_mm.abs().max(r0).max(1.0);
        if !(r0 > 1e-9 * scale && r1 > 1e-9 * scale) {
            return None;
        }
        let e1 = v0 / r0;
        // Clockwise about the axis: the rotation by −φ, so e2 = −(axis × e1) = e1 × axis.
        let e2 = e1.cross(&axis);
        let mut sweep = v1.dot(&e2).atan2(v1.dot(&e1));
        if sweep < 0.0 {
            sweep += TAU;
        }
        // Start and end on the same point of the circle (seen along the axis): a full
        // turn, or a full helical turn when the end is higher along the axis.
        if (v1 - v0).norm() <= 1e-9 * scale || sweep <= 1e-12 {
            sweep = TAU;
        }
        sweep += TAU * f64::from(arc.extra_turns);
        if !sweep.is_finite() {
            return None;
        }
        let dr = (r1 - r0) / sweep;
        let dh = (h1 - h0) / sweep;
        // Exact for a circle or a helix of constant radius; with a slightly different end
        // radius (file rounding) the mean speed is used.
        let r_mean = 0.5 * (r0 + r1);
        let len = sweep * (r_mean * r_mean + dr * dr + dh * dh).sqrt();
        if !above(len, ZERO_LENGTH_MM) || !len.is_finite() {
            return None;
        }
        Some(Curve::Arc {
            centre: c,
            axis,
            e1,
            e2,
            r0,
            dr,
            h0,
            dh,
            sweep,
            len,
        })
    }

    /// A cubic Hermite move from `p0` to `p1` with unit end tangents `t0`, `t1`
    /// (scaled by the chord); `None` when the chord is shorter than [`ZERO_LENGTH_MM`].
    pub(crate) fn hermite(p0: Point3, p1: Point3, t0: Vec3, t1: Vec3) -> Option<Curve> {
        let chord = (p1 - p0).norm();
        if !above(chord, ZERO_LENGTH_MM) {
            return None;
        }
        let m0 = t0 * chord;
        let m1 = t1 * chord;
        let mut table = [0.0; HERMITE_TABLE + 1];
        let mut curve = Curve::Hermite {
            p0,
            p1,
            m0,
            m1,
            table,
        };
        for j in 0..HERMITE_TABLE {
            let a = j as f64 / HERMITE_TABLE as f64;
            let b = (j + 1) as f64 / HERMITE_TABLE as f64;
            table[j + 1] = table[j] + curve.hermite_length(a, b);
        }
        if !above(table[HERMITE_TABLE], ZERO_LENGTH_MM) || !table[HERMITE_TABLE].is_finite() {
            return None;
        }
        if let Curve::Hermite { table: t, .. } = &mut curve {
            *t = table;
        }
        Some(curve)
    }

    /// Arc length, mm.
    pub(crate) fn len(&self) -> f64 {
        match self {
            Curve::Line { len, .. } | Curve::Arc { len, .. } => *len,
            Curve::Hermite { table, .. } => table[HERMITE_TABLE],
        }
    }

    /// A box that holds every point of the curve (lower, upper corner): the ends of a
    /// line, the cylinder of an arc or helix, the control points of a Hermite curve
    /// (its Bézier form lies in their convex hull).
    pub(crate) fn bounds(&self) -> (Point3, Point3) {
        let hull = |pts: &[Point3]| {
            let mut lo = pts[0];
            let mut hi = pts[0];
            for p in &pts[1..] {
                lo = lo.inf(p);
                hi = hi.sup(p);
            }
            (lo, hi)
        };
        match *self {
            Curve::Line { p0, dir, len } => hull(&[p0, p0 + dir * len]),
            Curve::Arc {
                centre,
                r0,
                dr,
                h0,
                dh,
                sweep,
                ..
            } => {
                let reach =
                    r0.abs().max((r0 + dr * sweep).abs()) + h0.abs().max((h0 + dh * sweep).abs());
                let r = Vec3::repeat(reach);
                (centre - r, centre + r)
            }
            Curve::Hermite { p0, p1, m0, m1, .. } => hull(&[p0, p0 + m0 / 3.0, p1 - m1 / 3.0, p1]),
        }
    }

    /// Whether the curve may come into the box `lo`…`hi` (false only when it cannot).
    pub(crate) fn may_meet(&self, lo: &Point3, hi: &Point3) -> bool {
        let (a, b) = self.bounds();
        (0..3).all(|k| a[k] <= hi[k] && b[k] >= lo[k])
    }

    /// The curve parameter u ∈ [0, 1] at arc length σ (clamped).
    pub(crate) fn param(&self, sigma: f64) -> f64 {
        match self {
            Curve::Line { len, .. } | Curve::Arc { len, .. } => (sigma / len).clamp(0.0, 1.0),
            Curve::Hermite { table, .. } => self.hermite_param(table, sigma),
        }
    }

    /// Point and unit tangent at parameter u (from [`Curve::param`]).
    pub(crate) fn eval(&self, u: f64) -> (Point3, Vec3) {
        match *self {
            Curve::Line { p0, dir, len } => (p0 + dir * (len * u), dir),
            Curve::Arc {
                centre,
                axis,
                e1,
                e2,
                r0,
                dr,
                h0,
                dh,
                sweep,
                ..
            } => {
                let phi = sweep * u;
                let (s, c) = phi.sin_cos();
                let radial = e1 * c + e2 * s;
                let r = r0 + dr * phi;
                let p = centre + axis * (h0 + dh * phi) + radial * r;
                let d = axis * dh + radial * dr + (e2 * c - e1 * s) * r;
                (p, d / d.norm())
            }
            Curve::Hermite { p0, p1, m0, m1, .. } => {
                let p = hermite_point(&p0, &p1, &m0, &m1, u);
                let d = hermite_derivative(&p0, &p1, &m0, &m1, u);
                let t = normalize_or_none(&d, 1e-15).unwrap_or_else(|| (p1 - p0).normalize());
                (p, t)
            }
        }
    }

    /// Unit tangent at the start (u = 0) and at the end (u = 1).
    pub(crate) fn end_tangents(&self) -> (Vec3, Vec3) {
        (self.eval(0.0).1, self.eval(1.0).1)
    }

    fn hermite_length(&self, a: f64, b: f64) -> f64 {
        let Curve::Hermite { p0, p1, m0, m1, .. } = self else {
            return 0.0;
        };
        // Gauss-Legendre, 4 points.
        const X: [f64; 4] = [
            -0.861_136_311_594_052_6,
            -0.339_981_043_584_856_3,
            0.339_981_043_584_856_3,
            0.861_136_311_594_052_6,
        ];
        const W: [f64; 4] = [
            0.347_854_845_137_453_9,
            0.652_145_154_862_546_1,
            0.652_145_154_862_546_1,
            0.347_854_845_137_453_9,
        ];
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        X.iter()
            .zip(W.iter())
            .map(|(x, w)| w * hermite_derivative(p0, p1, m0, m1, mid + half * x).norm())
            .sum::<f64>()
            * half
    }

    fn hermite_param(&self, table: &[f64; HERMITE_TABLE + 1], sigma: f64) -> f64 {
        let total = table[HERMITE_TABLE];
        if sigma <= 0.0 {
            return 0.0;
        }
        if sigma >= total {
            return 1.0;
        }
        let j = table
            .partition_point(|&s| s <= sigma)
            .saturating_sub(1)
            .min(HERMITE_TABLE - 1);
        let ua = j as f64 / HERMITE_TABLE as f64;
        let ub = (j + 1) as f64 / HERMITE_TABLE as f64;
        let (sa, sb) = (table[j], table[j + 1]);
        let mut u = if sb > sa {
            ua + (ub - ua) * (sigma - sa) / (sb - sa)
        } else {
            ua
        };
        let Curve::Hermite { p0, p1, m0, m1, .. } = self else {
            return u;
        };
        for _ in 0..4 {
            let f = sa + self.hermite_length(ua, u) - sigma;
            let speed = hermite_derivative(p0, p1, m0, m1, u).norm();
            if !above(speed, 1e-15) {
                break;
            }
            u = (u - f / speed).clamp(ua, ub);
        }
        u
    }
}

fn hermite_point(p0: &Point3, p1: &Point3, m0: &Vec3, m1: &Vec3, u: f64) -> Point3 {
    let u2 = u * u;
    let u3 = u2 * u;
    let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
    let h10 = u3 - 2.0 * u2 + u;
    let h01 = -2.0 * u3 + 3.0 * u2;
    let h11 = u3 - u2;
    Point3::from(p0.coords * h00 + m0 * h10 + p1.coords * h01 + m1 * h11)
}

fn hermite_derivative(p0: &Point3, p1: &Point3, m0: &Vec3, m1: &Vec3, u: f64) -> Vec3 {
    let u2 = u * u;
    let d00 = 6.0 * u2 - 6.0 * u;
    let d10 = 3.0 * u2 - 4.0 * u + 1.0;
    let d01 = -6.0 * u2 + 6.0 * u;
    let d11 = 3.0 * u2 - 2.0 * u;
    p0.coords * d00 + m0 * d10 + p1.coords * d01 + m1 * d11
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn arc(centre: Point3, axis: Vec3, extra_turns: u32) -> ArcMove {
        ArcMove {
            centre,
            axis,
            radius_mm: 10.0,
            extra_turns,
        }
    }

    #[test]
    fn arc_is_clockwise_about_its_axis() {
        // From (10,0) to (0,-10) about +z: clockwise seen from +z is a quarter turn.
        let c = Curve::arc(
            Point3::new(10.0, 0.0, 0.0),
            Point3::new(0.0, -10.0, 0.0),
            &arc(Point3::origin(), Vec3::z(), 0),
        )
        .unwrap();
        assert_relative_eq!(c.len(), 10.0 * std::f64::consts::FRAC_PI_2, epsilon = 1e-12);
        let (mid, tangent) = c.eval(0.5);
        let h = 10.0 / 2f64.sqrt();
        assert_relative_eq!(mid, Point3::new(h, -h, 0.0), epsilon = 1e-12);
        assert_relative_eq!(
            tangent,
            Vec3::new(-1.0, -1.0, 0.0).normalize(),
            epsilon = 1e-12
        );
        // About −z the same ends make three quarters of a turn.
        let c = Curve::arc(
            Point3::new(10.0, 0.0, 0.0),
            Point3::new(0.0, -10.0, 0.0),
            &arc(Point3::origin(), -Vec3::z(), 0),
        )
        .unwrap();
        assert_relative_eq!(c.len(), 10.0 * 1.5 * std::f64::consts::PI, epsilon = 1e-12);
        assert_relative_eq!(c.eval(1.0).0, Point3::new(0.0, -10.0, 0.0), epsilon = 1e-12);
    }

    #[test]
    fn full_circle_and_extra_turns_helix() {
        // Start = end: a full turn; one extra turn and a 3 mm descent: a helix of two turns.
        let p = Point3::new(10.0, 0.0, 3.0);
        let q = Point3::new(10.0, 0.0, 0.0);
        let c = Curve::arc(p, q, &arc(Point3::origin(), Vec3::z(), 1)).unwrap();
        let sweep = 2.0 * TAU;
        let dh = 3.0 / sweep;
        assert_relative_eq!(c.len(), sweep * (100.0 + dh * dh).sqrt(), epsilon = 1e-9);
        let (half, _) = c.eval(0.25);
        assert_relative_eq!(half, Point3::new(-10.0, 0.0, 2.25), epsilon = 1e-9);
        assert_relative_eq!(c.eval(1.0).0, q, epsilon = 1e-9);
    }

    #[test]
    fn degenerate_arcs_are_refused() {
        let a = arc(Point3::origin(), Vec3::z(), 0);
        assert!(Curve::arc(Point3::origin(), Point3::new(1.0, 0.0, 0.0), &a).is_none());
        let zero_axis = arc(Point3::origin(), Vec3::zeros(), 0);
        assert!(
            Curve::arc(
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(0.0, 1.0, 0.0),
                &zero_axis
            )
            .is_none()
        );
    }

    #[test]
    fn hermite_of_a_straight_line_is_the_line() {
        let p0 = Point3::new(0.0, 0.0, 0.0);
        let p1 = Point3::new(3.0, 4.0, 0.0);
        let t = (p1 - p0).normalize();
        let c = Curve::hermite(p0, p1, t, t).unwrap();
        assert_relative_eq!(c.len(), 5.0, epsilon = 1e-12);
        let u = c.param(2.0);
        assert_relative_eq!(c.eval(u).0, Point3::new(1.2, 1.6, 0.0), epsilon = 1e-9);
    }

    #[test]
    fn hermite_arc_length_inverts() {
        let c = Curve::hermite(
            Point3::origin(),
            Point3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0).normalize(),
            Vec3::new(1.0, -1.0, 0.0).normalize(),
        )
        .unwrap();
        let len = c.len();
        assert!(len > 1.0);
        for k in 1..10 {
            let sigma = len * k as f64 / 10.0;
            let u = c.param(sigma);
            let back = if let Curve::Hermite { table, .. } = &c {
                let j = (u * HERMITE_TABLE as f64).floor() as usize;
                table[j] + c.hermite_length(j as f64 / HERMITE_TABLE as f64, u)
            } else {
                unreachable!()
            };
            assert_relative_eq!(back, sigma, epsilon = 1e-10);
        }
    }
}
