//! Resampling: even feed per tooth and constant spindle step Δθ. Properties on random
//! 5-axis paths (issue 4 acceptance: samples on the original path, spacing equal to the
//! step except the last of each run, unit axes and normals, θ growing by exactly Δθ,
//! orthonormal local frames (f, g = n × f, n)); the incremental [`Resampler`] (postures
//! pushed one at a time, as `crest resample` streams a file) bit-identical to
//! [`resample_with`]; `crest resample` end to end on every real NX file with cutting moves,
//! both modes, contact columns, feed options, streaming and errors.

use std::f64::consts::TAU;
use std::path::Path;

use approx::{abs_diff_eq, assert_abs_diff_eq, relative_eq};
use crest::math::{Point3, Vec3};
use crest::resample::{
    AxisInterpolation, Mode, Options, ResampleError, Resampler, Sample, SpindleScan, SpindleSource,
    Stats, resample, resample_with,
};
use crest::toolpath::{ArcMove, MotionKind, Posture, Toolpath};
use proptest::prelude::*;

use crate::util::{
    RESAMPLE_HEADER, column, contact_below, crest, external_cls_files, external_samples, nx_sample,
    posture, read, read_number_csv, repo, stdout_json, step_geometry, tempdir, unit, write,
};

// ---------------------------------------------------------------------------------------
// Properties on random 5-axis paths
// ---------------------------------------------------------------------------------------

/// A random step: displacement, axis (polar, azimuth), normal (polar, azimuth), rapid.
type Step = ([f64; 3], [f64; 2], [f64; 2], bool);

/// One random posture: a step from the previous one, a tool axis within 60° of +z, a
/// contact point below the tip, a normal within 45° of +z; one in ten is a rapid.
fn step() -> impl Strategy<Value = Step> {
    (step_geometry(), prop::bool::weighted(0.1)).prop_map(|((d, a, n), rapid)| (d, a, n, rapid))
}

fn build(steps: &[Step], contact: bool) -> Toolpath {
    let mut position = Point3::origin();
    let mut postures = Vec::new();
    for (i, (d, a, n, rapid)) in steps.iter().enumerate() {
        position += Vec3::new(d[0], d[1], d[2]);
        let motion = if i == 0 || *rapid {
            MotionKind::Rapid
        } else {
            MotionKind::Cut
        };
        postures.push(Posture {
            contact: contact.then(|| contact_below(position, unit(n[0], n[1]))),
            feed_mm_min: Some(1000.0 + 100.0 * (i % 3) as f64),
            line: i as u32 + 1,
            ..posture(position, unit(a[0], a[1]), motion)
        });
    }
    Toolpath {
        postures,
        ..Default::default()
    }
}

