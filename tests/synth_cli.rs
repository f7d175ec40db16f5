//! `crest synth`: stepover and pass count in --json, CLSF and contact12 outputs, errors.

use assert_cmd::Command;
use std::path::{Path, PathBuf};

fn sample(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("samples/synth")
        .join(name)
}

fn synth(args: &[&str], tool: &str, out: &Path) -> std::process::Output {
    Command::cargo_bin("crest")
        .unwrap()
        .arg("synth")
        .args(args)
        .arg("--tool")
        .arg(sample(tool))
        .arg("-o")
        .arg(out)
        .output()
        .unwrap()
}

#[allow(dead_code)] // used by the writer round-trip tests
fn json(out: &std::process::Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn bad_requests_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.cls");
    let base = ["--feed-mm-min", "4000", "--rpm", "15000"];
    // Lead and tilt together.
    let o = synth(
        &[
            &[
                "plane",
                "--lead-deg",
                "3",
                "--tilt-deg",
                "3",
                "--stepover-mm",
                "1",
            ][..],
            &base,
        ]
        .concat(),
        "ball-r5.toml",
        &out,
    );
    assert_eq!(o.status.code(), Some(2));
    // Neither scallop nor stepover.
    let o = synth(&[&["plane"][..], &base].concat(), "ball-r5.toml", &out);
    assert_eq!(o.status.code(), Some(2));
    // A concave region tighter than R_eff = 202 mm.
    let o = synth(
        &[
            &["blade-patch", "--tilt-deg", "1", "--scallop-um", "5"][..],
            &base,
        ]
        .concat(),
        "torus-r5-rc1.5.toml",
        &out,
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("gouge"));
    // Unknown output extension.
    let o = synth(
        &[&["plane", "--stepover-mm", "1"][..], &base].concat(),
        "ball-r5.toml",
        &dir.path().join("p.nc"),
    );
    assert_eq!(o.status.code(), Some(2));
    // A bad tool file names the file.
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "shape = \"ball\"\nradius_mm = \"five\"\n").unwrap();
    let o = Command::cargo_bin("crest")
        .unwrap()
        .args([
            "synth",
            "plane",
            "--stepover-mm",
            "1",
            "--feed-mm-min",
            "1",
            "--rpm",
            "1",
            "--tool",
        ])
        .arg(&bad)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("bad.toml"));
    assert!(!out.exists());
}
