//! `crest feed` end to end on real NX files: JSON contract keys, CSV output, exit codes
//! and machine-file errors that name the file and the line.

use assert_cmd::Command;
use predicates::prelude::*;

const AC: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/samples/machines/table1_ac.toml"
);
const NUT: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/samples/machines/table1_nutating45.toml"
);
const CIRCLE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../shared/samples-external/nx_circle_times_from.cls"
);
const VARC: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../shared/samples-external/nx_5axis_varcontour_ijk_small.cls"
);

fn crest() -> Command {
    Command::cargo_bin("crest").unwrap()
}

#[test]
fn json_has_the_contract_keys() {
    let out = crest()
        .args(["feed", CIRCLE, "--machine", AC, "--json"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    let total = v["total_time_s"].as_f64().unwrap();
    let programmed = v["programmed_time_s"].as_f64().unwrap();
    let ratio = v["time_ratio"].as_f64().unwrap();
    assert!(total >= programmed && programmed > 0.0);
    assert!((ratio - total / programmed).abs() < 1e-12);
    let path = &v["paths"][0];
    let postures = path["postures"].as_array().unwrap();
    assert!(postures.len() > 5);
    let mut last_t = -1.0;
    for p in postures {
        let t = p["t_s"].as_f64().unwrap();
        assert!(t > last_t);
        last_t = t;
        assert!(p["feed_mm_min"].as_f64().unwrap() >= 0.0);
        assert!(p["limit"].is_string());
        for j in ["X", "Y", "Z", "A", "C"] {
            assert!(p["joints"][j].is_number(), "{j}");
        }
    }
    assert!((last_t - path["total_time_s"].as_f64().unwrap()).abs() < 1e-9);
    assert_eq!(path["fallbacks"], 0);
}

#[test]
fn five_axis_file_on_both_machines_with_csv() {
    let dir = tempfile::tempdir().unwrap();
    for m in [AC, NUT] {
        let csv = dir.path().join("poses.csv");
        crest()
            .args(["feed", VARC, "--machine", m, "--absolute", "-o"])
            .arg(&csv)
            .assert()
            .success()
            .stdout(predicate::str::contains("VARIABLE_CONTOUR"));
        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines = text.lines();
        assert!(lines.next().unwrap().starts_with(
            "path,index,line,t_s,feed_mm_min,path_speed_mm_min,programmed_feed_mm_min,limit,branch,X,Y,Z,"
        ));
        assert_eq!(lines.count(), 546);
    }
    // In the MCS the tool points along −Z: beyond A's ±120° travel.
    crest()
        .args(["feed", VARC, "--machine", AC])
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "nx_5axis_varcontour_ijk_small.cls:11:1",
        ));
}

#[test]
fn bad_machine_names_file_key_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("m.toml");
    let text = std::fs::read_to_string(AC)
        .unwrap()
        .replacen("amax = 5000.0", "amax = 5.0", 1);
    let line = text[..text.find("amax = 5.0").unwrap()].lines().count() + 1;
    std::fs::write(&bad, text).unwrap();
    crest()
        .args(["feed", CIRCLE, "--machine"])
        .arg(&bad)
        .assert()
        .code(2)
        .stderr(predicate::str::contains(format!("m.toml:{line}:1")))
        .stderr(predicate::str::contains("amax"));
}
