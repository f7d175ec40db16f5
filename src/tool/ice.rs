//! Infinitesimal cutting-edge (ICE) elements: each tooth's edge discretised into elements at
//! chosen heights (002 §2.3, model.md §2).
//!
//! An element is a point of one tooth at height z with its spindle-fixed angle ψ_j(z) (the
//! pitch plus the helix lag) and its local radius. On a torus or flat end the end-face part
//! of a tooth lies at z = 0; those elements are placed by radius instead of height.

use super::cutter::{Cutter, direction};
use crate::math::Vec3;
use std::f64::consts::FRAC_PI_2;

/// One element of one tooth's edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IceElement {
    /// 0-based tooth index.
    pub tooth: usize,
    /// Height above the tip, mm.
    pub z_mm: f64,
    /// Nominal local radius r(z) (or the end-face radius at z = 0), mm.
    pub local_radius_mm: f64,
    /// Spindle-fixed angle ψ_j(z), rad.
    pub angle_rad: f64,
}

impl Cutter {
    /// Heights of `n` elements along the end profile, evenly spaced in the polar angle κ
    /// from the tip (κ = 0) to the top of the corner arc (κ = 90°): z = c(1 − cos κ), with c
    /// the end height (the corner radius; R for a ball, the insert radius of a round insert,
    /// the end of a profile). A flat end gives `n` zeros.
    pub fn ice_heights(&self, n: usize) -> Vec<f64> {
        let c = self.end_height_mm();
        (0..n)
            .map(|i| {
                let k = if n > 1 {
                    FRAC_PI_2 * i as f64 / (n - 1) as f64
                } else {
                    0.0
                };
                c * (1.0 - k.cos())
            })
            .collect()
    }

    /// The elements of every tooth at the given heights (tooth-major order).
    pub fn ice_elements(&self, heights_mm: &[f64]) -> Vec<IceElement> {
        let mut out = Vec::with_capacity(self.teeth() * heights_mm.len());
        for j in 0..self.teeth() {
            for &z in heights_mm {
                out.push(IceElement {
                    tooth: j,
                    z_mm: z,
                    local_radius_mm: self.profile_radius(z),
                    angle_rad: self.tooth_angle(j, z),
                });
            }
        }
        out
    }

    /// End-face elements of tooth `j` at z = 0 for a torus or flat end: `n` radii from the
    /// axis to the start of the corner arc (empty for a ball or a round insert).
    pub fn end_face_elements(&self, j: usize, n: usize) -> Vec<IceElement> {
        let flat = self.flat_end_radius_mm();
        if flat <= 0.0 || n == 0 {
            return Vec::new();
        }
        (0..n)
            .map(|i| IceElement {
                tooth: j,
                z_mm: 0.0,
                local_radius_mm: flat * i as f64 / n as f64,
                angle_rad: self.tooth_angle(j, 0.0),
            })
            .collect()
    }

    /// Tool-frame position of an element at spindle angle θ, with run-out in the vector form
    /// of model.md §3.1 (as [`Cutter::edge_point`], but for any local radius).
    pub fn ice_point(&self, e: &IceElement, theta: f64) -> Vec3 {
        let radial =
            (e.local_radius_mm + self.tooth_dev_mm(e.tooth)) * direction(theta + e.angle_rad);
        let z = e.z_mm + self.tooth_axial_dev_mm(e.tooth);
        self.axis_offset(e.z_mm, theta) + radial + Vec3::new(0.0, 0.0, z)
    }

    /// The edge of tooth `j` at spindle angle θ as a polyline through `heights_mm`.
    pub fn edge_polyline(&self, j: usize, heights_mm: &[f64], theta: f64) -> Vec<Vec3> {
        heights_mm
            .iter()
            .map(|&z| self.edge_point(j, z, theta))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::Shape;
    use approx::assert_relative_eq;

    #[test]
    fn ice_heights_span_the_corner() {
        let c = Cutter::new(Shape::Ball, 5.0, 2, 0.5);
        let h = c.ice_heights(7);
        assert_eq!(h.len(), 7);
        assert_relative_eq!(h[0], 0.0);
        assert_relative_eq!(h[6], 5.0, epsilon = 1e-12);
        let e = c.ice_elements(&h);
        assert_eq!(e.len(), 14);
        for el in &e {
            let p = c.ice_point(el, 0.3);
            assert_relative_eq!(p, c.edge_point(el.tooth, el.z_mm, 0.3), epsilon = 1e-12);
        }
    }

    #[test]
    fn end_face_elements_lie_in_the_tip_plane() {
        let c = Cutter::new(
            Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            1,
            0.0,
        );
        let e = c.end_face_elements(0, 5);
        assert_eq!(e.len(), 5);
        for el in &e {
            let p = c.ice_point(el, 1.0);
            assert_relative_eq!(p.z, 0.0);
            assert_relative_eq!(p.xy().norm(), el.local_radius_mm, epsilon = 1e-12);
        }
    }
}
