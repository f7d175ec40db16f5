//! One straight pass over the plane z = 0, already on the cutting edge's clock: samples of
//! the tool along +x with the axis leaning by the lead into the feed, for the studies that
//! need a single pass without a CLSF round trip.

use crate::math::{Point3, Vec3};
use crate::resample::Sample;
use crate::tool::Cutter;
use std::f64::consts::TAU;

/// Largest number of samples a pass may have.
pub const MAX_PASS_SAMPLES: usize = 2_000_000;

/// Samples of a straight pass along +x over the plane z = 0: the contact point runs from
/// x = `x_start_mm` for `length_mm`, the tool axis is `(sin β, 0, cos β)` (lead β =
/// `lead_rad`, model.md §1.2), the tip is placed by [`super::tool_tip`] so that the body
/// touches the plane at the contact point, the spindle angle starts at 0 and turns 2π every
/// `Z·fz` of travel, and a sample is taken every `step_deg` of spindle. `None` when the pass
/// would need more than [`MAX_PASS_SAMPLES`] samples.
pub fn straight_pass(
    cutter: &Cutter,
    lead_rad: f64,
    fz_mm: f64,
    x_start_mm: f64,
    length_mm: f64,
    step_deg: f64,
) -> Option<Vec<Sample>> {
    let teeth = cutter.teeth() as f64;
    let axis = Vec3::new(lead_rad.sin(), 0.0, lead_rad.cos());
    let normal = Vec3::z();
    let ds = teeth * fz_mm * step_deg / 360.0;
    let n = (length_mm / ds).ceil();
    if !(n.is_finite() && n >= 0.0 && n <= MAX_PASS_SAMPLES as f64) {
        return None;
    }
    Some(
        (0..=n as usize)
            .map(|k| {
                let s = k as f64 * ds;
                let c = Point3::new(x_start_mm + s, 0.0, 0.0);
                Sample {
                    run: 0,
                    s_mm: s,
                    t_s: 0.0,
                    theta_rad: TAU * s / (teeth * fz_mm),
                    position: super::tool_tip(cutter, &c, &normal, &axis),
                    axis,
                    contact: Some(c),
                    normal: Some(normal),
                    feed_dir: Vec3::x(),
                    feed_mm_min: 1000.0,
                }
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::Shape;
    use approx::assert_relative_eq;

    #[test]
    fn a_ball_pass_keeps_its_centre_one_radius_above_the_plane() {
        let c = Cutter::new(Shape::Ball, 5.0, 4, 0.0);
        let s = straight_pass(&c, 15f64.to_radians(), 0.05, -1.0, 2.0, 10.0).unwrap();
        // 2 mm at Z fz · 10/360 = 1/180 mm per sample: 360 steps.
        assert_eq!(s.len(), 361);
        for p in [&s[0], &s[360]] {
            let centre = p.position + p.axis * 5.0;
            assert_relative_eq!(centre.z, 5.0, epsilon = 1e-12);
            assert_relative_eq!(centre.x, p.contact.unwrap().x, epsilon = 1e-12);
        }
        assert_relative_eq!(s[360].theta_rad, TAU * 2.0 / 0.2, epsilon = 1e-9);
        assert!(straight_pass(&c, 0.0, 1e-12, 0.0, 1e3, 10.0).is_none());
    }
}
