//! What an installed crest gives a user beyond its commands (issue 35): the version with the
//! commit, shell completions and man pages generated from the command line, and errors to a
//! pipe or a file as plain unwrapped lines whatever the path's length, with the control
//! characters of an input escaped.

use std::path::Path;
use std::process::Command;

use crate::util::{ROOT, crest, tempdir};

fn stdout_of(args: &[&str]) -> String {
    let out = crest()
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn version_names_the_package_version_and_the_commit() {
    let v = stdout_of(&["--version"]);
    assert!(
        v.starts_with(&format!("crest {}", env!("CARGO_PKG_VERSION"))),
        "{v}"
    );
    // In a git checkout (CI's clean clone) the binary names the commit it was built from.
    let git = Command::new("git")
        .args(["rev-parse", "--short=10", "HEAD"])
        .current_dir(ROOT)
        .output();
    if let Ok(g) = git
        && g.status.success()
        && std::env::var_os("CREST_COMMIT").is_none()
    {
        let head = String::from_utf8_lossy(&g.stdout).trim().to_string();
        assert!(
            v.contains(&format!("(commit {head})")),
            "{v} vs HEAD {head}"
        );
    }
}

#[test]
fn completions_cover_every_command_for_each_shell() {
    let commands = ["simulate", "inspect", "metrics", "completions", "man"];
    for (shell, marker) in [
        ("bash", "complete -F _crest"),
        ("zsh", "#compdef crest"),
        ("fish", "complete -c crest"),
        ("powershell", "Register-ArgumentCompleter"),
    ] {
        let text = stdout_of(&["completions", shell]);
        assert!(text.contains(marker), "{shell}: no {marker:?}");
        for c in commands {
            assert!(text.contains(c), "{shell}: no {c}");
        }
        // Options of a command, not only its name.
        assert!(text.contains("patch-near"), "{shell}");
    }
    crest().args(["completions", "tcsh"]).assert().code(2);
}

/// `man -l FILE` with a plain pager: the rendered text, and groff's warnings if any.
fn render_man(page: &Path) -> Option<(String, String)> {
    let out = Command::new("man")
        .arg("-l")
        .arg(page)
        .env("MANPAGER", "cat")
        .env("PAGER", "cat")
        .env("MANWIDTH", "100")
        .output();
    match out {
        Ok(o) if o.status.success() => Some((
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )),
        Ok(o) => panic!("man -l {page:?}: {}", String::from_utf8_lossy(&o.stderr)),
        Err(e) => {
            assert!(
                std::env::var_os("CREST_REQUIRE_MAN").is_none(),
                "man is required (CREST_REQUIRE_MAN) but cannot run: {e}"
            );
            eprintln!("man not found: the man pages are checked but not rendered");
            None
        }
    }
}

#[test]
fn man_pages_are_generated_and_render() {
    let root = stdout_of(&["man"]);
    assert!(
        root.starts_with(".ie") || root.contains(".TH crest 1"),
        "{root}"
    );
    assert!(root.contains("simulate"));
    let simulate = stdout_of(&["man", "simulate"]);
    assert!(simulate.contains(".TH crest-simulate 1"), "{simulate}");
    assert!(simulate.contains("patch\\-near"), "{simulate}");
    let nested = stdout_of(&["man", "runout identify"]);
    assert!(nested.contains(".TH crest-runout-identify 1"), "{nested}");
    crest().args(["man", "nonsense"]).assert().code(2);

    let dir = tempdir();
    let out = dir.path().join("man1");
    let msg = stdout_of(&["man", "--out-dir", out.to_str().unwrap_or("")]);
    assert!(msg.starts_with("wrote "), "{msg}");
    for page in [
        "crest.1",
        "crest-simulate.1",
        "crest-man.1",
        "crest-runout-identify.1",
    ] {
        assert!(out.join(page).is_file(), "{page}");
    }
    assert_eq!(
        std::fs::read_to_string(out.join("crest-simulate.1")).unwrap_or_default(),
        simulate
    );
    if let Some((text, warnings)) = render_man(&out.join("crest-simulate.1")) {
        assert!(text.contains("crest-simulate"), "{text}");
        assert!(text.contains("--patch-near"), "{text}");
        assert!(warnings.trim().is_empty(), "{warnings}");
    }
}

#[test]
fn errors_to_a_file_are_plain_lines_whatever_the_path() {
    // A folder whose path is longer than any terminal, with spaces in it.
    let dir = tempdir();
    let mut deep = dir.path().to_path_buf();
    for i in 0..4 {
        deep = deep.join(format!(
            "a folder with spaces and a long name number {i} of four"
        ));
    }
    std::fs::create_dir_all(&deep).unwrap_or_else(|e| panic!("{e}"));
    let bad = deep.join("bad path.cls");
    std::fs::write(
        &bad,
        "TOOL PATH/X,TOOL,T\nTLDATA/MILL,10,5,75,0,0\nFEDRAT/MMPM,1000\nGOTO/1,2,zz\x1b]0;owned\x07\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let shown = bad.display().to_string();
    assert!(shown.len() > 200, "{}", shown.len());
    let out = crest()
        .arg("inspect")
        .arg(&bad)
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    let first = err.lines().next().unwrap_or("");
    assert!(first.starts_with("error: "), "{err}");
    assert!(first.contains(&format!("{shown}:4:")), "{err}");
    for frame in ['×', '│', '╭', '─', '\x1b', '\x07'] {
        assert!(!err.contains(frame), "{frame:?} in {err}");
    }
    // What the input held is shown escaped, not sent to the terminal.
    assert!(
        !err.contains("owned") || err.contains("\\x1b]0;owned\\x07"),
        "{err}"
    );
}

/// The README's walkthrough ("Your own NX export, step by step") as a user types it: every
/// `$ crest …` line of its console blocks runs, in a fresh folder beside nothing but the
/// repository's `samples/`, and prints what the README shows (the run time aside).
#[cfg(unix)]
#[test]
fn the_readme_walkthrough_runs_as_printed() {
    let readme = std::fs::read_to_string(Path::new(ROOT).join("README.md"))
        .unwrap_or_else(|e| panic!("{e}"));
    let start = readme
        .find("## Your own NX export, step by step")
        .unwrap_or_else(|| panic!("no walkthrough in README.md"));
    let section = &readme[start..];
    let section = &section[..section[3..].find("\n## ").map_or(section.len(), |i| i + 3)];
    // (command line, expected output lines) in order.
    let mut steps: Vec<(String, Vec<String>)> = Vec::new();
    let mut in_console = false;
    let mut continued = false;
    for line in section.lines() {
        if line.starts_with("```") {
            in_console = line == "```console";
            continue;
        }
        if !in_console {
            continue;
        }
        if continued {
            let (cmd, _) = steps.last_mut().unwrap_or_else(|| unreachable!());
            cmd.push(' ');
            cmd.push_str(line.trim().trim_end_matches('\\'));
            continued = line.ends_with('\\');
        } else if let Some(cmd) = line.strip_prefix("$ ") {
            steps.push((cmd.trim_end_matches('\\').to_string(), Vec::new()));
            continued = line.ends_with('\\');
        } else if let Some((_, out)) = steps.last_mut() {
            out.push(line.to_string());
        }
    }
    assert!(steps.len() >= 6, "{steps:?}");
    let dir = tempdir();
    std::os::unix::fs::symlink(Path::new(ROOT).join("samples"), dir.path().join("samples"))
        .unwrap_or_else(|e| panic!("{e}"));
    // "…; 0.13 s" at the end of a simulate line is the run time.
    let untimed = |l: &str| match l.rsplit_once("; ") {
        Some((head, t)) if t.ends_with(" s") && t[..t.len() - 2].parse::<f64>().is_ok() => {
            head.to_string()
        }
        _ => l.to_string(),
    };
    for (cmd, expected) in &steps {
        let words: Vec<&str> = cmd.split_whitespace().collect();
        assert_eq!(words.first(), Some(&"crest"), "{cmd}");
        let out = crest()
            .args(&words[1..])
            .current_dir(dir.path())
            .output()
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            out.status.success(),
            "{cmd}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let got: Vec<String> = String::from_utf8_lossy(&out.stdout)
            .lines()
            .map(untimed)
            .collect();
        let want: Vec<String> = expected.iter().map(|l| untimed(l)).collect();
        assert_eq!(got, want, "{cmd}");
    }
}

/// File names with spaces, a backslash (an ordinary character on Unix) and CRLF line ends
/// read like any other.
#[cfg(unix)]
#[test]
fn odd_names_and_crlf_read_like_any_other() {
    let dir = tempdir();
    let sub = dir.path().join("a dir with spaces");
    std::fs::create_dir_all(&sub).unwrap_or_else(|e| panic!("{e}"));
    let src = crate::util::nx_sample("nx_iso_header_units_mm.cls");
    let text = std::fs::read_to_string(&src).unwrap_or_else(|e| panic!("{e}"));
    let odd = sub.join("back\\slash name.cls");
    std::fs::write(&odd, text.replace('\n', "\r\n")).unwrap_or_else(|e| panic!("{e}"));
    let plain = stdout_of(&["inspect", "--json", src.to_str().unwrap_or("")]);
    let crlf = stdout_of(&["inspect", "--json", odd.to_str().unwrap_or("")]);
    let strip = |s: &str| -> serde_json::Value {
        let mut v: serde_json::Value = serde_json::from_str(s).unwrap_or_else(|e| panic!("{e}"));
        v.as_object_mut().map(|o| o.remove("file"));
        v
    };
    assert_eq!(strip(&plain), strip(&crlf));
    assert!(crlf.contains("back\\\\slash name.cls"), "{crlf}");
}

/// On a terminal (a pseudo-terminal made by util-linux's `script`) errors get miette's
/// graphical report, in colour unless `NO_COLOR` is set.
#[cfg(target_os = "linux")]
#[test]
fn a_terminal_gets_the_graphical_report_and_no_color_is_respected() {
    let dir = tempdir();
    let bad = dir.path().join("bad.cls");
    std::fs::write(&bad, "TOOL PATH/X,TOOL,T\nGOTO/1,2,zz\n").unwrap_or_else(|e| panic!("{e}"));
    let bin = assert_cmd::cargo::cargo_bin("crest");
    let line = format!("'{}' inspect '{}'", bin.display(), bad.display());
    let run = |no_color: bool| -> Option<String> {
        let mut c = Command::new("script");
        c.args(["-qec", &line, "/dev/null"]).env_remove("NO_COLOR");
        if no_color {
            c.env("NO_COLOR", "1");
        }
        let out = c.output().ok()?;
        Some(String::from_utf8_lossy(&out.stdout).into_owned())
    };
    let Some(colour) = run(false) else {
        eprintln!("script (util-linux) not found: the terminal rendering is not checked");
        return;
    };
    assert!(colour.contains("bad.cls:2:10"), "{colour}");
    assert!(colour.contains('│'), "no frame on a terminal: {colour}");
    assert!(
        colour.contains("\x1b["),
        "no colour on a terminal: {colour}"
    );
    let plain = run(true).unwrap_or_default();
    assert!(
        plain.contains('│') && plain.contains("bad.cls:2:10"),
        "{plain}"
    );
    assert!(!plain.contains("\x1b["), "colour under NO_COLOR: {plain}");
}
