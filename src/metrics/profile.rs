//! Profiles through a height map and their ISO 4287 / ISO 21920-2 parameters.
//!
//! A profile is a row (`row:K`, along x), a column (`col:K`, along y), a straight line at
//! any angle through the centre of the map (`angle:DEG`, counter-clockwise from +x, y = row
//! index ascending) or the segment between two points (`line:X0,Y0,X1,Y1`, µm from the node
//! of column 0, row 0: the profile `crest view` picks by two clicks), sampled every
//! `min(dx, dy)` with bilinear interpolation (a sample is missing when one of its four nodes
//! is; points outside the map are clamped to its border). A `line:` profile starts at the
//! first point and has `floor(L / step + 1e-9) + 1` samples at `t = k · step` along it
//! (`L = sqrt(Δx² + Δy²)`), so it ends within one step of the second point.
//!
//! Parameters over the evaluation length, heights relative to the mean line: Ra, Rq, Rsk,
//! Rku, Rt (whole length), Rdq (forward differences), and Rp, Rv, Rz as the mean over
//! `sections` sampling lengths (5 by default, 002 Eq 15) cut with `numpy.array_split`
//! semantics (the first `N mod 5` sections get one extra sample). RSm: mean width of the
//! profile elements, an element being delimited by successive upward crossings of the mean
//! line, counted only when the profile went below −10 % and then above +10 % of Rz in between
//! (the ISO height discrimination; the 1 % width discrimination is not applied).

use super::MetricsError;
use crate::surface::HeightMap;

/// Which profile to take from a map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ProfileSpec {
    /// Row K (along x), 0-based.
    Row(usize),
    /// Column K (along y), 0-based.
    Col(usize),
    /// Line through the map centre at this angle, degrees CCW from +x.
    Angle(f64),
    /// Segment from (x0, y0) to (x1, y1), µm from the node of column 0, row 0.
    Line {
        /// Start, x, µm.
        x0_um: f64,
        /// Start, y, µm.
        y0_um: f64,
        /// End, x, µm.
        x1_um: f64,
        /// End, y, µm.
        y1_um: f64,
    },
}

/// Why a profile's text is not a [`ProfileSpec`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ProfileSpecError {
    /// Not one of the four forms.
    #[error("expected row:K, col:K, angle:DEG or line:X0,Y0,X1,Y1, found {0:?}")]
    Form(String),
    /// A row index that is not a whole number.
    #[error("bad row index {0:?}")]
    Row(String),
    /// A column index that is not a whole number.
    #[error("bad column index {0:?}")]
    Col(String),
    /// An angle that is not a finite number.
    #[error("bad angle {0:?}")]
    Angle(String),
    /// A segment that is not four finite numbers.
    #[error("bad line {0:?} (expected X0,Y0,X1,Y1 in µm)")]
    Line(String),
}

impl ProfileSpec {
    /// Parse `row:K`, `col:K`, `angle:DEG` or `line:X0,Y0,X1,Y1` (µm).
    pub fn parse(s: &str) -> Result<ProfileSpec, ProfileSpecError> {
        let (kind, val) = s
            .split_once(':')
            .ok_or_else(|| ProfileSpecError::Form(s.to_string()))?;
        match kind.trim().to_ascii_lowercase().as_str() {
            "row" => val
                .trim()
                .parse()
                .map(ProfileSpec::Row)
                .map_err(|_| ProfileSpecError::Row(val.to_string())),
            "col" | "column" => val
                .trim()
                .parse()
                .map(ProfileSpec::Col)
                .map_err(|_| ProfileSpecError::Col(val.to_string())),
            "angle" => val
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|a| a.is_finite())
                .map(ProfileSpec::Angle)
                .ok_or_else(|| ProfileSpecError::Angle(val.to_string())),
            "line" => {
                let v: Vec<f64> = val
                    .split(',')
                    .map(|t| t.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
                    .collect::<Option<_>>()
                    .filter(|v: &Vec<f64>| v.len() == 4)
                    .ok_or_else(|| ProfileSpecError::Line(val.to_string()))?;
                Ok(ProfileSpec::Line {
                    x0_um: v[0],
                    y0_um: v[1],
                    x1_um: v[2],
                    y1_um: v[3],
                })
            }
            _ => Err(ProfileSpecError::Form(s.to_string())),
        }
    }
}

