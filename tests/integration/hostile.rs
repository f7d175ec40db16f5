//! Hostile input and lost data (issue 18): every reproduction of the issue exits 2 with a
//! message naming the file (and the line and column for text), or 0 where the input is valid;
//! no panic, no abort, no hang, nothing destroyed.

use crate::util::{ROOT, crest, external_samples, repo, write};
use std::path::Path;
use std::time::Duration;

/// Run `crest args…` in `dir` with a 10 s limit; return (exit code, stderr).
fn run(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = crest()
        .current_dir(dir)
        .args(args)
        .timeout(Duration::from_secs(10))
        .output()
        .unwrap();
    let code = out.status.code().unwrap_or(-1);
    (code, String::from_utf8_lossy(&out.stderr).into_owned())
}

fn expect_2(dir: &Path, args: &[&str], needles: &[&str]) {
    let (code, err) = run(dir, args);
    assert_eq!(code, 2, "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: {n:?} not in {err}");
    }
}

#[test]
fn r18_1_panics_become_errors() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    write(p, "m.csv", "0,1,2\n1,1e308,0\n2,0,1\n");
    expect_2(
        p,
        &["metrics", "m.csv", "--dx-um", "10"],
        &["m.csv:2:", "1e308"],
    );
    // A real map and an absurd nesting index.
    let map = p.join("map.csv");
    std::fs::write(&map, "0,1,2,3\n1,2,3,4\n2,3,4,5\n").unwrap();
    expect_2(
        p,
        &[
            "metrics",
            "map.csv",
            "--dx-um",
            "10",
            "--lambda-c-um",
            "1e20",
        ],
        &["map.csv", "λc"],
    );
    expect_2(
        p,
        &[
            "metrics",
            "map.csv",
            "--dx-um",
            "10",
            "--lambda-c-um",
            "1e8",
        ],
        &["map.csv", "λc"],
    );
    let tool = std::fs::read_to_string(repo("samples/synth/ball-r5-presetter.toml"))
        .unwrap()
        .replace("radius_mm = 5.0", "radius_mm = 1e308");
    write(p, "big.toml", tool);
    expect_2(
        p,
        &["plot", "trochoid", "--tool", "big.toml", "-o", "t.svg"],
        &["big.toml:", "radius_mm"],
    );
    assert!(!p.join("t.svg").exists());
    let study = std::fs::read_to_string(repo("samples/studies/marin2023.toml"))
        .unwrap()
        .replace("fz_mm = 0.05", "fz_mm = 1e308")
        .replace("\"../tools/", &format!("\"{ROOT}/samples/tools/"));
    write(p, "s.toml", study);
    let table = repo("samples/measured/marin2023-table2.csv");
    expect_2(
        p,
        &[
            "report",
            "--measured",
            table.to_str().unwrap(),
            "--study",
            "s.toml",
            "-o",
            "rep",
        ],
        &["s.toml:", "fz_mm"],
    );
    assert!(!p.join("rep").exists());
}

