//! Studies and calibration on measured files (issue 34 §3): a measured table whose rows name
//! height maps (`measured_file`, relative to the table); `crest report` and `crest calibrate`
//! measure them with the predictions' filters (the values `crest metrics` gives for the same
//! file and filters) and the calibration finds the factor the files were scaled by.

use crate::util::{crest, stdout_json, tempdir, write};
use crest::surface::HeightMap;
use std::path::Path;

/// The factor the "measurements" are the predictions scaled by.
const K: f64 = 1.5;
/// Stepover of the study, mm.
const AE_MM: f64 = 0.2;
/// Rows of a measured map (one scallop period across them).
const ROWS: usize = 25;
/// Cases: (lead, fz mm); a ball end on a plane, all four teeth cutting.
const CASES: [(f64, f64); 4] = [(10.0, 0.06), (20.0, 0.08), (30.0, 0.10), (40.0, 0.12)];

fn study_toml() -> String {
    let mut s = format!(
        "title = \"measured files\"\ntool = \"{}\"\nmodel = \"crest\"\nrule = \"paper\"\nfz_mm = 0.1\nap_mm = 0.2\nstepover_mm = {AE_MM}\n\n[runout]\ntooth_radius_deviation_um = [0.0, 0.0, 0.0, 0.0]\n",
        crate::util::repo("samples/tools/ball-r5-z4.toml").display()
    );
    for (lead, fz) in CASES {
        s += &format!("\n[[case]]\nlead_deg = {lead}\nside = \"plane\"\nfz_mm = {fz}\n");
    }
    s
}

/// The study's predictions, scaled by `k·(1 ± 2 %)`, written as `.x3p` (sample S1) and
/// `.sdf` (sample S2) in `dir/maps/`: the feed-direction profile of each case along x plus
/// the scallop of the stepover across y (one period). Returns the table's text.
fn write_measurements(dir: &Path, study: &Path) -> String {
    // A table with numbers only, to load the study and its tool as `crest report` does.
    let mut numbers = String::from("lead_deg,side,sample,Rz_um\n");
    for (lead, _) in CASES {
        numbers += &format!("{lead},plane,S1,1\n");
    }
    let t0 = write(dir, "numbers.csv", numbers);
    let inputs = crest::pipeline::report::load(&t0, study).unwrap();
    std::fs::create_dir_all(dir.join("maps")).unwrap();
    let mut table = String::from("lead_deg,side,sample,measured_file\n");
    let r = inputs.cutter.radius_mm;
    for c in &inputs.study.cases {
        let p = crest::study::regression::predict_case(
            &inputs.study,
            &inputs.cutter,
            c,
            &inputs.study.process,
            0.0,
        )
        .unwrap();
        let dy = AE_MM / ROWS as f64;
        for (sample, ext, scale) in [("S1", "x3p", K * 0.98), ("S2", "sdf", K * 1.02)] {
            let mut z = Vec::new();
            for j in 0..ROWS {
                let y = j as f64 * dy;
                let d = y.min(AE_MM - y);
                let g = crest::tool::crest_height_mm(r, 2.0 * d) * 1e3;
                z.extend(p.profile_um.iter().map(|f| scale * (f + g)));
            }
            let map = HeightMap::from_rows(
                p.profile_um.len(),
                ROWS,
                p.profile_step_mm * 1e3,
                dy * 1e3,
                z,
            )
            .unwrap();
            let name = format!("maps/lead{}-{sample}.{ext}", c.lead_deg);
            crest::io::write_heightmap(&dir.join(&name), &map).unwrap();
            table += &format!("{},plane,{sample},{name}\n", c.lead_deg);
        }
    }
    table
}

fn metrics_json(args: &[&str]) -> serde_json::Value {
    stdout_json(
        &crest()
            .arg("metrics")
            .args(args)
            .arg("--json")
            .assert()
            .success(),
    )
}

/// What `crest metrics` gives for `file` with the predictions' filters: (Rz, Ra) along x as
/// the mean over the rows, and Sz, Sa, Sq, Sdq.
fn metrics_of(file: &Path) -> [f64; 6] {
    let f = file.to_str().unwrap();
    let areal = metrics_json(&[f, "--level", "plane", "--params", "Sz,Sa,Sq,Sdq"]);
    let (mut rz, mut ra) = (0.0, 0.0);
    for k in 0..ROWS {
        let row = format!("row:{k}");
        let v = metrics_json(&[
            f,
            "--level",
            "plane",
            "--profile",
            &row,
            "--params",
            "Rz,Ra",
        ]);
        rz += v["Rz"].as_f64().unwrap();
        ra += v["Ra"].as_f64().unwrap();
    }
    let a = |s: &str| areal[s].as_f64().unwrap();
    [
        rz / ROWS as f64,
        ra / ROWS as f64,
        a("Sz"),
        a("Sa"),
        a("Sq"),
        a("Sdq"),
    ]
}

