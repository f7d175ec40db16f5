//! Move kinds (issue 33): NX's `PAINT/COLOR` groups and feed changes told apart by the
//! lowering, counted by `crest inspect`, finishing regions (`inspect --regions`), and only
//! the cut moves simulated by default: a patch in the air is refused with its distance,
//! `--moves all` restores every feed move.

use crate::util::{crest, output_json, tempdir, write};
use std::collections::BTreeMap;

/// Passes of the synthetic export.
const PASSES: usize = 8;
/// Stepover between passes, mm (passes along x at y = k · STEP).
const STEP: f64 = 0.5;
/// Lead-in and lead-out arcs: radius (mm) and GOTOs per arc (after its start point).
const ARC_R: f64 = 8.0;
const ARC_GOTOS: usize = 12;
/// Cut GOTOs per pass: x = 2, 4, …, 20 on the floor z = 0.
const CUT_GOTOS: usize = 10;
const ENGAGE_FEED: f64 = 500.0;
const CUT_FEED: f64 = 1500.0;

/// A point of the lead-in arc at `deg` (0 = its start, 8 mm above the floor at x = −8;
/// 90 = the floor at x = 0): centre (0, y, 8), the tool tip going down to the floor
/// tangentially.
fn lead_in(y: f64, deg: f64) -> [f64; 3] {
    let a = deg.to_radians();
    [-ARC_R * a.cos(), y, ARC_R - ARC_R * a.sin()]
}

/// The lead-out arc, mirrored at x = 20 (0 = the floor at x = 20, 90 = 8 mm up at x = 28).
fn lead_out(y: f64, deg: f64) -> [f64; 3] {
    let a = deg.to_radians();
    [20.0 + ARC_R * a.sin(), y, ARC_R - ARC_R * a.cos()]
}

fn goto(p: [f64; 3]) -> String {
    // Rounded first, so that no −0.0000 is written (NX never writes one).
    let r = |v: f64| (v * 1e4).round() / 1e4 + 0.0;
    format!("GOTO/{:.4},{:.4},{:.4}\n", r(p[0]), r(p[1]), r(p[2]))
}

/// A synthetic NX-style export, as NX writes a variable-contour operation (compare the
/// first lines of `nx_5axis_varcontour_ijk_large.cls`): ball end D6, a rapid (186), per pass
/// an approach rapid (211), an engage arc (42) at 500 mm/min, a cut (31) at 1500 mm/min
/// and a retract arc (37) at 500 mm/min, and a departure rapid (211) at the end. Without
/// `colours` the PAINT records are left out.
fn export(colours: bool) -> String {
    let mut s = String::from(
        "TOOL PATH/VARIABLE_CONTOUR,TOOL,BALL-D6\nTLDATA/MILL,6.0000,3.0000,50.0000,0.0000,0.0000\n$$ centerline data\nPAINT/PATH\nPAINT/SPEED,10\nLOAD/TOOL,1,ADJUST,1\nSELECT/TOOL,1\n",
    );
    let paint = |s: &mut String, c: u32| {
        if colours {
            s.push_str(&format!("PAINT/COLOR,{c}\n"));
        }
    };
    paint(&mut s, 186);
    s.push_str("RAPID\nGOTO/-8.0000,0.0000,50.0000,0.0000000,0.0000000,1.0000000\n");
    for k in 0..PASSES {
        let y = k as f64 * STEP;
        paint(&mut s, 211);
        s.push_str("RAPID\n");
        s.push_str(&goto(lead_in(y, 0.0)));
        paint(&mut s, 42);
        s.push_str(&format!("FEDRAT/MMPM,{ENGAGE_FEED:.4}\n"));
        for j in 1..=ARC_GOTOS {
            s.push_str(&goto(lead_in(y, 90.0 * j as f64 / ARC_GOTOS as f64)));
        }
        paint(&mut s, 31);
        s.push_str(&format!("FEDRAT/MMPM,{CUT_FEED:.4}\n"));
        for j in 1..=CUT_GOTOS {
            s.push_str(&goto([2.0 * j as f64, y, 0.0]));
        }
        paint(&mut s, 37);
        s.push_str(&format!("FEDRAT/MMPM,{ENGAGE_FEED:.4}\n"));
        for j in 1..=ARC_GOTOS {
            s.push_str(&goto(lead_out(y, 90.0 * j as f64 / ARC_GOTOS as f64)));
        }
    }
    paint(&mut s, 211);
    s.push_str(
        "RAPID\nGOTO/28.0000,3.5000,50.0000\nPAINT/SPEED,10\nPAINT/TOOL,NOMORE\nEND-OF-PATH\n",
    );
    s
}

