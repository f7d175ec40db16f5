//! Two height maps put through the same chain side by side (`rayon::join`): a comparison's
//! prediction and measurement, each levelled and filtered, then its parameters and its 1-D
//! spectra; and the two turns of a registration. Each value is that of the functions called
//! one after the other.

use super::MetricsError;
use super::params::{Param, ParamSet, Preprocess, areal_parameters, preprocess_map};
use super::register::{
    LaySpectra, Placement, correlation_shift, feed_direction_deg, lay_spectra, place,
};
use crate::surface::HeightMap;

/// A map put through a preprocessing chain, and its feed direction (`NaN` when none is
/// found), for registration.
pub type Prepared = Result<(HeightMap, f64), MetricsError>;

/// [`preprocess_map`] then [`feed_direction_deg`] (`NaN` when there is none) of two maps,
/// side by side.
pub fn prepare_pair(maps: [&HeightMap; 2], pp: &Preprocess) -> [Prepared; 2] {
    let one = |m: &HeightMap| -> Prepared {
        let m = preprocess_map(m, pp)?;
        let d = feed_direction_deg(&m).unwrap_or(f64::NAN);
        Ok((m, d))
    };
    let (a, b) = rayon::join(|| one(maps[0]), || one(maps[1]));
    [a, b]
}

/// The prediction `pred` turned by each of `rotations_deg` onto `meas`'s grid ([`place`],
/// no shift) and its [`correlation_shift`] against `meas`, both turns side by side.
pub fn shifts_at_rotations(
    pred: &HeightMap,
    meas: &HeightMap,
    rotations_deg: [f64; 2],
) -> [Option<([f64; 2], f64)>; 2] {
    let one = |rotation_deg: f64| {
        let turned = place(
            pred,
            meas,
            &Placement {
                rotation_deg,
                shift_um: [0.0, 0.0],
            },
        );
        correlation_shift(meas, &turned)
    };
    let (a, b) = rayon::join(|| one(rotations_deg[0]), || one(rotations_deg[1]));
    [a, b]
}

/// A map put through the chain, its parameters and its spectra along and across its feed.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// The map after the chain.
    pub map: HeightMap,
    /// [`areal_parameters`] of the chained map.
    pub params: Result<Vec<(Param, f64)>, MetricsError>,
    /// [`lay_spectra`] along the feed direction given (`None` when it is not finite).
    pub lay: Option<LaySpectra>,
}

/// [`preprocess_map`], then [`areal_parameters`] and [`lay_spectra`] along `feed_deg[k]`, of
/// two maps side by side.
pub fn evaluate_pair(
    maps: [&HeightMap; 2],
    pp: &Preprocess,
    set: &ParamSet,
    feed_deg: [f64; 2],
) -> [Result<Evaluation, MetricsError>; 2] {
    let one = |m: &HeightMap, feed: f64| -> Result<Evaluation, MetricsError> {
        let map = preprocess_map(m, pp)?;
        let params = areal_parameters(&map, set);
        let lay = feed.is_finite().then(|| lay_spectra(&map, feed)).flatten();
        Ok(Evaluation { map, params, lay })
    };
    let (a, b) = rayon::join(|| one(maps[0], feed_deg[0]), || one(maps[1], feed_deg[1]));
    [a, b]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Side by side gives each map's values of the calls one after the other.
    #[test]
    fn a_pair_is_its_maps_one_by_one() {
        let map = |shift: f64| {
            let z = (0..48 * 40)
                .map(|k| {
                    let (r, c) = ((k / 48) as f64, (k % 48) as f64);
                    (c / 5.0 + shift).sin() + 0.3 * (r / 7.0).cos() + 0.01 * r
                })
                .collect();
            HeightMap::from_rows(48, 40, 1.0, 1.0, z).unwrap()
        };
        let (a, b) = (map(0.0), map(1.3));
        let pp = Preprocess {
            level: super::super::Level::Plane,
            lambda_s_um: None,
            lambda_c_um: None,
            ends: Default::default(),
        };
        let set = ParamSet::parse("Sa,Sq,Sdr,Sal,Str,Std", false).unwrap();
        let [pa, pb] = prepare_pair([&a, &b], &pp);
        for (m, p) in [(&a, pa), (&b, pb)] {
            let (chained, dir) = p.unwrap();
            let alone = preprocess_map(m, &pp).unwrap();
            assert_eq!(chained, alone);
            let d = feed_direction_deg(&alone).unwrap_or(f64::NAN);
            assert_eq!(dir.to_bits(), d.to_bits());
        }
        let [ea, eb] = evaluate_pair([&a, &b], &pp, &set, [0.0, f64::NAN]);
        let (ea, eb) = (ea.unwrap(), eb.unwrap());
        let alone = preprocess_map(&a, &pp).unwrap();
        assert_eq!(ea.map, alone);
        // Debug text: `NaN` values (a Str that does not decay) compare equal.
        let text = |v: &dyn std::fmt::Debug| format!("{v:?}");
        assert_eq!(text(&ea.params), text(&areal_parameters(&alone, &set)));
        assert!(ea.lay.is_some());
        assert_eq!(text(&ea.lay), text(&lay_spectra(&alone, 0.0)));
        assert!(eb.lay.is_none());
        // The two turns side by side are each turn alone.
        let rots = [3.0, -177.0];
        let found = shifts_at_rotations(&a, &b, rots);
        for (rot, got) in rots.into_iter().zip(found) {
            let turned = place(
                &a,
                &b,
                &Placement {
                    rotation_deg: rot,
                    shift_um: [0.0, 0.0],
                },
            );
            assert_eq!(text(&got), text(&correlation_shift(&b, &turned)));
        }
    }
}
