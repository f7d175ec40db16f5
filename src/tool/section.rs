//! The feed-direction section of a cutter on a plane, and the exact one-dimensional crest
//! of the marks that several teeth leave (model.md §3.2 "exact mode", §4, §7).
//!
//! With the tool tilted by the lead β in the feed plane, the section of the swept body by
//! the plane through the axis and the feed direction is the meridian section of the body of
//! revolution, rotated by β. Its lower boundary is the tooth's profile in the feed
//! direction. Each tooth leaves that profile once per revolution, at `(pitch_j/2π)·Z·fz +
//! k·Z·fz`, lowered by its run-out along the surface normal; the surface is the lower
//! envelope of all of them and the crest height is its peak-to-valley height.
//!
//! For a ball end the profile is a circle, and the tooth of normal deviation Δ_j is the
//! circle of radius R + Δ_j about the same centre (the oracle's convention, which is what a
//! presetter radius means). The envelope is then computed in closed form from the pairwise
//! intersections. For torus and flat ends the profile is the rotated section (two corner
//! circles, the end face and the front wall), lowered by Δ_j, and the envelope is sampled and
//! its peak refined by golden-section search. Round inserts and profiles use the exact
//! section of their meridian's segments ([`super::meridian::Section`]) the same way.

use super::Cutter;
use super::meridian::Section;
use std::f64::consts::FRAC_PI_2;
use std::sync::Arc as Shared;

/// The lower boundary of a cutter's meridian section tilted by the lead, in the plane
/// (u along the feed, v along the surface normal), with its lowest point at the origin.
#[derive(Debug, Clone, PartialEq)]
pub enum FeedProfile {
    /// A circle of the given radius (ball end): the exact closed-form path.
    Circle {
        /// Radius, mm.
        radius_mm: f64,
    },
    /// A filleted or flat end: flat-end radius Rd, corner radius rc, lead β ≥ 0.
    Section {
        /// Radius of the flat end face Rd = R − rc, mm.
        flat_radius_mm: f64,
        /// Corner radius rc, mm (0 for a flat end).
        corner_radius_mm: f64,
        /// Lead β, rad, in [0, π/2].
        lead_rad: f64,
    },
    /// Any other meridian (round inserts, profiles): its exact section.
    Meridian(Shared<Section>),
}

/// Stable `r − √(r² − d²)` for |d| ≤ r; +∞ beyond.
fn sag(radius: f64, d: f64) -> f64 {
    let q = radius * radius - d * d;
    if q < 0.0 {
        return f64::INFINITY;
    }
    d * d / (radius + q.sqrt())
}

impl FeedProfile {
    /// Height of the profile above its lowest point at feed position `u` (mm), +∞ where the
    /// tool does not reach.
    pub fn height(&self, u: f64) -> f64 {
        match *self {
            FeedProfile::Meridian(ref section) => section.height(u),
            FeedProfile::Circle { radius_mm } => sag(radius_mm, u),
            FeedProfile::Section {
                flat_radius_mm: rd,
                corner_radius_mm: rc,
                lead_rad: b,
            } => {
                let (sb, cb) = b.sin_cos();
                let rot = |x: f64, z: f64| (x * cb + z * sb, -x * sb + z * cb);
                // Lowest point: on the front corner circle, where its normal is −n.
                let (ufc, vfc) = rot(rd, rc);
                let (u_low, v_low) = (ufc, vfc - rc);
                let u = u + u_low;
                let mut best = f64::INFINITY;
                for (uc, vc) in [rot(rd, rc), rot(-rd, rc)] {
                    let s = sag(rc, u - uc);
                    if s.is_finite() {
                        best = best.min(vc - rc + s - v_low);
                    }
                }
                // End face z = 0 between −Rd and Rd: v = −u tan β.
                let (u0, u1) = (-rd * cb, rd * cb);
                if u >= u0 && u <= u1 {
                    best = best.min(-u * b.tan() - v_low);
                }
                // Front wall x = R, z ≥ rc: rises with slope cot β ahead of the corner.
                if b > 1e-12 {
                    let (uw, vw) = rot(rd + rc, rc);
                    if u >= uw {
                        best = best.min(vw + (u - uw) * cb / sb - v_low);
                    }
                }
                best.max(0.0)
            }
        }
    }
}

/// The profile of a cutter with end shape (corner radius `corner_radius_mm`, nominal radius
/// `radius_mm`) at lead `lead_rad`; a ball (corner = radius) gives the closed-form circle.
pub fn feed_profile(radius_mm: f64, corner_radius_mm: f64, lead_rad: f64) -> FeedProfile {
    if (corner_radius_mm - radius_mm).abs() <= 1e-15 * radius_mm.max(1.0) {
        FeedProfile::Circle { radius_mm }
    } else {
        FeedProfile::Section {
            flat_radius_mm: (radius_mm - corner_radius_mm).max(0.0),
            corner_radius_mm,
            lead_rad: lead_rad.abs().min(FRAC_PI_2),
        }
    }
}

