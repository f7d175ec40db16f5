//! `crest resample` streams the file (no `--machine`): the spindle speed is still derived
//! from the highest cutting feed of the whole path when a slower engage comes first (the
//! file is then resampled a second time), and `--path` counts tool paths without postures.

use assert_cmd::Command;
use std::path::Path;

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

fn run(file: &Path, out: &Path, extra: &[&str]) -> (serde_json::Value, String) {
    let assert = Command::cargo_bin("crest")
        .unwrap()
        .arg("resample")
        .arg(file)
        .args([
            "--mode", "fz", "--fz-mm", "0.1", "--teeth", "2", "--json", "-o",
        ])
        .arg(out)
        .args(extra)
        .assert()
        .success();
    let json = serde_json::from_slice(&assert.get_output().stdout).unwrap();
    (json, std::fs::read_to_string(out).unwrap())
}

#[test]
fn slower_engage_first_and_empty_tool_paths() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("engage.cls");
    std::fs::write(&file, CLSF).unwrap();
    let (json, csv) = run(&file, &dir.path().join("all.csv"), &[]);
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
    assert!((stats["length_mm"].as_f64().unwrap() - 16.0 - run2).abs() < 1e-9);
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
    assert!((end1[1].parse::<f64>().unwrap() - t).abs() < 1e-9);
    assert!((end1[2].parse::<f64>().unwrap() - 5000.0 * 360.0 * t / 60.0).abs() < 1e-6);
    assert_eq!(end1[18], "1000.000");
    // Run 2 restarts the clock.
    assert_eq!(rows[161][1], "0.000000000");

    // `--path 2` is the second tool path of the file, the first with postures.
    let (json2, csv2) = run(&file, &dir.path().join("two.csv"), &["--path", "2"]);
    assert_eq!(json2["paths"][0]["index"], 2);
    assert_eq!(json2["paths"][0]["stats"], *stats);
    assert_eq!(csv2, csv);
    let (json1, csv1) = run(&file, &dir.path().join("one.csv"), &["--path", "1"]);
    assert_eq!(json1["samples"], 0);
    assert_eq!(csv1.lines().count(), 1);
    // Out of range: an error, and no output file.
    let out = dir.path().join("three.csv");
    Command::cargo_bin("crest")
        .unwrap()
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