/// Distance from `p` to the closest cutting move of run `run` of `path`.
fn distance_to_run(path: &Toolpath, run: usize, p: &Point3) -> f64 {
    let r = path.cutting_runs()[run].clone();
    let ps = &path.postures[r];
    ps.windows(2)
        .map(|w| {
            let (a, b) = (w[0].position, w[1].position);
            let d = b - a;
            let l2 = d.norm_squared();
            let u = if l2 > 0.0 {
                ((p - a).dot(&d) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (a + d * u - p).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

fn check_frame(s: &Sample) {
    let f = s.feed_dir;
    assert!(
        abs_diff_eq!(s.axis.norm(), 1.0, epsilon = 1e-12),
        "axis {:?}",
        s.axis
    );
    assert!(abs_diff_eq!(f.norm(), 1.0, epsilon = 1e-12), "f {f:?}");
    let n = s.normal.unwrap_or(s.axis);
    assert!(abs_diff_eq!(n.norm(), 1.0, epsilon = 1e-12), "n {n:?}");
    assert!(
        abs_diff_eq!(f.dot(&n), 0.0, epsilon = 1e-12),
        "f·n {}",
        f.dot(&n)
    );
    let g = n.cross(&f);
    assert_abs_diff_eq!(g.norm(), 1.0, epsilon = 1e-12);
    assert_abs_diff_eq!(g.dot(&f), 0.0, epsilon = 1e-12);
    assert_abs_diff_eq!(g.dot(&n), 0.0, epsilon = 1e-12);
    assert!((f.cross(&g) - n).norm() < 1e-12);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn fz_mode_samples_lie_on_the_path_at_even_spacing(
        steps in prop::collection::vec(step(), 2..12),
        fz in 0.01..0.5f64,
        contact in any::<bool>(),
        nlerp in any::<bool>(),
    ) {
        let path = build(&steps, contact);
        let kind = if nlerp { AxisInterpolation::Nlerp } else { AxisInterpolation::Slerp };
        let opts = Options::new(Mode::FeedPerTooth, fz, 4).with_axis_interpolation(kind);
        let mut samples = Vec::new();
        let stats = resample_with(&path, &opts, |s| samples.push(s.clone())).unwrap();
        prop_assert_eq!(stats.samples as usize, samples.len());
        for s in &samples {
            prop_assert!(distance_to_run(&path, s.run, &s.position) < 1e-9);
            check_frame(s);
            prop_assert_eq!(s.contact.is_some(), contact);
        }
        for w in samples.windows(2) {
            if w[0].run != w[1].run {
                continue;
            }
            let ds = w[1].s_mm - w[0].s_mm;
            let chord = (w[1].position - w[0].position).norm();
            prop_assert!(chord <= ds + 1e-9, "chord {} > ds {}", chord, ds);
            prop_assert!(w[1].t_s > w[0].t_s && w[1].theta_rad > w[0].theta_rad);
            let last_of_run = samples
                .iter()
                .rfind(|s| s.run == w[1].run)
                .is_some_and(|l| std::ptr::eq(l, &w[1]));
            if last_of_run {
                prop_assert!(ds <= fz * (1.0 + 1e-6) + 1e-12, "last ds {} > fz {}", ds, fz);
            } else {
                prop_assert!(abs_diff_eq!(ds, fz, epsilon = 1e-9), "ds {} vs fz {}", ds, fz);
            }
        }
        // Both ends of every run are kept.
        for (run, r) in path.cutting_runs().iter().enumerate() {
            let of_run: Vec<_> = samples.iter().filter(|s| s.run == run).collect();
            if let (Some(first), Some(last)) = (of_run.first(), of_run.last()) {
                prop_assert!((first.position - path.postures[r.start].position).norm() < 1e-9);
                prop_assert!((last.position - path.postures[r.end - 1].position).norm() < 1e-9);
                prop_assert_eq!(first.t_s, 0.0);
            }
        }
    }

    #[test]
    fn dtheta_mode_steps_theta_exactly(
        steps in prop::collection::vec(step(), 2..8),
        dtheta_deg in 2.0..30.0f64,
        fz in 0.02..0.2f64,
        teeth in 1usize..6,
        posture_feed in any::<bool>(),
    ) {
        let path = build(&steps, true);
        let dtheta = dtheta_deg.to_radians();
        let mut opts = Options::new(Mode::SpindleStep { dtheta_rad: dtheta }, fz, teeth);
        if posture_feed {
            let feeds = (0..path.postures.len()).map(|i| 300.0 + 250.0 * (i % 4) as f64).collect();
            opts = opts.with_rpm(6000.0).with_posture_feed_mm_min(feeds);
        }
        let samples = resample(&path, &opts).unwrap();
        // The spindle is derived from fz and the highest programmed cutting feed.
        let v_ref = path
            .cutting_runs()
            .iter()
            .flat_map(|r| (r.start + 1)..r.end)
            .filter_map(|i| path.postures[i].feed_mm_min)
            .fold(0.0, f64::max);
        for s in &samples {
            prop_assert!(distance_to_run(&path, s.run, &s.position) < 1e-9);
            check_frame(s);
        }
        for (i, w) in samples.windows(2).enumerate() {
            if w[0].run != w[1].run {
                continue;
            }
            let last_of_run = samples.get(i + 2).is_none_or(|n| n.run != w[1].run);
            let dth = w[1].theta_rad - w[0].theta_rad;
            if last_of_run {
                prop_assert!(dth > 0.0 && dth <= dtheta * (1.0 + 1e-6));
            } else {
                let tol = 1e-12 * (1.0 + w[1].theta_rad);
                prop_assert!(abs_diff_eq!(dth, dtheta, epsilon = tol), "dθ {}", dth);
                prop_assert!(w[1].s_mm >= w[0].s_mm);
            }
            let omega = w[1].theta_rad / w[1].t_s.max(1e-300);
            if w[1].t_s > 0.0 && !posture_feed {
                // θ = Ω t.
                let expected = v_ref / (teeth as f64 * fz) * TAU / 60.0;
                prop_assert!(relative_eq!(omega, expected, epsilon = 0.0, max_relative = 1e-9));
            }
        }
    }

    #[test]
    fn arcs_with_extra_turns_are_sampled_on_the_helix(
        r in 0.5..20.0f64,
        start in 0.0..TAU,
        sweep in 0.05..6.2f64,
        turns in 0u32..3,
        rise in -3.0..3.0f64,
        ccw in any::<bool>(),
        fz in 0.05..1.0f64,
    ) {
        let axis = if ccw { -Vec3::z() } else { Vec3::z() };
        let centre = Point3::new(1.0, 2.0, 3.0);
        // Clockwise about +z: the angle decreases.
        let sign = if ccw { 1.0 } else { -1.0 };
        let at = |phi: f64, h: f64| centre + Vec3::new(r * phi.cos(), r * phi.sin(), h);
        let p0 = at(start, 0.0);
        let p1 = at(start + sign * sweep, rise);
        let vertical = |p: Point3, motion, arc| Posture {
            arc,
            feed_mm_min: Some(800.0),
            line: 1,
            ..posture(p, Vec3::z(), motion)
        };
        let arc = ArcMove { centre, axis, radius_mm: r, extra_turns: turns };
        let path = Toolpath {
            postures: vec![vertical(p0, MotionKind::Rapid, None), vertical(p1, MotionKind::Cut, Some(arc))],
            ..Default::default()
        };
        let total = sweep + TAU * turns as f64;
        let len = total * (r * r + (rise / total).powi(2)).sqrt();
        let mut samples = Vec::new();
        let stats = resample_with(&path, &Options::new(Mode::FeedPerTooth, fz, 2), |s| samples.push(s.clone())).unwrap();
        prop_assert_eq!(stats.arcs, 1);
        prop_assert!(abs_diff_eq!(stats.length_mm, len, epsilon = 1e-9 * len.max(1.0)));
        // A grid sample within 1e-6 fz of the end is the end itself.
        prop_assert_eq!(samples.len() as f64, (len / fz - 1e-6).ceil() + 1.0);
        for s in &samples {
            let phi = start + sign * s.s_mm / len * total;
            let h = rise * s.s_mm / len;
            prop_assert!((s.position - at(phi, h)).norm() < 1e-9);
            check_frame(s);
        }
        prop_assert!((samples.last().unwrap().position - p1).norm() < 1e-9);
    }
}

// ---------------------------------------------------------------------------------------
// The incremental resampler against the whole-path one: random paths with several cutting
// runs, rapids, arcs, zero-length moves, FEDRAT changes, contact data or not, per-posture
// feeds, both modes, the spline.
// ---------------------------------------------------------------------------------------

/// A random posture: displacement, axis (polar, azimuth), normal (polar, azimuth),
/// kind (0-6 cut, 7 rapid, 8 arc, 9 zero-length), feed index.
type MixedStep = ([f64; 3], [f64; 2], [f64; 2], u8, u8);

fn mixed_step() -> impl Strategy<Value = MixedStep> {
    (step_geometry(), 0u8..10, 0u8..4).prop_map(|((d, a, n), kind, feed)| (d, a, n, kind, feed))
}

fn build_mixed(steps: &[MixedStep], contact: bool, feed_changes: bool) -> Toolpath {
    let mut position = Point3::origin();
    let mut postures: Vec<Posture> = Vec::new();
    for (i, (d, a, n, kind, feed)) in steps.iter().enumerate() {
        let start = position;
        let mut arc = None;
        match kind {
            9 => {}
            8 => {
                // An arc about a vertical axis through a centre beside the start.
                let centre = start + Vec3::new(d[0], d[1], 0.0);
                let r = (start - centre).norm();
                let phi = 0.3 + 0.5 * a[1];
                let v = start - centre;
                let (s, c) = phi.sin_cos();
                // Clockwise about +z by φ.
                let rot = Vec3::new(c * v.x + s * v.y, -s * v.x + c * v.y, 0.0);
                position = centre + rot + Vec3::new(0.0, 0.0, d[2]);
                arc = Some(ArcMove {
                    centre,
                    axis: Vec3::z(),
                    radius_mm: r,
                    extra_turns: u32::from(*feed == 3),
                });
            }
            _ => position += Vec3::new(d[0], d[1], d[2]),
        }
        let motion = if i == 0 || *kind == 7 {
            MotionKind::Rapid
        } else {
            MotionKind::Cut
        };
        postures.push(Posture {
            arc,
            contact: contact.then(|| contact_below(position, unit(n[0], n[1]))),
            feed_mm_min: Some(if feed_changes {
                400.0 + 300.0 * f64::from(*feed)
            } else {
                1200.0
            }),
            spindle_rpm: Some(9000.0),
            line: i as u32 + 1,
            ..posture(position, unit(a[0], a[1]), motion)
        });
    }
    Toolpath {
        postures,
        ..Default::default()
    }
}

/// Push the postures one by one; the spindle from a scan of the whole path when `scan`,
/// else resolved by the resampler at the first cutting move.
fn streamed(
    path: &Toolpath,
    opts: &Options,
    scan: bool,
) -> Result<(Vec<Sample>, Stats), ResampleError> {
    let mut r = Resampler::new(opts)?;
    if scan {
        let mut sc = SpindleScan::new();
        for p in &path.postures {
            sc.push(p);
        }
        if let Some((rpm, source)) = sc.resolve(opts)? {
            r = r.with_spindle(rpm, source);
        }
    }
    let mut out = Vec::new();
    for (i, p) in path.postures.iter().enumerate() {
        match &opts.posture_feed_mm_min {
            Some(f) => r.push_with_feed(p, f[i], |s| out.push(s.clone()))?,
            None => r.push(p, |s| out.push(s.clone()))?,
        }
    }
    let stats = r.finish(|s| out.push(s.clone()))?;
    Ok((out, stats))
}

fn whole(path: &Toolpath, opts: &Options) -> Result<(Vec<Sample>, Stats), ResampleError> {
    let mut out = Vec::new();
    let stats = resample_with(path, opts, |s| out.push(s.clone()))?;
    Ok((out, stats))
}

/// Bit-identical samples (f64 `==` on every field, NaN excluded by the resampler).
fn assert_same(a: &[Sample], b: &[Sample]) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x, y);
        assert_eq!(x.s_mm.to_bits(), y.s_mm.to_bits());
        assert_eq!(x.theta_rad.to_bits(), y.theta_rad.to_bits());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn streaming_equals_whole_path(
        steps in prop::collection::vec(mixed_step(), 1..16),
        contact in any::<bool>(),
        feed_changes in any::<bool>(),
        spline in any::<bool>(),
        nlerp in any::<bool>(),
        dtheta in any::<bool>(),
        posture_feed in any::<bool>(),
        fz in 0.05..0.5f64,
    ) {
        let path = build_mixed(&steps, contact, feed_changes);
        let mode = if dtheta {
            Mode::SpindleStep { dtheta_rad: 20f64.to_radians() }
        } else {
            Mode::FeedPerTooth
        };
        let kind = if nlerp { AxisInterpolation::Nlerp } else { AxisInterpolation::Slerp };
        let mut opts = Options::new(mode, fz, 3)
            .with_axis_interpolation(kind)
            .with_spline(spline);
        if posture_feed {
            let feeds = (0..path.postures.len()).map(|i| 300.0 + 250.0 * (i % 4) as f64).collect();
            opts = opts.with_posture_feed_mm_min(feeds);
        }
        let reference = whole(&path, &opts);
        let scanned = streamed(&path, &opts, true);
        match (&reference, &scanned) {
            (Ok((a, sa)), Ok((b, sb))) => {
                assert_same(a, b);
                prop_assert_eq!(sa, sb);
                prop_assert_eq!(sa.samples as usize, a.len());
            }
            (Err(a), Err(b)) => prop_assert_eq!(a, b),
            _ => prop_assert!(false, "{:?} vs {:?}", reference.as_ref().err(), scanned.as_ref().err()),
        }
        // Resolved at the first cutting move: the same whenever no later cutting move is
        // faster than the first (always with a constant FEDRAT).
        if !feed_changes && !posture_feed {
            let lazy = streamed(&path, &opts, false);
            match (&reference, &lazy) {
                (Ok((a, sa)), Ok((b, sb))) => {
                    assert_same(a, b);
                    prop_assert_eq!(sa, sb);
                }
                (Err(a), Err(b)) => prop_assert_eq!(a, b),
                _ => prop_assert!(false, "{:?} vs {:?}", reference.as_ref().err(), lazy.as_ref().err()),
            }
        }
    }
}

#[test]
fn lazy_spindle_is_the_first_cutting_feed_and_the_scan_the_highest() {
    let at = |x: f64, motion, feed: f64| Posture {
        feed_mm_min: Some(feed),
        line: 1,
        ..posture(Point3::new(x, 0.0, 0.0), Vec3::z(), motion)
    };
    let ps = [
        at(0.0, MotionKind::Rapid, 250.0),
        at(1.0, MotionKind::Cut, 250.0),
        at(2.0, MotionKind::Cut, 1000.0),
    ];
    let opts = Options::new(Mode::FeedPerTooth, 0.05, 4);
    let mut r = Resampler::new(&opts).unwrap();
    let mut scan = SpindleScan::new();
    for p in &ps {
        scan.push(p);
        r.push(p, |_| {}).unwrap();
    }
    // 250/(4·0.05) = 1250 rpm at the first cutting move; 1000/(4·0.05) = 5000 over all.
    assert_eq!(r.spindle(), Some((1250.0, SpindleSource::DerivedFromFeed)));
    assert_eq!(
        scan.resolve(&opts).unwrap(),
        Some((5000.0, SpindleSource::DerivedFromFeed))
    );
    let path = Toolpath {
        postures: ps.to_vec(),
        ..Default::default()
    };
    let stats = resample_with(&path, &opts, |_| {}).unwrap();
    assert_eq!(stats.spindle_rpm, Some(5000.0));
    // Nothing cut yet: nothing resolved; the option wins over everything.
    assert_eq!(SpindleScan::new().resolve(&opts).unwrap(), None);
    assert_eq!(
        scan.resolve(&opts.clone().with_rpm(777.0)).unwrap(),
        Some((777.0, SpindleSource::Option))
    );
}

// ---------------------------------------------------------------------------------------
// `crest resample` end to end: every real NX file of `CREST_EXTERNAL_SAMPLES` with
// cutting moves, both modes, contact columns, feed options, and the errors.
// ---------------------------------------------------------------------------------------

/// Run `crest resample … --json`, return the JSON and the CSV rows (as numbers, `None`
/// for empty cells).
fn run(file: &Path, extra: &[&str]) -> (serde_json::Value, Vec<Vec<Option<f64>>>) {
    let dir = tempdir();
    let out = dir.path().join("out.csv");
    let assert = crest()
        .arg("resample")
        .arg(file)
        .args(extra)
        .arg("-o")
        .arg(&out)
        .arg("--json")
        .assert()
        .success();
    (stdout_json(&assert), read_number_csv(&out, RESAMPLE_HEADER))
}

fn col(name: &str) -> usize {
    column(RESAMPLE_HEADER, name)
}

fn vec3(row: &[Option<f64>], first: &str) -> Option<[f64; 3]> {
    let i = col(first);
    Some([row[i]?, row[i + 1]?, row[i + 2]?])
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[test]
fn every_external_file_with_cutting_moves_resamples() {
    let Some(ext) = external_samples() else {
        return;
    };
    let files = external_cls_files(&ext);
    assert!(files.len() >= 12, "{files:?}");
    let fz = 0.5;
    for file in &files {
        let name = file.file_name().unwrap().to_string_lossy().to_string();
        let (json, rows) = run(file, &["--mode", "fz", "--fz-mm", "0.5", "--teeth", "2"]);
        let samples = json["samples"].as_u64().unwrap();
        assert_eq!(samples as usize, rows.len(), "{name}");
        // The drilling cycle file has no cutting (feed) moves at all: only cycle holes.
        if name == "nx_cycle_drill_deep.cls" {
            assert_eq!(samples, 0, "{name}");
            continue;
        }
        assert!(
            samples > 0 && json["runs"].as_u64().unwrap() > 0,
            "{name}: {json}"
        );
        let (s, t) = (col("s_mm"), col("t_s"));
        for (k, row) in rows.iter().enumerate() {
            assert_eq!(row.len(), 19, "{name} row {k}");
            let axis = vec3(row, "i").unwrap();
            let f = vec3(row, "fx").unwrap();
            assert!(
                abs_diff_eq!(norm(axis), 1.0, epsilon = 1e-8),
                "{name} row {k}"
            );
            assert!(abs_diff_eq!(norm(f), 1.0, epsilon = 1e-8), "{name} row {k}");
            assert!(
                abs_diff_eq!(dot(f, axis), 0.0, epsilon = 1e-8),
                "{name} row {k}"
            );
            assert!(row[col("feed_mm_min")].unwrap() > 0.0);
            // No contact data in these files: CC and normal are empty.
            assert!(vec3(row, "cx").is_none() && vec3(row, "nx").is_none());
            if k > 0 {
                let ds = row[s].unwrap() - rows[k - 1][s].unwrap();
                assert!((-1e-9..=fz + 2e-6).contains(&ds), "{name} row {k}: ds {ds}");
                let new_run = row[t].unwrap() == 0.0;
                if !new_run {
                    // Spacing is fz except the last sample of a run.
                    let last_of_run = rows.get(k + 1).is_none_or(|n| n[t].unwrap() == 0.0);
                    if !last_of_run {
                        assert!(
                            abs_diff_eq!(ds, fz, epsilon = 2e-6),
                            "{name} row {k}: ds {ds}"
                        );
                    }
                    let p0 = vec3(&rows[k - 1], "x").unwrap();
                    let p1 = vec3(row, "x").unwrap();
                    let chord = norm([p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]]);
                    assert!(chord <= ds + 2e-6, "{name} row {k}: chord {chord} > {ds}");
                }
            }
        }
    }
}

#[test]
fn dtheta_mode_steps_the_spindle_angle() {
    let Some(ext) = external_samples() else {
        return;
    };
    let file = ext.join("nx_5axis_varcontour_ijk_small.cls");
    let (json, rows) = run(
        &file,
        &[
            "--mode",
            "dtheta",
            "--fz-mm",
            "0.1",
            "--teeth",
            "4",
            "--dtheta-deg",
            "30",
        ],
    );
    assert_eq!(json["mode"], "dtheta");
    // ΔS = Z fz Δθ/2π = 0.4 × 30/360 mm at the programmed feed.
    assert_abs_diff_eq!(
        json["step_mm"].as_f64().unwrap(),
        0.4 / 12.0,
        epsilon = 1e-12
    );
    let (th, t) = (col("theta_deg"), col("t_s"));
    let mut steps = 0;
    for k in 1..rows.len() {
        if rows[k][t].unwrap() == 0.0 {
            assert_eq!(rows[k][th].unwrap(), 0.0);
            continue;
        }
        let dth = rows[k][th].unwrap() - rows[k - 1][th].unwrap();
        let last_of_run = rows.get(k + 1).is_none_or(|n| n[t].unwrap() == 0.0);
        if last_of_run {
            assert!(dth > 0.0 && dth <= 30.0 + 2e-6, "row {k}: {dth}");
        } else {
            assert!(abs_diff_eq!(dth, 30.0, epsilon = 2e-6), "row {k}: {dth}");
            steps += 1;
        }
    }
    assert!(steps > 1000);
}

#[test]
fn contact12_gives_contact_columns_and_time_needs_a_feed() {
    let file = repo("samples/clsf/ball_lead15_contact12.txt");
    let dir = tempdir();
    let out = dir.path().join("out.csv");
    // contact12 has no feed and no spindle speed: a spindle step needs a clock, and the
    // error names the options to add; no output file is left behind.
    let assert = crest()
        .arg("resample")
        .arg(&file)
        .args(["--mode", "dtheta", "--fz-mm", "0.05", "--teeth", "4", "-o"])
        .arg(&out)
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    assert!(
        err.contains("--feed-mm-min") && err.contains("--rpm"),
        "{err}"
    );
    assert!(!out.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    // Feed per tooth and θ need no clock: time and feed are left empty.
    let (json0, timeless) = run(&file, &["--mode", "fz", "--fz-mm", "0.05", "--teeth", "4"]);
    assert_eq!(json0["paths"][0]["stats"]["spindle_source"], "nominal");
    assert!(json0["paths"][0]["stats"]["spindle_rpm"].is_null());

    let (json, rows) = run(
        &file,
        &[
            "--mode", "fz", "--fz-mm", "0.05", "--teeth", "4", "--rpm", "10000",
        ],
    );
    assert_eq!(timeless.len(), rows.len());
    for (a, b) in timeless.iter().zip(&rows) {
        assert!(a[col("t_s")].is_none() && a[col("feed_mm_min")].is_none());
        assert_eq!(a[col("s_mm")], b[col("s_mm")]);
        assert_eq!(a[col("x")], b[col("x")]);
        assert_abs_diff_eq!(
            a[col("theta_deg")].unwrap(),
            b[col("theta_deg")].unwrap(),
            epsilon = 2e-6
        );
    }
    let stats = &json["paths"][0]["stats"];
    assert_eq!(stats["spindle_source"], "option");
    // V = Z fz n = 2000 mm/min, so t = s/V within a run.
    assert_abs_diff_eq!(
        stats["feed_max_mm_min"].as_f64().unwrap(),
        2000.0,
        epsilon = 1e-9
    );
    assert!(!rows.is_empty());
    let mut with_contact = 0;
    for row in &rows {
        if let (Some(_), Some(n)) = (vec3(row, "cx"), vec3(row, "nx")) {
            with_contact += 1;
            let f = vec3(row, "fx").unwrap();
            assert_abs_diff_eq!(norm(n), 1.0, epsilon = 1e-8);
            assert!(
                abs_diff_eq!(dot(f, n), 0.0, epsilon = 1e-8),
                "f·n = {}",
                dot(f, n)
            );
        }
    }
    assert!(
        with_contact > rows.len() / 2,
        "{with_contact} of {}",
        rows.len()
    );
}

#[test]
fn feed_option_sets_the_clock() {
    let Some(ext) = external_samples() else {
        return;
    };
    let file = ext.join("nx_circle_times_from.cls");
    let (json, rows) = run(
        &file,
        &[
            "--mode",
            "fz",
            "--fz-mm",
            "0.05",
            "--teeth",
            "2",
            "--feed-mm-min",
            "600",
            // The engage and retract arcs too (6 arcs).
            "--moves",
            "all",
        ],
    );
    let stats = &json["paths"][0]["stats"];
    assert_eq!(stats["arcs"], 6);
    assert_eq!(stats["spindle_source"], "derived_from_feed");
    assert_abs_diff_eq!(
        stats["spindle_rpm"].as_f64().unwrap(),
        6000.0,
        epsilon = 1e-9
    );
    // One run: t = s/V and θ = 2π s/(Z fz) (180° a sample).
    let last = rows.last().unwrap();
    let s = last[col("s_mm")].unwrap();
    assert_abs_diff_eq!(last[col("t_s")].unwrap(), s / 10.0, epsilon = 1e-6);
    assert_abs_diff_eq!(
        last[col("theta_deg")].unwrap(),
        s / 0.1 * 360.0,
        epsilon = 1e-3
    );
    assert_abs_diff_eq!(rows[1][col("theta_deg")].unwrap(), 180.0, epsilon = 1e-6);
    // The first move is a helix about the arc centre (1287.5, −341.25), radius 56.25.
    for row in rows.iter().take(8000) {
        let (x, y) = (row[col("x")].unwrap(), row[col("y")].unwrap());
        let r = (x - 1287.5).hypot(y + 341.25);
        assert!(abs_diff_eq!(r, 56.25, epsilon = 1e-4), "{r}");
    }
}

#[test]
fn bad_options_are_usage_errors() {
    let file = nx_sample("nx_iso_header_units_mm.cls");
    let dir = tempdir();
    let out = dir.path().join("out.csv");
    crest()
        .arg("resample")
        .arg(&file)
        .args(["--mode", "fz", "--fz-mm", "0", "--teeth", "2", "-o"])
        .arg(&out)
        .assert()
        .code(2);
    crest()
        .arg("resample")
        .arg(&file)
        .args(["--mode", "sideways", "--fz-mm", "0.1", "--teeth", "2", "-o"])
        .arg(&out)
        .assert()
        .code(2);
    crest()
        .arg("resample")
        .arg(dir.path().join("missing.cls"))
        .args(["--mode", "fz", "--fz-mm", "0.1", "--teeth", "2", "-o"])
        .arg(&out)
        .assert()
        .code(2);
    assert!(!out.exists());
}

#[test]
fn machine_feed_follows_the_kinematics() {
    let Some(ext) = external_samples() else {
        return;
    };
    let file = ext.join("nx_circle_times_from.cls");
    let machine = repo("samples/machines/table1_ac.toml");
    let (json, rows) = run(
        &file,
        &[
            "--mode",
            "dtheta",
            "--dtheta-deg",
            "90",
            "--fz-mm",
            "0.1",
            "--teeth",
            "2",
            "--machine",
            machine.to_str().unwrap(),
            // From the engage on, which starts from rest.
            "--moves",
            "all",
        ],
    );
    let stats = &json["paths"][0]["stats"];
    // The spindle comes from fz and the programmed 530 mm/min: 530/(2·0.1) rpm.
    assert_eq!(stats["spindle_source"], "derived_from_feed");
    assert_abs_diff_eq!(
        stats["spindle_rpm"].as_f64().unwrap(),
        2650.0,
        epsilon = 1e-9
    );
    // The engage starts from rest and never exceeds the programmed feed.
    assert!(stats["variable_feed_moves"].as_u64().unwrap() > 0);
    let feed = col("feed_mm_min");
    assert_eq!(rows[0][feed], Some(0.0));
    assert!(rows.iter().all(|r| r[feed].unwrap() <= 530.0 + 1e-3));
    // θ still steps by exactly Δθ while the feed varies; the arc length per step follows
    // the feed (ΔS = V Δθ/Ω).
    let (th, s, t) = (col("theta_deg"), col("s_mm"), col("t_s"));
    let omega_deg_s = 2650.0 * 6.0;
    for k in 1..rows.len() - 1 {
        assert_abs_diff_eq!(
            rows[k][th].unwrap() - rows[k - 1][th].unwrap(),
            90.0,
            epsilon = 2e-6
        );
        assert_abs_diff_eq!(
            rows[k][th].unwrap(),
            omega_deg_s * rows[k][t].unwrap(),
            epsilon = 1e-3
        );
        assert!(rows[k][s].unwrap() >= rows[k - 1][s].unwrap());
    }
}

// ---------------------------------------------------------------------------------------
// `crest resample` streams the file (no `--machine`): the spindle speed is still derived
// from the highest cutting feed of the whole path when a slower engage comes first (the
// file is then resampled a second time), and `--path` counts tool paths without postures.
// ---------------------------------------------------------------------------------------

const CLSF: &str = "\
TOOL PATH/EMPTY,TOOL,T1
END-OF-PATH
TOOL PATH/CUT,TOOL,T1
RAPID
GOTO/0.0000,0.0000,1.0000,0.0000000,0.0000000,1.0000000
FEDRAT/MMPM,250.0000
GOTO/0.0000,0.0000,0.0000
FEDRAT/MMPM,1000.0000
GOTO/10.0000,0.0000,0.0000
GOTO/10.0000,5.0000,0.0000
RAPID
GOTO/10.0000,5.0000,5.0000
GOTO/20.0000,5.0000,0.0000
END-OF-PATH
";

/// `crest resample FILE --mode fz --fz-mm 0.1 --teeth 2 --json -o OUT …`: the JSON and
/// the CSV text.
fn run_to(file: &Path, out: &Path, extra: &[&str]) -> (serde_json::Value, String) {
    let assert = crest()
        .arg("resample")
        .arg(file)
        .args([
            "--mode", "fz", "--fz-mm", "0.1", "--teeth", "2", "--json", "-o",
        ])
        .arg(out)
        .args(extra)
        .assert()
        .success();
    (stdout_json(&assert), read(out))
}

#[test]
fn slower_engage_first_and_empty_tool_paths() {
    let dir = tempdir();
    let file = write(dir.path(), "engage.cls", CLSF);
    // Every feed move: the slower engage is resampled too.
    let (json, csv) = run_to(&file, &dir.path().join("all.csv"), &["--moves", "all"]);
    assert_eq!(json["paths"].as_array().unwrap().len(), 2);
    assert_eq!(json["paths"][0]["name"], "EMPTY");
    assert_eq!(json["paths"][0]["postures"], 0);
    assert_eq!(json["paths"][0]["stats"]["samples"], 0);
    let p = &json["paths"][1];
    assert_eq!(
        (p["index"].as_u64(), p["postures"].as_u64()),
        (Some(2), Some(6))
    );
    let stats = &p["stats"];
    // n = 1000/(2·0.1) = 5000 rpm from the fast moves, not 250/(2·0.1) from the engage.
    assert_eq!(stats["spindle_source"], "derived_from_feed");
    assert_eq!(stats["spindle_rpm"].as_f64(), Some(5000.0));
    assert_eq!(stats["runs"], 2);
    // Run 1: 1 mm at 250 then 15 mm at 1000 mm/min; run 2 (after the rapid): √125 mm.
    let run2 = 125f64.sqrt();
    assert_abs_diff_eq!(
        stats["length_mm"].as_f64().unwrap(),
        16.0 + run2,
        epsilon = 1e-9
    );
    assert_eq!(json["samples"], 161 + (run2 / 0.1).ceil() as u64 + 1);
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len() as u64, json["samples"].as_u64().unwrap());
    // End of run 1: t = 1/250 + 15/1000 min, θ = Ω t with Ω = 5000 rpm.
    let end1 = &rows[160];
    assert_eq!(end1[0], "16.000000");
    let t = (1.0 / 250.0 + 15.0 / 1000.0) * 60.0;
    assert_abs_diff_eq!(end1[1].parse::<f64>().unwrap(), t, epsilon = 1e-9);
    assert_abs_diff_eq!(
        end1[2].parse::<f64>().unwrap(),
        5000.0 * 360.0 * t / 60.0,
        epsilon = 1e-6
    );
    assert_eq!(end1[18], "1000.000");
    // Run 2 restarts the clock.
    assert_eq!(rows[161][1], "0.000000000");

    // `--path 2` is the second tool path of the file, the first with postures.
    let (json2, csv2) = run_to(
        &file,
        &dir.path().join("two.csv"),
        &["--path", "2", "--moves", "all"],
    );
    assert_eq!(json2["paths"][0]["index"], 2);
    assert_eq!(json2["paths"][0]["stats"], *stats);
    assert_eq!(csv2, csv);
    let (json1, csv1) = run_to(&file, &dir.path().join("one.csv"), &["--path", "1"]);
    assert_eq!(json1["samples"], 0);
    assert_eq!(csv1.lines().count(), 1);
    // By default only the cut moves: the slower first move (an engage by its feed, the
    // file has no colours) is left out, run 1 is the 15 mm at 1000 mm/min.
    let (json_cut, _) = run_to(&file, &dir.path().join("cut.csv"), &[]);
    let cut = &json_cut["paths"][1]["stats"];
    assert_abs_diff_eq!(
        cut["length_mm"].as_f64().unwrap(),
        15.0 + run2,
        epsilon = 1e-9
    );
    assert_eq!(cut["spindle_rpm"].as_f64(), Some(5000.0));
    // Out of range: an error, and no output file.
    let out = dir.path().join("three.csv");
    crest()
        .arg("resample")
        .arg(&file)
        .args([
            "--mode", "fz", "--fz-mm", "0.1", "--teeth", "2", "--path", "3", "-o",
        ])
        .arg(&out)
        .assert()
        .code(2);
    assert!(!out.exists());
}

/// `--mode dtheta` needs no feed per tooth when the file has its spindle speed: the same
/// samples as with the fz and teeth that give that speed (n = V / (Z fz)), every 90° the
/// tool advances V / n / 4; `--mode fz` without them is a usage error.
#[test]
fn dtheta_takes_the_spindle_from_the_file() {
    let file = nx_sample("nx_zlevel_core_spindl.cls"); // SPINDL 1000 rpm, FEDRAT 250 mm/min
    let (json, rows) = run(&file, &["--mode", "dtheta", "--dtheta-deg", "90"]);
    assert!(json["fz_mm"].is_null() && json["teeth"].is_null());
    assert_eq!(json["paths"][0]["stats"]["spindle_rpm"], 1000.0);
    let (_, same) = run(
        &file,
        &[
            "--mode",
            "dtheta",
            "--dtheta-deg",
            "90",
            "--fz-mm",
            "0.125",
            "--teeth",
            "2",
        ],
    );
    assert!(rows.len() > 10);
    assert_eq!(rows, same);
    let s = col("s_mm");
    let steps: Vec<f64> = rows
        .windows(2)
        .filter_map(|w| Some(w[1][s]? - w[0][s]?))
        .filter(|d| *d > 1e-9)
        .collect();
    let full = steps.iter().filter(|d| (*d - 0.0625).abs() < 1e-9).count();
    assert!(
        full * 10 > steps.len() * 9,
        "{full} of {} steps are 0.0625 mm",
        steps.len()
    );
    let dir = tempdir();
    crest()
        .arg("resample")
        .arg(&file)
        .args(["--mode", "fz", "-o"])
        .arg(dir.path().join("o.csv"))
        .assert()
        .code(2)
        .stderr(predicates::str::contains("--mode fz spaces the samples"));
}
