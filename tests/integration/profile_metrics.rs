//! `crest metrics PROFILE.csv` (issue 34): the ISO 21920-2 parameters of a measured
//! two-column `x_mm,z_um` profile, against closed forms of a sine: Ra = 2A/π (and its
//! sampled form), Rq = A/√2,
//! Rsk = 0, Rku = 3/2, RSm = λ, Rz = Rt = 2A, Rdq = 2πA/(λ√2); evenly spaced points as they
//! are, unevenly spaced ones resampled at their median step.

use std::f64::consts::PI;
use std::fmt::Write as _;

use crate::util::{crest, stdout_json, tempdir, write};

const A: f64 = 1.5; // µm
const LAMBDA: f64 = 0.05; // mm

fn sine_csv(xs: &[f64]) -> String {
    let mut s = String::from("x_mm,z_um\n");
    for &x in xs {
        writeln!(s, "{x},{}", A * (2.0 * PI * x / LAMBDA).sin()).unwrap();
    }
    s
}

fn metrics(csv: &str) -> serde_json::Value {
    let dir = tempdir();
    let p = write(dir.path(), "profile.csv", csv);
    let a = crest()
        .args(["metrics", p.to_str().unwrap(), "--json"])
        .assert()
        .success();
    stdout_json(&a)
}

fn close(j: &serde_json::Value, key: &str, want: f64, rel: f64) {
    let got = j[key].as_f64().unwrap_or_else(|| panic!("{key}: {j}"));
    assert!(
        (got - want).abs() <= rel * want.abs().max(1e-12),
        "{key}: {got} against {want} (relative {rel})"
    );
}

#[test]
fn an_evenly_sampled_sine_gives_the_closed_forms() {
    // 20 periods, 400 samples a period, the last point left out: whole periods exactly.
    let n = 20 * 400;
    let step = LAMBDA / 400.0;
    let xs: Vec<f64> = (0..n).map(|k| k as f64 * step).collect();
    let j = metrics(&sine_csv(&xs));
    assert_eq!(j["format"], "profile");
    assert_eq!(j["profile"]["resampled"], false);
    assert_eq!(j["profile"]["samples"], n);
    close(&j["profile"], "step_um", step * 1e3, 1e-9);
    close(&j, "Rq", A / 2f64.sqrt(), 1e-9);
    // Ra = 2A/π for the continuous sine; N samples a period give A·(2/N)·cot(π/N) exactly
    // (2A/π less a relative π²/(3N²), 2e-5 here).
    let per = 400.0;
    close(&j, "Ra", A * 2.0 / per / (PI / per).tan(), 1e-9);
    close(&j, "Ra", 2.0 * A / PI, 3e-5);
    close(&j, "Rz", 2.0 * A, 1e-4);
    close(&j, "Rt", 2.0 * A, 1e-4);
    close(&j, "Rku", 1.5, 1e-6);
    assert!(j["Rsk"].as_f64().unwrap().abs() < 1e-9, "{j}");
    close(&j, "RSm", LAMBDA * 1e3, 1e-6);
    close(&j, "Rdq", 2.0 * PI * A / (LAMBDA * 1e3) / 2f64.sqrt(), 1e-4);
}

#[test]
fn an_unevenly_sampled_sine_is_resampled_at_its_median_step() {
    // Steps of 0.8, 1.0 and 1.2 times λ/400 in turn: the median step is λ/400.
    let base = LAMBDA / 400.0;
    let mut xs = vec![0.0];
    let mut k = 0;
    while *xs.last().unwrap() < 20.0 * LAMBDA {
        let f = [1.0, 0.8, 1.2][k % 3];
        xs.push(xs.last().unwrap() + f * base);
        k += 1;
    }
    let j = metrics(&sine_csv(&xs));
    assert_eq!(j["profile"]["resampled"], true);
    close(&j["profile"], "step_um", base * 1e3, 1e-9);
    close(&j, "Rq", A / 2f64.sqrt(), 1e-3);
    close(&j, "Ra", 2.0 * A / PI, 1e-3);
    close(&j, "Rz", 2.0 * A, 1e-3);
    close(&j, "RSm", LAMBDA * 1e3, 1e-3);
}

#[test]
fn a_profile_refuses_map_options_and_bad_points() {
    let dir = tempdir();
    let p = write(
        dir.path(),
        "p.csv",
        "x_mm,z_um\n0,1\n0.001,2\n0.002,1\n0.003,0\n0.004,1\n0.005,2\n",
    );
    let a = crest()
        .args(["metrics", p.to_str().unwrap(), "--profile", "row:0"])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("--profile") && err.contains("p.csv"), "{err}");
    let q = write(
        dir.path(),
        "q.csv",
        "x_mm,z_um\n0,1\n0.002,2\n0.001,1\n0.003,0\n0.004,1\n0.005,2\n",
    );
    let a = crest()
        .args(["metrics", q.to_str().unwrap()])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("q.csv") && err.contains("point 3"), "{err}");
    // A grid CSV is still a height map.
    let g = write(dir.path(), "g.csv", "1,2,3\n4,5,6\n7,8,9\n");
    crest()
        .args([
            "metrics",
            g.to_str().unwrap(),
            "--dx-um",
            "1",
            "--params",
            "Sa",
        ])
        .assert()
        .success();
}