/// `crest report` and `crest calibrate` on a table that names `.x3p` and `.sdf` files: the
/// measured values are `crest metrics`' for the same files and filters, the areal parameters
/// (Sz, Sa, Sq, Sdq) are compared besides Rz and Ra along the feed, and the calibration's
/// constant factor is the factor the files were scaled by.
#[test]
fn calibrate_on_a_table_that_names_files() {
    let dir = tempdir();
    let study = write(dir.path(), "study.toml", study_toml());
    let table = write(
        dir.path(),
        "table.csv",
        write_measurements(dir.path(), &study),
    );
    let out = dir.path().join("report");
    let assert = crest()
        .args(["report", "--measured"])
        .arg(&table)
        .arg("--study")
        .arg(&study)
        .arg("-o")
        .arg(&out)
        .args(["--json", "--tolerance-pct", "60"])
        .assert()
        .success();
    let reg = stdout_json(&assert);
    let cases = reg["cases"].as_array().unwrap();
    assert_eq!(cases.len(), CASES.len());
    // Sample S1 of the first case against `crest metrics` of its file.
    let m = &cases[0]["measured"];
    assert_eq!(m["files"][0], "maps/lead10-S1.x3p");
    let want = metrics_of(&dir.path().join("maps/lead10-S1.x3p"));
    let extra = |i: usize| m["extra_values_um"][i][0].as_f64().unwrap();
    // Extra order: Sz, Sa, Rz stepover, Ra stepover, Sq, Sdq.
    let got = [
        m["rz_values_um"][0].as_f64().unwrap(),
        m["ra_values_um"][0].as_f64().unwrap(),
        extra(0),
        extra(1),
        extra(4),
        extra(5),
    ];
    for (g, w) in got.iter().zip(&want) {
        assert!(
            (g - w).abs() <= 1e-9 * w.abs().max(1.0),
            "{got:?} vs {want:?}"
        );
    }
    // Every case compares Rz, Ra and the areal parameters; the measurement is K times the
    // prediction (the mean of 0.98 K and 1.02 K), up to the rows' levelling and the map's
    // coarser scallop.
    for c in cases {
        let names: Vec<&str> = c["comparisons"]
            .as_array()
            .unwrap()
            .iter()
            .map(|k| k["parameter"].as_str().unwrap())
            .collect();
        assert_eq!(names, ["Rz", "Ra", "Sz", "Sa", "Sq", "Sdq"], "{c}");
        for k in c["comparisons"].as_array().unwrap() {
            let ratio = k["ratio"].as_f64().unwrap();
            let tol = if k["parameter"] == "Sdq" { 0.1 } else { 0.05 };
            assert!((ratio * K - 1.0).abs() < tol, "{k}");
        }
    }
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("maps/lead10-S1.x3p"), "{md}");
    assert!(out.join("sdq.svg").is_file() && out.join("sq.svg").is_file());

    // The calibration finds K as the constant factor on the geometric model.
    let cal = stdout_json(
        &crest()
            .args(["calibrate", "--measured"])
            .arg(&table)
            .arg("--study")
            .arg(&study)
            .args(["--free", "min_chip_um", "--json"])
            .assert()
            .success(),
    );
    for p in ["Rz", "Ra"] {
        let f = cal["factors"][p].as_f64().unwrap();
        assert!((f / K - 1.0).abs() < 0.01, "{p} factor {f}: {cal}");
    }
    for c in cal["cases"].as_array().unwrap() {
        let (g, loo) = (
            c["geometric_um"].as_f64().unwrap(),
            c["factor_loo_um"].as_f64().unwrap(),
        );
        assert!((loo / (K * g) - 1.0).abs() < 0.01, "{c}");
        // The measured mean is what `crest report` measured.
        assert!(c["measured_um"].as_f64().unwrap() > g);
    }
}

/// A measured file that is missing: exit 2, the message names the table, the row's line and
/// the file as written; nothing is written.
#[test]
fn a_missing_measured_file_names_table_line_and_file() {
    let dir = tempdir();
    let study = write(dir.path(), "study.toml", study_toml());
    let mut text = String::from("lead_deg,side,sample,Rz_um,measured_file\n");
    for (i, (lead, _)) in CASES.iter().enumerate() {
        let file = if i == 2 { "maps/nowhere.x3p" } else { "" };
        text += &format!("{lead},plane,S1,1.0,{file}\n");
    }
    write(dir.path(), "table.csv", text);
    for cmd in [
        vec!["report", "-o", "out"],
        vec!["calibrate", "--free", "min_chip_um"],
    ] {
        let o = crest()
            .current_dir(dir.path())
            .arg(cmd[0])
            .args(["--measured", "table.csv", "--study"])
            .arg(&study)
            .args(&cmd[1..])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{o:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("table.csv:4: measured_file `maps/nowhere.x3p`"),
            "{err}"
        );
        assert!(!dir.path().join("out").exists());
    }
    // An unreadable one (not a height map) is refused the same way.
    std::fs::create_dir_all(dir.path().join("maps")).unwrap();
    write(dir.path(), "maps/nowhere.x3p", "not a zip");
    let o = crest()
        .current_dir(dir.path())
        .args(["report", "--measured", "table.csv", "--study"])
        .arg(&study)
        .args(["-o", "out"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    assert!(String::from_utf8_lossy(&o.stderr).contains("table.csv:4"));
    assert!(!dir.path().join("out").exists());
}
