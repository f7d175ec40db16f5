//! `--feed programmed|predicted --machine machine.toml` on `crest resample` and
//! `crest simulate` (issue 8): on the 000 hyperbolic-paraboloid path at 5 m/min the Table I
//! AC machine must slow down where the tool axis passes near the C pole, so the predicted
//! feed, time stamps and cutting time differ from the programmed ones; the JSON says which
//! feed was used; the option combinations that make no sense are refused.

use assert_cmd::Command;
use std::path::Path;

const PATH: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/samples/synth/hyperbolic-paraboloid.cls"
);
const AC: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/samples/machines/table1_ac.toml"
);
const TOOL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/samples/synth/torus-r5-rc1.5.toml"
);
const HEADER: &str = "s_mm,t_s,theta_deg,x,y,z,i,j,k,cx,cy,cz,nx,ny,nz,fx,fy,fz,feed_mm_min";

fn crest() -> Command {
    Command::cargo_bin("crest").unwrap()
}

/// `crest resample PATH --path 5 --mode fz …` with `extra`; the JSON and the (t_s,
/// feed_mm_min) columns.
fn resample(extra: &[&str]) -> (serde_json::Value, Vec<(f64, f64)>) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r.csv");
    let a = crest()
        .args(["resample", PATH, "--path", "1", "--mode", "fz"])
        .args(["--fz-mm", "0.2", "--teeth", "1", "--json", "-o"])
        .arg(&out)
        .args(extra)
        .assert()
        .success();
    let json: serde_json::Value = serde_json::from_slice(&a.get_output().stdout).unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(HEADER));
    let cols: Vec<&str> = HEADER.split(',').collect();
    let (ti, fi) = (
        cols.iter().position(|c| *c == "t_s").unwrap(),
        cols.iter().position(|c| *c == "feed_mm_min").unwrap(),
    );
    let rows = lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (c[ti].parse().unwrap(), c[fi].parse().unwrap())
        })
        .collect();
    (json, rows)
}

/// Cutting time of a resampled path: t restarts at 0 at every run, so add the runs' ends.
fn cut_time(rows: &[(f64, f64)]) -> f64 {
    let mut total = 0.0;
    for w in rows.windows(2) {
        if w[1].0 < w[0].0 {
            total += w[0].0;
        }
    }
    total + rows.last().map_or(0.0, |r| r.0)
}

#[test]
fn resample_predicted_feed_is_slower_than_programmed() {
    let (jp, prog) = resample(&[]);
    let (jm, pred) = resample(&["--feed", "predicted", "--machine", AC]);
    assert_eq!(jp["feed"], "programmed");
    assert_eq!(jm["feed"], "predicted");
    assert_eq!(jm["machine"], AC);
    // Programmed: 5000 mm/min everywhere in the cut.
    assert!(prog.iter().all(|r| (r.1 - 5000.0).abs() < 1e-6));
    // Predicted: starting from rest, well below the programmed feed somewhere mid-path (the
    // C axis near its pole), and the run takes longer. The Eq 6 feed of the tool tip may
    // exceed F by a little: the planner bounds the speed along the chord between postures,
    // the tip follows the joint interpolation, which is a bit longer where A and C turn.
    let fmax = pred.iter().map(|r| r.1).fold(0.0, f64::max);
    let fmin_mid = pred[pred.len() / 4..3 * pred.len() / 4]
        .iter()
        .map(|r| r.1)
        .fold(f64::INFINITY, f64::min);
    assert!(fmax <= 5000.0 * 1.03, "{fmax}");
    assert!(pred[0].1 < 1e-6);
    assert!(fmin_mid < 0.8 * 5000.0, "{fmin_mid}");
    let (tp, tm) = (cut_time(&prog), cut_time(&pred));
    assert!(tm > tp * 1.05, "predicted {tm} s vs programmed {tp} s");
    // The plunges start and end at rest; they still take a finite, planned time (the whole
    // plan, rapids included, is 2.5x the programmed time).
    assert!(tm < tp * 4.0, "predicted {tm} s vs programmed {tp} s");
    // Time stamps increase inside every cutting run (t restarts at 0 at each run).
    assert!(pred.windows(2).all(|w| w[1].0 >= w[0].0 || w[1].0 == 0.0));
    // `--machine` alone means predicted, with the same result.
    let (jalone, alone) = resample(&["--machine", AC]);
    assert_eq!(jalone["feed"], "predicted");
    assert_eq!(alone, pred);
}

#[test]
fn resample_refuses_inconsistent_feed_options() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r.csv");
    let base = |c: &mut Command| {
        c.args(["resample", PATH, "--mode", "fz", "--fz-mm", "0.2"])
            .args(["--teeth", "1", "-o"])
            .arg(&out);
    };
    let mut c = crest();
    base(&mut c);
    let a = c.args(["--feed", "predicted"]).assert().code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("--machine"), "{err}");
    let mut c = crest();
    base(&mut c);
    let a = c
        .args(["--feed", "programmed", "--machine", AC])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("--feed predicted"), "{err}");
    assert!(!Path::new(&out).exists());
}

/// `crest simulate` on a 2 × 2 mm window at the saddle point; the JSON summary.
fn simulate(extra: &[&str]) -> serde_json::Value {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("h.csv");
    let a = crest()
        .args(["simulate", PATH, "--tool", TOOL, "--model", "dome"])
        .args(["--grid-um", "50", "--window=-1,-1,1,1", "--json", "-o"])
        .arg(&out)
        .args(extra)
        .assert()
        .success();
    serde_json::from_slice(&a.get_output().stdout).unwrap()
}

#[test]
fn simulate_with_predicted_feed_takes_longer_and_feeds_less() {
    let p = simulate(&["--feed", "programmed"]);
    let m = simulate(&["--feed", "predicted", "--machine", AC]);
    assert_eq!(p["feed"]["source"], "programmed");
    assert_eq!(m["feed"]["source"], "predicted");
    assert_eq!(m["feed"]["machine"], AC);
    let f = |v: &serde_json::Value, k: &str| v["feed"]["sample_feed_mm_min"][k].as_f64().unwrap();
    assert!((f(&p, "min") - 5000.0).abs() < 1e-6 && (f(&p, "max") - 5000.0).abs() < 1e-6);
    assert!(f(&m, "max") <= 5000.0 * 1.03);
    assert!(f(&m, "min") < 0.8 * 5000.0);
    assert!(f(&m, "mean") < f(&p, "mean"));
    let (tp, tm) = (
        p["feed"]["cut_time_s"].as_f64().unwrap(),
        m["feed"]["cut_time_s"].as_f64().unwrap(),
    );
    assert!(
        tm > tp * 1.05 && tm < tp * 4.0,
        "predicted {tm} s vs programmed {tp} s"
    );
    // Same spindle speed (from the file), so the surface is cut with a finer feed per
    // tooth where the machine is slow: the window is still cut.
    assert_eq!(p["rpm"], m["rpm"]);
    assert!(m["nodes_cut"].as_u64().unwrap() > 0);
    // Without a machine, `--feed predicted` is an error.
    let dir = tempfile::tempdir().unwrap();
    crest()
        .args(["simulate", PATH, "--tool", TOOL, "--model", "dome"])
        .args([
            "--grid-um",
            "50",
            "--window=-1,-1,1,1",
            "--feed",
            "predicted",
            "-o",
        ])
        .arg(dir.path().join("h.csv"))
        .assert()
        .code(2);
}
