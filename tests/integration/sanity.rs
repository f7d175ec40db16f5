//! Loud sanity checks (issue 33): each check fires on one synthetic path (exit 1, the
//! warning on stderr and in `--json` `warnings`) and stays quiet on a close one (exit 0);
//! the bounds are computed here from the closed forms, not by crest's code. On the large NX
//! export, the point gives no height beyond the bound with exit 0.

use crate::util::{crest, json, tempdir, write};
use std::path::Path;

/// Ball (or corner) radius of the synthetic tool, mm.
const R: f64 = 3.0;
/// Feed, rpm and teeth: fz = 1600 / (2 · 8000) = 0.1 mm.
const FEED: f64 = 1600.0;
const RPM: f64 = 8000.0;
const TEETH: f64 = 2.0;

/// R − √(R² − s²/4): the scallop of two circles of radius r a distance s apart, mm.
fn scallop(s: f64, r: f64) -> f64 {
    r - (r * r - s * s / 4.0).sqrt()
}

/// Straight passes along x (0 … 20 mm) over the floor z = 0, `step` mm apart, tool tip on
/// the floor, axis +z, the contact point and normal written by each GOTO with the contact
/// `offset` mm below the floor (a wrong reference when non-zero). `tldata` is the TLDATA
/// record's diameter and corner radius; `head` goes before the path (UNITS), `feed` is the
/// FEDRAT record.
fn floor_path(
    step: f64,
    passes: usize,
    offset: f64,
    tldata: (f64, f64),
    head: &str,
    feed: &str,
) -> String {
    let mut s = format!(
        "{head}TOOL PATH/SANITY,TOOL,T\nTLDATA/MILL,{:.4},{:.4},50.0000,0.0000,0.0000\n$$ crest: GOTO/x,y,z,i,j,k,cx,cy,cz[,nx,ny,nz] carries the CC point and normal\nSPINDL/RPM,{RPM:.4},CLW\n",
        tldata.0, tldata.1
    );
    for k in 0..passes {
        let y = k as f64 * step;
        s.push_str(&format!(
            "RAPID\nGOTO/0.0000,{y:.4},5.0000,0.0000000,0.0000000,1.0000000\n{feed}\n"
        ));
        for i in 0..=20 {
            let x = i as f64;
            s.push_str(&format!(
                "GOTO/{x:.4},{y:.4},0.0000,0.0000000,0.0000000,1.0000000,{x:.4},{y:.4},{:.4},0.0000000,0.0000000,1.0000000\n",
                -offset
            ));
        }
    }
    s.push_str("END-OF-PATH\n");
    s
}

fn mmpm() -> String {
    format!("FEDRAT/MMPM,{FEED:.4}")
}

/// `crest simulate FILE --patch-near X,Y,0 --patch-mm L,W --json` (dome, 10 µm, 2 teeth):
/// the exit code, the JSON and stderr.
fn simulate(
    file: &Path,
    y: f64,
    patch: (f64, f64),
    extra: &[&str],
) -> (i32, serde_json::Value, String) {
    let dir = file.parent().unwrap_or(Path::new("."));
    let out = crest()
        .arg("simulate")
        .arg(file)
        .args(["--teeth", "2", "--rpm", &RPM.to_string(), "--model", "dome"])
        .args(["--grid-um", "10", "--chord-tol-um", "1", "--band-um", "15"])
        .args(["--patch-near", &format!("10,{y},0")])
        .args(["--patch-mm", &format!("{},{}", patch.0, patch.1)])
        .args(extra)
        .arg("-o")
        .arg(dir.join("h.csv"))
        .arg("--json")
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let code = out.status.code().unwrap_or(-1);
    assert!(code == 0 || code == 1, "exit {code}: {stderr}");
    (code, json(&out.stdout), stderr)
}

fn warnings(j: &serde_json::Value) -> Vec<String> {
    j["warnings"]
        .as_array()
        .unwrap_or_else(|| panic!("no warnings array: {j}"))
        .iter()
        .map(|w| w.as_str().unwrap_or_default().to_string())
        .collect()
}

/// Exit 1 and a warning containing `text` in `--json` and on stderr.
fn fires(run: &(i32, serde_json::Value, String), text: &str) {
    let (code, j, err) = run;
    assert_eq!(*code, 1, "{err}");
    assert!(warnings(j).iter().any(|w| w.contains(text)), "{text}: {j}");
    assert!(err.contains(text), "{text}: {err}");
}

/// Exit 0 and no warning.
fn quiet(run: &(i32, serde_json::Value, String)) {
    let (code, j, err) = run;
    assert_eq!(*code, 0, "{err}");
    assert!(warnings(j).is_empty(), "{j}");
}