/// A sampled profile.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    /// Heights, µm (`NaN` = missing).
    pub z: Vec<f64>,
    /// Sample spacing, µm.
    pub step_um: f64,
}

/// A measured profile given as points (`x_mm` strictly ascending, heights µm) as an evenly
/// sampled [`Profile`], which ISO 21920-2's parameters need: the points themselves when
/// every step is within 1e-6 of the mean step, else the profile linearly interpolated every
/// median step from the first point to the last (a missing height leaves its neighbourhood
/// missing). The flag says whether it was resampled.
pub fn profile_from_points(x_mm: &[f64], z_um: &[f64]) -> Result<(Profile, bool), MetricsError> {
    let n = x_mm.len().min(z_um.len());
    if n < 2 {
        return Err(MetricsError::TooFew(format!(
            "a profile needs at least 2 points, it has {n}"
        )));
    }
    let mut steps = Vec::with_capacity(n - 1);
    for k in 1..n {
        let d = x_mm[k] - x_mm[k - 1];
        if !(d.is_finite() && d > 0.0) {
            return Err(MetricsError::BadProfile(format!(
                "x must rise from point to point: point {} has x = {} mm after {} mm",
                k + 1,
                x_mm[k],
                x_mm[k - 1]
            )));
        }
        steps.push(d);
    }
    let length = x_mm[n - 1] - x_mm[0];
    let mean = length / (n - 1) as f64;
    if steps.iter().all(|d| (d - mean).abs() <= 1e-6 * mean) {
        let z = z_um[..n].to_vec();
        return Ok((
            Profile {
                z,
                step_um: mean * 1e3,
            },
            false,
        ));
    }
    let mut sorted = steps.clone();
    sorted.sort_by(f64::total_cmp);
    let step = sorted[sorted.len() / 2];
    let samples = (length / step + 1e-9).floor() + 1.0;
    if samples > crate::math::limits::MAX_NODES as f64 {
        return Err(MetricsError::BadProfile(format!(
            "resampling {length} mm every {step} mm (the median step) needs more than {} samples",
            crate::math::limits::MAX_NODES
        )));
    }
    let mut z = Vec::with_capacity(samples as usize);
    let mut k = 0;
    for i in 0..samples as usize {
        let x = x_mm[0] + i as f64 * step;
        while k + 2 < n && x_mm[k + 1] < x {
            k += 1;
        }
        let t = ((x - x_mm[k]) / (x_mm[k + 1] - x_mm[k])).clamp(0.0, 1.0);
        z.push(if t == 0.0 {
            z_um[k]
        } else if t == 1.0 {
            z_um[k + 1]
        } else {
            z_um[k] + t * (z_um[k + 1] - z_um[k])
        });
    }
    Ok((
        Profile {
            z,
            step_um: step * 1e3,
        },
        true,
    ))
}

