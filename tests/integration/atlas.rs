//! `crest atlas` (issue 33): a patch every D mm over the finishing regions of an NX-style
//! export made here (ball end D6, PAINT/COLOR lead-in and lead-out arcs, eight parallel
//! passes 0.5 mm apart on the floor z = 0, the axis leaning by a known lead and tilt), with
//! the numbers checked against closed forms; csv and ply agree; shards merge to the
//! unsharded table; a patch in the air keeps its row with a warning.

use crate::util::{crest, json, output_json, read, tempdir, write};

const PASSES: usize = 8;
const STEP: f64 = 0.5;
const R: f64 = 3.0;
const ARC_R: f64 = 8.0;
const ARC_GOTOS: usize = 12;
const CUT_GOTOS: usize = 10;
/// Lead and tilt of the tool axis, degrees: a = (tan lead, tan tilt, 1) normalised, with
/// the feed along +x and the normal +z (so g = n × f = +y).
const LEAD_DEG: f64 = 10.0;
const TILT_DEG: f64 = 5.0;

fn axis() -> [f64; 3] {
    let (l, t) = (LEAD_DEG.to_radians().tan(), TILT_DEG.to_radians().tan());
    let n = (l * l + t * t + 1.0).sqrt();
    [l / n, t / n, 1.0 / n]
}

/// The GOTO of the tool tip whose ball touches the contact point `c` (normal +z): ball
/// centre c + R·z, tip = centre − R·a.
fn goto(c: [f64; 3]) -> String {
    let a = axis();
    let tip = [c[0] - R * a[0], c[1] - R * a[1], c[2] + R - R * a[2]];
    let r = |v: f64| (v * 1e6).round() / 1e6 + 0.0;
    format!(
        "GOTO/{:.6},{:.6},{:.6},{:.7},{:.7},{:.7}\n",
        r(tip[0]),
        r(tip[1]),
        r(tip[2]),
        a[0],
        a[1],
        a[2]
    )
}

/// The export, as in `moves.rs`, with a leaning axis: per pass a lead-in arc (colour 42),
/// the cut (31) along +x from x = 0 to 20 on y = k · STEP, a lead-out arc (37).
fn export() -> String {
    let mut s = String::from(
        "TOOL PATH/VARIABLE_CONTOUR,TOOL,BALL-D6\nTLDATA/MILL,6.0000,3.0000,50.0000,0.0000,0.0000\nLOAD/TOOL,1,ADJUST,1\nPAINT/COLOR,186\nRAPID\nGOTO/-8.0000,0.0000,50.0000,0.0000000,0.0000000,1.0000000\n",
    );
    for k in 0..PASSES {
        let y = k as f64 * STEP;
        let arc_in = |deg: f64| {
            let a = deg.to_radians();
            [-ARC_R * a.cos(), y, ARC_R - ARC_R * a.sin()]
        };
        let arc_out = |deg: f64| {
            let a = deg.to_radians();
            [20.0 + ARC_R * a.sin(), y, ARC_R - ARC_R * a.cos()]
        };
        s.push_str("PAINT/COLOR,211\nRAPID\n");
        s.push_str(&goto(arc_in(0.0)));
        s.push_str("PAINT/COLOR,42\nFEDRAT/MMPM,500.0000\n");
        for j in 1..=ARC_GOTOS {
            s.push_str(&goto(arc_in(90.0 * j as f64 / ARC_GOTOS as f64)));
        }
        s.push_str("PAINT/COLOR,31\nFEDRAT/MMPM,1500.0000\n");
        for j in 1..=CUT_GOTOS {
            s.push_str(&goto([2.0 * j as f64, y, 0.0]));
        }
        s.push_str("PAINT/COLOR,37\nFEDRAT/MMPM,500.0000\n");
        for j in 1..=ARC_GOTOS {
            s.push_str(&goto(arc_out(90.0 * j as f64 / ARC_GOTOS as f64)));
        }
    }
    s.push_str("PAINT/COLOR,211\nRAPID\nGOTO/28.0000,3.5000,50.0000\nEND-OF-PATH\n");
    s
}

/// 1500 mm/min at 7500 rpm with 2 teeth: fz = 0.1 mm.
const FZ: f64 = 0.1;

fn atlas(dir: &std::path::Path, file: &std::path::Path, extra: &[&str]) -> std::process::Output {
    crest()
        .current_dir(dir)
        .arg("atlas")
        .arg(file)
        .args(["--teeth", "2", "--rpm", "7500"])
        .args(extra)
        .output()
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The CSV as header names and rows of fields.
fn table(path: &std::path::Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{e}"));
    let header = r
        .headers()
        .unwrap_or_else(|e| panic!("{e}"))
        .iter()
        .map(str::to_string)
        .collect();
    let rows = r
        .records()
        .map(|x| {
            x.unwrap_or_else(|e| panic!("{e}"))
                .iter()
                .map(str::to_string)
                .collect()
        })
        .collect();
    (header, rows)
}

fn field(header: &[String], row: &[String], name: &str) -> f64 {
    let i = header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name}"));
    row[i].parse().unwrap_or(f64::NAN)
}

