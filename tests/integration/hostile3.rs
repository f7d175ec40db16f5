//! Hostile input, third round (issue 37): a command that fails changes nothing (every
//! output of a command checked before its work and landed together), a study design refused
//! before its first run when a run would pass the budget, and no control character from the
//! input on a terminal.

use crate::util::{ROOT, crest, tempdir, write};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Every file and folder under `dir` (relative paths) with the bytes of each file.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Option<Vec<u8>>> {
    let mut out = BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            let rel = p.strip_prefix(dir).unwrap().to_path_buf();
            if e.file_type().unwrap().is_dir() {
                out.insert(rel, None);
                todo.push(p);
            } else {
                out.insert(rel, Some(std::fs::read(&p).unwrap()));
            }
        }
    }
    out
}

/// Run `crest args…` in `dir` (30 s limit); return (exit code, stderr).
fn run(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = crest()
        .current_dir(dir)
        .args(args)
        .timeout(Duration::from_secs(30))
        .output()
        .unwrap();
    let code = out.status.code().unwrap_or(-1);
    (code, String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Run `args` in `dir`, which holds outputs of an earlier run and one blocked name: exit 2
/// with a message naming `blocked`, and every file and folder under `dir` as it was (no file
/// replaced, none added, no temporary file left).
fn changes_nothing(dir: &Path, args: &[&str], blocked: &str) {
    let before = snapshot(dir);
    let (code, err) = run(dir, args);
    assert_eq!(code, 2, "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    assert!(
        err.contains(blocked),
        "{args:?}: {blocked:?} not named in {err}"
    );
    let after = snapshot(dir);
    let changed: Vec<_> = after
        .iter()
        .filter(|(k, v)| before.get(*k) != Some(*v))
        .map(|(k, _)| k.display().to_string())
        .chain(
            before
                .keys()
                .filter(|k| !after.contains_key(*k))
                .map(|k| k.display().to_string()),
        )
        .collect();
    assert!(
        changed.is_empty(),
        "{args:?} failed but changed {changed:?}: {err}"
    );
}

fn tiny_design(feeds: &str) -> String {
    format!(
        "title = \"tiny\"\nsurface = \"plane\"\ntool = \"{}\"\nrpm = 15000.0\ngrid_um = 2.0\n\
         dtheta_deg = 1.0\nresponses = [\"Sz\", \"Sq\"]\n[factors]\ntilt_deg = [10.0]\n\
         stepover_mm = [0.05]\nfeed_mm_min = [{feeds}]\n",
        Path::new(ROOT)
            .join("samples/tools/torus-r5-rc1.5.toml")
            .display()
    )
}

/// `crest study -o DIR` re-run with another design into a DIR where `effects.svg` is a
/// folder: refused, and `runs.csv`, `effects.csv` of the first design untouched (the old
/// code replaced them before failing on the chart).
#[test]
fn r37_a_study_into_a_blocked_folder_changes_nothing() {
    let d = tempdir();
    let p = d.path();
    write(p, "a.toml", tiny_design("2000.0, 4000.0"));
    write(p, "b.toml", tiny_design("2000.0, 3000.0"));
    let (code, err) = run(p, &["study", "a.toml", "-o", "out"]);
    assert_eq!(code, 0, "{err}");
    assert!(p.join("out/runs.csv").is_file() && p.join("out/effects.svg").is_file());
    std::fs::remove_file(p.join("out/effects.svg")).unwrap();
    std::fs::create_dir(p.join("out/effects.svg")).unwrap();
    changes_nothing(p, &["study", "b.toml", "-o", "out"], "effects.svg");
    // The output folder is a file: refused as well, nothing made.
    write(p, "plain", "not a folder");
    changes_nothing(p, &["study", "b.toml", "-o", "plain/out"], "plain");
}

/// `crest simulate … -o map.gsf --view DIR` where the page's name is a folder: refused before
/// the simulation, and the map of an earlier run untouched (the old code wrote it).
#[test]
fn r37_simulate_with_a_blocked_view_changes_nothing() {
    let d = tempdir();
    let p = d.path();
    let cls = Path::new(ROOT).join("samples/synth/plane-trial3.cls");
    let tool = Path::new(ROOT).join("samples/synth/torus-r5-rc1.5.toml");
    let (cls, tool) = (cls.to_str().unwrap(), tool.to_str().unwrap());
    let args = |out: &'static str, view: &'static str| {
        vec![
            "simulate",
            cls,
            "--tool",
            tool,
            "--model",
            "dome",
            "--grid-um",
            "10",
            "--window",
            "0,0,0.27,0.2",
            "-o",
            out,
            "--view",
            view,
        ]
    };
    write(p, "map.gsf", "an earlier map");
    std::fs::create_dir(p.join("page.html")).unwrap();
    changes_nothing(p, &args("map.gsf", "page.html"), "page.html");
    // The map's folder does not exist: refused, naming it, and the page not written.
    write(p, "page2.html", "an earlier page");
    changes_nothing(p, &args("none/map.gsf", "page2.html"), "none");
    // Both outputs writable: both land.
    let (code, err) = run(p, &args("map.gsf", "page2.html"));
    assert_eq!(code, 0, "{err}");
    assert_ne!(std::fs::read(p.join("map.gsf")).unwrap(), b"an earlier map");
    assert_ne!(
        std::fs::read(p.join("page2.html")).unwrap(),
        b"an earlier page"
    );
}

/// `crest synth … -o PATH --part-stl STL` where the STL's name is a folder: the path of an
/// earlier run untouched (the old code wrote it, then failed on the STL).
#[test]
fn r37_synth_with_a_blocked_mesh_changes_nothing() {
    let d = tempdir();
    let p = d.path();
    let tool = Path::new(ROOT).join("samples/synth/ball-r5.toml");
    write(p, "p.cls", "an earlier path");
    std::fs::create_dir(p.join("part.stl")).unwrap();
    changes_nothing(
        p,
        &[
            "synth",
            "plane",
            "--tool",
            tool.to_str().unwrap(),
            "--stepover-mm",
            "0.4",
            "--size-mm",
            "4,4",
            "--feed-mm-min",
            "1000",
            "--rpm",
            "20000",
            "-o",
            "p.cls",
            "--part-stl",
            "part.stl",
        ],
        "part.stl",
    );
}

/// A design with a run past the budget of a simulation (the grid's nodes, the resampled
/// poses, the memory of a run) or an impossible scallop is refused before its first run,
/// naming the run or the key, the estimate and the limit (the old code built each run's
/// path first: 14 GB for a 1 m window). Nothing is written.
#[test]
fn r37_a_design_past_the_budget_is_refused_before_its_runs() {
    let d = tempdir();
    let p = d.path();
    let tool = Path::new(ROOT).join("samples/tools/torus-r5-rc1.5.toml");
    let design = |extra: &str, step: &str| {
        format!(
            "title = \"t\"\nsurface = \"plane\"\ntool = \"{}\"\nrpm = 15000.0\ngrid_um = 2.0\n\
             {extra}responses = [\"Sz\", \"Sq\"]\n[factors]\ntilt_deg = [10.0]\n{step}\n\
             feed_mm_min = [2000.0, 4000.0]\n",
            tool.display()
        )
    };
    for (name, text, needles) in [
        (
            "w1000.toml",
            design("window_mm = [1000, 1000]\n", "stepover_mm = [0.05]"),
            &["w1000.toml", "run 1", "2.500e11 nodes", "4e8", "window_mm"][..],
        ),
        (
            "w50.toml",
            design("window_mm = [50, 50]\n", "stepover_mm = [0.05]"),
            &["w50.toml", "run 2", "6.251e8 nodes", "4e8"][..],
        ),
        (
            "w10.toml",
            design("window_mm = [10, 10]\n", "stepover_mm = [0.05]"),
            &[
                "w10.toml",
                "run 1",
                "GB",
                "more than the 1 GB a run may take",
            ][..],
        ),
        (
            "scallop.toml",
            design("", "scallop_um = [0.0001]"),
            &["scallop.toml:9:", "scallop_um", "0.001 to 1e4"][..],
        ),
    ] {
        write(p, name, text);
        changes_nothing(p, &["study", name, "-o", "out"], needles[0]);
        let (code, err) = run(p, &["study", name, "-o", "out"]);
        assert_eq!(code, 2, "{name}: {err}");
        for n in needles {
            assert!(err.contains(n), "{name}: {n:?} not in {err}");
        }
    }
}

/// On a terminal (`script` gives one), the graphical report of a CLSF line holding
/// `ESC ]0;pwned BEL` and `ESC [2J` shows them escaped: under NO_COLOR no ESC, BEL or NUL byte
/// reaches the terminal at all (the old code printed the line raw).
#[test]
fn r37_no_control_character_from_the_input_reaches_a_terminal() {
    let d = tempdir();
    let bad = d.path().join("bad\x07.cls");
    std::fs::write(
        &bad,
        "TOOL PATH/X,TOOL,T\nGOTO/1,2,zz\x1b]0;pwned\x07\x1b[2J\0\n",
    )
    .unwrap();
    let bin = assert_cmd::cargo::cargo_bin("crest");
    let line = format!("'{}' inspect '{}'", bin.display(), bad.display());
    let out = match std::process::Command::new("script")
        .args(["-qec", &line, "/dev/null"])
        .env("NO_COLOR", "1")
        .output()
    {
        Ok(o) => o,
        Err(_) => {
            eprintln!("script (util-linux) not found: the terminal rendering is not checked");
            return;
        }
    };
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(text.contains('│') && text.contains(":2:"), "{text}");
    assert!(text.contains("\\x1b]0;pwned"), "the input escaped: {text}");
    for b in [0x1b, 0x07, 0x00] {
        assert!(
            !out.stdout.contains(&b),
            "byte {b:#04x} on the terminal: {text:?}"
        );
    }
}
