//! `crest tool` end to end: JSON keys and values, text output, and rejected tool files that
//! name the key, the file and the line.

use assert_cmd::Command;
use predicates::prelude::*;

const BALL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/samples/tools/ball-r5-z4.toml");
const TORUS: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/samples/tools/torus-r5-rc1.5.toml"
);

fn crest() -> Command {
    Command::cargo_bin("crest").unwrap()
}

fn json(args: &[&str]) -> serde_json::Value {
    let out = crest()
        .args(args)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    serde_json::from_slice(&out).unwrap()
}

#[test]
fn json_has_the_contract_keys_and_table3_values() {
    let v = json(&[
        "tool",
        "--tool",
        BALL,
        "--lead-deg",
        "25",
        "--ap-mm",
        "0.4",
        "--fz-mm",
        "0.05",
        "--json",
    ]);
    for key in [
        "effective_radius_mm",
        "cutting_speed_ratio",
        "crest_height_um",
        "teeth",
        "zc",
        "fz_effective_mm",
        "crest_height_corrected_um",
    ] {
        assert!(v.get(key).is_some(), "missing {key}: {v}");
    }
    assert!((v["effective_radius_mm"].as_f64().unwrap() - 3.72004).abs() < 6e-6);
    let ratio = v["cutting_speed_ratio"].as_f64().unwrap();
    assert!((ratio - 0.74401).abs() < 6e-6);
    assert!((v["crest_height_um"].as_f64().unwrap() - 0.0625004).abs() < 1e-6);
    assert_eq!(v["zc"], 1);
    assert!((v["fz_effective_mm"].as_f64().unwrap() - 0.2).abs() < 1e-12);
    assert!((v["crest_height_corrected_um"].as_f64().unwrap() - 1.0001).abs() < 1e-4);
    assert_eq!(v["rule"], "paper");
    let teeth = v["teeth"].as_array().unwrap();
    assert_eq!(teeth.len(), 4);
    for (i, t) in teeth.iter().enumerate() {
        assert_eq!(t["index"], i + 1);
        assert!(t["radius_mm"].is_f64());
        assert_eq!(t["participates"], i == 0);
    }
    assert!((teeth[3]["radius_mm"].as_f64().unwrap() - 4.975).abs() < 1e-12);
    assert!((teeth[3]["effective_radius_mm"].as_f64().unwrap() - 3.70484).abs() < 6e-6);
}

#[test]
fn exact_rule_and_torus() {
    let v = json(&[
        "tool",
        "--tool",
        BALL,
        "--lead-deg",
        "15",
        "--ap-mm",
        "0.4",
        "--fz-mm",
        "0.05",
        "--rule",
        "exact",
        "--json",
    ]);
    assert_eq!(v["rule"], "exact");
    assert!((v["crest_height_corrected_um"].as_f64().unwrap() - 1.0021).abs() < 1e-4);
    let v = json(&[
        "tool",
        "--tool",
        TORUS,
        "--lead-deg",
        "10",
        "--ap-mm",
        "0.2",
        "--fz-mm",
        "0.26667",
        "--json",
    ]);
    assert_eq!(v["shape"], "torus");
    assert_eq!(v["zc"], 1);
    // Generating radius rc on both sides at 10°: 1.5 − √(1.5² − s²/4).
    let hc = (1.5 - (2.25f64 - 0.26667f64.powi(2) / 4.0).sqrt()) * 1e3;
    assert!((v["crest_height_um"].as_f64().unwrap() - hc).abs() < 1e-6);
}

#[test]
fn text_output_lists_teeth() {
    crest()
        .args([
            "tool",
            "--tool",
            BALL,
            "--lead-deg",
            "5",
            "--ap-mm",
            "0.4",
            "--fz-mm",
            "0.05",
        ])
        .assert()
        .success()
        .stdout(predicate::str::contains("2.35305"))
        .stdout(predicate::str::contains("zc = 1 of 4"));
}

fn rejected(body: &str, key: &str, line: usize) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tool.toml");
    std::fs::write(&path, body).unwrap();
    let p = path.to_str().unwrap();
    crest()
        .args([
            "tool",
            "--tool",
            p,
            "--lead-deg",
            "15",
            "--ap-mm",
            "0.4",
            "--fz-mm",
            "0.05",
        ])
        .assert()
        .code(2)
        .stdout(predicate::str::is_empty())
        .stderr(predicate::str::contains(format!("tool.toml:{line}:")))
        .stderr(predicate::str::contains(key));
}

#[test]
fn bad_tool_files_name_key_and_line() {
    let head = "shape = \"ball\"\nradius_mm = 5.0\nteeth = 4\nhelix_deg = 30.0\n";
    rejected(&format!("{head}flutes = 4\n"), "flutes", 5);
    rejected(
        "shape = \"ball\"\nradius_mm = -5.0\nteeth = 4\nhelix_deg = 30.0\n",
        "radius_mm",
        2,
    );
    rejected(
        "shape = \"ball\"\nradius_mm = 5.0\nteeth = 0\nhelix_deg = 30.0\n",
        "teeth",
        3,
    );
    rejected(
        "shape = \"torus\"\nradius_mm = 5.0\ncorner_radius_mm = 5.5\nteeth = 2\nhelix_deg = 0\n",
        "corner_radius_mm",
        3,
    );
    rejected(
        &format!("{head}\n[runout]\noffset_um = 5\ntooth_radius_deviation_um = [1, 2, 3]\n"),
        "tooth_radius_deviation_um",
        8,
    );
    rejected(&format!("{head}[runout]\nphase_deg = 5\n"), "phase_deg", 6);
    rejected(
        "shape = \"ball\"\nteeth = 4\nhelix_deg = 30.0\n",
        "radius_mm",
        1,
    );
}

#[test]
fn missing_file_and_bad_numbers_exit_2() {
    crest()
        .args([
            "tool",
            "--tool",
            "/nonexistent/tool.toml",
            "--lead-deg",
            "5",
            "--ap-mm",
            "0.4",
            "--fz-mm",
            "0.05",
        ])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("/nonexistent/tool.toml"));
    crest()
        .args([
            "tool",
            "--tool",
            BALL,
            "--lead-deg",
            "5",
            "--ap-mm",
            "0.4",
            "--fz-mm",
            "-1",
        ])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("feed per tooth"));
}
