//! `crest simulate` end to end on the project's own synthetic samples.

use assert_cmd::Command;
use predicates::prelude::*;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn crest() -> Command {
    Command::cargo_bin("crest").unwrap()
}

#[test]
fn simulate_trial_3_window_writes_a_map_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t3.csv");
    let assert = crest()
        .current_dir(ROOT)
        .args([
            "simulate",
            "samples/synth/plane-trial3.cls",
            "--tool",
            "samples/synth/torus-r5-rc1.5.toml",
            "--model",
            "ice",
            "--dtheta-deg",
            "2",
            "--grid-um",
            "10",
            "--window",
            "0,0,0.27,0.2",
            "-o",
        ])
        .arg(&out)
        .arg("--json")
        .assert()
        .success();
    let v: serde_json::Value = serde_json::from_slice(&assert.get_output().stdout).unwrap();
    assert_eq!(v["nx"], 28);
    assert_eq!(v["ny"], 21);
    assert_eq!(v["dx_um"], 10.0);
    assert_eq!(v["nodes_cut"], 28 * 21);
    assert_eq!(v["rpm"], 15000.0);
    assert_eq!(v["feed_mm_min"], 4000.0);
    let fz = v["fz_mm"].as_f64().unwrap();
    assert!((fz - 4000.0 / 15000.0).abs() < 1e-12);
    // Feed marks of one tooth at fz = 0.267 mm and the lateral scallop: a few µm.
    let sz = v["heights_um"]["sz"].as_f64().unwrap();
    assert!(sz > 1.0 && sz < 16.0, "Sz {sz}");
    let text = std::fs::read_to_string(&out).unwrap();
    assert_eq!(text.lines().filter(|l| !l.starts_with('#')).count(), 21);
}

#[test]
fn contact12_without_feed_asks_for_the_options() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.gsf");
    crest()
        .current_dir(ROOT)
        .args([
            "simulate",
            "samples/synth/blade-patch-ball.txt",
            "--tool",
            "samples/synth/ball-r5.toml",
            "--model",
            "dome",
            "--grid-um",
            "10",
            "--window",
            "0,0,0.1,0.1",
            "-o",
        ])
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--rpm"));
    assert!(!out.exists());
}

#[test]
fn bad_window_and_unknown_process_key_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let process = dir.path().join("process.toml");
    std::fs::write(&process, "rpm = 15000\nspindle = 3\n").unwrap();
    let out = dir.path().join("x.gsf");
    crest()
        .current_dir(ROOT)
        .args([
            "simulate",
            "samples/synth/plane-trial3.cls",
            "--tool",
            "samples/synth/torus-r5-rc1.5.toml",
            "--model",
            "ice",
            "--grid-um",
            "10",
            "--window",
            "0,0,0.1",
            "-o",
        ])
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("window"));
    crest()
        .current_dir(ROOT)
        .args([
            "simulate",
            "samples/synth/plane-trial3.cls",
            "--tool",
            "samples/synth/torus-r5-rc1.5.toml",
            "--model",
            "ice",
            "--grid-um",
            "10",
            "--window",
            "0,0,0.1,0.1",
            "--process",
        ])
        .arg(&process)
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(
            predicate::str::contains("process.toml:2:").and(predicate::str::contains("spindle")),
        );
}