/// Take a profile from a map.
pub fn extract_profile(map: &HeightMap, spec: ProfileSpec) -> Result<Profile, MetricsError> {
    match spec {
        ProfileSpec::Row(k) => {
            if k >= map.ny {
                return Err(MetricsError::BadProfile(format!(
                    "row {k} is outside the map (rows 0..{})",
                    map.ny
                )));
            }
            Ok(Profile {
                z: map.row(k).to_vec(),
                step_um: map.dx_um,
            })
        }
        ProfileSpec::Col(k) => {
            if k >= map.nx {
                return Err(MetricsError::BadProfile(format!(
                    "column {k} is outside the map (columns 0..{})",
                    map.nx
                )));
            }
            Ok(Profile {
                z: (0..map.ny).map(|r| map.get(k, r)).collect(),
                step_um: map.dy_um,
            })
        }
        ProfileSpec::Angle(deg) => {
            let (w, h) = (
                (map.nx - 1) as f64 * map.dx_um,
                (map.ny - 1) as f64 * map.dy_um,
            );
            let (c, s) = (deg.to_radians().cos(), deg.to_radians().sin());
            // Half length of the chord through the centre (slab method).
            let mut half = f64::INFINITY;
            if c.abs() > 1e-12 {
                half = half.min(w / 2.0 / c.abs());
            }
            if s.abs() > 1e-12 {
                half = half.min(h / 2.0 / s.abs());
            }
            let step = map.dx_um.min(map.dy_um);
            if !half.is_finite() || half * 2.0 < step {
                return Err(MetricsError::BadProfile(format!(
                    "a line at {deg}° through the centre is shorter than one step"
                )));
            }
            let n = (2.0 * half / step + 1e-9).floor() as usize + 1;
            let start = -((n - 1) as f64) * step / 2.0;
            let z = (0..n)
                .map(|k| {
                    let t = start + k as f64 * step;
                    let x = (w / 2.0 + t * c) / map.dx_um;
                    let y = (h / 2.0 + t * s) / map.dy_um;
                    bilinear(map, x, y)
                })
                .collect();
            Ok(Profile { z, step_um: step })
        }
        ProfileSpec::Line {
            x0_um,
            y0_um,
            x1_um,
            y1_um,
        } => {
            let (ex, ey) = (x1_um - x0_um, y1_um - y0_um);
            let len = (ex * ex + ey * ey).sqrt();
            let step = map.dx_um.min(map.dy_um);
            if len.is_nan() || len < step {
                return Err(MetricsError::BadProfile(format!(
                    "the line from ({x0_um}, {y0_um}) to ({x1_um}, {y1_um}) µm is shorter than one step ({step} µm)"
                )));
            }
            let (c, s) = (ex / len, ey / len);
            let n = (len / step + 1e-9).floor() as usize + 1;
            let z = (0..n)
                .map(|k| {
                    let t = k as f64 * step;
                    bilinear(
                        map,
                        (x0_um + t * c) / map.dx_um,
                        (y0_um + t * s) / map.dy_um,
                    )
                })
                .collect();
            Ok(Profile { z, step_um: step })
        }
    }
}

fn bilinear(map: &HeightMap, x: f64, y: f64) -> f64 {
    let x = x.clamp(0.0, (map.nx - 1) as f64);
    let y = y.clamp(0.0, (map.ny - 1) as f64);
    let (i, j) = (y.floor() as usize, x.floor() as usize);
    let (fy, fx) = (y - i as f64, x - j as f64);
    let i1 = (i + 1).min(map.ny - 1);
    let j1 = (j + 1).min(map.nx - 1);
    let v = |r: usize, c: usize, wgt: f64| if wgt == 0.0 { 0.0 } else { wgt * map.get(c, r) };
    v(i, j, (1.0 - fy) * (1.0 - fx))
        + v(i, j1, (1.0 - fy) * fx)
        + v(i1, j, fy * (1.0 - fx))
        + v(i1, j1, fy * fx)
}

/// Profile parameters, µm (Rdq µm/µm, RSm µm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileValues {
    /// Arithmetic mean deviation.
    pub ra: f64,
    /// Root-mean-square deviation.
    pub rq: f64,
    /// Mean of the section peak heights.
    pub rp: f64,
    /// Mean of the section valley depths.
    pub rv: f64,
    /// Mean of the section peak-to-valley heights (002 Eq 15).
    pub rz: f64,
    /// Peak-to-valley over the evaluation length.
    pub rt: f64,
    /// Skewness.
    pub rsk: f64,
    /// Kurtosis.
    pub rku: f64,
    /// Root-mean-square slope.
    pub rdq: f64,
    /// Mean width of the profile elements (`NaN` with fewer than two elements).
    pub rsm: f64,
}

/// Parameters of a profile (`sections` sampling lengths for Rp, Rv, Rz).
pub fn profile_values(p: &Profile, sections: usize) -> Result<ProfileValues, MetricsError> {
    let stats = super::height_stats(&p.z)
        .filter(|s| s.n >= 2)
        .ok_or_else(|| MetricsError::TooFew("a profile needs at least 2 valid samples".into()))?;
    let sections = sections.max(1);
    let n = p.z.len();
    if n < sections {
        return Err(MetricsError::TooFew(format!(
            "{n} samples cannot make {sections} sampling lengths"
        )));
    }
    let eta: Vec<f64> = p.z.iter().map(|v| v - stats.mean).collect();
    let (sp, sv, sz, used) = section_extremes(&eta, sections);
    let u = used as f64;
    let (mut sd, mut cd) = (0.0, 0usize);
    for w in eta.windows(2) {
        let d = w[1] - w[0];
        if d.is_finite() {
            sd += d * d;
            cd += 1;
        }
    }
    let rdq = if cd > 0 {
        (sd / cd as f64).sqrt() / p.step_um
    } else {
        f64::NAN
    };
    let rz = sz / u;
    Ok(ProfileValues {
        ra: stats.sa,
        rq: stats.sq,
        rp: sp / u,
        rv: sv / u,
        rz,
        rt: stats.sz(),
        rsk: stats.ssk,
        rku: stats.sku,
        rdq,
        rsm: rsm(&eta, p.step_um, 0.1 * rz),
    })
}