fn inspect(file: &std::path::Path, extra: &[&str]) -> serde_json::Value {
    output_json(
        &crest()
            .arg("inspect")
            .arg(file)
            .arg("--json")
            .args(extra)
            .output()
            .unwrap_or_else(|e| panic!("{e}")),
    )
}

fn counts(v: &serde_json::Value) -> BTreeMap<String, u64> {
    v.as_object()
        .unwrap_or_else(|| panic!("not an object: {v}"))
        .iter()
        .map(|(k, n)| (k.clone(), n.as_u64().unwrap_or(u64::MAX)))
        .collect()
}

fn expect(pairs: &[(&str, usize)]) -> BTreeMap<String, u64> {
    pairs
        .iter()
        .map(|(k, n)| ((*k).to_string(), *n as u64))
        .collect()
}

#[test]
fn inspect_counts_the_colour_groups_of_a_synthetic_export() {
    let dir = tempdir();
    let file = write(dir.path(), "nx.cls", export(true));
    let v = inspect(&file, &[]);
    let n = PASSES;
    // Built above: one rapid, an approach per pass, the last 211 a departure.
    let want = expect(&[
        ("rapid", 1),
        ("approach", n),
        ("engage", n * ARC_GOTOS),
        ("cut", n * CUT_GOTOS),
        ("retract", n * ARC_GOTOS),
        ("departure", 1),
    ]);
    assert_eq!(counts(&v["moves"]), want);
    assert_eq!(counts(&v["paths"][0]["moves"]), want);
    let groups = expect(&[
        ("rapid", 1),
        ("approach", n),
        ("engage", n),
        ("cut", n),
        ("retract", n),
        ("departure", 1),
    ]);
    assert_eq!(counts(&v["paths"][0]["move_groups"]), groups);
    // Cutting length: the cut moves only, 20 mm per pass (the first cut leaves the arc's
    // end at x = 0).
    let cut = v["paths"][0]["cutting_length_mm"].as_f64().unwrap_or(0.0);
    assert!((cut - 20.0 * n as f64).abs() < 1e-6, "{cut}");
    // `crest convert` to CLSF writes the colours back: the kinds read back the same.
    let back = dir.path().join("back.cls");
    crest()
        .arg("convert")
        .arg(&file)
        .arg("-o")
        .arg(&back)
        .assert()
        .success();
    let w = inspect(&back, &[]);
    assert_eq!(counts(&w["moves"]), want);
    assert_eq!(counts(&w["paths"][0]["move_groups"]), groups);
}

#[test]
fn without_colours_the_feed_changes_tell_engage_and_retract() {
    let dir = tempdir();
    let file = write(dir.path(), "plain.cls", export(false));
    let v = inspect(&file, &[]);
    let n = PASSES;
    // No colours: the approach and departure rapids are plain rapids; the slower feed
    // before and after the cut is the engage and the retract.
    let want = expect(&[
        ("rapid", n + 2),
        ("approach", 0),
        ("engage", n * ARC_GOTOS),
        ("cut", n * CUT_GOTOS),
        ("retract", n * ARC_GOTOS),
        ("departure", 0),
    ]);
    assert_eq!(counts(&v["moves"]), want);
}