#[test]
fn r18_2_hangs_are_refused_at_once() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let tool = repo("samples/synth/ball-r5-presetter.toml");
    let tool = tool.to_str().unwrap();
    for (opt, v) in [
        ("--fz-mm", "1e305"),
        ("--stepover-mm", "1e305"),
        ("--heights-mm", "1e308"),
    ] {
        expect_2(
            p,
            &["plot", "trochoid", "--tool", tool, opt, v, "-o", "t.svg"],
            &[opt],
        );
    }
    let table = std::fs::read_to_string(repo("samples/measured/marin2023-table2.csv")).unwrap();
    let mut lines: Vec<String> = table.lines().map(String::from).collect();
    let i = lines.iter().position(|l| l.starts_with("5,")).unwrap();
    let mut f: Vec<String> = lines[i].split(',').map(String::from).collect();
    f[3] = "1e300".into();
    lines[i] = f.join(",");
    write(p, "t.csv", lines.join("\n"));
    let study = repo("samples/studies/marin2023.toml");
    expect_2(
        p,
        &[
            "report",
            "--measured",
            "t.csv",
            "--study",
            study.to_str().unwrap(),
            "-o",
            "rep",
        ],
        &[&format!("t.csv:{}:", i + 1)],
    );
    let cls = repo("samples/synth/plane-trial3.cls");
    let torus = repo("samples/synth/torus-r5-rc1.5.toml");
    expect_2(
        p,
        &[
            "simulate",
            cls.to_str().unwrap(),
            "--tool",
            torus.to_str().unwrap(),
            "--model",
            "ice",
            "--dtheta-deg",
            "1e-9",
            "--grid-um",
            "10",
            "--window",
            "0,0,0.1,0.1",
            "-o",
            "x.gsf",
        ],
        &["--dtheta-deg"],
    );
    let machine = std::fs::read_to_string(repo("samples/machines/table1_ac.toml")).unwrap();
    write(
        p,
        "m1.toml",
        machine.replacen("cycle_time = 0.003", "cycle_time = 1e-9", 1),
    );
    expect_2(
        p,
        &["feed", cls.to_str().unwrap(), "--machine", "m1.toml"],
        &["m1.toml:", "cycle_time"],
    );
    let m2 = if machine.contains("min_block_cycles") {
        let start = machine.find("min_block_cycles").unwrap();
        let end = start + machine[start..].find('\n').unwrap();
        format!(
            "{}min_block_cycles = 1e12{}",
            &machine[..start],
            &machine[end..]
        )
    } else {
        format!("min_block_cycles = 1e12\n{machine}")
    };
    write(p, "m2.toml", m2);
    expect_2(
        p,
        &["feed", cls.to_str().unwrap(), "--machine", "m2.toml"],
        &["m2.toml:", "min_block_cycles"],
    );
    let design = std::fs::read_to_string(repo("samples/studies/lavernhe-doe16.toml"))
        .unwrap()
        .replace("\"../", &format!("\"{ROOT}/samples/"));
    write(p, "d.toml", format!("dtheta_deg = 1e-9\n{design}"));
    expect_2(
        p,
        &["study", "d.toml", "-o", "out"],
        &["d.toml:1:", "dtheta_deg"],
    );
}

#[test]
fn r18_3_allocation_aborts_become_errors() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let design = std::fs::read_to_string(repo("samples/studies/lavernhe-doe16.toml"))
        .unwrap()
        .replace("\"../", &format!("\"{ROOT}/samples/"));
    write(
        p,
        "rpm.toml",
        design.replace("rpm = 15000.0", "rpm = 1e300"),
    );
    expect_2(
        p,
        &["study", "rpm.toml", "-o", "out"],
        &["rpm.toml:", "rpm"],
    );
    for feed in ["1e12", "1e-9"] {
        let text = regex_replace_feed(&design, feed);
        write(p, "feed.toml", text);
        expect_2(
            p,
            &["study", "feed.toml", "-o", "out"],
            &["feed.toml:", "feed_mm_min"],
        );
    }
    let tool = repo("samples/synth/ball-r5.toml");
    let tool = tool.to_str().unwrap();
    let synth = [
        "synth",
        "plane",
        "--tool",
        tool,
        "--stepover-mm",
        "0.5",
        "--feed-mm-min",
        "1000",
        "--rpm",
        "10000",
        "-o",
        "s.cls",
    ];
    let mut a = synth.to_vec();
    a.extend(["--point-step-mm", "1e-9"]);
    expect_2(p, &a, &["points"]);
    let mut a = synth.to_vec();
    a.extend(["--size-mm", "1e9,1e9"]);
    expect_2(p, &a, &["10 m"]);
    // One coordinate of 1e308 in a path.
    let cls = std::fs::read_to_string(repo("samples/synth/plane-trial3.cls")).unwrap();
    let line = cls.lines().position(|l| l.starts_with("GOTO/")).unwrap() + 1;
    let bad: Vec<String> = cls
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i + 1 == line {
                "GOTO/1e308,0,0".to_string()
            } else {
                l.to_string()
            }
        })
        .collect();
    write(p, "big.cls", bad.join("\n"));
    let torus = repo("samples/synth/torus-r5-rc1.5.toml");
    expect_2(
        p,
        &[
            "simulate",
            "big.cls",
            "--tool",
            torus.to_str().unwrap(),
            "--model",
            "dome",
            "--grid-um",
            "10",
            "--window",
            "0,0,0.1,0.1",
            "-o",
            "x.gsf",
        ],
        &[&format!("big.cls:{line}:")],
    );
    let study = std::fs::read_to_string(repo("samples/studies/marin2023.toml"))
        .unwrap()
        .replace("fz_mm = 0.05", "fz_mm = 1e-12")
        .replace("\"../tools/", &format!("\"{ROOT}/samples/tools/"));
    write(p, "s.toml", study);
    let table = repo("samples/measured/marin2023-table2.csv");
    expect_2(
        p,
        &[
            "report",
            "--measured",
            table.to_str().unwrap(),
            "--study",
            "s.toml",
            "-o",
            "rep",
        ],
        &["s.toml:", "fz_mm"],
    );
}

