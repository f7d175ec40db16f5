//! `crest plot`: every plot kind is written, non-empty, with its title and axis labels.

use std::path::{Path, PathBuf};

use approx::{abs_diff_eq, assert_abs_diff_eq};

use crate::util::{crest, output_json, synth_sample, tempdir};

fn write_map(dir: &Path) -> PathBuf {
    // A 40 × 20 grid, 5 µm spacing: cusps across y, feed marks along x, a missing corner.
    let (nx, ny) = (40, 20);
    let z: Vec<f64> = (0..nx * ny)
        .map(|i| {
            let (c, r) = ((i % nx) as f64, (i / nx) as f64);
            if c > 30.0 && r < 4.0 {
                f64::NAN
            } else {
                2.0 * (r * 0.6).cos() + 0.5 * (c * 1.3).sin()
            }
        })
        .collect();
    let map = crest::surface::HeightMap::from_rows(nx, ny, 5.0, 5.0, z).unwrap();
    let path = dir.join("map.gsf");
    crest::io::write_heightmap(&path, &map).unwrap();
    path
}

#[test]
fn trochoid_svg_and_png() {
    let dir = tempdir();
    let svg = dir.path().join("t.svg");
    let out = crest()
        .args(["plot", "trochoid", "--tool"])
        .arg(synth_sample("ball-r5-presetter.toml"))
        .args(["--lead-deg", "15", "--revolutions", "1", "--json", "-o"])
        .arg(&svg)
        .output()
        .unwrap();
    let v = output_json(&out);
    // Six heights × two fz × one lead. At z = 3 mm (r = √21 mm), fz 0.2, lead 15°, Z = 4
    // the outer arcs of consecutive marks cross at θ with v θ + r cos 15° sin θ = fz/2,
    // v = Z fz/2π; the crest is r (1 − cos θ) = 1.105 µm (Eq 14 with fz/cos β: 1.170 µm).
    let crests = v["crests"].as_array().unwrap();
    assert_eq!(crests.len(), 12);
    let c = crests
        .iter()
        .find(|c| c["fz_mm"] == 0.2 && c["height_mm"] == 3.0)
        .unwrap()["crest_um"]
        .as_f64()
        .unwrap();
    let (r, v, rp) = (
        21f64.sqrt(),
        0.8 / std::f64::consts::TAU,
        21f64.sqrt() * 15f64.to_radians().cos(),
    );
    let mut th = 0.0f64;
    for _ in 0..50 {
        th -= (v * th + rp * th.sin() - 0.1) / (v + rp * th.cos());
    }
    let expect = r * (1.0 - th.cos()) * 1e3;
    assert_abs_diff_eq!(c, expect, epsilon = 1e-6);
    assert_abs_diff_eq!(c, 1.105, epsilon = 1e-3);
    let text = std::fs::read_to_string(&svg).unwrap();
    for t in [
        "Trochoidal paths of ICE elements",
        "x feed [mm]",
        "crest height [µm]",
    ] {
        assert!(text.contains(t), "missing {t}");
    }
    let png = dir.path().join("t.png");
    crest()
        .args(["plot", "trochoid", "--tool"])
        .arg(synth_sample("ball-r5.toml"))
        .args(["--revolutions", "1", "-o"])
        .arg(&png)
        .assert()
        .success();
    let bytes = std::fs::read(&png).unwrap();
    assert!(bytes.len() > 10_000 && bytes.starts_with(b"\x89PNG"));
}

#[test]
fn heightmap_and_profile() {
    let dir = tempdir();
    let map = write_map(dir.path());
    let svg = dir.path().join("m.svg");
    crest()
        .args(["plot", "heightmap"])
        .arg(&map)
        .args(["--title", "Map under test", "-o"])
        .arg(&svg)
        .assert()
        .success();
    let text = std::fs::read_to_string(&svg).unwrap();
    for t in ["Map under test", "x [mm]", "y [mm]", "height [µm]"] {
        assert!(text.contains(t), "missing {t}");
    }
    let png = dir.path().join("m.png");
    crest()
        .args(["plot", "heightmap"])
        .arg(&map)
        .arg("-o")
        .arg(&png)
        .assert()
        .success();
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));

    let measured = dir.path().join("measured.csv");
    std::fs::write(&measured, "x_mm,z_um\n0.0,1.0\n0.05,-1.0\n0.1,1.5\n").unwrap();
    let prof = dir.path().join("p.svg");
    let out = crest()
        .args(["plot", "profile"])
        .arg(&map)
        .args(["--y-mm", "0.05", "--json", "--measured"])
        .arg(&measured)
        .arg("-o")
        .arg(&prof)
        .output()
        .unwrap();
    let v = output_json(&out);
    assert_eq!(v["points"], 40);
    assert_eq!(v["profile"], "along x at y = 0.050 mm");
    let text = std::fs::read_to_string(&prof).unwrap();
    for t in ["simulated", "measured", "height [µm]"] {
        assert!(text.contains(t), "missing {t}");
    }

    // A bad measured row names file, line and column.
    std::fs::write(&measured, "x_mm,z_um\n0.0,1.0\n0.05,abc\n").unwrap();
    let out = crest()
        .args(["plot", "profile"])
        .arg(&map)
        .arg("--measured")
        .arg(&measured)
        .arg("-o")
        .arg(&prof)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("measured.csv:3:6"), "{err}");
}

