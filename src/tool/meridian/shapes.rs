//! The shapes crest builds as meridians by name: ball, torus and flat ends as profiles,
//! round inserts, APT's seven-parameter cutter, `profile_mm` polylines and arc lists, and
//! the circle-segment families (barrel, lens, oval, taper barrel), each from its own
//! parameters and checked (tangent joins, a tip on the axis at z = 0).
//!
//! The circle-segment families (segment radius Rs ≫ R):
//!
//! * **barrel**: flat end, corner radius rc, then the segment of radius Rs whose widest
//!   point (radius R) lies at `segment_height_mm` above the tip, symmetric about it: a
//!   barrel on its side, for walls with the axis nearly along them;
//! * **lens**: the segment across the end (centre on the axis, Rs above the tip), then the
//!   corner radius rc up to the cylinder R: for floors at a small tilt;
//! * **oval**: the tip radius rt about the axis, then the segment up to the vertical at R
//!   (its centre at (R − Rs, zs), tangent to the tip circle): floors and walls;
//! * **taper barrel**: the tip radius rt up to where the profile makes the taper angle τ
//!   with the axis, then the segment tangent to it up to the radius R: walls, with the
//!   tip for the fillets.

use super::{Family, Meridian, ProfileError, Segment, arc_point, err};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Ball, torus or flat end: flat face from the axis to R − rc, then the corner arc.
pub fn classic(radius_mm: f64, corner_radius_mm: f64) -> Result<Meridian, ProfileError> {
    let rc = corner_radius_mm.clamp(0.0, radius_mm);
    let rd = radius_mm - rc;
    let mut s = Vec::new();
    if rd > 0.0 {
        s.push(Segment::Line {
            a: [0.0, 0.0],
            b: [rd, 0.0],
        });
    }
    if rc > 0.0 {
        s.push(Segment::Arc {
            centre: [rd, rc],
            radius: rc,
            t0: 0.0,
            t1: FRAC_PI_2,
        });
    }
    Meridian::new(s, Family::Classic)
}

/// A round-insert face mill: the lower half of the insert circle of radius `insert_mm`
/// about (R − ri, ri), inner flank included (cut off at the axis).
pub fn round_insert(radius_mm: f64, insert_mm: f64) -> Result<Meridian, ProfileError> {
    if !(insert_mm > 0.0 && insert_mm <= radius_mm) {
        return err(format!(
            "the insert radius {insert_mm} mm must be positive and at most the radius {radius_mm} mm"
        ));
    }
    let arc = Segment::Arc {
        centre: [radius_mm - insert_mm, insert_mm],
        radius: insert_mm,
        t0: -FRAC_PI_2,
        t1: FRAC_PI_2,
    };
    let s = arc.clip_axis().into_iter().collect();
    Meridian::new(s, Family::Classic)
}