fn extreme(j: &serde_json::Value) -> f64 {
    let h = &j["heights_um"];
    let (lo, hi) = (
        h["min"].as_f64().unwrap_or(f64::NAN),
        h["max"].as_f64().unwrap_or(f64::NAN),
    );
    lo.abs().max(hi.abs())
}

#[test]
fn heights_beyond_the_bound_fail_and_plausible_ones_pass() {
    let step = 0.5;
    let fz = FEED / (TEETH * RPM);
    // 3 × the larger scallop + chord tolerance 1 µm + 5 µm: about 37.4 µm.
    let bound = 3.0 * scallop(step, R).max(scallop(fz, R)) * 1e3 + 1.0 + 5.0;
    let dir = tempdir();
    // A reference 20 µm below the floor: heights 20 … 31 µm, inside the bound.
    let close = write(
        dir.path(),
        "close.cls",
        floor_path(step, 8, 0.020, (6.0, 3.0), "", &mmpm()),
    );
    let run = simulate(&close, 1.75, (1.0, 1.0), &[]);
    quiet(&run);
    let e = extreme(&run.1);
    assert!(e > 15.0 && e <= bound, "{e} {bound}");
    // 40 µm below: heights 40 … 51 µm, beyond it.
    let wrong = write(
        dir.path(),
        "wrong.cls",
        floor_path(step, 8, 0.040, (6.0, 3.0), "", &mmpm()),
    );
    let run = simulate(&wrong, 1.75, (1.0, 1.0), &[]);
    let e = extreme(&run.1);
    assert!(e > bound, "{e} {bound}");
    fires(
        &run,
        &format!("beyond the {bound:.1} µm that a finishing pass can leave"),
    );
}

#[test]
fn a_patch_narrower_than_one_period_fails() {
    let dir = tempdir();
    let f = write(
        dir.path(),
        "p.cls",
        floor_path(0.5, 8, 0.0, (6.0, 3.0), "", &mmpm()),
    );
    // Across: the stepover is 0.5 mm.
    fires(
        &simulate(&f, 1.75, (1.0, 0.4), &[]),
        "narrower than the local stepover 0.5000 mm",
    );
    quiet(&simulate(&f, 1.75, (1.0, 0.6), &[]));
    // Along: the feed-mark period is fz = 0.1 mm.
    fires(
        &simulate(&f, 1.75, (0.08, 1.0), &[]),
        "shorter than the feed-mark period 0.1000 mm",
    );
    quiet(&simulate(&f, 1.75, (0.12, 1.0), &[]));
}

#[test]
fn an_ap_that_clips_the_scallop_fails() {
    let step = 2.0;
    let h = scallop(step, R); // 171.6 µm
    let dir = tempdir();
    let f = write(
        dir.path(),
        "ap.cls",
        floor_path(step, 5, 0.0, (6.0, 3.0), "", &mmpm()),
    );
    let clipped = simulate(&f, 3.0, (1.0, 2.5), &["--ap-mm", &format!("{}", 0.6 * h)]);
    fires(
        &clipped,
        &format!(
            "scallop of the stepover 2.0000 mm with R_eff 3 mm is {:.1} µm",
            h * 1e3
        ),
    );
    assert!(clipped.1["nodes_not_reached"].as_u64().unwrap_or(0) > 0);
    let whole = simulate(&f, 3.0, (1.0, 2.5), &["--ap-mm", &format!("{}", 1.2 * h)]);
    quiet(&whole);
    assert_eq!(whole.1["nodes_not_reached"].as_u64(), Some(0));
    assert!(extreme(&whole.1) <= h * 1e3 + 1.0 + 0.5);
}

#[test]
fn a_tool_without_corner_on_a_floor_fails() {
    let dir = tempdir();
    let flat = write(
        dir.path(),
        "flat.cls",
        floor_path(0.5, 8, 0.0, (6.0, 0.0), "", &mmpm()),
    );
    fires(
        &simulate(&flat, 1.75, (1.0, 1.0), &[]),
        "has no corner radius",
    );
    let bull = write(
        dir.path(),
        "bull.cls",
        floor_path(0.5, 8, 0.0, (6.0, 0.5), "", &mmpm()),
    );
    quiet(&simulate(&bull, 1.75, (1.0, 1.0), &[]));
}

