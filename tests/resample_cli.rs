//! `crest resample` end to end: every real NX file of `../shared/samples-external/` with
//! cutting moves, both modes, contact columns, feed options, and the errors.

use assert_cmd::Command;
use std::path::{Path, PathBuf};

const HEADER: &str = "s_mm,t_s,theta_deg,x,y,z,i,j,k,cx,cy,cz,nx,ny,nz,fx,fy,fz,feed_mm_min";

fn external(name: &str) -> PathBuf {
    Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/samples-external/"
    ))
    .join(name)
}

fn repo_sample(name: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/samples/")).join(name)
}

fn crest() -> Command {
    Command::cargo_bin("crest").unwrap()
}

/// Run `crest resample … --json`, return the JSON and the CSV rows (as numbers, `None`
/// for empty cells).
fn run(file: &Path, extra: &[&str]) -> (serde_json::Value, Vec<Vec<Option<f64>>>) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let assert = crest()
        .arg("resample")
        .arg(file)
        .args(extra)
        .arg("-o")
        .arg(&out)
        .arg("--json")
        .assert()
        .success();
    let json: serde_json::Value = serde_json::from_slice(&assert.get_output().stdout).unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(HEADER));
    let rows: Vec<Vec<Option<f64>>> = lines
        .map(|l| {
            l.split(',')
                .map(|c| (!c.is_empty()).then(|| c.parse::<f64>().unwrap()))
                .collect()
        })
        .collect();
    (json, rows)
}

fn col(name: &str) -> usize {
    HEADER.split(',').position(|c| c == name).unwrap()
}

fn vec3(row: &[Option<f64>], first: &str) -> Option<[f64; 3]> {
    let i = col(first);
    Some([row[i]?, row[i + 1]?, row[i + 2]?])
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[test]
fn every_external_file_with_cutting_moves_resamples() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(external(""))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "cls"))
        .collect();
    files.sort();
    assert!(files.len() >= 12, "{files:?}");
    let fz = 0.5;
    for file in &files {
        let name = file.file_name().unwrap().to_string_lossy().to_string();
        let (json, rows) = run(file, &["--mode", "fz", "--fz-mm", "0.5", "--teeth", "2"]);
        let samples = json["samples"].as_u64().unwrap();
        assert_eq!(samples as usize, rows.len(), "{name}");
        // The drilling cycle file has no cutting (feed) moves at all: only cycle holes.
        if name == "nx_cycle_drill_deep.cls" {
            assert_eq!(samples, 0, "{name}");
            continue;
        }
        assert!(
            samples > 0 && json["runs"].as_u64().unwrap() > 0,
            "{name}: {json}"
        );
        let (s, t) = (col("s_mm"), col("t_s"));
        for (k, row) in rows.iter().enumerate() {
            assert_eq!(row.len(), 19, "{name} row {k}");
            let axis = vec3(row, "i").unwrap();
            let f = vec3(row, "fx").unwrap();
            assert!((norm(axis) - 1.0).abs() < 1e-8, "{name} row {k}");
            assert!((norm(f) - 1.0).abs() < 1e-8, "{name} row {k}");
            assert!(dot(f, axis).abs() < 1e-8, "{name} row {k}");
            assert!(row[col("feed_mm_min")].unwrap() > 0.0);
            // No contact data in these files: CC and normal are empty.
            assert!(vec3(row, "cx").is_none() && vec3(row, "nx").is_none());
            if k > 0 {
                let ds = row[s].unwrap() - rows[k - 1][s].unwrap();
                assert!((-1e-9..=fz + 2e-6).contains(&ds), "{name} row {k}: ds {ds}");
                let new_run = row[t].unwrap() == 0.0;
                if !new_run {
                    // Spacing is fz except the last sample of a run.
                    let last_of_run = rows.get(k + 1).is_none_or(|n| n[t].unwrap() == 0.0);
                    if !last_of_run {
                        assert!((ds - fz).abs() < 2e-6, "{name} row {k}: ds {ds}");
                    }
                    let p0 = vec3(&rows[k - 1], "x").unwrap();
                    let p1 = vec3(row, "x").unwrap();
                    let chord = norm([p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]]);
                    assert!(chord <= ds + 2e-6, "{name} row {k}: chord {chord} > {ds}");
                }
            }
        }
    }
}

#[test]
fn dtheta_mode_steps_the_spindle_angle() {
    let file = external("nx_5axis_varcontour_ijk_small.cls");
    let (json, rows) = run(
        &file,
        &[
            "--mode",
            "dtheta",
            "--fz-mm",
            "0.1",
            "--teeth",
            "4",
            "--dtheta-deg",
            "30",
        ],
    );
    assert_eq!(json["mode"], "dtheta");
    // ΔS = Z fz Δθ/2π = 0.4 × 30/360 mm at the programmed feed.
    assert!((json["step_mm"].as_f64().unwrap() - 0.4 / 12.0).abs() < 1e-12);
    let (th, t) = (col("theta_deg"), col("t_s"));
    let mut steps = 0;
    for k in 1..rows.len() {
        if rows[k][t].unwrap() == 0.0 {
            assert_eq!(rows[k][th].unwrap(), 0.0);
            continue;
        }
        let dth = rows[k][th].unwrap() - rows[k - 1][th].unwrap();
        let last_of_run = rows.get(k + 1).is_none_or(|n| n[t].unwrap() == 0.0);
        if last_of_run {
            assert!(dth > 0.0 && dth <= 30.0 + 2e-6, "row {k}: {dth}");
        } else {
            assert!((dth - 30.0).abs() < 2e-6, "row {k}: {dth}");
            steps += 1;
        }
    }
    assert!(steps > 1000);
}