/// APT's `CUTTER/d,r,e,f,a,b,h` (lengths mm, angles degrees): the end line through the tip
/// at angle `a` above the plane normal to the axis, the corner circle of radius r about
/// (e, f), the side line at angle `b` from the axis (positive: widening upward) up to the
/// height h. `e = f = 0` with `r > 0` (or all zero) is read as the two-parameter form
/// `CUTTER/d,r` (corner centre at (d/2 − r, r)). Returns the meridian and, when the
/// diameter d disagrees with the profile, a warning.
pub fn apt(p: [f64; 7]) -> Result<(Meridian, Option<String>), ProfileError> {
    let [d, r, mut e, mut f, a_deg, b_deg, h] = p;
    if !p.iter().all(|v| v.is_finite()) {
        return err("the APT cutter has a non-finite parameter");
    }
    if d <= 0.0 || r < 0.0 {
        return err(format!(
            "the APT cutter needs d > 0 and r ≥ 0, found d = {d}, r = {r}"
        ));
    }
    if !((0.0..90.0).contains(&a_deg) && -90.0 < b_deg && b_deg < 90.0) {
        return err(format!(
            "the APT cutter needs 0 ≤ a < 90° and −90° < b < 90°, found a = {a_deg}°, b = {b_deg}°"
        ));
    }
    if a_deg + b_deg >= 90.0 {
        return err(format!(
            "the APT cutter's end (a = {a_deg}°) and side (b = {b_deg}°) lines do not meet below the corner"
        ));
    }
    if e == 0.0 && f == 0.0 && a_deg == 0.0 && b_deg == 0.0 {
        e = 0.5 * d - r;
        f = r;
    }
    let (a, b) = (a_deg.to_radians(), b_deg.to_radians());
    let height = if h > 0.0 { h } else { f64::INFINITY };
    let mut segs = Vec::new();
    // End line: from the axis at angle a to the tangent point (e + r sin a, f − r cos a).
    let te = [e + r * a.sin(), f - r * a.cos()];
    let z0 = te[1] - te[0] * a.tan();
    if te[0] > 1e-12 {
        segs.push(Segment::Line {
            a: [0.0, z0],
            b: te,
        });
    }
    let (t_side, mut t_start) = (FRAC_PI_2 - b, a);
    if te[0] <= 1e-12 && r > 0.0 {
        // The corner circle reaches the axis: start where it crosses it.
        let s = (-e / r).clamp(-1.0, 1.0);
        t_start = t_start.max(s.asin());
    }
    let mut tip_z = z0;
    if r > 0.0 {
        let arc = Segment::Arc {
            centre: [e, f],
            radius: r,
            t0: t_start,
            t1: t_side,
        };
        if te[0] <= 1e-12 {
            tip_z = arc.start()[1];
        }
        segs.push(arc);
    }
    let ts = [e + r * b.cos(), f - r * b.sin()];
    let top = if height.is_finite() {
        height
    } else {
        ts[1] + 2.0 * d
    };
    if top > ts[1] {
        let len = (top - ts[1]) / b.cos();
        segs.push(Segment::Line {
            a: ts,
            b: [ts[0] + len * b.sin(), top],
        });
    }
    if tip_z.abs() > 1e-6 * d.max(1.0) {
        return err(format!(
            "CUTTER/{d},{r},{e},{f},{a_deg},{b_deg},{h}: the end meets the axis at z = {tip_z:.6} mm, not at the tool tip (f, e, r and a disagree)"
        ));
    }
    // Cut at the height h, and where the side crosses the axis.
    let segs: Vec<Segment> = segs.into_iter().filter_map(|s| s.clip_axis()).collect();
    let m = Meridian::new(segs, Family::Apt(p))?;
    let m = clip_height(&m, top)?;
    // The diameter where the side line (extended) meets the end line (extended).
    let corner_r = {
        // End: z = x tan a; side: (x, z) = ts + s (sin b, cos b).
        let den = b.sin() * a.tan() - b.cos();
        if den.abs() < 1e-12 {
            ts[0]
        } else {
            let s = (ts[1] - ts[0] * a.tan()) / den;
            ts[0] + s * b.sin()
        }
    };
    let warning = ((2.0 * corner_r - d).abs() > 1e-3 * d.max(1.0)).then(|| {
        format!(
            "CUTTER/ gives d = {d} mm but its corner (r {r}, e {e}, f {f}) and angles put the diameter at the end at {:.4} mm; the profile follows r, e, f, a, b",
            2.0 * corner_r
        )
    });
    Ok((m, warning))
}

/// The meridian cut at height `top` (the part above is removed).
fn clip_height(m: &Meridian, top: f64) -> Result<Meridian, ProfileError> {
    let mut out = Vec::new();
    for s in m.segments() {
        let (a, b) = (s.start(), s.end());
        if a[1] >= top && b[1] >= top {
            break;
        }
        if b[1] <= top {
            out.push(*s);
            continue;
        }
        match *s {
            Segment::Line { a, b } => {
                let f = (top - a[1]) / (b[1] - a[1]);
                out.push(Segment::Line {
                    a,
                    b: [a[0] + (b[0] - a[0]) * f, top],
                });
            }
            Segment::Arc {
                centre,
                radius,
                t0,
                t1,
            } => {
                let c = ((centre[1] - top) / radius).clamp(-1.0, 1.0).acos();
                let t = if t1 >= t0 {
                    [c, -c, c + TAU, -c + TAU]
                        .into_iter()
                        .filter(|t| *t >= t0 && *t <= t1)
                        .reduce(f64::min)
                } else {
                    [c, -c, c - TAU, -c - TAU]
                        .into_iter()
                        .filter(|t| *t <= t0 && *t >= t1)
                        .reduce(f64::max)
                };
                if let Some(t) = t {
                    out.push(Segment::Arc {
                        centre,
                        radius,
                        t0,
                        t1: t,
                    });
                }
            }
        }
        break;
    }
    Meridian::new(out, m.family().clone())
}