#[test]
fn regions_of_the_synthetic_export() {
    let dir = tempdir();
    let file = write(dir.path(), "nx.cls", export(true));
    let v = inspect(&file, &["--regions"]);
    let regions = v["regions"].as_array().unwrap_or_else(|| panic!("{v}"));
    assert_eq!(regions.len(), 1, "{v}");
    let r = &regions[0];
    assert_eq!(r["passes"].as_u64(), Some(PASSES as u64));
    let num = |x: &serde_json::Value| x.as_f64().unwrap_or(f64::NAN);
    assert!((num(&r["stepover_mm"]) - STEP).abs() < 1e-9, "{r}");
    // The cut moves: x 0 … 20 on the floor, y 0 … 3.5; no engage or retract arc.
    let lo: Vec<f64> = (0..3).map(|k| num(&r["min_mm"][k])).collect();
    let hi: Vec<f64> = (0..3).map(|k| num(&r["max_mm"][k])).collect();
    assert_eq!(lo, vec![0.0, 0.0, 0.0]);
    assert_eq!(hi, vec![20.0, STEP * (PASSES - 1) as f64, 0.0]);
    assert_eq!(r["feeds_mm_min"], serde_json::json!([CUT_FEED]));
    assert!((num(&r["cut_length_mm"]) - 20.0 * PASSES as f64).abs() < 1e-6);
    assert_eq!(r["axis_deg"], serde_json::json!([0.0, 0.0]));
    // The centre: half-way along the middle pass (pass 4 of 0..7).
    assert_eq!(r["centre_mm"], serde_json::json!([10.0, 2.0, 0.0]));
}

