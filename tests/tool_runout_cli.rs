//! `crest runout` end to end: the sample study writes one CSV row per case and three plots
//! (SVG and PNG); bad study files name the line.

use assert_cmd::Command;
use predicates::prelude::*;

const STUDY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/samples/studies/runout.toml");

#[test]
fn sample_study_writes_csv_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::cargo_bin("crest")
        .unwrap()
        .args(["runout", STUDY, "-o"])
        .arg(dir.path())
        .arg("--json")
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    // 3 leads × 1 fz × 13 offsets × 2 phases.
    assert_eq!(v["cases"], 78);
    let csv = std::fs::read_to_string(dir.path().join("runout.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(lines.clone().count(), 78);
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (zc, offset, phase) = (col("zc"), col("offset_um"), col("offset_phase_deg"));
    let (fz_eff, teeth) = (col("fz_effective_mm"), col("participating_teeth"));
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    for r in &rows {
        let n: usize = r[zc].parse().unwrap();
        assert_eq!(r[teeth].split(';').count(), n);
        let f: f64 = r[fz_eff].parse().unwrap();
        assert!((f - 0.2 * 4.0 / n as f64).abs() < 1e-12);
        // Zero offset leaves only the tool's sub-micron deviations: every tooth cuts at 1 µm crests.
        if r[offset] == "0" {
            assert_eq!(n, 4, "{r:?}");
        }
        // A 5 µm offset at phase 45° leaves teeth 1 and 4 (model.md R3 pattern).
        if r[offset] == "5" && r[phase] == "45" {
            assert_eq!(r[teeth], "1;4", "{r:?}");
        }
    }
    for name in [
        "runout-teeth.svg",
        "runout-teeth.png",
        "runout-crest.svg",
        "runout-crest.png",
        "runout-lateral.svg",
        "runout-lateral.png",
    ] {
        let bytes = std::fs::read(dir.path().join(name)).unwrap();
        assert!(bytes.len() > 1000, "{name} is too small");
        if name.ends_with(".png") {
            assert_eq!(&bytes[..4], b"\x89PNG");
        } else {
            let text = String::from_utf8(bytes).unwrap();
            assert!(text.contains("run-out"), "{name} lacks its axis label");
        }
    }
}

#[test]
fn bad_study_names_line() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study.toml");
    std::fs::write(
        &study,
        "tool = \"x.toml\"\nap_mm = 0.4\n[sweep]\nlead_deg = [5, 95]\nfz_mm = [0.05]\n",
    )
    .unwrap();
    Command::cargo_bin("crest")
        .unwrap()
        .args(["runout"])
        .arg(&study)
        .arg("-o")
        .arg(dir.path().join("out"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("study.toml:4:"))
        .stderr(predicate::str::contains("lead_deg"));
    assert!(!dir.path().join("out").exists());
}
