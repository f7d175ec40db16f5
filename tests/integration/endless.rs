//! Endless and special inputs (issue 37): every reader stops at the budget of its format
//! (`io::input`), so `/dev/zero` or a pipe that never closes is refused at once, in little
//! memory; a FIFO, `/dev/stdin` or `-` is read once and reads as the regular file does.

use crate::util::{repo, write};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const CREST: &str = env!("CARGO_BIN_EXE_crest");

fn exists(tool: &str) -> bool {
    Command::new(tool)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// `crest args…` in `dir`, under a 1 GB address-space limit where `prlimit` exists and
/// killed after 60 s where `timeout` exists (an input opened twice waits for ever), with
/// `stdin` as standard input; the output and how long it took.
fn run_limited(dir: &Path, args: &[&str], stdin: Option<&[u8]>) -> (Output, Duration) {
    let mut line: Vec<&str> = Vec::new();
    if exists("timeout") {
        line.extend(["timeout", "60"]);
    }
    if exists("prlimit") {
        line.extend(["prlimit", "--as=1000000000", "--"]);
    }
    line.push(CREST);
    let mut cmd = Command::new(line[0]);
    cmd.args(&line[1..]);
    cmd.current_dir(dir)
        .args(args)
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let start = Instant::now();
    let mut child = cmd.spawn().unwrap();
    if let Some(bytes) = stdin {
        let mut pipe = child.stdin.take().unwrap();
        let bytes = bytes.to_vec();
        std::thread::spawn(move || {
            let _ = pipe.write_all(&bytes);
        });
    }
    let out = child.wait_with_output().unwrap();
    (out, start.elapsed())
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// A 20-GOTO CLSF path with its tool and spindle.
fn small_path() -> String {
    let mut s =
        "TOOL PATH/OP,TOOL,T\nTLDATA/MILL,10,5,50,0,0\nSPINDL/RPM,8000,CLW\nFEDRAT/MMPM,500\n"
            .to_string();
    for i in 0..20 {
        s.push_str(&format!("GOTO/{},0,0,0,0,1\n", f64::from(i) * 0.25));
    }
    s.push_str("END-OF-PATH\n");
    s
}

/// A FIFO at `dir/name` that a thread fills with `bytes` (then `forever` repeated until the
/// reader goes away), or `None` where FIFOs cannot be made.
fn fifo(dir: &Path, name: &str, bytes: Vec<u8>, forever: Option<Vec<u8>>) -> Option<PathBuf> {
    let p = dir.join(name);
    let made = Command::new("mkfifo").arg(&p).status();
    if !made.is_ok_and(|s| s.success()) {
        return None;
    }
    let q = p.clone();
    // Not joined: a reader that never opens the FIFO would leave it blocked in `open`.
    std::thread::spawn(move || {
        let Ok(mut f) = std::fs::OpenOptions::new().write(true).open(&q) else {
            return;
        };
        if f.write_all(&bytes).is_err() {
            return;
        }
        if let Some(chunk) = forever {
            while f.write_all(&chunk).is_ok() {}
        }
    });
    Some(p)
}

#[test]
fn dev_zero_is_refused_at_once_by_every_reader() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    #[cfg(unix)]
    for name in ["x.gsf", "x.sdf", "x.csv"] {
        std::os::unix::fs::symlink("/dev/zero", p.join(name)).unwrap();
    }
    let design = std::fs::read_to_string(repo("samples/studies/lavernhe-doe16.toml"))
        .unwrap()
        .lines()
        .map(|l| {
            if l.starts_with("tool =") {
                "tool = \"/dev/zero\"".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    write(p, "design.toml", design);
    let cases: &[(&[&str], &[&str])] = &[
        (&["inspect", "/dev/zero"], &["/dev/zero:", "1 MiB"]),
        (
            &["convert", "/dev/zero", "-o", "o.csv"],
            &["/dev/zero:", "1 MiB"],
        ),
        (
            &["contact", "/dev/zero", "--teeth", "2", "-o", "c.csv"],
            &["/dev/zero:", "1 MiB"],
        ),
        (
            &["resample", "/dev/zero", "--mode", "dtheta", "-o", "r.csv"],
            &["/dev/zero:", "1 MiB"],
        ),
        (&["metrics", "x.gsf"], &["x.gsf:", "not a Gwyddion"]),
        (&["metrics", "x.sdf"], &["x.sdf:", "not an SDF"]),
        (
            &["metrics", "x.csv", "--dx-um", "1"],
            &["x.csv:", "not text"],
        ),
        (&["metrics", "/dev/zero"], &["/dev/zero:", "not text"]),
        (
            &["view", "x.gsf", "-o", "v.html"],
            &["x.gsf:", "not a Gwyddion"],
        ),
        (
            &["study", "design.toml", "-o", "out"],
            &["/dev/zero:", "not text"],
        ),
    ];
    for (args, needles) in cases {
        let (out, took) = run_limited(p, args, None);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(took < Duration::from_secs(5), "{args:?}: {took:?}");
        for n in *needles {
            assert!(err.contains(n), "{args:?}: {n:?} not in {err}");
        }
    }
}

#[test]
fn an_endless_map_or_config_stops_at_its_budget() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    // A valid .gsf header, then zeros without end: the header says 100 × 100 float32.
    let head = b"Gwyddion Simple Field 1.0\nXRes = 100\nYRes = 100\n".to_vec();
    let mut start = head.clone();
    start.extend(std::iter::repeat_n(0u8, 4 - head.len() % 4));
    let budget = start.len() + 100 * 100 * 4;
    let Some(_) = fifo(p, "e.gsf", start, Some(vec![0u8; 1 << 16])) else {
        return;
    };
    let (out, took) = run_limited(p, &["metrics", "e.gsf"], None);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(took < Duration::from_secs(5), "{took:?}");
    assert!(
        err.contains("e.gsf:") && err.contains(&format!("{budget} bytes")),
        "{budget}: {err}"
    );
    // A tool file that goes on and on (valid TOML comments): its 8 MiB.
    let comment = b"# a comment line of a tool file\n".to_vec();
    let Some(_) = fifo(p, "tool.toml", comment.clone(), Some(comment)) else {
        return;
    };
    let (out, took) = run_limited(
        p,
        &[
            "tool",
            "--tool",
            "tool.toml",
            "--lead-deg",
            "15",
            "--ap-mm",
            "0.2",
            "--fz-mm",
            "0.05",
        ],
        None,
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(took < Duration::from_secs(5), "{took:?}");
    assert!(err.contains("tool.toml:") && err.contains("8 MiB"), "{err}");
}

#[test]
fn a_fifo_is_read_once_and_reads_as_the_file() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let cls = small_path();
    write(p, "a.cls", &cls);
    let (file, _) = run_limited(p, &["inspect", "a.cls"], None);
    assert!(file.status.success(), "{}", stderr(&file));
    let Some(_) = fifo(p, "f.cls", cls.into_bytes(), None) else {
        return;
    };
    let (piped, took) = run_limited(p, &["inspect", "f.cls"], None);
    assert!(piped.status.success(), "{}", stderr(&piped));
    assert!(took < Duration::from_secs(10), "{took:?}");
    assert_eq!(stdout(&piped).replace("f.cls", "a.cls"), stdout(&file));
    // A height map through a FIFO: the numbers of the file.
    let (sim, _) = run_limited(
        p,
        &[
            "simulate",
            "a.cls",
            "--teeth",
            "2",
            "--window",
            "0,-0.5,2,0.5",
            "--grid-um",
            "10",
            "-o",
            "m.gsf",
        ],
        None,
    );
    assert!(sim.status.success(), "{}", stderr(&sim));
    let (file, _) = run_limited(p, &["metrics", "m.gsf", "--json"], None);
    assert!(file.status.success(), "{}", stderr(&file));
    let map = std::fs::read(p.join("m.gsf")).unwrap();
    let Some(_) = fifo(p, "f.gsf", map, None) else {
        return;
    };
    let (piped, _) = run_limited(p, &["metrics", "f.gsf", "--json"], None);
    assert!(piped.status.success(), "{}", stderr(&piped));
    assert_eq!(stdout(&piped).replace("f.gsf", "m.gsf"), stdout(&file));
}

#[test]
fn standard_input_reads_as_the_file() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let cls = small_path();
    write(p, "a.cls", &cls);
    // Tool paths: told by content, read once (resample reads its input more than once).
    for args in [
        vec!["inspect", "{}"],
        vec!["inspect", "{}", "--json"],
        vec!["convert", "{}", "-o", "{}.cls"],
        vec!["resample", "{}", "--mode", "dtheta", "-o", "{}.csv"],
        vec![
            "simulate",
            "{}",
            "--teeth",
            "2",
            "--window",
            "0,-0.5,2,0.5",
            "--grid-um",
            "10",
            "-o",
            "{}.gsf",
        ],
    ] {
        let with = |name: &str| -> Vec<String> {
            args.iter()
                .map(|a| a.replace("{}", name))
                .collect::<Vec<_>>()
        };
        let file_args = with("a.cls");
        let file_args: Vec<&str> = file_args.iter().map(String::as_str).collect();
        let (file, _) = run_limited(p, &file_args, None);
        assert!(file.status.success(), "{file_args:?}: {}", stderr(&file));
        let stdin_args: Vec<String> = args
            .iter()
            .enumerate()
            .map(|(i, a)| {
                if i == 1 {
                    "-".into()
                } else {
                    a.replace("{}", "s")
                }
            })
            .collect();
        let stdin_args: Vec<&str> = stdin_args.iter().map(String::as_str).collect();
        let (piped, _) = run_limited(p, &stdin_args, Some(cls.as_bytes()));
        assert!(piped.status.success(), "{stdin_args:?}: {}", stderr(&piped));
        let name_free = |s: String| {
            s.replace("a.cls.", "s.")
                .replace("a.cls", "-")
                .replace("\"a\"", "\"-\"")
        };
        // simulate prints its time.
        if args[0] != "simulate" {
            assert_eq!(stdout(&piped), name_free(stdout(&file)), "{stdin_args:?}");
        }
        if let Some(out) = file_args.iter().find(|a| a.starts_with("a.cls.")) {
            let theirs = std::fs::read(p.join(out)).unwrap();
            let ours = std::fs::read(p.join(out.replace("a.cls.", "s."))).unwrap();
            assert!(theirs == ours, "{out}: the outputs differ");
        }
    }
    // A height map on standard input: its format from its content.
    let (file, _) = run_limited(p, &["metrics", "a.cls.gsf"], None);
    assert!(file.status.success(), "{}", stderr(&file));
    let map = std::fs::read(p.join("a.cls.gsf")).unwrap();
    let (piped, _) = run_limited(p, &["metrics", "-"], Some(&map));
    assert!(piped.status.success(), "{}", stderr(&piped));
    assert_eq!(stdout(&piped), stdout(&file).replace("a.cls.gsf", "-"));
}

/// A `.gsf` of `n × n` nodes at 2 µm: waves along x and y and a small pattern.
fn gsf(n: usize) -> Vec<u8> {
    let mut h = format!(
        "Gwyddion Simple Field 1.0\nXRes = {n}\nYRes = {n}\nXReal = {}\nYReal = {}\nZUnits = m\n",
        n as f64 * 2e-6,
        n as f64 * 2e-6
    )
    .into_bytes();
    h.extend(std::iter::repeat_n(0u8, 4 - h.len() % 4));
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (j as f64 * 2e-6, i as f64 * 2e-6);
            let z = 1e-6 * (x / 2e-4 * std::f64::consts::TAU).sin()
                + 3e-7 * (y / 7e-5 * std::f64::consts::TAU).cos()
                + 5e-8 * (((i * 104_729 + j * 7919) % 1000) as f64 / 1000.0 - 0.5);
            h.extend((z as f32).to_le_bytes());
        }
    }
    h
}