/// `crest simulate FILE --patch-near P --patch-mm 0.5,0.5 …` as (exit code, JSON or
/// stderr).
fn simulate(file: &std::path::Path, near: &str, extra: &[&str]) -> (i32, String, String) {
    let dir = file.parent().unwrap_or_else(|| panic!("parent"));
    let out = crest()
        .arg("simulate")
        .arg(file)
        .args([
            "--teeth",
            "2",
            "--rpm",
            "8000",
            "--model",
            "dome",
            "--grid-um",
            "10",
            "--patch-mm",
            "0.5,0.5",
            "--json",
            "--patch-near",
            near,
            "-o",
        ])
        .arg(dir.join("patch.csv"))
        .args(extra)
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_patch_on_the_lead_in_arc_is_refused_with_its_distance() {
    let dir = tempdir();
    let file = write(dir.path(), "nx.cls", export(true));
    // Half-way down the lead-in arc of pass 4: 8 − 8 sin 45° = 2.34 mm above the floor and
    // 8 cos 45° = 5.66 mm before the cut starts at x = 0, the nearest point of the cut
    // surface: more than a tool radius beyond the cut, so the whole distance counts.
    let y = 4.0 * STEP;
    let p = lead_in(y, 45.0);
    let want = (p[0] * p[0] + p[2] * p[2]).sqrt();
    let (code, _, err) = simulate(&file, &format!("{},{},{}", p[0], p[1], p[2]), &[]);
    assert_eq!(code, 2, "{err}");
    assert!((distance_in(&err) - want).abs() < 0.01, "{want}: {err}");
    // 3 mm straight above the passes (half-way between passes 3 and 4): the height along
    // the floor's normal, 3 mm, more than 1.5 stepovers (0.75 mm).
    let (code, _, err) = simulate(&file, "10,1.75,3", &[]);
    assert_eq!(code, 2, "{err}");
    assert!((distance_in(&err) - 3.0).abs() < 0.01, "{err}");
    // 0.5 mm above: still refused; 0.3 mm above is within the tolerance and simulated.
    assert_eq!(simulate(&file, "10,1.75,0.8", &[]).0, 2);
    let (code, out, err) = simulate(&file, "10,1.75,0.3", &[]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    let d = v["patch_distance_mm"].as_f64().unwrap_or(f64::NAN);
    assert!((d - 0.3).abs() < 0.01, "{v}");
    assert!(
        (v["patch_tolerance_mm"].as_f64().unwrap_or(0.0) - 0.75).abs() < 0.01,
        "{v}"
    );
}

/// The distance a refusal names: "… is D mm from the surface …".
fn distance_in(err: &str) -> f64 {
    let flat = err.replace(['│', '\n'], " ");
    let flat = flat.split_whitespace().collect::<Vec<_>>().join(" ");
    let at = flat
        .find(" mm from the surface")
        .unwrap_or_else(|| panic!("no distance in: {err}"));
    let number = flat[..at].rsplit(' ').next().unwrap_or("");
    number.parse().unwrap_or_else(|e| panic!("{e}: {err}"))
}

#[test]
fn a_patch_on_the_passes_takes_the_cut_feed() {
    let dir = tempdir();
    let file = write(dir.path(), "nx.cls", export(true));
    // Half-way between passes 3 and 4, mid-way along them.
    let (code, out, err) = simulate(&file, "10,1.75,0", &[]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    assert_eq!(v["feed_mm_min"].as_f64(), Some(CUT_FEED), "{v}");
    assert_eq!(v["moves"], "cut");
    // Without --part the patch is centred at the nearest contact point: on pass 3 or 4
    // (y = 1.5 or 2, the point asked is half-way), on the floor, near x = 10.
    let c: Vec<f64> = v["centre_mm"]
        .as_array()
        .unwrap_or_else(|| panic!("no centre_mm: {v}"))
        .iter()
        .map(|x| x.as_f64().unwrap_or(f64::NAN))
        .collect();
    assert!((c[0] - 10.0).abs() < 0.1, "centre {c:?}");
    assert!(c[1] == 1.5 || c[1] == 2.0, "centre {c:?}");
    assert!(c[2].abs() < 1e-9, "centre {c:?}");
    let h = &v["heights_um"];
    let (lo, hi) = (h["min"].as_f64(), h["max"].as_f64());
    assert!(
        lo.is_some_and(f64::is_finite) && hi.is_some_and(f64::is_finite),
        "{v}"
    );
    // A ball of radius 3 at a stepover of 0.5 leaves a scallop of 3 − √(9 − 0.25²) ≈ 10.4 µm.
    let scallop = (3.0 - (9.0f64 - 0.0625).sqrt()) * 1e3;
    let sz = h["sz"].as_f64().unwrap_or(f64::NAN);
    assert!(
        sz > 0.0 && sz < scallop + 5.0,
        "Sz {sz} µm, scallop {scallop} µm"
    );
    assert!(v["nodes_cut"].as_u64().unwrap_or(0) > 0);
}

#[test]
fn moves_all_simulates_the_engage_arcs_as_before() {
    let dir = tempdir();
    let file = write(dir.path(), "nx.cls", export(true));
    // On the passes: every feed move counts, the first feed met is the engage's.
    let (code, out, err) = simulate(&file, "10,1.75,0", &["--moves", "all"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    assert_eq!(v["feed_mm_min"].as_f64(), Some(ENGAGE_FEED), "{v}");
    assert_eq!(v["moves"], "all");
    // On the lead-in arc: simulated (as crest did before), with a warning and exit 1.
    let p = lead_in(4.0 * STEP, 45.0);
    let (code, out, err) = simulate(
        &file,
        &format!("{},{},{}", p[0], p[1], p[2]),
        &["--moves", "all"],
    );
    assert_eq!(code, 1, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    let warned = v["warnings"].as_array().is_some_and(|w| {
        w.iter().any(|m| {
            m.as_str()
                .is_some_and(|m| m.contains("engage and retract moves only"))
        })
    });
    assert!(warned, "{v}");
    assert!(err.contains("engage and retract moves only"), "{err}");
}

/// The colour groups of an NX file counted from its text: GOTOs after each
/// `PAINT/COLOR,n` (until the next), and how many times each colour is written.
fn colour_groups(text: &str) -> (BTreeMap<u32, usize>, BTreeMap<u32, usize>) {
    let (mut gotos, mut groups) = (BTreeMap::new(), BTreeMap::new());
    let mut colour = 0u32;
    for line in text.lines() {
        if let Some(c) = line.strip_prefix("PAINT/COLOR,") {
            colour = c.trim().parse().unwrap_or(0);
            *groups.entry(colour).or_insert(0) += 1;
        } else if line.starts_with("GOTO/") {
            *gotos.entry(colour).or_insert(0) += 1;
        }
    }
    (gotos, groups)
}

#[test]
fn the_large_nx_export_counts_428_of_each_group() {
    let Some(dir) = crate::util::external_samples() else {
        return;
    };
    let file = dir.join("nx_5axis_varcontour_ijk_large.cls");
    let (gotos, groups) = colour_groups(&crate::util::read(&file));
    // What `grep` says of the file: 42, 31 and 37 are written 428 times each, 211 429 times
    // (before each engage, and once after the last retract), 186 once.
    assert_eq!(
        (
            groups[&42],
            groups[&31],
            groups[&37],
            groups[&211],
            groups[&186]
        ),
        (428, 428, 428, 429, 1)
    );
    let v = inspect(&file, &[]);
    let m = counts(&v["paths"][0]["moves"]);
    let g = counts(&v["paths"][0]["move_groups"]);
    let n = |k: &str| m[k] as usize;
    assert_eq!(n("engage"), gotos[&42]);
    assert_eq!(n("cut"), gotos[&31]);
    assert_eq!(n("retract"), gotos[&37]);
    assert_eq!(n("rapid"), gotos[&186]);
    assert_eq!(n("approach") + n("departure"), gotos[&211]);
    assert_eq!(
        (
            g["approach"],
            g["engage"],
            g["cut"],
            g["retract"],
            g["departure"],
            g["rapid"]
        ),
        (428, 428, 428, 428, 1, 1)
    );
    // The cuts run at 250 mm/min.
    let regions = inspect(&file, &["--regions"]);
    let r = regions["regions"]
        .as_array()
        .unwrap_or_else(|| panic!("{regions}"));
    assert!(!r.is_empty());
    for region in r {
        assert_eq!(
            region["feeds_mm_min"],
            serde_json::json!([250.0]),
            "{region}"
        );
    }
}

#[test]
fn contact_derives_the_cut_moves_only_unless_all() {
    let dir = tempdir();
    let file = write(dir.path(), "nx.cls", export(true));
    let run = |moves: &str| {
        output_json(
            &crest()
                .arg("contact")
                .arg(&file)
                .args(["--teeth", "2", "--json", "--moves", moves, "-o"])
                .arg(dir.path().join(format!("{moves}.csv")))
                .output()
                .unwrap_or_else(|e| panic!("{e}")),
        )
    };
    let cut = run("cut");
    // The cutting postures: 10 cut GOTOs per pass; with every feed move, the 2 × 12 arc
    // GOTOs of each pass too.
    assert_eq!(
        cut["postures"].as_u64(),
        Some((PASSES * CUT_GOTOS) as u64),
        "{cut}"
    );
    assert_eq!(cut["moves"], "cut");
    assert_eq!(
        cut["move_kinds"]["engage"].as_u64(),
        Some((PASSES * ARC_GOTOS) as u64)
    );
    let all = run("all");
    assert_eq!(
        all["postures"].as_u64(),
        Some((PASSES * (CUT_GOTOS + 2 * ARC_GOTOS)) as u64),
        "{all}"
    );
    // The kinds written back are the file's, whichever moves got contacts.
    assert_eq!(all["move_kinds"], cut["move_kinds"]);
}