fn regex_replace_feed(design: &str, v: &str) -> String {
    design
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("feed_mm_min") {
                format!("feed_mm_min = [{v}]")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn r18_4_unbounded_outputs_are_refused_before_writing() {
    let Some(ext) = external_samples() else {
        return;
    };
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let src = std::fs::read_to_string(ext.join("nx_fixed_contour_nurbs.cls")).unwrap();
    let typo: Vec<String> = src
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i + 1 == 46 {
                l.replace("248.2061", "24852061")
            } else {
                l.to_string()
            }
        })
        .collect();
    write(p, "typo.cls", typo.join("\n"));
    expect_2(
        p,
        &[
            "resample", "typo.cls", "--mode", "fz", "--fz-mm", "0.05", "--teeth", "4", "-o",
            "r.csv",
        ],
        &["typo.cls:46:"],
    );
    assert!(!p.join("r.csv").exists());
    let small = ext.join("nx_5axis_varcontour_ijk_small.cls");
    expect_2(
        p,
        &[
            "resample",
            small.to_str().unwrap(),
            "--mode",
            "dtheta",
            "--fz-mm",
            "0.05",
            "--teeth",
            "2",
            "-o",
            "rs.csv",
        ],
        &["GB", "--max-output-gb", "--force"],
    );
    assert!(!p.join("rs.csv").exists());
    // A parse error far into the file is found before anything is written.
    let mut lines: Vec<String> = src.lines().map(String::from).collect();
    lines[294] = "GOTO/1,2,zz".into();
    write(p, "bad.cls", lines.join("\n"));
    expect_2(
        p,
        &[
            "resample", "bad.cls", "--mode", "fz", "--fz-mm", "0.05", "--teeth", "4", "-o", "r.csv",
        ],
        &["bad.cls:295:"],
    );
    assert!(!p.join("r.csv").exists());
    // A full device: the write fails, the error names it, and the command stops.
    if Path::new("/dev/full").exists() {
        let plane = repo("samples/synth/plane-trial3.cls");
        let (code, err) = run(
            p,
            &[
                "resample",
                plane.to_str().unwrap(),
                "--mode",
                "fz",
                "--fz-mm",
                "0.05",
                "--teeth",
                "4",
                "-o",
                "/dev/full",
            ],
        );
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("/dev/full"), "{err}");
    }
}

#[cfg(unix)]
#[test]
fn r18_5_outputs_do_not_destroy_what_is_there() {
    use std::os::unix::fs::FileTypeExt;
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let plane = repo("samples/synth/plane-trial3.cls");
    std::fs::copy(&plane, p.join("x.cls")).unwrap();
    let before = std::fs::read(p.join("x.cls")).unwrap();
    expect_2(
        p,
        &[
            "resample", "x.cls", "--mode", "fz", "--fz-mm", "0.05", "--teeth", "4", "-o", "x.cls",
        ],
        &["x.cls", "inputs"],
    );
    expect_2(p, &["convert", "x.cls", "-o", "x.cls"], &["inputs"]);
    // Through a link to the input.
    std::os::unix::fs::symlink("x.cls", p.join("link.cls")).unwrap();
    expect_2(p, &["convert", "x.cls", "-o", "link.cls"], &["inputs"]);
    assert_eq!(std::fs::read(p.join("x.cls")).unwrap(), before);
    // A link to another file is written through, and stays a link.
    std::fs::write(p.join("target.csv"), "old").unwrap();
    std::os::unix::fs::symlink("target.csv", p.join("out.csv")).unwrap();
    let (code, err) = run(p, &["convert", "x.cls", "-o", "out.csv", "--all-moves"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        std::fs::symlink_metadata(p.join("out.csv"))
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(
        std::fs::read_to_string(p.join("target.csv"))
            .unwrap()
            .starts_with("x,y,z")
    );
    // /dev/null stays a character device.
    let (code, err) = run(p, &["convert", "x.cls", "-o", "/dev/null"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device()
    );
    // A device node made here (root only): written, not replaced.
    let node = p.join("null-here");
    let made = std::process::Command::new("mknod")
        .arg(&node)
        .args(["c", "1", "3"])
        .status()
        .is_ok_and(|s| s.success());
    if made {
        let (code, err) = run(p, &["convert", "x.cls", "-o", node.to_str().unwrap()]);
        assert_eq!(code, 0, "{err}");
        assert!(
            std::fs::metadata(&node)
                .unwrap()
                .file_type()
                .is_char_device()
        );
    }
    // A FIFO is written directly (a reader drains it).
    let fifo = p.join("pipe");
    if std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(&fifo).unwrap())
        };
        let (code, err) = run(
            p,
            &[
                "convert",
                "x.cls",
                "-o",
                fifo.to_str().unwrap(),
                "--all-moves",
            ],
        );
        assert_eq!(code, 0, "{err}");
        let got = reader.join().unwrap();
        assert!(got.starts_with(b"x,y,z"));
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    }
    // A simulate whose output is its own input, and a synth whose tool is its output.
    let tool = repo("samples/synth/ball-r5.toml");
    std::fs::copy(&tool, p.join("t.csv")).unwrap();
    expect_2(
        p,
        &[
            "synth",
            "plane",
            "--tool",
            "t.csv",
            "--stepover-mm",
            "0.5",
            "--feed-mm-min",
            "1000",
            "--rpm",
            "10000",
            "-o",
            "t.csv",
        ],
        &["inputs"],
    );
    assert_eq!(
        std::fs::read(p.join("t.csv")).unwrap(),
        std::fs::read(&tool).unwrap()
    );
}

