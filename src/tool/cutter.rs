//! The cutter body of revolution and its helical edges with run-out.

use crate::math::Vec3;
use std::f64::consts::TAU;

/// The shape of the end of the tool.
#[derive(Debug, Clone, Copy, PartialEq)]
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

    /// The same cutter with nominal radius `radius_mm` (a torus keeps its corner radius,
    /// clamped to the new radius). Used for per-tooth radii (002 Table 3).
    pub fn with_radius(&self, radius_mm: f64) -> Cutter {
        let shape = match self.shape {
            Shape::Torus { corner_radius_mm } => Shape::Torus {
                corner_radius_mm: corner_radius_mm.min(radius_mm),
            },
            s => s,
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

    /// Corner radius: R for a ball, rc for a torus, 0 for a flat end.
    pub fn corner_radius_mm(&self) -> f64 {
        match self.shape {
            Shape::Ball => self.radius_mm,
            Shape::Torus { corner_radius_mm } => corner_radius_mm,
            Shape::Flat => 0.0,
        }
    }

    /// Nominal local radius r(z) of the body at height `z_mm` above the tip (R above the end).
    /// Negative heights give 0.
    pub fn profile_radius(&self, z_mm: f64) -> f64 {
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
        let rc = self.corner_radius_mm();
        let flat_radius = self.radius_mm - rc;
        if r_mm <= flat_radius {
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
    pub fn edge_point(&self, j: usize, z_mm: f64, theta: f64) -> Vec3 {
        let dir = direction(theta + self.tooth_angle(j, z_mm));
        let radial = (self.profile_radius(z_mm) + self.tooth_dev_mm(j)) * dir;
        self.axis_offset(z_mm, theta) + radial + Vec3::new(0.0, 0.0, z_mm)
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
