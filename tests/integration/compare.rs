//! `crest compare` (issue 34 §2): registration of a closed-form scallop and feed-mark map
//! rotated, shifted, tilted, noisy and with missing points; a map against itself; exit codes.

use std::path::{Path, PathBuf};

use crest::io::write_heightmap;
use crest::surface::HeightMap;

use crate::util::{crest, stdout_json, tempdir};

/// Stepover (scallop period across the feed), µm.
const STEPOVER: f64 = 30.0;
/// Feed-mark period along the feed, µm.
const FEED: f64 = 12.0;

/// The closed-form surface at (u along the feed, v across), µm: a parabolic scallop of a
/// 0.5 mm ball across, and asymmetric feed marks (a fundamental and its second harmonic)
/// along.
fn surface(u: f64, v: f64) -> f64 {
    let w = v - STEPOVER * (v / STEPOVER).round();
    let t = 2.0 * std::f64::consts::PI * u / FEED;
    w * w / 1000.0 + 0.02 * (t.sin() + 0.35 * (2.0 * t).sin())
}

/// A small deterministic generator in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The prediction: feed along +x, 600 × 600 nodes at 0.8 µm.
fn predicted() -> HeightMap {
    let (n, d) = (600, 0.8);
    let c = (n - 1) as f64 * d / 2.0;
    let mut z = Vec::with_capacity(n * n);
    for r in 0..n {
        for col in 0..n {
            z.push(surface(col as f64 * d - c, r as f64 * d - c));
        }
    }
    HeightMap::from_rows(n, n, d, d, z).unwrap()
}

/// The "measurement": the prediction's surface rotated by `deg` about the centre, moved by
/// `shift` µm, tilted, with noise and missing nodes; 320 × 320 nodes at 1 µm.
fn measured(deg: f64, shift: [f64; 2], seed: u64) -> HeightMap {
    let (n, d) = (320, 1.0);
    let c = (n - 1) as f64 * d / 2.0;
    let (s, co) = deg.to_radians().sin_cos();
    let mut rng = Lcg(seed);
    let mut z = Vec::with_capacity(n * n);
    for r in 0..n {
        for col in 0..n {
            let (x, y) = (col as f64 * d, r as f64 * d);
            let (mx, my) = (x - c - shift[0], y - c - shift[1]);
            let (u, v) = (co * mx + s * my, -s * mx + co * my);
            let mut h = surface(u, v) + 0.002 * x - 0.001 * y + 0.02 * (rng.next() - 0.5);
            if rng.next() < 0.02 || (40..46).contains(&r) && (200..230).contains(&col) {
                h = f64::NAN;
            }
            z.push(h);
        }
    }
    HeightMap::from_rows(n, n, d, d, z).unwrap()
}

fn save(dir: &Path, name: &str, m: &HeightMap) -> PathBuf {
    let p = dir.join(name);
    write_heightmap(&p, m).unwrap();
    p
}

/// Distance between two axis directions (mod 180°), degrees.
fn axis_err(a: f64, b: f64) -> f64 {
    ((a - b + 90.0).rem_euclid(180.0) - 90.0).abs()
}