/// SIGINT (Ctrl-C), SIGTERM (kill) and SIGHUP (a closed terminal, a dropped ssh; issue 37)
/// each remove the temporary output and exit with 128 + the signal, as a shell reports it.
#[cfg(unix)]
#[test]
fn r18_6_an_interrupted_run_leaves_no_temporary_file() {
    for (signal, code) in [("-INT", 130), ("-TERM", 143), ("-HUP", 129)] {
        interrupted_run_leaves_no_temporary_file(signal, code);
    }
}

#[cfg(unix)]
fn interrupted_run_leaves_no_temporary_file(signal: &str, code: i32) {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let plane = repo("samples/synth/plane-trial3.cls");
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("crest"))
        .current_dir(p)
        .args([
            "resample",
            plane.to_str().unwrap(),
            "--mode",
            "dtheta",
            "--dtheta-deg",
            "0.001",
            "--fz-mm",
            "0.05",
            "--teeth",
            "4",
            "--force",
            "-o",
            "big.csv",
        ])
        .spawn()
        .unwrap();
    // Wait until the temporary output exists, then interrupt.
    let tmp = || {
        std::fs::read_dir(p)
            .unwrap()
            .flatten()
            .any(|e| e.file_name().to_string_lossy().starts_with(".crest-"))
    };
    let t0 = std::time::Instant::now();
    while !tmp() && t0.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(tmp(), "no temporary output appeared");
    let _ = std::process::Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(code), "{signal}");
    assert!(!tmp(), "{signal}: a temporary file was left behind");
    assert!(!p.join("big.csv").exists());
}

#[test]
fn r18_7_byte_order_marks_are_read() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let rows: String = (0..129)
        .map(|i| format!("{i} 0 1 0 0 1 {i} 0 0 0 0 1\n"))
        .collect();
    write(p, "bom.txt", format!("\u{feff}{rows}"));
    let a = crest()
        .current_dir(p)
        .args(["inspect", "bom.txt", "--json"])
        .assert()
        .success();
    let j = crate::util::json(&a.get_output().stdout);
    assert_eq!(j["paths"][0]["postures"], 129, "{j}");
    let cls = std::fs::read_to_string(repo("samples/synth/plane-trial3.cls")).unwrap();
    write(p, "bom.cls", format!("\u{feff}{cls}"));
    crest()
        .current_dir(p)
        .args(["inspect", "bom.cls"])
        .assert()
        .success();
}

