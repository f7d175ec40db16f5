//! The cutter body of revolution and its helical edges with run-out.

use super::meridian::{self, Meridian, ProfileError};
use crate::math::Vec3;
use std::f64::consts::TAU;

/// The shape of the end of the tool.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// Ball end of radius R (002).
    Ball,
    /// Filleted (torus, bull-nose) end with corner radius rc < R (000, 001).
    Torus {
        /// Corner radius rc, mm.
        corner_radius_mm: f64,
    },
    /// Flat end.
    Flat,
    /// Round-insert face mill: the insert circle of radius ri about (R − ri, ri) cuts with
    /// its whole lower half, the inner flank included (unlike a torus, which has a flat end
    /// inside its corner).
    RoundInsert {
        /// Insert radius ri, mm.
        insert_radius_mm: f64,
    },
    /// Any other body of revolution, by its meridian: APT seven-parameter cutters,
    /// `profile_mm` polylines and arc lists, the circle-segment families.
    Profile(Meridian),
}

impl Shape {
    /// The `shape` name of `tool.toml` (`ball`, `torus`, `flat`, `round_insert`, `apt`,
    /// `profile`, `barrel`, `lens`, `oval`, `taper_barrel`).
    pub fn name(&self) -> &'static str {
        match self {
            Shape::Ball => "ball",
            Shape::Torus { .. } => "torus",
            Shape::Flat => "flat",
            Shape::RoundInsert { .. } => "round_insert",
            Shape::Profile(m) => m.family().name(),
        }
    }

    /// Ball, torus or flat end: the shapes with closed forms everywhere.
    pub fn is_classic(&self) -> bool {
        matches!(self, Shape::Ball | Shape::Torus { .. } | Shape::Flat)
    }
}

/// Run-out parameters of model.md §3.1, in mm and radians.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Runout {
    /// e0: eccentricity of the tool axis at the tip, mm.
    pub offset_mm: f64,
    /// φ_e: direction of the offset in the spindle-fixed frame, rad (like θ, from tooth 1).
    pub offset_phase_rad: f64,
    /// τ: tilt of the tool axis against the spindle axis, rad.
    pub tilt_rad: f64,
    /// φ_τ: direction of the tilt, rad.
    pub tilt_phase_rad: f64,
    /// δ_j: per-tooth radial deviation, mm (empty = all zero).
    pub tooth_radius_dev_mm: Vec<f64>,
    /// ε_j: per-tooth axial deviation, mm; positive lifts the tooth toward the shank
    /// (empty = all zero).
    pub tooth_axial_dev_mm: Vec<f64>,
}

/// A milling cutter: body of revolution, teeth and run-out.
#[derive(Debug, Clone, PartialEq)]
pub struct Cutter {
    /// End shape.
    pub shape: Shape,
    /// Nominal tool radius R, mm.
    pub radius_mm: f64,
    /// Helix angle α, rad (0 = straight edges).
    pub helix_rad: f64,
    /// Angular position of each tooth at the tip, rad, in cutting order: tooth j trails
    /// tooth 1 by `pitch_rad[j]` (`pitch_rad[0] = 0`). Its length is the number of teeth.
    pub pitch_rad: Vec<f64>,
    /// Run-out.
    pub runout: Runout,
}

/// 002 Eq 14: the crest between two circles of radius `radius_mm` whose centres are
/// `spacing_mm` apart, `R − √(R² − s²/4)`, mm.
pub fn crest_height_mm(radius_mm: f64, spacing_mm: f64) -> f64 {
    let half = 0.5 * spacing_mm;
    if half >= radius_mm {
        return radius_mm;
    }
    // R − √(R² − h²) written without cancellation.
    half * half / (radius_mm + (radius_mm * radius_mm - half * half).sqrt())
}

/// The edge direction of spindle angle θ in the tool frame: `d(θ) = (sin θ, cos θ, 0)`.
pub fn direction(theta: f64) -> Vec3 {
    let (s, c) = theta.sin_cos();
    Vec3::new(s, c, 0.0)
}

