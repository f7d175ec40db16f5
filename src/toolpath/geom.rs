//! Geometry of CLSF moves: circular arcs (clockwise about the CIRCLE axis, clsf.md §2) and
//! the clamped cubic B-splines of `NURBS/KNOT/CNTRL` blocks.

use super::ArcMove;
use crate::math::{Point3, Vec3, normalize_or_none};
use std::f64::consts::TAU;

impl ArcMove {
    /// Swept angle from `start` to `end`, rad, clockwise about `axis` (NX convention):
    /// in (0, 2π] for the arc itself (equal start and end = a full circle), plus 2π per
    /// extra turn.
    pub fn sweep_rad(&self, start: &Point3, end: &Point3) -> f64 {
        let a = self.axis;
        let u = (start - self.centre) - a * a.dot(&(start - self.centre));
        let v = (end - self.centre) - a * a.dot(&(end - self.centre));
        let ccw = a.dot(&u.cross(&v)).atan2(u.dot(&v));
        let mut cw = (-ccw).rem_euclid(TAU);
        if cw < 1e-12 {
            cw = TAU;
        }
        cw + TAU * f64::from(self.extra_turns)
    }

    /// Length of the (possibly helical) arc from `start` to `end`, mm.
    pub fn length_mm(&self, start: &Point3, end: &Point3) -> f64 {
        let sweep = self.sweep_rad(start, end);
        let rise = self.axis.dot(&(end - start));
        let u = (start - self.centre) - self.axis * self.axis.dot(&(start - self.centre));
        let v = (end - self.centre) - self.axis * self.axis.dot(&(end - self.centre));
        let r = 0.5 * (u.norm() + v.norm());
        ((r * sweep).powi(2) + rise * rise).sqrt()
    }

    /// The point at fraction `t` ∈ [0, 1] of the arc from `start` to `end`: the angle and
    /// the radius (start to end) and the axial rise vary linearly with `t`.
    pub fn point_at(&self, start: &Point3, end: &Point3, t: f64) -> Point3 {
        let a = self.axis;
        let sweep = self.sweep_rad(start, end);
        let h0 = a.dot(&(start - self.centre));
        let h1 = a.dot(&(end - self.centre));
        let u = (start - self.centre) - a * h0;
        let v = (end - self.centre) - a * h1;
        let (r0, r1) = (u.norm(), v.norm());
        let Some(x) = normalize_or_none(&u, 1e-12) else {
            return start + (end - start) * t;
        };
        let y = x.cross(&a); // clockwise about a: from x towards −(a × x) = x × a
        let phi = sweep * t;
        let r = r0 + (r1 - r0) * t;
        self.centre + a * (h0 + (h1 - h0) * t) + (x * phi.cos() + y * phi.sin()) * r
    }
}

/// A clamped cubic B-spline in the form NX writes it (clsf.md §2): the control points are
/// the current position followed by the `CNTRL` points, and the listed knots omit the
/// four leading zeros and three of the four closing ones.
#[derive(Debug, Clone, PartialEq)]
pub struct Spline {
    knots: Vec<f64>,
    points: Vec<Point3>,
}

impl Spline {
    /// Build from the start point, the listed knots and the `CNTRL` points. Accepts the NX
    /// form (`knots.len() == cntrl.len() − 2`, last knot 1) and a full knot vector
    /// (`cntrl.len() + 5` values). `None` when the counts or the order do not fit.
    pub fn from_clsf(start: Point3, listed: &[f64], cntrl: &[Point3]) -> Option<Spline> {
        let mut points = Vec::with_capacity(cntrl.len() + 1);
        points.push(start);
        points.extend_from_slice(cntrl);
        let n = points.len();
        if n < 4 {
            return None;
        }
        let knots: Vec<f64> = if listed.len() + 2 == cntrl.len() {
            let mut k = vec![0.0; 4];
            k.extend_from_slice(listed);
            k.extend_from_slice(&[listed.last().copied()?; 3]);
            k
        } else if listed.len() == n + 4 {
            listed.to_vec()
        } else {
            return None;
        };
        let ordered = knots.windows(2).all(|w| w[0] <= w[1]);
        let lo = knots[3];
        let hi = knots[n];
        if !ordered || hi <= lo || knots.iter().any(|k| !k.is_finite()) {
            return None;
        }
        Some(Spline { knots, points })
    }

    /// Parameter range.
    pub fn range(&self) -> (f64, f64) {
        (self.knots[3], self.knots[self.points.len()])
    }

    /// Evaluate at `u` (de Boor).
    pub fn eval(&self, u: f64) -> Point3 {
        let n = self.points.len();
        let (lo, hi) = self.range();
        let u = u.clamp(lo, hi);
        // Span index k with knots[k] <= u < knots[k+1], k in 3..n.
        let mut k = 3;
        while k + 1 < n && self.knots[k + 1] <= u {
            k += 1;
        }
        let mut d: [Vec3; 4] = [Vec3::zeros(); 4];
        for (j, dj) in d.iter_mut().enumerate() {
            *dj = self.points[k - 3 + j].coords;
        }
        for r in 1..=3 {
            for j in (r..=3).rev() {
                let i = k - 3 + j;
                let denom = self.knots[i + 4 - r] - self.knots[i];
                let alpha = if denom > 0.0 {
                    (u - self.knots[i]) / denom
                } else {
                    0.0
                };
                d[j] = d[j - 1] * (1.0 - alpha) + d[j] * alpha;
            }
        }
        Point3::from(d[3])
    }