#[test]
fn metrics_beyond_the_memory_cap_are_refused_up_front_with_the_params_that_fit() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    write(p, "m.gsf", gsf(600));
    // The autocorrelation of 360 000 nodes needs about 38 MB; the rest fits in 30 MB.
    let (out, took) = run_limited(p, &["metrics", "m.gsf", "--max-memory-gb", "0.03"], None);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(took < Duration::from_secs(5), "{took:?}");
    assert!(
        err.contains("m.gsf:")
            && err.contains("600×600 nodes need about 0.0")
            && err.contains("GB of memory, more than --max-memory-gb 0.03"),
        "{err}"
    );
    let fit = err
        .split("--params ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .unwrap_or_else(|| panic!("no --params in {err}"))
        .to_string();
    assert!(!fit.contains("Sal") && !fit.contains("Str"), "{fit}");
    assert!(
        fit.contains("Std") && fit.contains("Sk") && fit.contains("Sa"),
        "{fit}"
    );
    // The parameters that fit run under the cap and give the numbers of the whole set.
    let (some, _) = run_limited(
        p,
        &[
            "metrics",
            "m.gsf",
            "--max-memory-gb",
            "0.03",
            "--params",
            &fit,
            "--json",
        ],
        None,
    );
    assert!(some.status.success(), "{}", stderr(&some));
    let (all, _) = run_limited(p, &["metrics", "m.gsf", "--json"], None);
    assert!(all.status.success(), "{}", stderr(&all));
    let some: serde_json::Value = serde_json::from_slice(&some.stdout).unwrap();
    let all: serde_json::Value = serde_json::from_slice(&all.stdout).unwrap();
    for sym in fit.split(',') {
        assert_eq!(some[sym], all[sym], "{sym}");
    }
    assert!(all["Sal"].is_number(), "{all}");
}