impl Cutter {
    /// A cutter with `teeth` evenly spaced teeth and no run-out.
    pub fn new(shape: Shape, radius_mm: f64, teeth: usize, helix_rad: f64) -> Cutter {
        let pitch_rad = (0..teeth).map(|j| TAU * j as f64 / teeth as f64).collect();
        Cutter {
            shape,
            radius_mm,
            helix_rad,
            pitch_rad,
            runout: Runout::default(),
        }
    }

    /// A cutter with teeth at the given angular positions at the tip (degrees, in cutting
    /// order, the first 0): uneven pitch. No run-out.
    pub fn with_pitch_deg(
        shape: Shape,
        radius_mm: f64,
        pitch_deg: &[f64],
        helix_rad: f64,
    ) -> Cutter {
        Cutter {
            shape,
            radius_mm,
            helix_rad,
            pitch_rad: pitch_deg.iter().map(|a| a.to_radians()).collect(),
            runout: Runout::default(),
        }
    }

    /// A cutter of the given meridian (radius = its largest radius) with `teeth` evenly
    /// spaced teeth and no run-out.
    pub fn from_meridian(meridian: Meridian, teeth: usize, helix_rad: f64) -> Cutter {
        let r = meridian.r_max();
        Cutter::new(Shape::Profile(meridian), r, teeth, helix_rad)
    }

    /// The same cutter with nominal radius `radius_mm` (a torus keeps its corner radius and
    /// a round insert its insert radius, clamped to the new radius; a profile moves
    /// outward). Used for per-tooth radii (002 Table 3).
    pub fn with_radius(&self, radius_mm: f64) -> Cutter {
        let shape = match &self.shape {
            Shape::Torus { corner_radius_mm } => Shape::Torus {
                corner_radius_mm: corner_radius_mm.min(radius_mm),
            },
            Shape::RoundInsert { insert_radius_mm } => Shape::RoundInsert {
                insert_radius_mm: insert_radius_mm.min(radius_mm),
            },
            Shape::Profile(m) => m
                .shifted_radially(radius_mm - self.radius_mm)
                .map_or_else(|_| self.shape.clone(), Shape::Profile),
            s => s.clone(),
        };
        Cutter {
            shape,
            radius_mm,
            ..self.clone()
        }
    }

    /// Polar angle κ(z) of the end profile at height z: the angle between the axis and the
    /// outward normal of the corner arc (ball: κ = acos(1 − z/R)); 0 on a flat end face,
    /// π/2 on the cylinder above the end.
    pub fn kappa_at(&self, z_mm: f64) -> f64 {
        let rc = self.corner_radius_mm();
        if z_mm <= 0.0 || rc <= 0.0 {
            return if z_mm > 0.0 {
                std::f64::consts::FRAC_PI_2
            } else {
                0.0
            };
        }
        if z_mm >= rc {
            return std::f64::consts::FRAC_PI_2;
        }
        (1.0 - z_mm / rc).clamp(-1.0, 1.0).acos()
    }

    /// Radial run-out ρ_j(z) = r_j(z) − r(z) of tooth `j` (0-based) at height z (Eq 6).
    pub fn runout_mm(&self, j: usize, z_mm: f64) -> f64 {
        self.tooth_radius(j, z_mm) - self.profile_radius(z_mm)
    }

    /// Number of teeth Z.
    pub fn teeth(&self) -> usize {
        self.pitch_rad.len()
    }

    /// Corner radius: R for a ball, rc for a torus, 0 for a flat end, the insert radius of
    /// a round insert; for a profile its corner or tip radius (APT r, a barrel's or lens's
    /// corner, an oval's or taper barrel's tip; 0 for `profile_mm`).
    pub fn corner_radius_mm(&self) -> f64 {
        match &self.shape {
            Shape::Ball => self.radius_mm,
            Shape::Torus { corner_radius_mm } => *corner_radius_mm,
            Shape::Flat => 0.0,
            Shape::RoundInsert { insert_radius_mm } => *insert_radius_mm,
            Shape::Profile(m) => match m.family() {
                meridian::Family::Apt(p) => p[1],
                meridian::Family::Barrel {
                    corner_radius_mm, ..
                }
                | meridian::Family::Lens {
                    corner_radius_mm, ..
                } => *corner_radius_mm,
                meridian::Family::Oval { tip_radius_mm, .. }
                | meridian::Family::TaperBarrel { tip_radius_mm, .. } => *tip_radius_mm,
                meridian::Family::Classic | meridian::Family::Polyline => 0.0,
            },
        }
    }