/// One point of `profile_mm`: (r, z) and, for an arc from the previous point, its signed
/// radius (positive: convex, bulging away from the axis side; negative: concave).
pub fn polyline(points: &[[f64; 3]]) -> Result<Meridian, ProfileError> {
    if points.len() < 2 {
        return err("`profile_mm` needs at least two points");
    }
    let mut segs = Vec::new();
    for (i, w) in points.windows(2).enumerate() {
        let (p, q) = ([w[0][0], w[0][1]], [w[1][0], w[1][1]]);
        let rho = w[1][2];
        let chord = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
        if chord < 1e-9 {
            return err(format!(
                "`profile_mm` points {} and {} coincide",
                i + 1,
                i + 2
            ));
        }
        if rho == 0.0 {
            segs.push(Segment::Line { a: p, b: q });
            continue;
        }
        let rr = rho.abs();
        if rr < 0.5 * chord - 1e-12 {
            return err(format!(
                "`profile_mm` point {}: the arc radius {rr} mm is shorter than half the chord ({:.6} mm)",
                i + 2,
                0.5 * chord
            ));
        }
        // Centre on the side of the chord: convex arcs bulge to the right of p → q
        // (away from the material), so the centre lies to the left.
        let (mx, mz) = (0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1]));
        let (tx, tz) = ((q[0] - p[0]) / chord, (q[1] - p[1]) / chord);
        let off = (rr * rr - 0.25 * chord * chord).max(0.0).sqrt();
        let sign = if rho > 0.0 { 1.0 } else { -1.0 };
        // Left normal of the chord: (−tz, tx).
        let c = [mx - tz * off * sign, mz + tx * off * sign];
        let ang = |x: [f64; 2]| (x[0] - c[0]).atan2(c[1] - x[1]);
        let t0 = ang(p);
        let mut t1 = ang(q);
        if rho > 0.0 {
            while t1 <= t0 {
                t1 += TAU;
            }
            while t1 - t0 > PI + 1e-9 {
                t1 -= TAU;
            }
        } else {
            while t1 >= t0 {
                t1 -= TAU;
            }
            while t0 - t1 > PI + 1e-9 {
                t1 += TAU;
            }
        }
        segs.push(Segment::Arc {
            centre: c,
            radius: rr,
            t0,
            t1,
        });
    }
    Meridian::new(segs, Family::Polyline)
}

/// Barrel: flat end, corner radius rc, then the segment arc of radius Rs whose widest point
/// (radius R) lies at `segment_height_mm` above the tip, symmetric about it.
pub fn barrel(
    radius_mm: f64,
    segment_radius_mm: f64,
    segment_height_mm: f64,
    corner_radius_mm: f64,
) -> Result<Meridian, ProfileError> {
    let (r, rs, zb, rc) = (
        radius_mm,
        segment_radius_mm,
        segment_height_mm,
        corner_radius_mm,
    );
    if !(rc > 0.0 && rs > rc && zb > rc && rs >= r) {
        return err(format!(
            "a barrel needs 0 < corner radius < segment height, segment radius ≥ R; found rc {rc}, height {zb}, Rs {rs}, R {r}"
        ));
    }
    let c = [r - rs, zb];
    let q = (rs - rc).powi(2) - (zb - rc).powi(2);
    let xc = c[0] + q.max(0.0).sqrt();
    if q < 0.0 || xc < 0.0 {
        return err(format!(
            "a barrel of R {r} mm with segment radius {rs} mm at height {zb} mm leaves no room for the corner radius {rc} mm"
        ));
    }
    let u = [(xc - c[0]) / (rs - rc), (rc - zb) / (rs - rc)];
    let tj = u[0].atan2(-u[1]);
    let mut s = Vec::new();
    if xc > 0.0 {
        s.push(Segment::Line {
            a: [0.0, 0.0],
            b: [xc, 0.0],
        });
    }
    s.push(Segment::Arc {
        centre: [xc, rc],
        radius: rc,
        t0: 0.0,
        t1: tj,
    });
    s.push(Segment::Arc {
        centre: c,
        radius: rs,
        t0: tj,
        t1: PI - tj,
    });
    let family = Family::Barrel {
        segment_radius_mm: rs,
        segment_height_mm: zb,
        corner_radius_mm: rc,
    };
    Meridian::new(s, family)
}

