//! 5-axis G-code end to end: CLSF → G-code through the inverse kinematics of the Table I AC
//! machine and of the nutating-head machine (`crest convert … --machine`), read back through
//! the forward kinematics: the same postures; `crest simulate` of the CLSF and of its G-code;
//! a hand-written program read by `inspect`; errors that name line and column.

use crate::util::{crest, repo, tempdir};
use crest::io::toolpath::{ReadOptions, read_program_with};
use crest::kinematics::Machine;
use crest::toolpath::{LowerOptions, MotionKind, Program};
use std::path::Path;

fn machine(rel: &str) -> Machine {
    let text = std::fs::read_to_string(repo(rel)).unwrap_or_else(|e| panic!("{e}"));
    Machine::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}"))
}

fn read_clsf(p: &Path) -> Program {
    read_program_with(p, LowerOptions::default()).unwrap_or_else(|e| panic!("{e:?}"))
}

fn read_gcode(p: &Path, m: &Machine) -> Program {
    let opts = ReadOptions {
        machine: Some(m.clone()),
        ..Default::default()
    };
    read_program_with(p, opts).unwrap_or_else(|e| panic!("{e:?}"))
}

/// Largest position (mm) and axis (rad) differences between the postures of two programs,
/// after checking they have the same paths, postures, motions, spindle and feeds.
fn compare(a: &Program, b: &Program) -> (f64, f64) {
    assert_eq!(a.paths.len(), b.paths.len());
    let (mut dp, mut da) = (0.0f64, 0.0f64);
    for (pa, pb) in a.paths.iter().zip(&b.paths) {
        assert_eq!(pa.postures.len(), pb.postures.len());
        assert_eq!(pa.stats.gotos, pb.stats.gotos);
        for (qa, qb) in pa.postures.iter().zip(&pb.postures) {
            // FROM and GOHOME are rapid moves in G-code, approach and departure rapids;
            // G-code has no colours: engage, cut and retract are feed moves alike.
            let class = |m: MotionKind| match m {
                MotionKind::From | MotionKind::GoHome => MotionKind::Rapid,
                m if m.is_rapid() => MotionKind::Rapid,
                m if m.is_feed() => MotionKind::Cut,
                m => m,
            };
            assert_eq!(class(qa.motion), class(qb.motion), "line {}", qa.line);
            assert_eq!(qa.spindle_rpm, qb.spindle_rpm, "line {}", qa.line);
            if qa.motion.is_feed() {
                let (fa, fb) = (qa.feed_mm_min.unwrap_or(0.0), qb.feed_mm_min.unwrap_or(0.0));
                assert!(
                    (fa - fb).abs() <= 1e-4,
                    "line {}: feed {fa} vs {fb}",
                    qa.line
                );
            }
            assert_eq!(qa.contact.is_some(), qb.contact.is_some());
            dp = dp.max((qa.position - qb.position).norm());
            // atan2(|a × b|, a · b): exact for nearly parallel axes (acos is not).
            let (u, v) = (qa.axis.normalize(), qb.axis.normalize());
            da = da.max(u.cross(&v).norm().atan2(u.dot(&v)));
        }
    }
    (dp, da)
}

fn round_trip(cls: &str, machine_file: &str, rtcp: &str) -> (f64, f64) {
    let dir = tempdir();
    let nc = dir.path().join("out.nc");
    crest()
        .arg("convert")
        .arg(repo(cls))
        .arg("-o")
        .arg(&nc)
        .args(["--machine"])
        .arg(repo(machine_file))
        .args(["--rtcp", rtcp])
        .assert()
        .success();
    let a = read_clsf(&repo(cls));
    let b = read_gcode(&nc, &machine(machine_file));
    assert!(b.warnings.is_empty(), "{:?}", b.warnings);
    compare(&a, &b)
}

#[test]
fn clsf_to_gcode_and_back_on_the_table_i_ac_machine() {
    for cls in [
        "samples/synth/hyperbolic-paraboloid.cls",
        "samples/synth/plane-trial3.cls",
    ] {
        for rtcp in ["off", "on"] {
            let (dp, da) = round_trip(cls, "samples/machines/table1_ac.toml", rtcp);
            println!("{cls} AC rtcp {rtcp}: position {dp:.3e} mm, axis {da:.3e} rad");
            assert!(
                dp < 1e-6 && da < 1e-6,
                "{cls} rtcp {rtcp}: {dp} mm, {da} rad"
            );
        }
    }
}

#[test]
fn clsf_to_gcode_and_back_on_the_nutating_machine() {
    for cls in [
        "samples/synth/hyperbolic-paraboloid.cls",
        "samples/synth/plane-trial3.cls",
    ] {
        for rtcp in ["off", "on"] {
            let (dp, da) = round_trip(cls, "samples/machines/table1_nutating45.toml", rtcp);
            println!("{cls} nutating rtcp {rtcp}: position {dp:.3e} mm, axis {da:.3e} rad");
            assert!(
                dp < 1e-6 && da < 1e-6,
                "{cls} rtcp {rtcp}: {dp} mm, {da} rad"
            );
        }
    }
}