fn num(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

#[test]
fn registration_of_rotated_shifted_tilted_noisy_maps() {
    let dir = tempdir();
    let pred = save(dir.path(), "pred.gsf", &predicted());
    let shift = [3.4, -2.7];
    for (k, deg) in [0.0, 30.0, 90.0, 135.0, 172.5].into_iter().enumerate() {
        let meas = save(
            dir.path(),
            &format!("meas{k}.gsf"),
            &measured(deg, shift, k as u64 + 1),
        );
        let out = dir.path().join(format!("out{k}"));
        let a = crest()
            .arg("compare")
            .arg(&pred)
            .arg(&meas)
            .arg("-o")
            .arg(&out)
            .arg("--json")
            .assert();
        let code = a.get_output().status.code();
        assert!(code == Some(0) || code == Some(1), "{deg}°: {code:?}");
        let j = stdout_json(&a);
        let dp = num(&j["feed_direction_deg"]["predicted"]);
        let dm = num(&j["feed_direction_deg"]["measured"]);
        assert!(axis_err(dp, 0.0) < 0.5, "{deg}°: predicted direction {dp}");
        assert!(axis_err(dm, deg) < 0.5, "{deg}°: measured direction {dm}");
        let (sx, sy) = (num(&j["shift_um"][0]), num(&j["shift_um"][1]));
        assert!(
            (sx - shift[0]).hypot(sy - shift[1]) < 1.0,
            "{deg}°: shift ({sx}, {sy}) for {shift:?}"
        );
        assert!(num(&j["correlation"]) > 0.9, "{deg}°: {}", j["correlation"]);
        for (key, want) in [("feed_period_um", FEED), ("stepover_um", STEPOVER)] {
            for side in ["predicted", "measured"] {
                let got = num(&j[key][side]);
                assert!(
                    (got / want - 1.0).abs() < 0.02,
                    "{deg}°: {key} {side} {got} for {want}"
                );
            }
        }
        for f in [
            "compare.md",
            "compare.html",
            "measured.png",
            "difference.png",
            "profiles-along.svg",
        ] {
            assert!(out.join(f).is_file(), "{deg}°: no {f}");
        }
    }
}

#[test]
fn a_map_against_itself() {
    let dir = tempdir();
    let meas = save(dir.path(), "m.gsf", &measured(30.0, [0.0, 0.0], 7));
    let out = dir.path().join("out");
    let a = crest()
        .arg("compare")
        .arg(&meas)
        .arg(&meas)
        .arg("-o")
        .arg(&out)
        .arg("--json")
        .assert()
        .code(0);
    let j = stdout_json(&a);
    assert!(
        (num(&j["correlation"]) - 1.0).abs() < 1e-9,
        "{}",
        j["correlation"]
    );
    assert!(num(&j["residual_sq_um"]).abs() < 1e-9);
    assert_eq!(num(&j["shift_um"][0]), 0.0);
    assert_eq!(num(&j["shift_um"][1]), 0.0);
    let params = j["params"].as_object().unwrap();
    for name in [
        "Sa", "Sq", "Sp", "Sv", "Sz", "Ssk", "Sku", "Sdq", "Sdr", "Sal", "Str", "Std",
    ] {
        let p = &params[name];
        let d = &p["diff_pct"];
        assert!(
            d.is_null() || d.as_f64().unwrap().abs() < 1e-6,
            "{name}: {p}"
        );
        assert_eq!(p["predicted"], p["measured"], "{name}");
    }
    // The measured values are those of `crest metrics` with the same chain.
    let m = stdout_json(
        &crest()
            .arg("metrics")
            .arg(&meas)
            .args(["--level", "plane", "--params", "Sa,Sq,Sdq,Sal", "--json"])
            .assert()
            .success(),
    );
    for name in ["Sa", "Sq", "Sdq", "Sal"] {
        let (a, b) = (num(&params[name]["measured"]), num(&m[name]));
        assert!((a / b - 1.0).abs() < 1e-6, "{name}: {a} vs {b}");
    }
    let md = std::fs::read_to_string(out.join("compare.md")).unwrap();
    assert!(md.contains("PASS"), "{md}");
}

#[test]
fn exit_codes() {
    let dir = tempdir();
    let m = measured(0.0, [0.0, 0.0], 3);
    let meas = save(dir.path(), "m.gsf", &m);
    let mut high = m.clone();
    for z in high.z_um.iter_mut() {
        *z *= 1.5;
    }
    let pred = save(dir.path(), "p.gsf", &high);
    let a = crest()
        .arg("compare")
        .arg(&pred)
        .arg(&meas)
        .arg("-o")
        .arg(dir.path().join("o1"))
        .assert()
        .code(1);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("verdict fails") && err.contains("Sa"), "{err}");
    // Within a wide tolerance the same pair passes.
    crest()
        .arg("compare")
        .arg(&pred)
        .arg(&meas)
        .arg("-o")
        .arg(dir.path().join("o2"))
        .args(["--tolerance-pct", "200"])
        .assert()
        .code(0);
    // A prediction too small to cover the measurement: exit 2, both files named.
    let tiny = HeightMap::from_rows(4, 4, 1.0, 1.0, (0..16).map(f64::from).collect()).unwrap();
    let tiny = save(dir.path(), "tiny.gsf", &tiny);
    let a = crest()
        .arg("compare")
        .arg(&tiny)
        .arg(&meas)
        .arg("-o")
        .arg(dir.path().join("o4"))
        .arg("--no-register")
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("tiny.gsf") && err.contains("m.gsf"), "{err}");
    // Bad input: a missing file, a damaged one; named, nothing written.
    let bad = crate::util::write(
        dir.path(),
        "bad.gsf",
        "Gwyddion Simple Field 1.0\nXRes = 3\n",
    );
    for f in [dir.path().join("none.gsf"), bad] {
        let out = dir.path().join("o3");
        let a = crest()
            .arg("compare")
            .arg(&pred)
            .arg(&f)
            .arg("-o")
            .arg(&out)
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        assert!(err.contains(&name), "{err}");
        assert!(!out.join("compare.md").exists());
    }
}