/// Sums over `sections` sampling lengths of the peak height, valley depth and peak-to-valley
/// height of `eta` (heights about the mean line), and the number of sections with a valid
/// sample. Sections are cut with `numpy.array_split` semantics: the first `n mod sections`
/// get one more sample. The one rule for Rp, Rv and Rz in crest.
fn section_extremes(eta: &[f64], sections: usize) -> (f64, f64, f64, usize) {
    let n = eta.len();
    let (base, extra) = (n / sections, n % sections);
    let (mut sp, mut sv, mut sz, mut used) = (0.0, 0.0, 0.0, 0usize);
    let mut start = 0;
    for k in 0..sections {
        let len = base + usize::from(k < extra);
        let part = &eta[start..start + len];
        start += len;
        let (mut hi, mut lo) = (f64::NEG_INFINITY, f64::INFINITY);
        for &v in part.iter().filter(|v| v.is_finite()) {
            hi = hi.max(v);
            lo = lo.min(v);
        }
        if hi.is_finite() {
            sp += hi;
            sv -= lo;
            sz += hi - lo;
            used += 1;
        }
    }
    (sp, sv, sz, used)
}

/// ISO 4288 sampling length λc for a periodic profile of mean spacing `rsm_mm`, mm.
pub fn sampling_length_mm(rsm_mm: f64) -> f64 {
    match rsm_mm {
        s if s <= 0.04 => 0.08,
        s if s <= 0.13 => 0.25,
        s if s <= 0.4 => 0.8,
        s if s <= 1.3 => 2.5,
        _ => 8.0,
    }
}

/// Rz and Ra (µm) of a profile without form or waviness (no filter) that covers five
/// sampling lengths: Ra = mean |z − z̄|, Rz = the mean of the five sections' peak-to-valley
/// heights (002 Eq 15), sections cut as in [`profile_values`]. NaN for an empty profile.
pub fn rz_ra(heights_um: &[f64]) -> (f64, f64) {
    let Some(stats) = super::height_stats(heights_um) else {
        return (f64::NAN, f64::NAN);
    };
    let sections = 5.min(heights_um.len()).max(1);
    let eta: Vec<f64> = heights_um.iter().map(|v| v - stats.mean).collect();
    let (_, _, sz, used) = section_extremes(&eta, sections);
    (sz / used.max(1) as f64, stats.sa)
}

