//! Run-out identified from a measured height map: the feed direction found from the map's
//! 2-D spectrum (`metrics::feed_direction_deg`, as `crest compare` registers maps: the
//! scallops run along the feed), several profiles taken along it across the map, and the
//! identification of [`super::identify`] averaged over them.
//!
//! The spectrum gives the feed's axis, not its sense: the profiles are read towards the
//! sense whose x component is positive (the feed angle in (−90°, 90°]); on a map cut the
//! other way the cutting order, and so the teeth after tooth 1 and the phase, come mirrored.

use super::identify::{Identification, IdentifyError, identify_profiles};
use crate::metrics::{bilinear, feed_direction_deg};
use crate::surface::HeightMap;
use crate::tool::Cutter;
use serde::Serialize;

/// Profiles taken across the map (those shorter than two revolutions' feed are left out).
pub const MAP_PROFILES: usize = 9;

/// Why a map cannot identify the run-out.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MapIdentifyError {
    /// The map has no periodic texture to give a feed direction.
    #[error("no feed direction: the map's spectrum has no peak (too small, flat or empty)")]
    NoFeedDirection,
    /// The profiles along the feed cannot identify the run-out.
    #[error("the profiles along the feed at {feed_deg:.2}°: {source}")]
    Profiles {
        /// The feed direction, degrees.
        feed_deg: f64,
        /// Why.
        #[source]
        source: IdentifyError,
    },
}

/// The run-out identified from a map.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MapIdentification {
    /// The feed direction found, degrees counter-clockwise from +x, in (−90, 90].
    pub feed_deg: f64,
    /// Length of the longest profile taken, mm.
    pub profile_length_mm: f64,
    /// The identification averaged over the profiles.
    #[serde(flatten)]
    pub identification: Identification,
}

/// Profiles of `map` along the direction `feed_deg` (degrees from +x): `count` parallel lines
/// evenly spaced across the map, each sampled every node spacing (bilinear; missing nodes
/// and the outside left out). Each profile is (position along the line mm, height µm).
pub fn profiles_along(map: &HeightMap, feed_deg: f64, count: usize) -> Vec<(Vec<f64>, Vec<f64>)> {
    let (s, c) = feed_deg.to_radians().sin_cos();
    let step = map.dx_um.min(map.dy_um);
    let (w, h) = (
        (map.nx.saturating_sub(1)) as f64 * map.dx_um,
        (map.ny.saturating_sub(1)) as f64 * map.dy_um,
    );
    let (cx, cy) = (0.5 * w, 0.5 * h);
    // Half extent of the map along and across the feed.
    let along = 0.5 * (w * c.abs() + h * s.abs());
    let across = 0.5 * (w * s.abs() + h * c.abs());
    let n = (2.0 * along / step).ceil() as usize + 1;
    (0..count)
        .map(|k| {
            let v = across * ((k as f64 + 0.5) / count as f64 * 2.0 - 1.0) * 0.95;
            let (mut xs, mut zs) = (Vec::new(), Vec::new());
            for i in 0..n {
                let u = -along + i as f64 * step;
                let (x, y) = (cx + u * c - v * s, cy + u * s + v * c);
                let z = bilinear(map, x / map.dx_um, y / map.dy_um);
                if z.is_finite() {
                    xs.push((u + along) * 1e-3);
                    zs.push(z);
                }
            }
            (xs, zs)
        })
        .collect()
}

/// Identify the run-out of `cutter` from the height map `map` cut with feed per tooth
/// `fz_mm` at lead `lead_deg`: the feed direction from the map, then [`MAP_PROFILES`]
/// profiles along it, averaged.
pub fn identify_map(
    map: &HeightMap,
    cutter: &Cutter,
    fz_mm: f64,
    lead_deg: f64,
) -> Result<MapIdentification, MapIdentifyError> {
    let axis = feed_direction_deg(map).ok_or(MapIdentifyError::NoFeedDirection)?;
    let feed_deg = if axis > 90.0 { axis - 180.0 } else { axis };
    let profiles = profiles_along(map, feed_deg, MAP_PROFILES);
    let longest = profiles
        .iter()
        .map(|(x, _)| x.last().copied().unwrap_or(0.0) - x.first().copied().unwrap_or(0.0))
        .fold(0.0, f64::max);
    let refs: Vec<(&[f64], &[f64])> = profiles
        .iter()
        .map(|(x, z)| (x.as_slice(), z.as_slice()))
        .collect();
    let identification = identify_profiles(&refs, cutter, fz_mm, lead_deg, false)
        .map_err(|source| MapIdentifyError::Profiles { feed_deg, source })?;
    Ok(MapIdentification {
        feed_deg,
        profile_length_mm: longest,
        identification,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profiles_follow_the_direction() {
        // z = x (µm per µm): along 0° the heights rise one per µm, along 90° they are flat.
        let mut map = HeightMap::new_nan(41, 31, 1.0, 1.0);
        for i in 0..31 {
            for j in 0..41 {
                map.z_um[i * 41 + j] = j as f64;
            }
        }
        let p = profiles_along(&map, 0.0, 3);
        assert_eq!(p.len(), 3);
        let (x, z) = &p[1];
        let slope = (z[z.len() - 1] - z[0]) / ((x[x.len() - 1] - x[0]) * 1e3);
        assert!((slope - 1.0).abs() < 1e-9, "{slope}");
        let (_, z) = &profiles_along(&map, 90.0, 3)[0];
        let spread = z.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - z.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(spread < 1e-9, "{spread}");
    }
}
