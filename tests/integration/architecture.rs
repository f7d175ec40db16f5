//! The invariants of ARCHITECTURE.md that a machine can check, read off the source: which
//! stages a stage imports, which stages may use rayon, which may touch files or the terminal,
//! file sizes and stray files. Code after a file's `#[cfg(test)]` is test code and exempt
//! (tests may build fixtures with later stages).

use approx::assert_relative_eq;
use std::path::{Path, PathBuf};

/// The library's stages in pipeline order; a stage may use only earlier ones.
const STAGES: [&str; 17] = [
    "math",
    "parse",
    "toolpath",
    "resample",
    "tool",
    "part",
    "synth",
    "kinematics",
    "nc",
    "surface",
    "metrics",
    "study",
    "config",
    "io",
    "plot",
    "report",
    "pipeline",
];

/// Stages that may run rayon (fixed chunking: results identical for any thread count).
const RAYON: [&str; 5] = ["part", "kinematics", "surface", "metrics", "study"];

/// Stages that may touch files or the terminal.
const FILES: [&str; 3] = ["io", "plot", "report"];

fn root() -> PathBuf {
    PathBuf::from(crate::util::ROOT)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The non-test code of a file, with comment lines dropped.
fn code(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let body = match text.find("#[cfg(test)]") {
        Some(i) => &text[..i],
        None => &text[..],
    };
    body.lines()
        .filter(|l| {
            let t = l.trim_start();
            !(t.starts_with("//") || t.starts_with("/*") || t.starts_with('*'))
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The stage a library file belongs to (`src/<stage>/…` or `src/<stage>.rs`).
fn stage_of(path: &Path) -> Option<&'static str> {
    let rel = path.strip_prefix(root().join("src")).ok()?;
    let first = rel.components().next()?.as_os_str().to_str()?;
    let name = first.strip_suffix(".rs").unwrap_or(first);
    STAGES.iter().copied().find(|s| *s == name)
}

fn library_files() -> Vec<(PathBuf, &'static str)> {
    let mut files = Vec::new();
    rust_files(&root().join("src"), &mut files);
    files
        .into_iter()
        .filter_map(|p| stage_of(&p).map(|s| (p, s)))
        .collect()
}

#[test]
fn stages_import_only_earlier_stages() {
    let mut bad = Vec::new();
    for (path, stage) in library_files() {
        let rank = STAGES.iter().position(|s| *s == stage).unwrap();
        let text = code(&path);
        for (i, later) in STAGES.iter().enumerate().skip(rank + 1) {
            for pat in [
                format!("crate::{later}::"),
                format!("crate::{later}}}"),
                format!("crate::{later};"),
            ] {
                if text.contains(&pat) {
                    bad.push(format!(
                        "{} ({stage}) uses {later} (stage {i})",
                        path.display()
                    ));
                }
            }
        }
    }
    bad.dedup();
    assert!(
        bad.is_empty(),
        "imports against the pipeline order:\n{}",
        bad.join("\n")
    );
}

#[test]
fn only_the_batch_stages_use_rayon() {
    let bad: Vec<String> = library_files()
        .into_iter()
        .filter(|(p, s)| !RAYON.contains(s) && code(p).contains("rayon::"))
        .map(|(p, _)| p.display().to_string())
        .collect();
    assert!(bad.is_empty(), "rayon outside {RAYON:?}: {bad:?}");
}

#[test]
fn only_the_edge_stages_touch_files_or_the_terminal() {
    let touches = [
        "std::fs::",
        "File::open",
        "File::create",
        "tempfile::",
        "println!",
        "eprintln!",
        "print!(",
        "std::io::stdout",
        "std::io::stderr",
    ];
    let bad: Vec<String> = library_files()
        .into_iter()
        .filter(|(p, s)| !FILES.contains(s) && touches.iter().any(|t| code(p).contains(t)))
        .map(|(p, _)| p.display().to_string())
        .collect();
    assert!(
        bad.is_empty(),
        "files or terminal touched outside {FILES:?}: {bad:?}"
    );
}

#[test]
fn no_source_file_is_over_1200_lines_and_no_stray_files() {
    let mut files = Vec::new();
    for dir in ["src", "tests", "benches", "python/src", "fuzz/fuzz_targets"] {
        rust_files(&root().join(dir), &mut files);
    }
    let long: Vec<String> = files
        .iter()
        .filter_map(|p| {
            let n = std::fs::read_to_string(p).unwrap().lines().count();
            (n > 1200).then(|| format!("{} ({n} lines)", p.display()))
        })
        .collect();
    assert!(long.is_empty(), "files over 1,200 lines: {long:?}");
    let mut all = Vec::new();
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else {
                out.push(p);
            }
        }
    }
    walk(&root().join("src"), &mut all);
    let stray: Vec<String> = all
        .iter()
        .filter(|p| {
            p.extension()
                .is_some_and(|x| x == "orig" || x == "rej" || x == "bak")
        })
        .map(|p| p.display().to_string())
        .collect();
    assert!(stray.is_empty(), "stray merge or backup files: {stray:?}");
}

#[test]
fn every_source_file_opens_with_a_line_that_says_its_job() {
    let mut files = Vec::new();
    rust_files(&root().join("src"), &mut files);
    let bad: Vec<String> = files
        .iter()
        .filter(|p| {
            !std::fs::read_to_string(p)
                .unwrap()
                .trim_start()
                .starts_with("//!")
        })
        .map(|p| p.display().to_string())
        .collect();
    assert!(bad.is_empty(), "files without a leading //! line: {bad:?}");
}

/// The configuration reference (`docs/config.md`) shows files that crest reads: its
/// `tool.toml` and `process.toml` examples load as written, and its machine example has
/// only keys the machine reader knows (it shows one axis of each kind, so the reader's
/// complaint, if any, is about a missing axis, never an unknown key).
#[test]
fn config_reference_examples_load() {
    let doc =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/config.md")).unwrap();
    let blocks: Vec<&str> = doc
        .split("```toml\n")
        .skip(1)
        .map(|b| b.split("```").next().unwrap())
        .collect();
    assert_eq!(blocks.len(), 3, "tool, process and machine examples");
    let cutter = crest::config::load_tool_toml(blocks[0]).unwrap();
    assert_eq!(cutter.teeth(), 4);
    let process = crest::config::ProcessConfig::parse(blocks[1], "process.toml").unwrap();
    assert_eq!(process.rpm, Some(15000.0));
    // The machine example shows one axis of each kind ("one per linear axis"): completed
    // with Y, Z and C it must load, every key with the documented meaning and unit.
    let rest = r#"
[[linear]]
name = "Y"
direction = [0.0, 1.0, 0.0]
sign = 1
vmax = 833.333
amax = 5000.0
jmax = 80000.0
tol = 0.01

[[linear]]
name = "Z"
direction = [0.0, 0.0, 1.0]
sign = 1
vmax = 833.333
amax = 5000.0
jmax = 100000.0
tol = 0.01

[[rotary]]
name = "C"
side = "table"
axis = [0.0, 0.0, 1.0]
point = [0.0, 0.0, 0.0]
sign = 1
limits = []
vmax = 300.0
amax = 1080.0
jmax = 36000.0
tol = 0.01
"#;
    let m = crest::kinematics::Machine::from_toml_str(&format!("{}{rest}", blocks[2]))
        .unwrap_or_else(|e| panic!("docs/config.md's machine example: {e}"));
    assert_eq!(m.name, "5-axis AC table");
    assert_relative_eq!(m.cycle_time, 0.003);
    assert_relative_eq!(m.min_block_cycles, 1.0);
    assert_eq!(m.lookahead_blocks, 0);
    assert!(m.junction_spacing_rule);
    assert_eq!(m.dir_home, crest::math::Vec3::new(0.0, 0.0, 1.0));
    let x = &m.linear[0];
    assert_eq!(x.name, "X");
    assert_eq!(x.direction, crest::math::Vec3::new(1.0, 0.0, 0.0));
    assert_relative_eq!(x.sign, 1.0);
    assert_relative_eq!(x.limits.vmax, 833.333);
    assert_relative_eq!(x.limits.amax, 5000.0);
    assert_relative_eq!(x.limits.jmax, 40000.0);
    assert_relative_eq!(x.limits.tol, 0.01);
    let a = &m.rotary[0];
    assert_eq!(a.name, "A");
    assert_eq!(a.axis, crest::math::Vec3::new(1.0, 0.0, 0.0));
    // Rotary values are documented in degrees; the machine holds radians.
    let (lo, hi) = a.travel.expect("limits = [-120, 120]");
    assert_relative_eq!(lo, (-120.0f64).to_radians(), epsilon = 1e-12);
    assert_relative_eq!(hi, 120.0f64.to_radians(), epsilon = 1e-12);
    assert_relative_eq!(a.limits.vmax, 300.0f64.to_radians(), epsilon = 1e-12);
    assert_relative_eq!(a.limits.amax, 1080.0f64.to_radians(), epsilon = 1e-12);
    assert_relative_eq!(a.limits.jmax, 36000.0f64.to_radians(), epsilon = 1e-9);
    assert_relative_eq!(a.limits.tol, 0.01f64.to_radians(), epsilon = 1e-15);
    assert_eq!(m.rotary[1].travel, None, "limits = [] is endless");
}

/// Every input is read through `io::input` (ARCHITECTURE.md): no other source file opens or
/// reads a file whole, and only `io::input` reads standard input. `io/mod.rs` opens a regular
/// `.gsf` for `GsfRows` (`pread` at offsets) and `io/output.rs` reads back its own staged
/// outputs.
#[test]
fn every_input_is_read_through_io_input() {
    let reads = [
        "File::open",
        "fs::read(",
        "read_to_string(",
        "fs::read_to_string",
        "io::stdin",
    ];
    let allowed = [
        ("src/io/input.rs", ""),
        ("src/io/mod.rs", "File::open"),
        ("src/io/output.rs", "fs::read("),
    ];
    let mut files = Vec::new();
    rust_files(&root().join("src"), &mut files);
    let mut bad = Vec::new();
    for p in files {
        let rel = p
            .strip_prefix(root())
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let text = code(&p);
        for r in reads {
            let ok = allowed
                .iter()
                .any(|(f, what)| rel == *f && (what.is_empty() || *what == r));
            if !ok && text.contains(r) {
                bad.push(format!("{rel}: {r}"));
            }
        }
    }
    assert!(bad.is_empty(), "inputs read outside io::input: {bad:?}");
}

/// The lines of every function of `text` (non-test code, comments dropped): name and length
/// from its `fn` line to its closing brace (braces in string and char literals skipped).
fn function_lengths(text: &str) -> Vec<(String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let braces = |l: &str| -> i64 {
        let (mut depth, mut in_str, mut esc) = (0i64, false, false);
        let b = l.as_bytes();
        let mut k = 0;
        while k < b.len() {
            let c = b[k];
            if in_str {
                if esc {
                    esc = false;
                } else if c == b'\\' {
                    esc = true;
                } else if c == b'"' {
                    in_str = false;
                }
            } else if c == b'"' {
                in_str = true;
            } else if c == b'\'' && k + 2 < b.len() && b[k + 2] == b'\'' {
                k += 2;
            } else if c == b'{' {
                depth += 1;
            } else if c == b'}' {
                depth -= 1;
            }
            k += 1;
        }
        depth
    };
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim_start();
        let t = t
            .strip_prefix("pub ")
            .or_else(|| t.strip_prefix("pub(crate) "))
            .or_else(|| t.strip_prefix("pub(super) "))
            .unwrap_or(t);
        let Some(rest) = t.strip_prefix("fn ") else {
            continue;
        };
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let (mut depth, mut opened) = (0i64, false);
        for (j, m) in lines[i..].iter().enumerate() {
            depth += braces(m);
            opened |= m.contains('{');
            if opened && depth <= 0 {
                out.push((name.clone(), j + 1));
                break;
            }
            if !opened && m.trim_end().ends_with(';') {
                break;
            }
        }
    }
    out
}

#[test]
fn no_function_in_the_pipeline_is_over_150_lines() {
    // The counter itself, on a function of three lines and one of a string with braces.
    let sample = "fn a() {\n    let s = \"{}}}\";\n}\nfn b(x: u8) -> u8 {\n    x\n}\n";
    assert_eq!(
        function_lengths(sample),
        vec![("a".to_string(), 3), ("b".to_string(), 3)]
    );
    let mut long = Vec::new();
    for (p, stage) in library_files() {
        if stage != "pipeline" {
            continue;
        }
        for (name, n) in function_lengths(&code(&p)) {
            if n > 150 {
                long.push(format!("{}: {name} ({n} lines)", p.display()));
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over 150 lines in pipeline/: {long:?}"
    );
}
