//! The stepover direction and the areal surface of a regression case: the scallop profile
//! across the passes, and Sa, Sz of the surface it makes with the feed-direction profile.
//!
//! Across the passes a ball end of radius R leaves circular arcs of radius R spaced by the
//! stepover ae (on a plane; the curvature of a case applies to the feed direction only). Its
//! Rz and Ra are computed as the feed direction's ([`super::regression::profile_roughness`]:
//! 5 sampling lengths λc chosen by ISO 4288 from RSm = ae, no filter).
//!
//! The areal surface is z(x, y) = f(x) + g(y): f the case's evaluated feed-direction profile
//! (crest or simulate model), g the scallop profile. For a ball end this is the lower
//! envelope of the tool's marks to second order (near its lowest point a sphere is the
//! paraboloid (x² + y²)/2R, whose lower envelope over a lattice of centres separates into a
//! sum). Sa, Sq and Sz are computed on it by [`crate::metrics::height_stats`] (mean plane
//! removed, no filter) and Sdq by [`crate::metrics::sdq`] over the 5λc of f and one period of
//! g (a whole period: the values over any number of periods are the same).

use super::measured::Param;
use super::regression::{PROFILE_STEP_MM, profile_roughness};
use crate::tool::{Cutter, Shape, crest_height_mm};

/// Largest areal map of the estimate, nodes (the scallop is sampled more coarsely past it).
const MAX_NODES: usize = 2_000_000;

/// What a case predicts across the passes and over the area, µm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Across {
    /// Rz of the stepover-direction profile.
    pub rz_um: f64,
    /// Ra of the stepover-direction profile.
    pub ra_um: f64,
    /// Sz of the areal surface.
    pub sz_um: f64,
    /// Sa of the areal surface.
    pub sa_um: f64,
    /// Sq of the areal surface.
    pub sq_um: f64,
    /// Sdq of the areal surface (a ratio).
    pub sdq: f64,
}

impl Across {
    /// The value of an areal or stepover-direction parameter (NaN for the feed direction's,
    /// which the case model gives).
    pub fn value(&self, p: Param) -> f64 {
        match p {
            Param::RzStepover => self.rz_um,
            Param::RaStepover => self.ra_um,
            Param::Sz => self.sz_um,
            Param::Sa => self.sa_um,
            Param::Sq => self.sq_um,
            Param::Sdq => self.sdq,
            Param::Rz | Param::Ra => f64::NAN,
        }
    }
}

/// Why the stepover-direction and areal values cannot be estimated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AcrossError {
    /// The tool is not a ball end.
    #[error(
        "the stepover direction and the areal parameters need a ball-end tool (its profile across the passes is an arc of radius R)"
    )]
    NotBall,
    /// `stepover_mm` is not in (0, 2R).
    #[error(
        "stepover_mm must be positive and below the tool diameter {diameter_mm} mm, found {stepover_mm}"
    )]
    Stepover {
        /// The stepover, mm.
        stepover_mm: f64,
        /// The tool diameter, mm.
        diameter_mm: f64,
    },
    /// The feed-direction profile is empty or not finite.
    #[error("the feed-direction profile has no finite heights")]
    NoProfile,
    /// The estimated surface has no finite height.
    #[error("the areal estimate has no finite height")]
    NoHeight,
}

/// The stepover-direction Rz, Ra and the areal Sz, Sa, Sq, Sdq of a ball end `cutter` at
/// stepover `stepover_mm`, with the evaluated feed-direction profile `feed_profile_um`, evenly
/// spaced `feed_step_mm` apart.
pub fn predict(
    cutter: &Cutter,
    stepover_mm: f64,
    feed_profile_um: &[f64],
    feed_step_mm: f64,
) -> Result<Across, AcrossError> {
    if !matches!(cutter.shape, Shape::Ball) {
        return Err(AcrossError::NotBall);
    }
    let r = cutter.radius_mm;
    if !(stepover_mm.is_finite() && stepover_mm > 0.0 && stepover_mm < 2.0 * r) {
        return Err(AcrossError::Stepover {
            stepover_mm,
            diameter_mm: 2.0 * r,
        });
    }
    if feed_profile_um.is_empty() || feed_profile_um.iter().any(|h| !h.is_finite()) {
        return Err(AcrossError::NoProfile);
    }
    let (rz, ra, _) = profile_roughness(r, stepover_mm);
    // One period of the scallop in an even number of steps (crest and valley are samples).
    let nx = feed_profile_um.len();
    let mut m = 2.0 * (0.5 * stepover_mm / PROFILE_STEP_MM).ceil().max(1.0);
    while m > 2.0 && nx as f64 * m > MAX_NODES as f64 {
        m = 2.0 * (0.25 * m).ceil();
    }
    let dy = stepover_mm / m;
    let scallop: Vec<f64> = (0..m as usize)
        .map(|j| {
            let y = j as f64 * dy;
            let d = if y > 0.5 * stepover_mm {
                stepover_mm - y
            } else {
                y
            };
            crest_height_mm(r, 2.0 * d) * 1e3
        })
        .collect();
    let z: Vec<f64> = scallop
        .iter()
        .flat_map(|g| feed_profile_um.iter().map(move |f| f + g))
        .collect();
    let stats = crate::metrics::height_stats(&z).ok_or(AcrossError::NoHeight)?;
    let sdq =
        crate::surface::HeightMap::from_rows(nx, scallop.len(), feed_step_mm * 1e3, dy * 1e3, z)
            .map_or(f64::NAN, |map| crate::metrics::sdq(&map));
    Ok(Across {
        rz_um: rz,
        ra_um: ra,
        sz_um: stats.sz(),
        sa_um: stats.sa,
        sq_um: stats.sq,
        sdq,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn flat_feed_profile_leaves_the_scallop() {
        // With no feed marks the surface is the scallop alone: Sz is its crest, Sa its Ra
        // over one period (the profile's Ra over 5λc of whole periods is the same).
        let c = Cutter::new(Shape::Ball, 5.0, 2, 0.0);
        let a = predict(&c, 0.3, &vec![0.0; 101], 0.001).unwrap();
        let hc = crest_height_mm(5.0, 0.3) * 1e3;
        assert_relative_eq!(a.sz_um, hc, max_relative = 1e-9);
        assert_relative_eq!(a.rz_um, hc, max_relative = 1e-6);
        // (5λc = 4 mm holds 13⅓ periods of 0.3 mm: the profile's Ra differs from one
        // period's mean |η| by the partial period's share.)
        assert_relative_eq!(a.sa_um, a.ra_um, max_relative = 2e-2);
        // A feed profile adds its own peak-to-valley height to Sz.
        let f: Vec<f64> = (0..=100)
            .map(|i| if i % 2 == 0 { 0.0 } else { 0.5 })
            .collect();
        let b = predict(&c, 0.3, &f, 0.001).unwrap();
        assert_relative_eq!(b.sz_um, hc + 0.5, max_relative = 1e-9);
        assert!(predict(&c, 0.0, &f, 0.001).is_err());
        assert!(predict(&c, 0.3, &[], 0.001).is_err());
    }
}