/// The feed profile of any cutter at lead `lead_rad`: [`feed_profile`] for ball, torus and
/// flat ends, the section of the meridian for round inserts and profiles.
pub fn feed_profile_for(cutter: &Cutter, lead_rad: f64) -> FeedProfile {
    if !cutter.shape.is_classic()
        && let Ok(m) = cutter.meridian()
    {
        return FeedProfile::Meridian(Shared::new(Section::new(&m, lead_rad.abs().min(FRAC_PI_2))));
    }
    feed_profile(cutter.radius_mm, cutter.corner_radius_mm(), lead_rad)
}

/// The lower envelope of the marks of several teeth: who cuts, and the crest height.
#[derive(Debug, Clone, PartialEq)]
pub struct Envelope {
    /// For each tooth, whether its profile is on the envelope over a non-empty interval.
    pub participates: Vec<bool>,
    /// Peak-to-valley height of the envelope (the exact crest height), mm.
    pub crest_mm: f64,
    /// Feed positions (mm, within one period) where the envelope peaks.
    pub peak_u_mm: f64,
}

/// Width below which an envelope segment is taken as a touch, not a cut, mm.
const MIN_SEGMENT_MM: f64 = 1e-12;

/// Exact envelope of teeth marks on a plane.
///
/// * `profile`: the nominal feed profile (see [`feed_profile`]);
/// * `positions_mm[j]`: the mark of tooth j within the period, in [0, period);
/// * `deviation_mm[j]`: how far tooth j reaches below nominal along the surface normal;
/// * `period_mm`: the feed per revolution Z·fz.
///
/// For a circle the tooth profile is the circle of radius R + Δ_j; otherwise the nominal
/// profile lowered by Δ_j.
pub fn envelope(
    profile: &FeedProfile,
    positions_mm: &[f64],
    deviation_mm: &[f64],
    period_mm: f64,
) -> Envelope {
    let n = positions_mm.len().min(deviation_mm.len());
    if n == 0 || period_mm.is_nan() || period_mm <= 0.0 {
        return Envelope {
            participates: vec![true; n],
            crest_mm: 0.0,
            peak_u_mm: 0.0,
        };
    }
    match *profile {
        FeedProfile::Circle { radius_mm } => {
            circle_envelope(radius_mm, &positions_mm[..n], &deviation_mm[..n], period_mm)
        }
        _ => sampled_envelope(profile, &positions_mm[..n], &deviation_mm[..n], period_mm),
    }
}

struct Arc {
    tooth: usize,
    x: f64,
    dev: f64,
    radius: f64,
}

impl Arc {
    fn height(&self, x: f64) -> f64 {
        -self.dev + sag(self.radius, x - self.x)
    }
}

