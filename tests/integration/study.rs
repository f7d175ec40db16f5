//! `crest study`: a tiny 2-run design through the whole pipeline (synthetic path, resample,
//! ICE surface, areal parameters), its numbers against the closed-form feed cusp, the
//! effects arithmetic against runs.csv, thread-count independence and bad designs.

use std::path::{Path, PathBuf};

use approx::{abs_diff_eq, assert_abs_diff_eq};

use crate::util::{crest, output_json, read, read_csv, repo, tempdir, write};

fn tool() -> PathBuf {
    repo("samples/tools/torus-r5-rc1.5.toml")
}

/// Tilt 10°, yaw 0, a pass interval of 0.05 mm (the scallop across, s²/(8 R_eff) with
/// R_eff = 21.66 mm, is 0.014 µm) and feeds 2000/4000 mm/min at 15000 rpm, one tooth:
/// fz = 0.1333 / 0.2667 mm. At tilt 10° both sides of a feed mark are cut by the corner
/// radius rc (model.md §7), so the unit cell fz × s is a row of arcs of radius rc: cusp
/// h = fz²/(8 rc), and for that parabolic profile Sq = h·√(4/45), Sa = h·4/(9√3).
fn design(dir: &Path) -> PathBuf {
    let text = format!(
        "title = \"tiny\"\n\
         surface = \"plane\"\n\
         tool = \"{}\"\n\
         rpm = 15000.0\n\
         grid_um = 2.0\n\
         dtheta_deg = 1.0\n\
         responses = [\"Sz\", \"Sq\", \"Sa\"]\n\
         [factors]\n\
         tilt_deg = [10.0]\n\
         stepover_mm = [0.05]\n\
         feed_mm_min = [2000.0, 4000.0]\n",
        tool().display()
    );
    write(dir, "tiny.toml", text)
}