#[test]
fn contact12_gives_contact_columns_and_needs_a_feed() {
    let file = repo_sample("clsf/ball_lead15_contact12.txt");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    // contact12 has no feed and no spindle speed: the error names the options to add,
    // and no output file is left behind.
    let assert = crest()
        .arg("resample")
        .arg(&file)
        .args(["--mode", "fz", "--fz-mm", "0.05", "--teeth", "4", "-o"])
        .arg(&out)
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    assert!(
        err.contains("--feed-mm-min") && err.contains("--rpm"),
        "{err}"
    );
    assert!(!out.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);

    let (json, rows) = run(
        &file,
        &[
            "--mode", "fz", "--fz-mm", "0.05", "--teeth", "4", "--rpm", "10000",
        ],
    );
    let stats = &json["paths"][0]["stats"];
    assert_eq!(stats["spindle_source"], "option");
    // V = Z fz n = 2000 mm/min, so t = s/V within a run.
    assert!((stats["feed_max_mm_min"].as_f64().unwrap() - 2000.0).abs() < 1e-9);
    assert!(!rows.is_empty());
    let mut with_contact = 0;
    for row in &rows {
        if let (Some(_), Some(n)) = (vec3(row, "cx"), vec3(row, "nx")) {
            with_contact += 1;
            let f = vec3(row, "fx").unwrap();
            assert!((norm(n) - 1.0).abs() < 1e-8);
            assert!(dot(f, n).abs() < 1e-8, "f·n = {}", dot(f, n));
        }
    }
    assert!(
        with_contact > rows.len() / 2,
        "{with_contact} of {}",
        rows.len()
    );
}

#[test]
fn feed_option_sets_the_clock() {
    let file = external("nx_circle_times_from.cls");
    let (json, rows) = run(
        &file,
        &[
            "--mode",
            "fz",
            "--fz-mm",
            "0.05",
            "--teeth",
            "2",
            "--feed-mm-min",
            "600",
        ],
    );
    let stats = &json["paths"][0]["stats"];
    assert_eq!(stats["arcs"], 6);
    assert_eq!(stats["spindle_source"], "derived_from_feed");
    assert!((stats["spindle_rpm"].as_f64().unwrap() - 6000.0).abs() < 1e-9);
    // One run: t = s/V and θ = 2π s/(Z fz) (180° a sample).
    let last = rows.last().unwrap();
    let s = last[col("s_mm")].unwrap();
    assert!((last[col("t_s")].unwrap() - s / 10.0).abs() < 1e-6);
    assert!((last[col("theta_deg")].unwrap() - s / 0.1 * 360.0).abs() < 1e-3);
    assert!((rows[1][col("theta_deg")].unwrap() - 180.0).abs() < 1e-6);
    // The first move is a helix about the arc centre (1287.5, −341.25), radius 56.25.
    for row in rows.iter().take(8000) {
        let (x, y) = (row[col("x")].unwrap(), row[col("y")].unwrap());
        let r = (x - 1287.5).hypot(y + 341.25);
        assert!((r - 56.25).abs() < 1e-4, "{r}");
    }
}

#[test]
fn bad_options_are_usage_errors() {
    let file = external("nx_circle_times_from.cls");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    crest()
        .arg("resample")
        .arg(&file)
        .args(["--mode", "fz", "--fz-mm", "0", "--teeth", "2", "-o"])
        .arg(&out)
        .assert()
        .code(2);
    crest()
        .arg("resample")
        .arg(&file)
        .args(["--mode", "sideways", "--fz-mm", "0.1", "--teeth", "2", "-o"])
        .arg(&out)
        .assert()
        .code(2);
    crest()
        .arg("resample")
        .arg(dir.path().join("missing.cls"))
        .args(["--mode", "fz", "--fz-mm", "0.1", "--teeth", "2", "-o"])
        .arg(&out)
        .assert()
        .code(2);
    assert!(!out.exists());
}

#[test]
fn machine_feed_follows_the_kinematics() {
    let file = external("nx_circle_times_from.cls");
    let machine = repo_sample("machines/table1_ac.toml");
    let (json, rows) = run(
        &file,
        &[
            "--mode",
            "dtheta",
            "--dtheta-deg",
            "90",
            "--fz-mm",
            "0.1",
            "--teeth",
            "2",
            "--machine",
            machine.to_str().unwrap(),
        ],
    );
    let stats = &json["paths"][0]["stats"];
    // The spindle comes from fz and the programmed 530 mm/min: 530/(2·0.1) rpm.
    assert_eq!(stats["spindle_source"], "derived_from_feed");
    assert!((stats["spindle_rpm"].as_f64().unwrap() - 2650.0).abs() < 1e-9);
    // The engage starts from rest and never exceeds the programmed feed.
    assert!(stats["variable_feed_moves"].as_u64().unwrap() > 0);
    let feed = col("feed_mm_min");
    assert_eq!(rows[0][feed], Some(0.0));
    assert!(rows.iter().all(|r| r[feed].unwrap() <= 530.0 + 1e-3));
    // θ still steps by exactly Δθ while the feed varies; the arc length per step follows
    // the feed (ΔS = V Δθ/Ω).
    let (th, s, t) = (col("theta_deg"), col("s_mm"), col("t_s"));
    let omega_deg_s = 2650.0 * 6.0;
    for k in 1..rows.len() - 1 {
        assert!((rows[k][th].unwrap() - rows[k - 1][th].unwrap() - 90.0).abs() < 2e-6);
        assert!((rows[k][th].unwrap() - omega_deg_s * rows[k][t].unwrap()).abs() < 1e-3);
        assert!(rows[k][s].unwrap() >= rows[k - 1][s].unwrap());
    }
}