fn heights(csv: &Path) -> Vec<f64> {
    std::fs::read_to_string(csv)
        .unwrap_or_else(|e| panic!("{e}"))
        .split([',', '\n'])
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap_or(f64::NAN))
        .collect()
}

#[test]
fn simulate_from_the_clsf_and_from_its_gcode() {
    let dir = tempdir();
    let cls = repo("samples/synth/plane-trial3.cls");
    let m = repo("samples/machines/table1_ac.toml");
    let tool = repo("samples/synth/torus-r5-rc1.5.toml");
    let sim = |input: &Path, out: &Path, machine: bool| {
        let mut c = crest();
        c.arg("simulate").arg(input).arg("--tool").arg(&tool);
        if machine {
            c.arg("--machine").arg(&m);
        }
        c.args([
            "--model",
            "dome",
            "--grid-um",
            "20",
            "--window",
            "-1,-1,1,1",
        ])
        .arg("-o")
        .arg(out)
        .arg("--json");
        let out = c.assert().success().get_output().stdout.clone();
        let v: serde_json::Value = serde_json::from_slice(&out).unwrap_or_else(|e| panic!("{e}"));
        v
    };
    let reference = sim(&cls, &dir.path().join("clsf.csv"), false);
    let want = heights(&dir.path().join("clsf.csv"));
    for rtcp in ["off", "on"] {
        let nc = dir.path().join(format!("plane-{rtcp}.nc"));
        crest()
            .arg("convert")
            .arg(&cls)
            .arg("-o")
            .arg(&nc)
            .arg("--machine")
            .arg(&m)
            .args(["--rtcp", rtcp])
            .assert()
            .success();
        let csv = dir.path().join(format!("gcode-{rtcp}.csv"));
        let v = sim(&nc, &csv, true);
        assert_eq!(v["feed"]["source"], "programmed");
        assert_eq!(v["nodes_cut"], reference["nodes_cut"]);
        let got = heights(&csv);
        assert_eq!(got.len(), want.len());
        let worst = got
            .iter()
            .zip(&want)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!(
            "rtcp {rtcp}: {} heights, largest difference {worst:.3e} µm",
            got.len()
        );
        // The same surface to far below a nanometre: the G-code carries the joints with
        // nine decimals (mm, degrees).
        assert!(worst < 1e-6, "rtcp {rtcp}: {worst} µm");
    }
}

/// A hand-written program in the style of a Fanuc 5-axis post: line numbers, both comment
/// styles, a tool change, TCP on, an arc, inverse time.
const PROGRAM: &str = "%
O1000 (FINISH BLADE)
N10 G90 G17 G21 G40 G80 G94 ; metric, absolute
N20 T3 M6
N30 G54 G43.4 H3
N40 S12000 M3
N50 G0 X10. Y0. Z20. A0. C0.
N60 G1 Z0. F1500.
N70 G2 X0. Y-10. I-10. J0.
N80 G1 X0 Y-10 Z0 A15. C45.
N90 G93 G1 X5 Y-10 Z0 F300.
N100 G94 G49
N110 M5
N120 M30
%
";

#[test]
fn inspect_reads_a_hand_written_program() {
    let dir = tempdir();
    let nc = dir.path().join("blade.nc");
    std::fs::write(&nc, PROGRAM).unwrap_or_else(|e| panic!("{e}"));
    let out = crest()
        .arg("inspect")
        .arg(&nc)
        .arg("--machine")
        .arg(repo("samples/machines/table1_ac.toml"))
        .arg("--json")
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(v["format"], "gcode");
    assert_eq!(v["warnings"].as_array().map(Vec::len), Some(0), "{v}");
    let p = &v["paths"][0];
    assert_eq!(p["tool_name"], "T3");
    assert_eq!(
        (p["gotos"].as_u64(), p["circles"].as_u64()),
        (Some(5), Some(1))
    );
    assert_eq!(
        (p["rapids"].as_u64(), p["cutting_postures"].as_u64()),
        (Some(1), Some(4))
    );
    // 20 mm down, a quarter circle of radius 10, a turn of the axis, 5 mm in 1/300 min.
    let len = p["cutting_length_mm"].as_f64().unwrap_or(0.0);
    assert!(
        (len - (20.0 + 5.0 * std::f64::consts::PI + 5.0)).abs() < 1e-3,
        "{len}"
    );
    let feeds: Vec<f64> = p["feeds_mm_min"]
        .as_array()
        .map(|a| a.iter().filter_map(|x| x.as_f64()).collect())
        .unwrap_or_default();
    assert_eq!(feeds, [1500.0]);
    assert_eq!(p["spindles_rpm"][0].as_f64(), Some(12000.0));
}