    /// Height of the end above the tip, mm: where the body becomes its side (R for a ball,
    /// rc for a torus, 0 for a flat end, ri for a round insert; for a profile where its last
    /// straight side starts, else its top).
    pub fn end_height_mm(&self) -> f64 {
        match &self.shape {
            Shape::Profile(m) => m.end_height(),
            _ => self.corner_radius_mm(),
        }
    }

    /// The smallest radius of the body's profile, mm (0 unless a round insert's inner flank
    /// or a profile starts off the axis).
    pub fn min_radius_mm(&self) -> f64 {
        match &self.shape {
            Shape::RoundInsert { insert_radius_mm } => {
                (self.radius_mm - 2.0 * insert_radius_mm).max(0.0)
            }
            Shape::Profile(m) => m.r_min(),
            _ => 0.0,
        }
    }

    /// Radius of the flat end face at z = 0, mm (R − rc for a torus or flat end, 0 for a
    /// ball or round insert; for a profile the length of a first horizontal line from the
    /// axis).
    pub fn flat_end_radius_mm(&self) -> f64 {
        match &self.shape {
            Shape::RoundInsert { .. } => 0.0,
            Shape::Profile(m) => match m.segments().first() {
                Some(meridian::Segment::Line { a, b })
                    if a[0] <= 1e-12 && a[1].abs() <= 1e-12 && b[1].abs() <= 1e-12 =>
                {
                    b[0]
                }
                _ => 0.0,
            },
            _ => (self.radius_mm - self.corner_radius_mm()).max(0.0),
        }
    }

    /// The meridian of the body (built for the classic shapes and round inserts).
    pub fn meridian(&self) -> Result<Meridian, ProfileError> {
        match &self.shape {
            Shape::Profile(m) => Ok(m.clone()),
            Shape::RoundInsert { insert_radius_mm } => {
                meridian::round_insert(self.radius_mm, *insert_radius_mm)
            }
            _ => meridian::classic(self.radius_mm, self.corner_radius_mm()),
        }
    }

    /// Nominal local radius r(z) of the body at height `z_mm` above the tip (R above the end;
    /// the outer flank of a round insert). Negative heights give the radius at the tip.
    pub fn profile_radius(&self, z_mm: f64) -> f64 {
        if let Shape::Profile(m) = &self.shape {
            return m.radius_at(z_mm);
        }
        if z_mm <= 0.0 {
            return if matches!(self.shape, Shape::Ball) {
                0.0
            } else {
                self.radius_mm - self.corner_radius_mm()
            };
        }
        let rc = self.corner_radius_mm();
        if z_mm >= rc {
            return self.radius_mm;
        }
        let flat_radius = self.radius_mm - rc;
        flat_radius + (z_mm * (2.0 * rc - z_mm)).sqrt()
    }

    /// Lowest height h(r) of the body at radial distance `r_mm` from the axis, or `None`
    /// beyond the tool radius.
    pub fn profile_height(&self, r_mm: f64) -> Option<f64> {
        if !(0.0..=self.radius_mm).contains(&r_mm) {
            return None;
        }
        if let Shape::Profile(m) = &self.shape {
            return m.height_at(r_mm);
        }
        let rc = self.corner_radius_mm();
        let flat_radius = self.radius_mm - rc;
        if r_mm <= flat_radius {
            if matches!(self.shape, Shape::RoundInsert { .. }) {
                // The inner flank of the insert circle.
                let u = flat_radius - r_mm;
                if u > rc {
                    return None;
                }
                return Some(u * u / (rc + (rc * rc - u * u).max(0.0).sqrt()));
            }
            return Some(0.0);
        }
        let u = r_mm - flat_radius;
        // rc − √(rc² − u²), without cancellation.
        Some(u * u / (rc + (rc * rc - u * u).max(0.0).sqrt()))
    }