fn circle_envelope(radius: f64, pos: &[f64], dev: &[f64], period: f64) -> Envelope {
    let n = pos.len();
    let mut arcs = Vec::with_capacity(3 * n);
    for k in [-1.0, 0.0, 1.0] {
        for j in 0..n {
            arcs.push(Arc {
                tooth: j,
                x: pos[j].rem_euclid(period) + k * period,
                dev: dev[j],
                radius: (radius + dev[j]).max(0.0),
            });
        }
    }
    let mut cuts = vec![0.0, period];
    for (a, arc_a) in arcs.iter().enumerate() {
        for arc_b in &arcs[a + 1..] {
            let dx = arc_b.x - arc_a.x;
            if dx.abs() < 1e-15 {
                continue;
            }
            // R_a² − (x − x_a)² = R_b² − (x − x_b)².
            let x = 0.5 * (arc_a.x + arc_b.x)
                + (arc_a.dev - arc_b.dev) * (arc_a.radius + arc_b.radius) / (2.0 * dx);
            if x > 0.0 && x < period {
                cuts.push(x);
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    let lowest = |x: f64| {
        let mut best = (f64::INFINITY, usize::MAX);
        for arc in &arcs {
            let h = arc.height(x);
            if h < best.0 {
                best = (h, arc.tooth);
            }
        }
        best
    };
    let mut participates = vec![false; n];
    for w in cuts.windows(2) {
        if w[1] - w[0] > MIN_SEGMENT_MM {
            let (_, tooth) = lowest(0.5 * (w[0] + w[1]));
            if tooth < n {
                participates[tooth] = true;
            }
        }
    }
    let (mut top, mut top_x) = (f64::NEG_INFINITY, 0.0);
    for &x in &cuts {
        let (h, _) = lowest(x);
        if h > top {
            top = h;
            top_x = x;
        }
    }
    let bottom = -dev.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let crest = if top.is_finite() {
        top - bottom
    } else {
        radius + dev.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    };
    Envelope {
        participates,
        crest_mm: crest,
        peak_u_mm: top_x,
    }
}

/// Samples per period of the sampled envelope (torus and flat ends).
const SAMPLES_PER_PERIOD: usize = 8192;

fn sampled_envelope(profile: &FeedProfile, pos: &[f64], dev: &[f64], period: f64) -> Envelope {
    let n = pos.len();
    let eval = |u: f64| {
        let mut best = (f64::INFINITY, usize::MAX);
        for j in 0..n {
            let p = pos[j].rem_euclid(period);
            for k in [-1.0, 0.0, 1.0] {
                let h = profile.height(u - p - k * period) - dev[j];
                if h < best.0 {
                    best = (h, j);
                }
            }
        }
        best
    };
    let step = period / SAMPLES_PER_PERIOD as f64;
    let mut participates = vec![false; n];
    let (mut top, mut top_i) = (f64::NEG_INFINITY, 0usize);
    for i in 0..SAMPLES_PER_PERIOD {
        let (h, j) = eval(i as f64 * step);
        if j < n {
            participates[j] = true;
        }
        if h > top {
            top = h;
            top_i = i;
        }
    }
    // Also count each tooth whose own lowest point is on the envelope (narrow segments).
    for j in 0..n {
        let (_, owner) = eval(pos[j].rem_euclid(period));
        if owner == j {
            participates[j] = true;
        }
    }
    // Golden-section refinement of the peak (min of a falling and a rising profile).
    let (mut a, mut b) = ((top_i as f64 - 1.0) * step, (top_i as f64 + 1.0) * step);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..80 {
        let c = b - g * (b - a);
        let d = a + g * (b - a);
        if eval(c).0 > eval(d).0 {
            b = d;
        } else {
            a = c;
        }
    }
    let peak_u = 0.5 * (a + b);
    let refined = eval(peak_u).0;
    let top = top.max(refined);
    let bottom = -dev.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Envelope {
        participates,
        crest_mm: if top.is_finite() {
            top - bottom
        } else {
            f64::INFINITY
        },
        peak_u_mm: peak_u.rem_euclid(period),
    }
}

/// Crest height of one nominal tooth whose marks are `spacing_mm` apart (Eq 14 for a ball;
/// the section envelope for torus and flat ends), mm.
pub fn nominal_crest_mm(profile: &FeedProfile, spacing_mm: f64) -> f64 {
    match *profile {
        FeedProfile::Circle { radius_mm } => super::crest_height_mm(radius_mm, spacing_mm),
        _ => envelope(profile, &[0.0], &[0.0], spacing_mm).crest_mm,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn circle_envelope_of_one_tooth_is_eq14() {
        let p = feed_profile(5.0, 5.0, 0.3);
        let e = envelope(&p, &[0.0], &[0.0], 0.2);
        assert_relative_eq!(e.crest_mm * 1e3, 1.0001000, epsilon = 1e-7);
        assert_relative_eq!(e.peak_u_mm, 0.1, epsilon = 1e-12);
    }

    #[test]
    fn torus_feed_marks_match_model_section7() {
        // model.md §7: R 5, rc 1.5; tilt 10° gives fz²/(8 rc) = 5.9 µm at fz 0.267;
        // tilt 1° gives about 3.0 µm at 0.267 and 1.3 µm at 0.133 (end face behind).
        let p10 = feed_profile(5.0, 1.5, 10f64.to_radians());
        let h10 = nominal_crest_mm(&p10, 0.26667) * 1e3;
        assert_relative_eq!(
            h10,
            super::super::crest_height_mm(1.5, 0.26667) * 1e3,
            epsilon = 1e-6
        );
        assert!((h10 - 5.9).abs() < 0.05, "{h10}");
        // Tilt 1°: model.md says "about 3.0 µm at 0.267 and 1.3 µm at 0.133"; those figures
        // take the end-face line through the lowest point. The exact section puts the end
        // face behind the short corner arc (rc sin β back, rc(1 − cos β) up), 0.18 µm lower.
        let b = 1f64.to_radians();
        let p1 = feed_profile(5.0, 1.5, b);
        let rc = 1.5;
        for (s, about) in [(0.26667, 3.0), (0.13333, 1.3)] {
            let h = nominal_crest_mm(&p1, s) * 1e3;
            assert!((h - about).abs() < 0.25, "{h} vs about {about}");
            // Closed form: circle sag(rc, u) meets the next mark's end face
            // v = rc(1 − 1/cos β) + (s − u) tan β.
            let c0 = rc * (1.0 - 1.0 / b.cos());
            let t = b.tan();
            let mut u = 0.5 * s;
            for _ in 0..60 {
                let f = sag(rc, u) - c0 - (s - u) * t;
                let df = u / (rc * rc - u * u).sqrt() + t;
                u -= f / df;
            }
            assert_relative_eq!(h, sag(rc, u) * 1e3, epsilon = 1e-3);
        }
    }

    #[test]
    fn flat_end_v_notch() {
        // Flat end at lead β: end face behind (slope tan β), wall ahead (slope cot β):
        // crest = s sin β cos β.
        let b = 20f64.to_radians();
        let p = feed_profile(5.0, 0.0, b);
        let h = nominal_crest_mm(&p, 0.2);
        assert_relative_eq!(h, 0.2 * b.sin() * b.cos(), epsilon = 1e-9);
    }
}