#[test]
fn unknown_picture_format_is_a_usage_error() {
    let dir = tempdir();
    let out = dir.path().join("t.pdf");
    crest()
        .args(["plot", "trochoid", "--tool"])
        .arg(synth_sample("ball-r5.toml"))
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2);
    assert!(!out.exists());
}

#[test]
fn feed_and_crest_along_a_synthetic_path() {
    let dir = tempdir();
    let cls = dir.path().join("p.cls");
    crest()
        .args([
            "synth",
            "plane",
            "--lead-deg",
            "15",
            "--stepover-mm",
            "2",
            "--size-mm",
            "10,4",
        ])
        .args(["--feed-mm-min", "4000", "--rpm", "10000", "--tool"])
        .arg(synth_sample("ball-r5.toml"))
        .arg("-o")
        .arg(&cls)
        .assert()
        .success();
    let svg = dir.path().join("f.svg");
    let out = crest()
        .args(["plot", "feed"])
        .arg(&cls)
        .args(["--json", "-o"])
        .arg(&svg)
        .output()
        .unwrap();
    let v = output_json(&out);
    // 3 passes of 21 CC points, each run starting at its clearance point.
    assert_eq!(v["points"], 3 * 22);
    let text = std::fs::read_to_string(&svg).unwrap();
    for t in ["Feed along p.cls", "feed [mm/min]", "path length [mm]"] {
        assert!(text.contains(t), "missing {t}");
    }
    // fz = 4000 / (4 · 10000) = 0.1 mm on R = 5: 0.250006 µm (model.md R2).
    let out = crest()
        .args(["plot", "feed", "--crest", "--tool"])
        .arg(synth_sample("ball-r5.toml"))
        .arg(&cls)
        .args(["--json", "-o"])
        .arg(dir.path().join("c.png"))
        .output()
        .unwrap();
    let v = output_json(&out);
    for k in ["crest_um_min", "crest_um_max"] {
        assert!(
            abs_diff_eq!(v[k].as_f64().unwrap(), 0.250006, epsilon = 1e-6),
            "{k}: {}",
            v[k]
        );
    }
}

#[test]
fn runout_against_tool_height() {
    let dir = tempdir();
    let png = dir.path().join("r.png");
    let out = crest()
        .args(["plot", "runout", "--tool"])
        .arg(synth_sample("ball-r5-presetter.toml"))
        .args([
            "--lead-deg",
            "5,15",
            "--heights-mm",
            "0.5,2",
            "--json",
            "-o",
        ])
        .arg(&png)
        .output()
        .unwrap();
    let v = output_json(&out);
    let curves = v["curves"].as_array().unwrap();
    assert_eq!(curves.len(), 2);
    // Only the presetter radii (−10, −15, −24, −25 µm) deviate. A radius deviation δ of a
    // ball lies along the ball's normal at κ (z = R(1 − cos κ)); the surface normal at lead β
    // sees δ cos(κ − β): the spread is (25 − 10) cos(κ − β) µm.
    for c in curves {
        let lead = c["lead_deg"].as_f64().unwrap().to_radians();
        let marks = c["marks"].as_array().unwrap();
        assert_eq!(marks.len(), 2);
        for m in marks {
            let z = m["height_mm"].as_f64().unwrap();
            let kappa = (1.0 - z / 5.0).acos();
            let expect = 15.0 * (kappa - lead).cos();
            let d = m["runout_um"].as_f64().unwrap();
            assert!(
                abs_diff_eq!(d, expect, epsilon = 1e-6),
                "z {z}: {d} vs {expect}"
            );
        }
    }
    let bytes = std::fs::read(&png).unwrap();
    assert!(bytes.len() > 10_000 && bytes.starts_with(b"\x89PNG"));
    let svg = dir.path().join("r.svg");
    crest()
        .args(["plot", "runout", "--tool"])
        .arg(synth_sample("ball-r5-presetter.toml"))
        .arg("-o")
        .arg(&svg)
        .assert()
        .success();
    let text = std::fs::read_to_string(&svg).unwrap();
    for t in [
        "Lateral run-out against tool height",
        "tool height z",
        "lead 25°",
    ] {
        assert!(text.contains(t), "missing {t}");
    }
    // A height beyond the ball end is bad input: exit 2, no picture.
    let bad = dir.path().join("bad.svg");
    crest()
        .args(["plot", "runout", "--tool"])
        .arg(synth_sample("ball-r5-presetter.toml"))
        .args(["--heights-mm", "7", "-o"])
        .arg(&bad)
        .assert()
        .code(2);
    assert!(!bad.exists());
}