    /// Helix lag φ(z) = z tan α / R (002 Eqs 3-4, constant lead on the cylinder of radius R).
    pub fn helix_lag(&self, z_mm: f64) -> f64 {
        z_mm * self.helix_rad.tan() / self.radius_mm
    }

    /// Spindle-fixed angle ψ_j(z) = −pitch_j − φ(z) of tooth `j` (0-based) at height z.
    pub fn tooth_angle(&self, j: usize, z_mm: f64) -> f64 {
        -self.pitch_rad[j] - self.helix_lag(z_mm)
    }

    /// Per-tooth radial deviation δ_j, mm.
    pub fn tooth_dev_mm(&self, j: usize) -> f64 {
        self.runout
            .tooth_radius_dev_mm
            .get(j)
            .copied()
            .unwrap_or(0.0)
    }

    /// Per-tooth axial deviation ε_j, mm (positive: lifted toward the shank).
    pub fn tooth_axial_dev_mm(&self, j: usize) -> f64 {
        self.runout
            .tooth_axial_dev_mm
            .get(j)
            .copied()
            .unwrap_or(0.0)
    }

    /// Whether any tooth has an axial deviation.
    pub fn has_axial_dev(&self) -> bool {
        self.runout.tooth_axial_dev_mm.iter().any(|&e| e != 0.0)
    }

    /// Radial run-out ρ_j(z) of tooth `j` at height z without the profile (offset, tilt and
    /// δ_j), mm: the same as [`Cutter::runout_mm`] for any local radius.
    pub fn radial_runout_mm(&self, j: usize, z_mm: f64) -> f64 {
        let psi = self.tooth_angle(j, z_mm);
        let r = &self.runout;
        r.offset_mm * (psi - r.offset_phase_rad).cos()
            + z_mm * r.tilt_rad.tan() * (psi - r.tilt_phase_rad).cos()
            + self.tooth_dev_mm(j)
    }

    /// Offset of the tool axis from the spindle axis at height z, in the spindle-fixed frame
    /// (angle 0 = tooth 1 at the tip), as a vector in the plane normal to the axis.
    pub fn axis_offset(&self, z_mm: f64, theta: f64) -> Vec3 {
        let r = &self.runout;
        direction(theta + r.offset_phase_rad) * r.offset_mm
            + direction(theta + r.tilt_phase_rad) * (z_mm * r.tilt_rad.tan())
    }

    /// Radial form of the run-out (model.md Eq 5-6): r_j(z) = r(z) + ρ_j(z).
    pub fn tooth_radius(&self, j: usize, z_mm: f64) -> f64 {
        let psi = self.tooth_angle(j, z_mm);
        let r = &self.runout;
        self.profile_radius(z_mm)
            + r.offset_mm * (psi - r.offset_phase_rad).cos()
            + z_mm * r.tilt_rad.tan() * (psi - r.tilt_phase_rad).cos()
            + self.tooth_dev_mm(j)
    }

    /// ICE point of tooth `j` at height z for spindle angle θ, in the tool frame, using the
    /// unlinearised vector form `c(z) + (r(z) + δ_j) d(θ + ψ_j(z)) + z ẑ` (model.md §3.1).
    /// The tooth's axial deviation ε_j lifts the point along the axis.
    pub fn edge_point(&self, j: usize, z_mm: f64, theta: f64) -> Vec3 {
        self.edge_point_at(j, self.profile_radius(z_mm), z_mm, theta)
    }

    /// [`Cutter::edge_point`] at the profile point of local radius `r_mm` and height `z_mm`
    /// (any point of the meridian: a round insert's inner flank, a profile's).
    pub fn edge_point_at(&self, j: usize, r_mm: f64, z_mm: f64, theta: f64) -> Vec3 {
        let dir = direction(theta + self.tooth_angle(j, z_mm));
        let radial = (r_mm + self.tooth_dev_mm(j)) * dir;
        let mut p = self.axis_offset(z_mm, theta) + radial + Vec3::new(0.0, 0.0, z_mm);
        let eps = self.tooth_axial_dev_mm(j);
        if eps != 0.0 {
            p.z += eps;
        }
        p
    }