/// Lens: the segment arc of radius Rs across the end (centre on the axis at Rs), then the
/// corner radius rc up to the vertical at R.
pub fn lens(
    radius_mm: f64,
    segment_radius_mm: f64,
    corner_radius_mm: f64,
) -> Result<Meridian, ProfileError> {
    let (r, rs, rc) = (radius_mm, segment_radius_mm, corner_radius_mm);
    if !(rc > 0.0 && rc < r && rs > r) {
        return err(format!(
            "a lens needs 0 < corner radius < R < segment radius; found rc {rc}, R {r}, Rs {rs}"
        ));
    }
    let zc = rs - ((rs - rc).powi(2) - (r - rc).powi(2)).sqrt();
    let u = [(r - rc) / (rs - rc), (zc - rs) / (rs - rc)];
    let tj = u[0].atan2(-u[1]);
    let s = vec![
        Segment::Arc {
            centre: [0.0, rs],
            radius: rs,
            t0: 0.0,
            t1: tj,
        },
        Segment::Arc {
            centre: [r - rc, zc],
            radius: rc,
            t0: tj,
            t1: FRAC_PI_2,
        },
    ];
    let family = Family::Lens {
        segment_radius_mm: rs,
        corner_radius_mm: rc,
    };
    Meridian::new(s, family)
}

/// Oval: the tip radius rt about (0, rt), then the segment arc of radius Rs up to the
/// vertical at R (centre at (R − Rs, zs), tangent to the tip circle).
pub fn oval(
    radius_mm: f64,
    segment_radius_mm: f64,
    tip_radius_mm: f64,
) -> Result<Meridian, ProfileError> {
    let (r, rs, rt) = (radius_mm, segment_radius_mm, tip_radius_mm);
    if !(rt > 0.0 && rt < r && rs > r) {
        return err(format!(
            "an oval needs 0 < tip radius < R < segment radius; found rt {rt}, R {r}, Rs {rs}"
        ));
    }
    let q = (rs - rt).powi(2) - (rs - r).powi(2);
    if q <= 0.0 {
        return err(format!(
            "an oval of R {r} mm cannot join a tip radius {rt} mm to a segment radius {rs} mm"
        ));
    }
    let zs = rt + q.sqrt();
    let c = [r - rs, zs];
    // Internal tangency: the point on the segment circle in the direction of the tip centre.
    let d = [0.0 - c[0], rt - c[1]];
    let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
    let tj = (d[0] / len).atan2(-d[1] / len);
    let s = vec![
        Segment::Arc {
            centre: [0.0, rt],
            radius: rt,
            t0: 0.0,
            t1: tj,
        },
        Segment::Arc {
            centre: c,
            radius: rs,
            t0: tj,
            t1: FRAC_PI_2,
        },
    ];
    let family = Family::Oval {
        segment_radius_mm: rs,
        tip_radius_mm: rt,
    };
    Meridian::new(s, family)
}

/// Taper barrel: the tip radius rt about (0, rt) up to where its tangent makes the taper
/// angle τ with the axis, then the segment arc of radius Rs tangent to it up to the radius
/// R (the shank's cylinder above).
pub fn taper_barrel(
    radius_mm: f64,
    segment_radius_mm: f64,
    tip_radius_mm: f64,
    taper_deg: f64,
) -> Result<Meridian, ProfileError> {
    let (r, rs, rt) = (radius_mm, segment_radius_mm, tip_radius_mm);
    if !(rt > 0.0 && rt < r && rs > rt && taper_deg > 0.0 && taper_deg < 90.0) {
        return err(format!(
            "a taper barrel needs 0 < tip radius < R, segment radius > tip radius, 0 < taper < 90°; found rt {rt}, R {r}, Rs {rs}, taper {taper_deg}°"
        ));
    }
    let t0 = FRAC_PI_2 - taper_deg.to_radians();
    let p = arc_point([0.0, rt], rt, t0);
    let c = [p[0] - rs * t0.sin(), p[1] + rs * t0.cos()];
    let s1 = (r - c[0]) / rs;
    if s1 > 1.0 || s1 < t0.sin() {
        return err(format!(
            "a taper barrel with tip radius {rt} mm, taper {taper_deg}° and segment radius {rs} mm does not reach the radius {r} mm before turning back"
        ));
    }
    let t1 = s1.asin();
    let s = vec![
        Segment::Arc {
            centre: [0.0, rt],
            radius: rt,
            t0: 0.0,
            t1: t0,
        },
        Segment::Arc {
            centre: c,
            radius: rs,
            t0,
            t1,
        },
    ];
    let family = Family::TaperBarrel {
        segment_radius_mm: rs,
        tip_radius_mm: rt,
        taper_deg,
    };
    Meridian::new(s, family)
}