#[test]
fn closed_stdout_is_not_a_failure() {
    // `crest plot … --json | head -c 1`: the reader goes away before the JSON is written.
    let dir = tempdir();
    let svg = dir.path().join("r.svg");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_crest"))
        .args(["plot", "runout", "--tool"])
        .arg(synth_sample("ball-r5-presetter.toml"))
        .args(["--json", "-o"])
        .arg(&svg)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{:?}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `plot feed --from-mm/--to-mm` (issue 33): only the cutting length asked is drawn; a range
/// with no cutting move in it is refused and nothing is written.
#[test]
fn feed_plot_over_a_range_of_path_length() {
    let dir = tempdir();
    let cls = dir.path().join("line.cls");
    // One cutting run along x, a posture every 1 mm: path lengths 0, 1, …, 10 mm.
    let gotos: String = (0..=10).map(|i| format!("GOTO/{i},0,0,0,0,1\n")).collect();
    std::fs::write(
        &cls,
        format!(
            "TOOL PATH/LINE,TOOL,BALL\nTLDATA/MILL,10,5,50,0,0\nSPINDL/RPM,10000,CLW\nFEDRAT/MMPM,1000\n{gotos}END-OF-PATH\n"
        ),
    )
    .unwrap();
    let svg = dir.path().join("f.svg");
    let points = |range: &[&str]| {
        let out = crest()
            .args(["plot", "feed"])
            .arg(&cls)
            .args(range)
            .args(["--json", "-o"])
            .arg(&svg)
            .output()
            .unwrap();
        output_json(&out)["points"].as_u64().unwrap()
    };
    assert_eq!(points(&[]), 11);
    // The bounds cut the moves 2 → 3 and 6 → 7: a point at 2.5 and at 6.5 mm.
    assert_eq!(points(&["--from-mm", "2.5", "--to-mm", "6.5"]), 6);
    assert_eq!(points(&["--from-mm", "8"]), 3);
    assert_eq!(points(&["--to-mm", "0.5"]), 2);
    std::fs::remove_file(&svg).unwrap();
    for range in [["--from-mm", "10.5"], ["--to-mm", "-1"]] {
        let out = crest()
            .args(["plot", "feed"])
            .arg(&cls)
            .args(range)
            .arg("-o")
            .arg(&svg)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{range:?}");
        assert!(!svg.exists(), "{range:?}");
    }
}

#[test]
fn a_measured_profile_aligns_to_the_simulated_one() {
    // A bump on feed marks, 80 nodes at 5 µm; the measured profile is the same line moved
    // by −11.3 µm and raised 2 µm, sampled every 4 µm: --align moves it back.
    let dir = tempdir();
    let line = |c: f64| 3.0 * (-((c - 40.0) / 8.0).powi(2)).exp() + 0.5 * (c * 1.3).sin();
    let (nx, ny) = (80, 3);
    let z: Vec<f64> = (0..nx * ny).map(|i| line((i % nx) as f64)).collect();
    let map = crest::surface::HeightMap::from_rows(nx, ny, 5.0, 5.0, z).unwrap();
    let path = dir.path().join("map.x3p");
    crest::io::write_heightmap(&path, &map).unwrap();
    let mut text = String::from("x_mm,z_um\n");
    for i in 0..90 {
        let x = 0.002 + i as f64 * 0.004;
        text.push_str(&format!("{x},{}\n", line((x + 0.0113) / 0.005) + 2.0));
    }
    let measured = dir.path().join("measured.csv");
    std::fs::write(&measured, text).unwrap();
    let prof = dir.path().join("p.svg");
    let out = crest()
        .args(["plot", "profile"])
        .arg(&path)
        .args(["--json", "--align", "--measured"])
        .arg(&measured)
        .arg("-o")
        .arg(&prof)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = output_json(&out);
    let a = &v["align"];
    let shift = a["shift_mm"].as_f64().unwrap();
    let offset = a["offset_um"].as_f64().unwrap();
    assert!((shift - 0.0113).abs() < 0.005, "{a}");
    assert!((offset + 2.0).abs() < 0.05, "{a}");
    assert!(a["correlation"].as_f64().unwrap() > 0.99, "{a}");
    // Without --measured, --align is a usage error.
    crest()
        .args(["plot", "profile"])
        .arg(&path)
        .args(["--align", "-o"])
        .arg(&prof)
        .assert()
        .code(2);
}