    /// A one-line description: `ball end R 5 mm`, `round insert R 10 mm, insert radius 5 mm`, …
    pub fn describe(&self) -> String {
        // At most six decimals: an APT cutter's R is derived and has many.
        let r = format!("{:.6}", self.radius_mm)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string();
        match &self.shape {
            Shape::Ball => format!("ball end R {r} mm"),
            Shape::Torus { corner_radius_mm } => {
                format!("bull nose R {r} mm, corner radius {corner_radius_mm} mm")
            }
            Shape::Flat => format!("flat end R {r} mm"),
            Shape::RoundInsert { insert_radius_mm } => {
                format!("round insert R {r} mm, insert radius {insert_radius_mm} mm")
            }
            Shape::Profile(m) => match m.family() {
                meridian::Family::Apt(p) => format!(
                    "APT cutter d {}, r {}, e {}, f {}, a {}°, b {}°, h {} (R {r} mm)",
                    p[0], p[1], p[2], p[3], p[4], p[5], p[6]
                ),
                meridian::Family::Polyline | meridian::Family::Classic => {
                    format!("profile of {} segments, R {r} mm", m.segments().len())
                }
                meridian::Family::Barrel {
                    segment_radius_mm,
                    segment_height_mm,
                    corner_radius_mm,
                } => format!(
                    "barrel R {r} mm, segment radius {segment_radius_mm} mm at {segment_height_mm} mm, corner radius {corner_radius_mm} mm"
                ),
                meridian::Family::Lens {
                    segment_radius_mm,
                    corner_radius_mm,
                } => format!(
                    "lens R {r} mm, segment radius {segment_radius_mm} mm, corner radius {corner_radius_mm} mm"
                ),
                meridian::Family::Oval {
                    segment_radius_mm,
                    tip_radius_mm,
                } => format!(
                    "oval R {r} mm, segment radius {segment_radius_mm} mm, tip radius {tip_radius_mm} mm"
                ),
                meridian::Family::TaperBarrel {
                    segment_radius_mm,
                    tip_radius_mm,
                    taper_deg,
                } => format!(
                    "taper barrel R {r} mm, segment radius {segment_radius_mm} mm, tip radius {tip_radius_mm} mm, taper {taper_deg}°"
                ),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn crest_height_matches_model_r2() {
        // model.md R2: hc(0.05) = 0.0625004 µm, hc(0.2) = 1.0001000 µm for R = 5.
        assert_relative_eq!(crest_height_mm(5.0, 0.05) * 1e3, 0.0625004, epsilon = 1e-6);
        assert_relative_eq!(crest_height_mm(5.0, 0.2) * 1e3, 1.0001000, epsilon = 1e-6);
        assert_relative_eq!(crest_height_mm(5.0, 0.1) * 1e3, 0.250006, epsilon = 1e-6);
    }

    #[test]
    fn ball_edge_lies_on_dome_without_runout() {
        let c = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        for &z in &[0.1, 1.0, 2.5, 4.9] {
            let p = c.edge_point(2, z, 0.7);
            let centre = Vec3::new(0.0, 0.0, 5.0);
            assert_relative_eq!((p - centre).norm(), 5.0, epsilon = 1e-12);
        }
        // The lag at κ = 90° is tan 30° rad = 33.08°.
        assert_relative_eq!(c.helix_lag(5.0).to_degrees(), 33.0797, epsilon = 1e-4);
    }

    #[test]
    fn torus_profile_inverts() {
        let c = Cutter::new(
            Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            1,
            0.0,
        );
        for &z in &[0.01, 0.5, 1.0, 1.49] {
            let r = c.profile_radius(z);
            assert_relative_eq!(c.profile_height(r).unwrap(), z, epsilon = 1e-9);
        }
        assert_eq!(c.profile_height(3.0), Some(0.0));
    }
}
