//! APT cutter-location files of other CAM systems (`samples/apt/`, written for these tests in
//! each system's style): every GOTO and CIRCLE counted, the tool read from `CUTTER/`, the
//! 5-axis tool axes kept, no warning on a standard record; NX contact-contour data turned
//! into tool tips.

use crate::util::{crest, repo, tempdir};
use crest::io::toolpath::read_program;
use crest::math::{Point3, Vec3};
use crest::toolpath::{MotionKind, Program};
use std::path::PathBuf;

fn sample(name: &str) -> PathBuf {
    repo("samples/apt").join(name)
}

fn inspect(name: &str) -> serde_json::Value {
    let out = crest()
        .arg("inspect")
        .arg(sample(name))
        .arg("--json")
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    serde_json::from_slice(&out).unwrap_or_else(|e| panic!("{e}"))
}

fn program(name: &str) -> Program {
    read_program(&sample(name)).unwrap_or_else(|e| panic!("{e:?}"))
}

/// The GOTO and CIRCLE records of a file, counted on its text (continuations joined).
fn count(name: &str, word: &str) -> usize {
    std::fs::read_to_string(sample(name))
        .unwrap_or_else(|e| panic!("{e}"))
        .lines()
        .filter(|l| {
            let t = l.trim_start().to_ascii_uppercase();
            t.starts_with(word) && t[word.len()..].trim_start().starts_with('/')
        })
        .count()
}

fn sum(v: &serde_json::Value, key: &str) -> u64 {
    v["paths"]
        .as_array()
        .map(|a| a.iter().filter_map(|p| p[key].as_u64()).sum())
        .unwrap_or(0)
}

#[test]
fn every_dialect_reads_without_a_warning_and_counts_every_motion_record() {
    for name in [
        "catia-v5.aptsource",
        "ncl-inch.cl",
        "makino-ffcam.cls",
        "nx-contact-contour.cls",
    ] {
        let v = inspect(name);
        assert_eq!(v["format"], "clsf", "{name}");
        assert_eq!(v["warnings"], serde_json::json!([]), "{name}");
        assert_eq!(sum(&v, "raw_records"), 0, "{name}");
        assert_eq!(sum(&v, "gotos"), count(name, "GOTO") as u64, "{name}");
        assert_eq!(sum(&v, "circles"), count(name, "CIRCLE") as u64, "{name}");
        assert!(sum(&v, "gotos") > 0);
    }
}

#[test]
fn catia_v5_cutter_tool_and_five_axis_gotos() {
    let v = inspect("catia-v5.aptsource");
    let p = &v["paths"][0];
    assert_eq!(p["name"], "BLADE_FINISH");
    assert_eq!(p["tool_name"], "T1 End Mill D 10 R 5");
    assert_eq!(p["prints"], 2);
    let t = &p["tool"];
    assert_eq!(
        (
            t["diameter_mm"].as_f64(),
            t["corner_radius_mm"].as_f64(),
            t["length_mm"].as_f64()
        ),
        (Some(10.0), Some(5.0), Some(75.0))
    );
    assert_eq!(
        t["apt"],
        serde_json::json!([10.0, 5.0, 0.0, 5.0, 0.0, 0.0, 75.0])
    );
    assert_eq!(p["spindles_rpm"], serde_json::json!([12000.0]));
    assert_eq!(p["feeds_mm_min"], serde_json::json!([3000.0, 1500.0]));
    let prog = program("catia-v5.aptsource");
    let ps = &prog.paths[0].postures;
    assert_eq!(ps.len(), 12);
    // The axes as written, the continued records too.
    assert_eq!(ps[2].axis, Vec3::new(0.034899, 0.0, 0.999391));
    assert_eq!(ps[2].position, Point3::new(-4.0, -5.0, 0.05));
    assert_eq!(ps[11].axis, Vec3::new(0.34202, 0.0, 0.939693));
}