#[test]
fn r18_8_bad_input_is_not_accepted() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let tool = repo("samples/synth/ball-r5.toml");
    let tool = tool.to_str().unwrap();
    expect_2(
        p,
        &[
            "synth",
            "plane",
            "--tool",
            tool,
            "--stepover-mm",
            "0.5",
            "--feed-mm-min",
            "1000",
            "--rpm",
            "10000",
            "--pass-angle-deg",
            "NaN",
            "-o",
            "s.cls",
        ],
        &["pass angle"],
    );
    assert!(!p.join("s.cls").exists());
    let machine = std::fs::read_to_string(repo("samples/machines/table1_ac.toml")).unwrap();
    let i = machine.find("direction = [").unwrap();
    let j = i + machine[i..].find(']').unwrap();
    write(
        p,
        "m.toml",
        format!("{}direction = [1, 0, 0, 7{}", &machine[..i], &machine[j..]),
    );
    let cls = repo("samples/synth/plane-trial3.cls");
    expect_2(
        p,
        &["feed", cls.to_str().unwrap(), "--machine", "m.toml"],
        &["m.toml", "3 numbers"],
    );
    let t = std::fs::read_to_string(repo("samples/tools/ball-r5-z4.toml"))
        .unwrap()
        .replace(
            "[-10.0, -15.0, -24.0, -25.0]",
            "[-10.0, -15.0, -24.0, -5000.0]",
        );
    write(p, "neg.toml", t);
    expect_2(
        p,
        &[
            "tool",
            "--tool",
            "neg.toml",
            "--lead-deg",
            "15",
            "--ap-mm",
            "0.4",
            "--fz-mm",
            "0.05",
        ],
        &["neg.toml:", "negative"],
    );
    expect_2(
        p,
        &[
            "plot",
            "feed",
            cls.to_str().unwrap(),
            "--crest",
            "--tool",
            tool,
            "--rpm",
            "0",
            "-o",
            "f.svg",
        ],
        &["--rpm"],
    );
    write(p, "inf.csv", "0,1\n1,inf\n");
    expect_2(p, &["metrics", "inf.csv", "--dx-um", "10"], &["inf.csv:2:"]);
    write(p, "big.csv", "0,1\n1,1e400\n");
    expect_2(p, &["metrics", "big.csv", "--dx-um", "10"], &["big.csv:2:"]);
}

#[test]
fn r18_9_messages_name_the_place() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let cls = repo("samples/synth/plane-trial3.cls");
    let cls = cls.to_str().unwrap();
    let torus = repo("samples/synth/torus-r5-rc1.5.toml");
    let torus = torus.to_str().unwrap();
    let sim = |extra: &[&str]| {
        let mut a = vec![
            "simulate",
            cls,
            "--tool",
            torus,
            "--model",
            "dome",
            "--grid-um",
            "10",
            "--window",
            "0,0,0.1,0.1",
            "-o",
            "x.gsf",
        ];
        a.extend_from_slice(extra);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    write(p, "proc.toml", "# rpm is the spindle speed\nrpm = 0.0\n");
    let a = sim(&["--process", "proc.toml"]);
    expect_2(
        p,
        &a.iter().map(String::as_str).collect::<Vec<_>>(),
        &["proc.toml:2:"],
    );
    write(p, "cut.toml", "rpm =");
    let a = sim(&["--process", "cut.toml"]);
    let (code, err) = run(p, &a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 2);
    assert!(
        err.contains("cut.toml:1:") && err.len() > "cut.toml:1:1: ".len() + 10,
        "{err}"
    );
    std::fs::write(p.join("latin1.toml"), b"rpm = 1000 # \xe9\n").unwrap();
    let a = sim(&["--process", "latin1.toml"]);
    expect_2(
        p,
        &a.iter().map(String::as_str).collect::<Vec<_>>(),
        &["latin1.toml:1:"],
    );
    let a = sim(&["--feed-mm-min", "0"]);
    let (code, err) = run(p, &a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 2);
    assert!(!err.contains("line 0"), "{err}");
    // FEDRAT/MMPM,0 names its line.
    let text = std::fs::read_to_string(cls).unwrap();
    let zero: String = text
        .lines()
        .map(|l| {
            if l.starts_with("FEDRAT") {
                "FEDRAT/MMPM,0".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    write(p, "z.cls", zero);
    let (code, err) = run(
        p,
        &[
            "simulate",
            "z.cls",
            "--tool",
            torus,
            "--model",
            "dome",
            "--grid-um",
            "10",
            "--window",
            "0,0,0.1,0.1",
            "-o",
            "x.gsf",
        ],
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("z.cls:") && err.contains("FEDRAT 0"), "{err}");
    // A 4 MB bad line is not echoed whole.
    let long = format!(
        "TOOL PATH/A,TOOL,T\nGOTO/1,2,{}zz\nEND-OF-PATH\n",
        "9".repeat(4_000_000)
    );
    write(p, "long.cls", long);
    let (code, err) = run(p, &["inspect", "long.cls"]);
    assert_eq!(code, 2);
    assert!(err.len() < 10_000, "{} bytes of message", err.len());
}