#[test]
fn atlas_numbers_match_the_closed_forms_and_the_path() {
    let dir = tempdir();
    let file = write(dir.path(), "nx.cls", export());
    // D = 4 mm: k = round(4 / 0.5) = 8 passes apart, starting at pass ⌊8/2⌋ = 4 (0-based):
    // one pass of the eight; along its 20 mm, ⌊20 / 4⌋ = 5 patches at x = 2, 6, …, 18.
    let out = atlas(
        dir.path(),
        &file,
        &[
            "--every-mm",
            "4",
            "--grid-um",
            "5",
            "-o",
            "a.csv",
            "-o",
            "a.ply",
            "--json",
        ],
    );
    let v = output_json(&out);
    assert_eq!(out.status.code(), Some(0), "{v}");
    assert_eq!(v["patches"], 5, "{v}");
    assert_eq!(v["regions"], 1);
    let (h, rows) = table(&dir.path().join("a.csv"));
    assert_eq!(rows.len(), 5);
    let r = R;
    let scallop = (r - (r * r - STEP * STEP / 4.0).sqrt()) * 1e3;
    let marks = FZ * FZ / (8.0 * r) * 1e3;
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(field(&h, row, "pass"), 5.0);
        assert!(
            (field(&h, row, "x") - (2.0 + 4.0 * k as f64)).abs() < 0.02,
            "{row:?}"
        );
        assert!((field(&h, row, "y") - 2.0).abs() < 0.02, "{row:?}");
        // The scallop across the feed: a ball of R 3 over s = 0.5 mm leaves
        // R − √(R² − s²/4) = 10.435 µm. Tolerance 0.25 µm: the 5 µm grid samples the sharp
        // crest within half a node, 2.5 µm × its slope s / 2R = 0.083 (0.21 µm); the dome
        // mesh's chord (by default a hundredth of the closed-form scallop, 0.10 µm) lifts
        // crest and valley alike, so it leaves their difference.
        let s = field(&h, row, "scallop_um");
        assert!((s - scallop).abs() < 0.25, "scallop {s} vs {scallop}");
        // The feed marks along the pass bottom: fz² / 8R = 0.4167 µm. Tolerance 0.05 µm:
        // half a node times the marks' crest slope fz / 2R (0.04 µm), the chord as above.
        let m = field(&h, row, "feed_mark_um");
        assert!((m - marks).abs() < 0.05, "feed marks {m} vs {marks}");
        assert!((field(&h, row, "scallop_closed_um") - scallop).abs() < 0.2);
        assert!((field(&h, row, "feed_mark_closed_um") - marks).abs() < 1e-9);
        // The local stepover and the lead and tilt the path was made with (GOTOs printed
        // with 7 decimals in the axis: 1e-5° is far below the tolerance).
        assert!(
            (field(&h, row, "stepover_mm") - STEP).abs() < 1e-3,
            "{row:?}"
        );
        assert!(
            (field(&h, row, "lead_deg") - LEAD_DEG).abs() < 0.01,
            "{row:?}"
        );
        assert!(
            (field(&h, row, "tilt_deg") - TILT_DEG).abs() < 0.01,
            "{row:?}"
        );
        // A flat floor: no curvature.
        assert!(field(&h, row, "curvature_along_per_mm").abs() < 1e-3);
        assert!(field(&h, row, "curvature_across_per_mm").abs() < 1e-3);
        let sa = field(&h, row, "Sa_um");
        assert!(sa > 0.1 * scallop && sa < scallop, "Sa {sa}");
        assert_eq!(row.last().map(String::as_str), Some(""));
    }
    // The point cloud holds the same numbers (x y z and Sa as written in the table).
    let ply = read(&dir.path().join("a.ply"));
    let props: Vec<&str> = ply
        .lines()
        .filter_map(|l| l.strip_prefix("property float "))
        .collect();
    let body: Vec<Vec<f64>> = ply
        .lines()
        .skip_while(|l| *l != "end_header")
        .skip(1)
        .map(|l| {
            l.split(' ')
                .map(|t| t.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    assert_eq!(body.len(), rows.len());
    for (p, row) in body.iter().zip(&rows) {
        for name in [
            "x",
            "y",
            "z",
            "Sa_um",
            "scallop_um",
            "lead_deg",
            "stepover_mm",
        ] {
            let i = props
                .iter()
                .position(|q| *q == name)
                .unwrap_or_else(|| panic!("{name}"));
            assert_eq!(p[i], field(&h, row, name), "{name}");
        }
    }
    // `crest view --colour-by` reads any column of the cloud.
    crest()
        .current_dir(dir.path())
        .args(["view", "a.ply", "--colour-by", "scallop_um", "-o", "v.html"])
        .assert()
        .success();
    crest()
        .current_dir(dir.path())
        .args(["view", "a.ply", "--colour-by", "nonsense", "-o", "w.html"])
        .assert()
        .failure();
}

/// Nodes farther apart than half the feed per tooth (0.1 mm here) cannot see the marks:
/// their column is left empty and the run says why, while the rest of the row stands.
#[test]
fn marks_finer_than_the_grid_are_left_empty_with_the_reason() {
    let dir = tempdir();
    let file = write(dir.path(), "nx.cls", export());
    for (grid, resolved) in [("50", true), ("60", false)] {
        let csv = format!("g{grid}.csv");
        let out = atlas(
            dir.path(),
            &file,
            &["--every-mm", "4", "--grid-um", grid, "-o", &csv, "--json"],
        );
        let v = output_json(&out);
        assert_eq!(out.status.code(), Some(0), "{v}");
        let note = v["warnings"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|w| w.as_str())
            .any(|w| w.contains("feed marks are not resolved") && w.contains("50 µm"));
        assert_eq!(note, !resolved, "{v}");
        let (h, rows) = table(&dir.path().join(&csv));
        assert_eq!(rows.len(), 5);
        for row in &rows {
            assert_eq!(
                field(&h, row, "feed_mark_um").is_finite(),
                resolved,
                "{row:?}"
            );
            assert!(field(&h, row, "scallop_um").is_finite(), "{row:?}");
            assert!(field(&h, row, "Sa_um") > 0.0, "{row:?}");
        }
    }
}

#[test]
fn shards_merge_to_the_unsharded_atlas() {
    let dir = tempdir();
    let file = write(dir.path(), "nx.cls", export());
    // D = 2 mm: k = 4, passes 2 and 6 (0-based), 10 patches each.
    let args = ["--every-mm", "2", "--grid-um", "10", "--model", "swept"];
    let whole = atlas(
        dir.path(),
        &file,
        &[&args[..], &["-o", "whole.csv"]].concat(),
    );
    assert_eq!(whole.status.code(), Some(0), "{whole:?}");
    for k in ["1/3", "2/3", "3/3"] {
        let out = atlas(
            dir.path(),
            &file,
            &[&args[..], &["--shard", k, "-o", "shards"]].concat(),
        );
        assert_eq!(out.status.code(), Some(0), "{out:?}");
    }
    crest()
        .current_dir(dir.path())
        .args([
            "merge",
            "shards/shard-3-of-3.jsonl",
            "shards/shard-1-of-3.jsonl",
            "shards/shard-2-of-3.jsonl",
            "-o",
            "merged.csv",
        ])
        .assert()
        .success();
    let a = read(&dir.path().join("whole.csv"));
    assert_eq!(a.lines().count(), 21);
    assert_eq!(a, read(&dir.path().join("merged.csv")));
    // A missing shard is refused.
    crest()
        .current_dir(dir.path())
        .args(["merge", "shards/shard-1-of-3.jsonl", "-o", "part.csv"])
        .assert()
        .failure();
}

/// An ASCII STL of the plane z = `z` over x −10 … 30, y −1 … `y1`, facing +z.
fn plane_stl(z: f64, y1: f64) -> String {
    let v = |x: f64, y: f64| format!("      vertex {x} {y} {z}\n");
    let tri = |a: String, b: String, c: String| {
        format!("  facet normal 0 0 1\n    outer loop\n{a}{b}{c}    endloop\n  endfacet\n")
    };
    format!(
        "solid floor\n{}{}endsolid floor\n",
        tri(v(-10.0, -1.0), v(30.0, -1.0), v(30.0, y1)),
        tri(v(-10.0, -1.0), v(30.0, y1), v(-10.0, y1))
    )
}

#[test]
fn a_patch_in_the_air_keeps_its_row_with_the_reason() {
    let dir = tempdir();
    let file = write(dir.path(), "nx.cls", export());
    // The part ends at y = 2: the patches on pass 2 (y = 1) lie on it, those on pass 6
    // (y = 3) are 1 mm beside it, more than the 0.75 mm tolerance (1.5 stepovers).
    write(dir.path(), "half.stl", plane_stl(0.0, 2.0));
    let args = ["--every-mm", "2", "--grid-um", "10", "--model", "swept"];
    let out = atlas(
        dir.path(),
        &file,
        &[&args[..], &["--part", "half.stl", "-o", "a.csv", "--json"]].concat(),
    );
    let v = json(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{v}");
    assert_eq!(v["patches"], 20);
    assert_eq!(v["patches_with_numbers"], 10, "{v}");
    let (h, rows) = table(&dir.path().join("a.csv"));
    for row in &rows {
        let y = field(&h, row, "y");
        let w = row.last().cloned().unwrap_or_default();
        if y < 2.0 {
            assert!(
                field(&h, row, "Sa_um").is_finite() && w.is_empty(),
                "{row:?}"
            );
        } else {
            assert!(field(&h, row, "Sa_um").is_nan(), "{row:?}");
            assert!(w.contains("in the air"), "{w}");
        }
    }
    // A part 5 mm below every pass: no patch has numbers, the run fails saying why.
    write(dir.path(), "low.stl", plane_stl(-5.0, 5.0));
    let out = atlas(
        dir.path(),
        &file,
        &[&args[..], &["--part", "low.stl", "-o", "b.csv"]].concat(),
    );
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("none of the 20 patches produced numbers") && err.contains("in the air"),
        "{err}"
    );
    assert!(!dir.path().join("b.csv").exists());
}
