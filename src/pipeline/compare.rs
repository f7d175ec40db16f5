//! `crest compare`: a predicted height map held against a measured one: both read, the
//! prediction registered (feed direction, rotation, shift) and resampled onto the measured
//! grid, both put through the same ISO 25178-3 chain over their overlap, and compared
//! parameter by parameter, spectrum by spectrum.

use std::path::Path;

use crate::pipeline::{Error, Result};

use crate::io::{ReadOptions, read_heightmap};
use crate::metrics::{
    LaySpectra, Param, ParamSet, Placement, Preprocess, evaluate_pair, height_stats, place,
    prepare_pair, shift_peak_is_coefficient, shifts_at_rotations,
};
use crate::surface::HeightMap;

pub use crate::report::compare::{
    COMPARED, CompareOptions, Comparison, DEFAULT_TOLERANCE_PCT, JUDGED, Pair,
};

fn read(path: &Path) -> Result<HeightMap> {
    let name = path.display().to_string();
    read_heightmap(path, &ReadOptions::default()).map_err(|e| {
        if e.to_string().contains(&name) {
            Error::stage(e)
        } else {
            Error::within(name, e)
        }
    })
}

fn preprocess(opts: &CompareOptions) -> Preprocess {
    Preprocess {
        level: opts.level,
        lambda_s_um: opts.lambda_s_um,
        lambda_c_um: opts.lambda_c_um,
        ends: Default::default(),
    }
}

/// The rotation (degrees, in (−180, 180]) and shift (µm) that lay the prediction onto the
/// measurement; of the two rotations that align the feed directions, the one whose
/// placement correlates better with the measurement over their common nodes: for large maps
/// the coefficient the shift search ([`crate::metrics::correlation_shift`]) returns (at its best whole lag,
/// so no second placement), for the others that of the placed map.
fn register(pred: &HeightMap, meas: &HeightMap, dirs: [f64; 2]) -> Placement {
    let base = dirs[1] - dirs[0];
    let rots = [0.0, 180.0].map(|turn| {
        let rot = (base + turn + 180.0).rem_euclid(360.0) - 180.0;
        if rot.abs() < 1e-9 { 0.0 } else { rot }
    });
    // Both turns placed and searched side by side.
    let found = shifts_at_rotations(pred, meas, rots);
    let mut best: Option<(f64, Placement)> = None;
    for (rot, found) in rots.into_iter().zip(found) {
        if let Some((shift_um, r)) = found {
            let pl = Placement {
                rotation_deg: rot,
                shift_um,
            };
            let r = if shift_peak_is_coefficient(meas) {
                r
            } else {
                pearson(&place(pred, meas, &pl).z_um, &meas.z_um)
            };
            if best.is_none_or(|b| r > b.0) {
                best = Some((r, pl));
            }
        }
    }
    best.map(|b| b.1).unwrap_or_default()
}

/// Both maps with `NaN` outside their common valid nodes, cropped to those nodes' bounding box.
fn overlap(a: &HeightMap, b: &HeightMap) -> Option<(HeightMap, HeightMap)> {
    let both = |k: usize| a.z_um[k].is_finite() && b.z_um[k].is_finite();
    let (mut c0, mut c1, mut r0, mut r1) = (usize::MAX, 0, usize::MAX, 0);
    let mut count = 0usize;
    for r in 0..a.ny {
        for c in 0..a.nx {
            if both(r * a.nx + c) {
                (c0, c1, r0, r1) = (c0.min(c), c1.max(c), r0.min(r), r1.max(r));
                count += 1;
            }
        }
    }
    if count < 64 || c1 - c0 < 7 || r1 - r0 < 7 {
        return None;
    }
    let (nx, ny) = (c1 - c0 + 1, r1 - r0 + 1);
    let crop = |m: &HeightMap| {
        let mut z = Vec::with_capacity(nx * ny);
        for r in r0..=r1 {
            for c in c0..=c1 {
                let k = r * m.nx + c;
                z.push(if both(k) { m.z_um[k] } else { f64::NAN });
            }
        }
        let mut o = HeightMap::from_rows(nx, ny, m.dx_um, m.dy_um, z)?;
        o.x0_mm = m.x0_mm + c0 as f64 * m.dx_um / 1000.0;
        o.y0_mm = m.y0_mm + r0 as f64 * m.dy_um / 1000.0;
        Some(o)
    };
    Some((crop(a)?, crop(b)?))
}

/// Pearson correlation of the nodes valid in both (three passes over the pairs, in order; no
/// copy of them).
fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let pairs = || {
        a.iter()
            .zip(b)
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(x, y)| (*x, *y))
    };
    let n = pairs().count() as f64;
    let (ma, mb) = pairs().fold((0.0, 0.0), |s, p| (s.0 + p.0 / n, s.1 + p.1 / n));
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in pairs() {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt()
}

/// The values of [`COMPARED`], in that order, from a map's parameters.
fn compared(vals: &[(Param, f64)]) -> Vec<f64> {
    COMPARED
        .iter()
        .map(|s| {
            vals.iter()
                .find(|(p, _)| p.symbol() == *s)
                .map_or(f64::NAN, |v| v.1)
        })
        .collect()
}