#[test]
fn inch_feeds_without_units_fail() {
    let dir = tempdir();
    // 63 in/min = 1600.2 mm/min.
    let ipm = "FEDRAT/IPM,63.0000";
    let bare = write(
        dir.path(),
        "bare.cls",
        floor_path(0.5, 8, 0.0, (6.0, 3.0), "", ipm),
    );
    let text = "contradictory units";
    fires(&simulate(&bare, 1.75, (1.0, 1.0), &[]), text);
    let out = crest()
        .arg("inspect")
        .arg(&bare)
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stdout).contains(text));
    assert!(String::from_utf8_lossy(&out.stderr).contains(&format!("{}:", bare.display())));
    let units = write(
        dir.path(),
        "units.cls",
        floor_path(0.5, 8, 0.0, (6.0, 3.0), "UNITS/MM\n", ipm),
    );
    quiet(&simulate(&units, 1.75, (1.0, 1.0), &[]));
    let out = crest()
        .arg("inspect")
        .arg(&units)
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(out.status.code(), Some(0));
}

/// The point on the large NX export (bull nose D32 R5, where the axis turns): before,
/// heights of −37,773 … −2,392 µm with exit 0. Now plausible heights or exit ≠ 0.
#[test]
fn the_large_export_gives_no_height_beyond_the_bound_with_exit_0() {
    let Some(dir) = crate::util::external_samples() else {
        return;
    };
    let file = dir.join("nx_5axis_varcontour_ijk_large.cls");
    let tmp = tempdir();
    let out = crest()
        .arg("simulate")
        .arg(&file)
        .args(["--teeth", "2", "--rpm", "8000", "--model", "dome"])
        .args(["--grid-um", "10", "--chord-tol-um", "1", "--band-um", "15"])
        .args(["--patch-near", "470.4,24.75,-55.6", "--patch-mm", "1,1"])
        .arg("-o")
        .arg(tmp.path().join("h.csv"))
        .arg("--json")
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    let err = String::from_utf8_lossy(&out.stderr);
    if out.status.success() {
        let j = json(&out.stdout);
        assert!(extreme(&j) <= 100.0, "{j}");
    } else {
        assert!(!err.trim().is_empty());
    }
}

/// Issue 33: on the large NX export (bull nose D32 R5, the axis turning up the walls) no
/// derived contact crest keeps has a normal facing away from the tool or jumps across the
/// cutter between neighbouring postures; the contacts the path contradicts are counted and
/// left out, and the floor keeps its own.
#[test]
fn the_large_export_keeps_no_contact_facing_away_and_counts_the_left_out() {
    let Some(dir) = crate::util::external_samples() else {
        return;
    };
    let file = dir.join("nx_5axis_varcontour_ijk_large.cls");
    let tmp = tempdir();
    let out_csv = tmp.path().join("c.csv");
    let out = crest()
        .arg("contact")
        .arg(&file)
        .args(["--teeth", "2", "--json", "-o"])
        .arg(&out_csv)
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    let j = json(&out.stdout);
    let left_out = j["inconsistent"].as_u64().unwrap_or(0);
    let kept = j["with_contact"].as_u64().unwrap_or(0);
    // Of the 8 789 cut postures, 1 497 have the axis along z (the flat floors, where the
    // flat end touches at its centre): most of those must keep their contact.
    assert!(left_out > 0 && kept > 1000, "{j}");
    assert!(
        warnings(&j).iter().any(|w| w.contains("inconsistent")),
        "{j}"
    );
    let text = std::fs::read_to_string(&out_csv).unwrap_or_else(|e| panic!("{e}"));
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(|v| v.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    let mut floor = 0;
    let mut prev: Option<([f64; 3], [f64; 3])> = None;
    for r in &rows {
        let (tip, a, cc, n) = (
            [r[0], r[1], r[2]],
            [r[3], r[4], r[5]],
            [r[6], r[7], r[8]],
            [r[9], r[10], r[11]],
        );
        if !cc[0].is_finite() {
            prev = None;
            continue;
        }
        let norm = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        let na = (n[0] * a[0] + n[1] * a[1] + n[2] * a[2]) / norm;
        assert!(na > 0.0, "normal faces away at {tip:?}: n·a = {na}");
        if na > 0.999_999 {
            floor += 1;
        }
        // The contact moves with the tool: never across the cutter (2 (R − rc) = 22 mm)
        // while the tip moves less than 2 mm.
        if let Some((ptip, pcc)) = prev {
            let dt = ((tip[0] - ptip[0]).powi(2)
                + (tip[1] - ptip[1]).powi(2)
                + (tip[2] - ptip[2]).powi(2))
            .sqrt();
            let dc =
                ((cc[0] - pcc[0]).powi(2) + (cc[1] - pcc[1]).powi(2) + (cc[2] - pcc[2]).powi(2))
                    .sqrt();
            assert!(!(dt < 2.0 && dc > 10.0), "contact jumps {dc} mm at {tip:?}");
        }
        prev = Some((tip, cc));
    }
    assert!(floor > 1000, "{floor} contacts on the floor");
}