    /// Points along the curve (without the start, with the end) such that the chord to
    /// the curve deviates by at most `tol_mm` at the checked midpoints.
    pub fn sample(&self, tol_mm: f64) -> Vec<Point3> {
        let tol = tol_mm.max(1e-6);
        let n = self.points.len();
        let mut params = Vec::new();
        for k in 3..n {
            let (a, b) = (self.knots[k], self.knots[k + 1]);
            if b <= a {
                continue;
            }
            // Bisect each span until the midpoint is within tolerance of the chord.
            let mut stack = vec![(a, b, 0u32)];
            let mut out_span = Vec::new();
            while let Some((x, y, depth)) = stack.pop() {
                let (p, q) = (self.eval(x), self.eval(y));
                let m = self.eval(0.5 * (x + y));
                let chord = q - p;
                let dev = match normalize_or_none(&chord, 1e-12) {
                    Some(c) => {
                        let w = m - p;
                        (w - c * w.dot(&c)).norm()
                    }
                    None => (m - p).norm(),
                };
                if dev > tol && depth < 12 {
                    stack.push((0.5 * (x + y), y, depth + 1));
                    stack.push((x, 0.5 * (x + y), depth + 1));
                } else {
                    out_span.push(y);
                }
            }
            params.extend(out_span);
        }
        let mut pts: Vec<Point3> = params.into_iter().map(|u| self.eval(u)).collect();
        if let Some(last) = pts.last_mut() {
            // Clamped: the curve ends exactly on the last control point.
            *last = *self.points.last().unwrap_or(last);
        }
        pts
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::f64::consts::PI;

    fn arc(axis: Vec3, extra: u32) -> ArcMove {
        ArcMove {
            centre: Point3::origin(),
            axis,
            radius_mm: 1.0,
            extra_turns: extra,
        }
    }

    #[test]
    fn arcs_run_clockwise_about_their_axis() {
        let s = Point3::new(1.0, 0.0, 0.0);
        let e = Point3::new(0.0, -1.0, 0.0);
        // Clockwise seen from +Z: a quarter turn from +x to −y.
        assert_relative_eq!(
            arc(Vec3::z(), 0).sweep_rad(&s, &e),
            PI / 2.0,
            epsilon = 1e-12
        );
        assert_relative_eq!(
            arc(-Vec3::z(), 0).sweep_rad(&s, &e),
            1.5 * PI,
            epsilon = 1e-12
        );
        assert_relative_eq!(
            arc(Vec3::z(), 1).sweep_rad(&s, &s),
            4.0 * PI,
            epsilon = 1e-12
        );
        let mid = arc(Vec3::z(), 0).point_at(&s, &e, 0.5);
        assert_relative_eq!(
            mid,
            Point3::new(0.5f64.sqrt(), -(0.5f64.sqrt()), 0.0),
            epsilon = 1e-12
        );
        assert_relative_eq!(
            arc(Vec3::z(), 0).length_mm(&s, &e),
            PI / 2.0,
            epsilon = 1e-12
        );
        // Helix: one full turn rising 2π mm has length 2π√2.
        let top = Point3::new(1.0, 0.0, TAU);
        assert_relative_eq!(
            arc(Vec3::z(), 0).length_mm(&s, &top),
            TAU * 2f64.sqrt(),
            epsilon = 1e-12
        );
    }

    #[test]
    fn spline_interpolates_ends_and_reproduces_a_line() {
        // Control points on a line, evenly spaced, give points on that line.
        let start = Point3::new(0.0, 0.0, 0.0);
        let cntrl: Vec<Point3> = (1..=5)
            .map(|k| Point3::new(f64::from(k), 0.0, 0.0))
            .collect();
        let sp = Spline::from_clsf(start, &[0.25, 0.5, 1.0], &cntrl[..])
            .unwrap_or_else(|| panic!("valid spline"));
        assert_relative_eq!(sp.eval(0.0), start, epsilon = 1e-12);
        assert_relative_eq!(sp.eval(1.0), cntrl[4], epsilon = 1e-12);
        let pts = sp.sample(0.001);
        assert_eq!(pts.last(), Some(&cntrl[4]));
        for p in &pts {
            assert_relative_eq!(p.y, 0.0, epsilon = 1e-12);
        }
        assert!(Spline::from_clsf(start, &[0.5, 1.0], &cntrl).is_none());
        assert!(Spline::from_clsf(start, &[0.5, 0.25, 1.0], &cntrl).is_none());
    }

    #[test]
    fn spline_samples_stay_within_tolerance_of_a_quarter_circle_polygon() {
        // Curve through a bent polygon: every sample lies within the convex hull bbox.
        let start = Point3::new(0.0, 0.0, 0.0);
        let cntrl = [
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(2.0, 1.0, 0.0),
            Point3::new(2.0, 2.0, 0.0),
            Point3::new(2.0, 3.0, 0.0),
        ];
        let sp = Spline::from_clsf(start, &[0.5, 1.0], &cntrl).unwrap_or_else(|| panic!("ok"));
        let pts = sp.sample(0.0005);
        assert!(pts.len() > 4);
        for w in pts.windows(2) {
            let m = sp.eval(0.0); // touch eval at the range start
            assert!(m.x.abs() < 1e-12);
            assert!(w[0].x <= 2.0 + 1e-12 && w[0].y <= 3.0 + 1e-12);
        }
    }
}