#[test]
fn ncl_inches_feed_per_revolution_and_tool_axes() {
    let prog = program("ncl-inch.cl");
    let t = &prog.paths[0];
    assert_eq!((t.name.as_str(), t.tool_name.as_str()), ("POCKET-3X", "T2"));
    let tool = t.tool.as_ref().unwrap_or_else(|| panic!("tool"));
    assert_eq!(
        (tool.diameter_mm, tool.corner_radius_mm, tool.apt),
        (12.7, 6.35, None)
    );
    let ps = &t.postures;
    assert_eq!(ps[0].motion, MotionKind::From);
    assert_eq!(ps[0].position, Point3::new(0.0, 0.0, 50.8));
    // 0.004 in/rev at 6000 rpm.
    assert!((ps[1].feed_mm_min.unwrap_or(0.0) - 609.6).abs() < 1e-9);
    let arc = ps[3].arc.as_ref().unwrap_or_else(|| panic!("arc"));
    assert_eq!(arc.radius_mm, 25.4);
    assert_eq!(ps[5].axis, Vec3::new(0.0, 0.6, 0.8));
    assert_eq!(ps[6].axis, Vec3::z());
}

#[test]
fn makino_two_tools_two_paths_and_eleven_value_circles() {
    let v = inspect("makino-ffcam.cls");
    let paths = v["paths"].as_array().cloned().unwrap_or_default();
    assert_eq!(paths.len(), 2);
    assert_eq!(paths[0]["tool_name"], "T5");
    assert_eq!(paths[0]["tool"]["diameter_mm"].as_f64(), Some(6.0));
    assert_eq!(paths[0]["circles"], 2);
    assert_eq!(paths[1]["tool_name"], "T6");
    assert_eq!(paths[1]["tool"]["corner_radius_mm"].as_f64(), Some(0.5));
    assert_eq!(paths[1]["feeds_mm_min"], serde_json::json!([1200.0]));
    let prog = program("makino-ffcam.cls");
    let ps = &prog.paths[0].postures;
    assert_eq!(ps[0].motion, MotionKind::From);
    // Two quarter circles of radius 20 and 5-axis moves after them.
    let arc = ps[4].arc.as_ref().unwrap_or_else(|| panic!("arc"));
    assert_eq!((arc.radius_mm, arc.axis), (20.0, Vec3::z()));
    assert_eq!(ps[6].axis, Vec3::new(0.2, 0.0, 0.979796));
    let last = prog.paths[1].postures.last().map(|p| p.axis);
    assert_eq!(last, Some(Vec3::new(0.0, -0.258819, 0.965926)));
}

#[test]
fn nx_contact_contour_points_become_tool_tips() {
    let prog = program("nx-contact-contour.cls");
    let ps = &prog.paths[0].postures;
    assert!(prog.warnings.is_empty(), "{:?}", prog.warnings);
    // The rapids are tool-end positions (contact status off).
    assert_eq!(ps[0].position, Point3::new(0.0, 0.0, 20.0));
    for p in ps.iter().filter(|p| p.motion == MotionKind::Cut) {
        // Ball R 5 touching the plane z = 0 at the contact point: tip = cc + 5 n − 5 a.
        let c = p.contact.as_ref().unwrap_or_else(|| panic!("contact"));
        assert!(!c.normal_derived);
        assert_eq!(c.normal, Vec3::z());
        let want = c.point + Vec3::z() * 5.0 - p.axis * 5.0;
        assert!(
            (p.position - want).norm() < 1e-12,
            "{} vs {want}",
            p.position
        );
        assert!(p.position.z >= -1e-12 && p.position.z < 0.2);
    }
    assert_eq!(ps.iter().filter(|p| p.contact.is_some()).count(), 6);
}

#[test]
fn contact_contour_without_normals_says_what_is_missing() {
    let dir = tempdir();
    let f = dir.path().join("cc.cls");
    std::fs::write(
        &f,
        "TOOL PATH/A,TOOL,B\nTLDATA/MILL,10,5,75,0,0\n$$ CONTACT CONTOUR DATA\nGOTO/1,2,3,0,0,1\nEND-OF-PATH\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let out = crest()
        .arg("inspect")
        .arg(&f)
        .arg("--json")
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap_or_else(|e| panic!("{e}"));
    let w = &v["warnings"][0];
    assert_eq!(
        (w["line"].as_u64(), w["column"].as_u64()),
        (Some(4), Some(1))
    );
    let msg = w["message"].as_str().unwrap_or("");
    assert!(msg.contains("without its surface normal"), "{msg}");
    assert!(msg.contains("CONTACT/x,y,z,nx,ny,nz"), "{msg}");
}