fn study(design: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    crest()
        .arg("study")
        .arg(design)
        .arg("-o")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn two_run_design_matches_the_feed_cusp_and_its_effects() {
    let dir = tempdir();
    let d = design(dir.path());
    let out = dir.path().join("out");
    let o = study(&d, &out, &["--json", "--threads", "2"]);
    let j = output_json(&o);
    let runs = j["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);

    let rc = 1.5;
    for (k, r) in runs.iter().enumerate() {
        let fz = [2000.0, 4000.0][k] / 15000.0;
        assert_eq!(r["run"], k + 1);
        assert_abs_diff_eq!(r["fz_mm"].as_f64().unwrap(), fz, epsilon = 1e-12);
        assert_abs_diff_eq!(r["stepover_mm"].as_f64().unwrap(), 0.05, epsilon = 1e-12);
        let h = 1e3 * fz * fz / (8.0 * rc);
        let sz = r["responses"]["Sz"].as_f64().unwrap();
        let sq = r["responses"]["Sq"].as_f64().unwrap();
        let sa = r["responses"]["Sa"].as_f64().unwrap();
        eprintln!(
            "run {}: Sz {sz:.4} Sq {sq:.4} Sa {sa:.4} (cusp {h:.4})",
            k + 1
        );
        // The grid (2 µm) can miss the cusp tip by up to ~(1 µm)²/(2 rc)·2 and the arcs
        // are traced by a sweeping edge, not a circle: 3 % of the cusp h, absolute.
        assert!(
            abs_diff_eq!(sz, h, epsilon = 0.03 * h),
            "Sz vs fz²/(8 rc): {sz}"
        );
        let parabolic_sq = h * (4.0f64 / 45.0).sqrt();
        assert!(
            abs_diff_eq!(sq, parabolic_sq, epsilon = 0.03 * h),
            "Sq vs parabolic cusp: {sq}"
        );
        let parabolic_sa = h * 4.0 / (9.0 * 3f64.sqrt());
        assert!(
            abs_diff_eq!(sa, parabolic_sa, epsilon = 0.03 * h),
            "Sa vs parabolic cusp: {sa}"
        );
    }

    // runs.csv holds the same numbers; effects.csv follows Eqs 7-8 from them.
    let rows = read_csv(&out.join("runs.csv"));
    assert_eq!(
        rows[0],
        [
            "run",
            "tilt_deg",
            "stepover_mm",
            "feed_mm_min",
            "fz_mm",
            "step_mm",
            "Sz",
            "Sq",
            "Sa",
            "error"
        ]
    );
    assert_eq!(rows.len(), 3);
    let sz: Vec<f64> = rows[1..].iter().map(|r| r[6].parse().unwrap()).collect();
    assert_abs_diff_eq!(
        sz[0],
        runs[0]["responses"]["Sz"].as_f64().unwrap(),
        epsilon = 1e-6
    );
    let mean = 0.5 * (sz[0] + sz[1]);
    let eff = read_csv(&out.join("effects.csv"));
    assert_eq!(
        eff[0],
        [
            "response",
            "factor",
            "level",
            "mean",
            "effect",
            "relative_first"
        ]
    );
    let row = eff
        .iter()
        .find(|r| r[0] == "Sz" && r[1] == "feed_mm_min" && r[2] == "2000")
        .expect("Sz feed row");
    let cell = |i: usize| -> f64 { row[i].parse().unwrap() };
    // M, EF_11 = M_11 − M and EF_11/M.
    assert_abs_diff_eq!(cell(3), mean, epsilon = 2e-6);
    assert_abs_diff_eq!(cell(4), sz[0] - mean, epsilon = 2e-6);
    assert_abs_diff_eq!(cell(5), (sz[0] - mean) / mean, epsilon = 2e-6);
    // Sz scales with fz²: the effect of halving the feed is (1/4 − 5/8)/(5/8) = −60 %.
    assert_abs_diff_eq!(cell(5), -0.6, epsilon = 0.02);
    // A factor held at one level has no effect.
    let tilt = eff
        .iter()
        .find(|r| r[0] == "Sz" && r[1] == "tilt_deg")
        .unwrap();
    assert_abs_diff_eq!(tilt[4].parse::<f64>().unwrap(), 0.0, epsilon = 1e-9);

    let svg = read(&out.join("effects.svg"));
    assert!(svg.starts_with("<svg") && svg.contains("feed_mm_min"));
    let outputs = &j["outputs"];
    assert!(outputs["runs_csv"].as_str().unwrap().ends_with("runs.csv"));
    assert_eq!(outputs["charts"].as_array().unwrap().len(), 1);
    let e = &j["effects"][0];
    assert_eq!(e["response"], "Sz");
    // The JSON's M.
    assert_abs_diff_eq!(e["mean"].as_f64().unwrap(), mean, epsilon = 1e-6);

    // One thread gives the same files.
    let out1 = dir.path().join("out1");
    let o = study(&d, &out1, &["--threads", "1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["runs.csv", "effects.csv"] {
        assert_eq!(
            std::fs::read(out.join(f)).unwrap(),
            std::fs::read(out1.join(f)).unwrap(),
            "{f} depends on the thread count"
        );
    }
}

#[test]
fn bad_design_names_file_line_column_and_writes_nothing() {
    let dir = tempdir();
    let d = dir.path().join("bad.toml");
    std::fs::write(
        &d,
        "surface = \"plane\"\ntool = \"t.toml\"\nrpm = 15000.0\ngrid_um = 2.0\n\
         responses = [\"Sz\"]\n[factors]\nscallop_um = [5.0]\nfeed_mm_min = [2000.0]\n\
         tilt_dgr = [1.0]\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = study(&d, &out, &[]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.toml:9:1"), "{err}");
    assert!(err.contains("tilt_dgr"), "{err}");
    assert!(!out.exists(), "an output folder was created");

    // A bad value: the line of its key.
    std::fs::write(
        &d,
        "surface = \"plane\"\ntool = \"t.toml\"\nrpm = 15000.0\ngrid_um = -2.0\n\
         responses = [\"Sz\"]\n[factors]\nscallop_um = [5.0]\nfeed_mm_min = [2000.0]\n",
    )
    .unwrap();
    let o = study(&d, &out, &[]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.toml:4:1"), "{err}");
    assert!(!out.exists());

    // A missing tool file is named.
    let good = design(dir.path());
    let text = read(&good).replace(&tool().display().to_string(), "no-such-tool.toml");
    std::fs::write(&d, text).unwrap();
    let o = study(&d, &out, &[]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    // (miette wraps long lines.)
    assert!(
        err.contains("cannot read tool file") && err.contains("no-such-"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn a_run_that_cannot_be_simulated_fails_the_study_without_output() {
    // Scallop 1 mm cannot be left by a 5 mm tool at tilt 10° on a plane at a sane step:
    // the exact envelope has no solution, so the run fails and nothing is written.
    let dir = tempdir();
    let d = design(dir.path());
    let text = read(&d).replace("stepover_mm = [0.05]", "scallop_um = [5000.0]");
    std::fs::write(&d, text).unwrap();
    let out = dir.path().join("out");
    let o = study(&d, &out, &[]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("runs failed"), "{err}");
    assert!(!out.exists());
}
