//! `crest metrics` end to end: JSON keys are ISO symbols, only the asked parameters are
//! computed, profiles and filters are wired, bad input exits 2 with a located message.

use std::f64::consts::PI;
use std::path::Path;

use assert_cmd::Command;
use crest::io::write_heightmap;
use crest::surface::HeightMap;
use predicates::prelude::*;

fn crest() -> Command {
    Command::cargo_bin("crest").unwrap()
}

/// 5 periods of 2·sin(2πx/100) on 1000 × `ny` nodes, dx = dy = 0.5 µm.
fn write_sine_rows(dir: &Path, name: &str, ny: usize) -> std::path::PathBuf {
    let nx = 1000;
    let z = (0..nx * ny)
        .map(|k| 2.0 * (2.0 * PI * (k % nx) as f64 * 0.5 / 100.0).sin())
        .collect();
    let m = HeightMap::from_rows(nx, ny, 0.5, 0.5, z).unwrap();
    let p = dir.join(name);
    write_heightmap(&p, &m).unwrap();
    p
}

fn write_sine(dir: &Path, name: &str) -> std::path::PathBuf {
    write_sine_rows(dir, name, 20)
}

fn json(cmd: &mut Command) -> serde_json::Value {
    let out = cmd.assert().success().get_output().stdout.clone();
    serde_json::from_slice(&out).unwrap()
}

#[test]
fn quick_sa_on_csv_gives_only_what_was_asked() {
    let dir = tempfile::tempdir().unwrap();
    let f = write_sine(dir.path(), "s.csv");
    let v = json(
        crest()
            .args(["metrics"])
            .arg(&f)
            .args(["--dx-um", "0.5", "--params", "Sa,Sq", "--json"]),
    );
    let sa = v["Sa"].as_f64().unwrap();
    assert!(
        (sa - (2.0 * 2.0 / 200.0) / (PI / 200.0).tan()).abs() < 1e-9,
        "{sa}"
    );
    assert!((v["Sq"].as_f64().unwrap() - 2f64.sqrt()).abs() < 1e-9);
    assert!(v.get("Sdr").is_none() && v.get("Sal").is_none());
    assert_eq!(v["units"]["Sa"], "µm");
    assert_eq!(v["level"], "none");
    assert_eq!(v["nx"], 1000);
}

#[test]
fn gsf_all_areal_parameters_str_undefined_is_null() {
    let dir = tempfile::tempdir().unwrap();
    let f = write_sine(dir.path(), "s.gsf");
    let v = json(crest().args(["metrics"]).arg(&f).arg("--json"));
    for k in [
        "Sa", "Sq", "Sp", "Sv", "Sz", "Ssk", "Sku", "Sdq", "Sdr", "Sal", "Std", "Sk", "Vmp", "Vvv",
    ] {
        assert!(v[k].is_number(), "{k}: {}", v[k]);
    }
    assert!(v["Str"].is_null(), "1-D lay: Str undefined → null");
    assert!((v["Sz"].as_f64().unwrap() - 4.0).abs() < 1e-5);
}

#[test]
fn profile_rz_over_five_sampling_lengths() {
    let dir = tempfile::tempdir().unwrap();
    let f = write_sine(dir.path(), "s.sdf");
    let v = json(crest().args(["metrics"]).arg(&f).args([
        "--profile",
        "row:3",
        "--params",
        "Rz,Rt,RSm",
        "--json",
    ]));
    assert!((v["Rz"].as_f64().unwrap() - 4.0).abs() < 1e-9);
    assert!((v["Rt"].as_f64().unwrap() - 4.0).abs() < 1e-9);
    assert!((v["RSm"].as_f64().unwrap() - 100.0).abs() < 1e-6);
    assert_eq!(v["profile"]["sections"], 5);
    assert_eq!(v["profile"]["spec"], "row:3");
}

#[test]
fn filters_and_trim_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let f = write_sine_rows(dir.path(), "s.gsf", 240);
    let v = json(crest().args(["metrics"]).arg(&f).args([
        "--level",
        "poly:3",
        "--lambda-c-um",
        "100",
        "--ends",
        "trim",
        "--params",
        "Sq",
        "--json",
    ]));
    assert!(v["end_effects"].as_str().unwrap().contains("ISO 4288"));
    assert_eq!(v["evaluated_nx"], 1000 - 200);
    assert_eq!(v["evaluated_ny"], 240 - 200);
    // λ = λc: half the amplitude passes the high-pass: Sq ≈ 2/√2 · 0.5.
    let sq = v["Sq"].as_f64().unwrap();
    assert!((sq - 2f64.sqrt() * 0.5).abs() < 0.01, "{sq}");
}

#[test]
fn help_states_default_level() {
    crest()
        .args(["metrics", "--help"])
        .assert()
        .success()
        .stdout(predicate::str::contains("Default `none`"));
}

#[test]
fn bad_inputs_exit_2_with_location() {
    let dir = tempfile::tempdir().unwrap();
    let f = write_sine(dir.path(), "s.csv");
    crest()
        .args(["metrics"])
        .arg(&f)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--dx-um"));
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "1,2\n3,oops\n").unwrap();
    crest()
        .args(["metrics"])
        .arg(&bad)
        .args(["--dx-um", "1"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("bad.csv:2: field 2"));
    crest()
        .args(["metrics"])
        .arg(&f)
        .args(["--dx-um", "0.5", "--params", "Ra"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("profile"));
    crest()
        .args(["metrics"])
        .arg(&f)
        .args(["--dx-um", "0.5", "--level", "cylinder"])
        .assert()
        .code(2);
}