/// Mean element width with height discrimination `h` (see the module docs).
fn rsm(eta: &[f64], step: f64, h: f64) -> f64 {
    let mut last_up = f64::NAN;
    let mut seen_low = false;
    let mut bounds: Vec<f64> = Vec::new();
    let mut prev: Option<(usize, f64)> = None;
    for (i, &v) in eta.iter().enumerate() {
        if !v.is_finite() {
            prev = None;
            continue;
        }
        if let Some((j, u)) = prev
            && u <= 0.0
            && v > 0.0
        {
            let f = -u / (v - u);
            last_up = (j as f64 + f * (i - j) as f64) * step;
        }
        if v < -h {
            seen_low = true;
        } else if v > h && seen_low && last_up.is_finite() {
            bounds.push(last_up);
            seen_low = false;
        }
        prev = Some((i, v));
    }
    if bounds.len() < 2 {
        return f64::NAN;
    }
    (bounds[bounds.len() - 1] - bounds[0]) / (bounds.len() - 1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_specs() {
        assert_eq!(ProfileSpec::parse("row:3"), Ok(ProfileSpec::Row(3)));
        assert_eq!(ProfileSpec::parse("col:0"), Ok(ProfileSpec::Col(0)));
        assert_eq!(
            ProfileSpec::parse("angle:-30"),
            Ok(ProfileSpec::Angle(-30.0))
        );
        assert_eq!(
            ProfileSpec::parse("line:0,1.5,20,-3e1"),
            Ok(ProfileSpec::Line {
                x0_um: 0.0,
                y0_um: 1.5,
                x1_um: 20.0,
                y1_um: -30.0
            })
        );
        assert!(ProfileSpec::parse("line:0,1,2").is_err());
        assert!(ProfileSpec::parse("line:0,1,2,nan").is_err());
        assert!(ProfileSpec::parse("diag:1").is_err());
        assert!(ProfileSpec::parse("row:-1").is_err());
    }

    #[test]
    fn angle_profile_of_a_plane_is_linear() {
        let (nx, ny) = (21, 11);
        let z = (0..nx * ny)
            .map(|k| (k % nx) as f64 * 0.5 + (k / nx) as f64)
            .collect();
        let m = HeightMap::from_rows(nx, ny, 0.5, 1.0, z).unwrap();
        let p = extract_profile(&m, ProfileSpec::Angle(90.0)).unwrap();
        // Along y through the centre: heights 5 + y, y = 0..10 every 0.5.
        assert_eq!(p.z.len(), 21);
        assert!((p.z[0] - 5.0).abs() < 1e-12 && (p.z[20] - 15.0).abs() < 1e-12);
        assert!(extract_profile(&m, ProfileSpec::Row(11)).is_err());
    }

    #[test]
    fn line_profile_of_a_plane_is_linear_and_starts_at_the_first_point() {
        let (nx, ny) = (21, 11);
        let z = (0..nx * ny)
            .map(|k| (k % nx) as f64 * 0.5 + (k / nx) as f64)
            .collect();
        let m = HeightMap::from_rows(nx, ny, 0.5, 1.0, z).unwrap();
        // From (1, 2) to (9, 8) µm: length 10, 21 samples every 0.5 µm; height = x + y.
        let spec = ProfileSpec::parse("line:1,2,9,8").unwrap();
        let p = extract_profile(&m, spec).unwrap();
        assert_eq!((p.z.len(), p.step_um), (21, 0.5));
        for (k, v) in p.z.iter().enumerate() {
            let t = k as f64 * 0.5;
            let want = 1.0 + 0.8 * t + 2.0 + 0.6 * t;
            assert!((v - want).abs() < 1e-12, "{k}: {v} against {want}");
        }
        let short = ProfileSpec::parse("line:1,1,1.2,1").unwrap();
        assert!(extract_profile(&m, short).is_err());
    }

    #[test]
    fn rsm_of_sine_is_its_wavelength() {
        let z: Vec<f64> = (0..2000)
            .map(|k| (2.0 * std::f64::consts::PI * k as f64 * 0.5 / 80.0).sin())
            .collect();
        let v = profile_values(&Profile { z, step_um: 0.5 }, 5).unwrap();
        assert!((v.rsm - 80.0).abs() < 1e-6, "{}", v.rsm);
    }

    #[test]
    fn points_to_an_even_profile() {
        // Even: the points as they are.
        let (p, r) = profile_from_points(&[1.0, 1.002, 1.004], &[3.0, f64::NAN, 5.0]).unwrap();
        assert!(!r && p.z.len() == 3 && p.z[1].is_nan());
        assert!((p.step_um - 2.0).abs() < 1e-9);
        // Uneven: a line z = 1000·x + 2 resampled at the median step stays that line.
        let xs = [0.0, 0.001, 0.003, 0.004, 0.0065, 0.0075];
        let zs: Vec<f64> = xs.iter().map(|x| 1000.0 * x + 2.0).collect();
        let (p, r) = profile_from_points(&xs, &zs).unwrap();
        assert!(r);
        assert!((p.step_um - 1.0).abs() < 1e-9);
        assert_eq!(p.z.len(), 8);
        for (k, z) in p.z.iter().enumerate() {
            assert!((z - (k as f64 + 2.0)).abs() < 1e-9, "{k}: {z}");
        }
        assert!(profile_from_points(&[0.0, 0.0], &[1.0, 2.0]).is_err());
        assert!(profile_from_points(&[0.0], &[1.0]).is_err());
    }
}