#[test]
fn gcode_errors_name_line_and_column_and_need_the_machine() {
    let dir = tempdir();
    let nc = dir.path().join("bad.nc");
    std::fs::write(&nc, "G90 G21\nG1 X1 Y2 Z-q F100\n").unwrap_or_else(|e| panic!("{e}"));
    let m = repo("samples/machines/table1_ac.toml");
    let err = crest()
        .arg("inspect")
        .arg(&nc)
        .arg("--machine")
        .arg(&m)
        .assert()
        .code(2)
        .get_output()
        .stderr
        .clone();
    let err = String::from_utf8_lossy(&err);
    assert!(
        err.contains("bad.nc:2:11: expected a number after Z, found `-q`"),
        "{err}"
    );
    std::fs::write(&nc, "G90\nG0 X0 Y0 Z0 A0 C0\nG2 X1 Y1 F10\n").unwrap_or_else(|e| panic!("{e}"));
    let err = crest()
        .arg("inspect")
        .arg(&nc)
        .arg("--machine")
        .arg(&m)
        .assert()
        .code(2)
        .get_output()
        .stderr
        .clone();
    let err = String::from_utf8_lossy(&err);
    assert!(
        err.contains("bad.nc:3:1: expected the centre of the arc (I, J, K or R)"),
        "{err}"
    );
    let err = crest()
        .arg("inspect")
        .arg(&nc)
        .assert()
        .code(2)
        .get_output()
        .stderr
        .clone();
    assert!(
        String::from_utf8_lossy(&err).contains("give --machine MACHINE.toml"),
        "{}",
        String::from_utf8_lossy(&err)
    );
    // Writing G-code needs the machine too, and leaves no output behind without it.
    let out = dir.path().join("x.nc");
    crest()
        .arg("convert")
        .arg(repo("samples/synth/plane-trial3.cls"))
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2);
    assert!(!out.exists());
}

#[test]
fn gcode_feeds_every_command_like_its_clsf() {
    let dir = tempdir();
    let cls = repo("samples/synth/hyperbolic-paraboloid.cls");
    let m = repo("samples/machines/table1_nutating45.toml");
    let nc = dir.path().join("hp.nc");
    crest()
        .arg("convert")
        .arg(&cls)
        .arg("-o")
        .arg(&nc)
        .arg("--machine")
        .arg(&m)
        .assert()
        .success();
    // Back to CLSF: the same records, the same numbers (axes are unit vectors after the
    // kinematics: a written axis 1e-9 off unit length may change in its ninth decimal).
    let back = dir.path().join("back.cls");
    crest()
        .arg("convert")
        .arg(&nc)
        .arg("-o")
        .arg(&back)
        .arg("--machine")
        .arg(&m)
        .assert()
        .success();
    let gotos = |p: &Path| -> Vec<String> {
        std::fs::read_to_string(p)
            .unwrap_or_else(|e| panic!("{e}"))
            .lines()
            .filter(|l| l.starts_with("GOTO/") || l.starts_with("FEDRAT/") || l == &"RAPID")
            .map(str::to_string)
            .collect()
    };
    let (a, b) = (gotos(&cls), gotos(&back));
    assert_eq!(a.len(), b.len());
    let nums = |l: &str| -> Vec<f64> {
        l.split(['/', ','])
            .filter_map(|t| t.parse::<f64>().ok())
            .collect()
    };
    for (la, lb) in a.iter().zip(&b) {
        assert_eq!(la.split('/').next(), lb.split('/').next());
        let (na, nb) = (nums(la), nums(lb));
        assert_eq!(na.len(), nb.len(), "{la} / {lb}");
        for (x, y) in na.iter().zip(&nb) {
            assert!((x - y).abs() <= 1.5e-9, "{la} / {lb}");
        }
    }
    // Resample (streaming) and the planned feed: the same numbers.
    let json = |args: &[&str], file: &Path, machine: bool| -> serde_json::Value {
        let mut c = crest();
        c.args(&args[..1]).arg(file).args(&args[1..]);
        if machine {
            c.arg("--machine").arg(&m);
        }
        let out = c
            .arg("--json")
            .assert()
            .success()
            .get_output()
            .stdout
            .clone();
        serde_json::from_slice(&out).unwrap_or_else(|e| panic!("{e}"))
    };
    let csv = dir.path().join("r.csv");
    let csv = csv.to_str().unwrap_or("r.csv");
    let args = [
        "resample", "--mode", "fz", "--fz-mm", "0.1", "--teeth", "1", "-o", csv,
    ];
    let a = json(&args, &cls, false);
    let b = json(&args, &nc, true);
    assert_eq!(b["feed"], "programmed");
    assert_eq!(a["samples"], b["samples"]);
    let (ta, tb) = (
        a["paths"][0]["stats"]["duration_s"].as_f64().unwrap_or(0.0),
        b["paths"][0]["stats"]["duration_s"].as_f64().unwrap_or(1.0),
    );
    assert!((ta - tb).abs() < 1e-9 * ta, "{ta} vs {tb}");
    let a = json(&["feed"], &cls, true);
    let b = json(&["feed"], &nc, true);
    let (ta, tb) = (
        a["total_time_s"].as_f64().unwrap_or(0.0),
        b["total_time_s"].as_f64().unwrap_or(1.0),
    );
    assert!((ta - tb).abs() < 1e-6 * ta, "{ta} vs {tb}");
}