/// Compare the prediction in `predicted` with the measurement in `measured`.
pub fn compare(predicted: &Path, measured: &Path, opts: &CompareOptions) -> Result<Comparison> {
    let (pname, mname) = (
        predicted.display().to_string(),
        measured.display().to_string(),
    );
    let (pred_raw, meas_raw) = (read(predicted)?, read(measured)?);
    let pp = preprocess(opts);
    // Both maps' chains for registration and their feed directions, side by side.
    let [prep_p, prep_m] = prepare_pair([&pred_raw, &meas_raw], &pp);
    let (reg_p, dir_p) = prep_p.map_err(|e| Error::within(&pname, e))?;
    let (reg_m, dir_m) = prep_m.map_err(|e| Error::within(&mname, e))?;
    let dirs = [dir_p, dir_m];
    let placement = if opts.register && dirs.iter().all(|d| d.is_finite()) {
        register(&reg_p, &reg_m, dirs)
    } else {
        Placement::default()
    };
    let placed = place(&pred_raw, &meas_raw, &placement);
    let (cp, cm) = overlap(&placed, &meas_raw).ok_or_else(|| {
        Error::Result(format!("{pname} and {mname}: the prediction, placed on the measurement, overlaps fewer than 8 × 8 of its valid nodes"))
    })?;
    let pred_dir = if placement == Placement::default() {
        dirs[0]
    } else {
        dirs[1]
    };
    let set = ParamSet::parse(&COMPARED.join(","), false).map_err(Error::stage)?;
    // Both overlaps through the chain, their parameters and 1-D spectra, side by side.
    let [eval_p, eval_m] = evaluate_pair([&cp, &cm], &pp, &set, [pred_dir, dirs[1]]);
    let eval_p = eval_p.map_err(|e| Error::within(&pname, e))?;
    let eval_m = eval_m.map_err(|e| Error::within(&mname, e))?;
    let vp = compared(&eval_p.params.map_err(|e| Error::within(&pname, e))?);
    let vm = compared(&eval_m.params.map_err(|e| Error::within(&mname, e))?);
    let (proc_p, proc_m) = (eval_p.map, eval_m.map);
    let (lay_predicted, lay_measured) = (eval_p.lay, eval_m.lay);
    let mut difference = proc_m.clone();
    for (d, (p, m)) in difference
        .z_um
        .iter_mut()
        .zip(proc_p.z_um.iter().zip(&proc_m.z_um))
    {
        *d = p - m;
    }
    let params: Vec<(&'static str, Pair)> = COMPARED
        .iter()
        .zip(vp.iter().zip(&vm))
        .map(|(s, (p, m))| (*s, Pair::new(*p, *m)))
        .collect();
    let period = |l: &Option<LaySpectra>, along: bool| {
        l.as_ref().map_or(f64::NAN, |l| {
            if along {
                l.along.peak_period_um
            } else {
                l.across.peak_period_um
            }
        })
    };
    let feed_period = Pair::new(period(&lay_predicted, true), period(&lay_measured, true));
    let stepover = Pair::new(period(&lay_predicted, false), period(&lay_measured, false));
    let mut failing = Vec::new();
    let judged = params
        .iter()
        .filter(|(s, _)| JUDGED.contains(s))
        .map(|(s, p)| (s.to_string(), *p))
        .chain([
            ("feed-mark period".to_string(), feed_period),
            ("stepover".to_string(), stepover),
        ]);
    for (s, p) in judged {
        if p.diff_pct.abs() > opts.tolerance_pct {
            failing.push(format!("{s} {:+.1} %", p.diff_pct));
        }
    }
    Ok(Comparison {
        predicted_name: pname,
        measured_name: mname,
        options: *opts,
        params,
        feed_direction_deg: dirs,
        rotation_deg: placement.rotation_deg,
        shift_um: placement.shift_um,
        correlation: pearson(&proc_p.z_um, &proc_m.z_um),
        residual_sq_um: height_stats(&difference.z_um).map_or(f64::NAN, |s| s.sq),
        feed_period,
        stepover,
        predicted: proc_p,
        measured: proc_m,
        difference,
        lay_predicted,
        lay_measured,
        failing,
    })
}

/// The `--json` object of a comparison (non-finite numbers as `null`).
pub fn to_json(c: &Comparison) -> serde_json::Value {
    use serde_json::{Map, Value, json};
    let n = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
    let mut params = Map::new();
    for (s, p) in &c.params {
        params.insert(
            s.to_string(),
            json!({"predicted": n(p.predicted), "measured": n(p.measured), "diff_pct": n(p.diff_pct)}),
        );
    }
    let pm = |p: &Pair| json!({"predicted": n(p.predicted), "measured": n(p.measured)});
    json!({
        "params": params,
        "feed_direction_deg": {"predicted": n(c.feed_direction_deg[0]), "measured": n(c.feed_direction_deg[1])},
        "feed_period_um": pm(&c.feed_period),
        "stepover_um": pm(&c.stepover),
        "shift_um": [n(c.shift_um[0]), n(c.shift_um[1])],
        "correlation": n(c.correlation),
        "residual_sq_um": n(c.residual_sq_um),
    })
}
