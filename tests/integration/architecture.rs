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

/// The module path of a file under `src/` (`study/run.rs` → `study::run`, `nc/mod.rs` →
/// `nc`); `None` for `lib.rs` and `main.rs`.
fn module_of(src: &Path, path: &Path) -> Option<Vec<String>> {
    let rel = path.strip_prefix(src).ok()?;
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let last = parts.pop()?;
    let stem = last.strip_suffix(".rs")?;
    if stem != "mod" {
        parts.push(stem.to_string());
    }
    (parts.len() > 1 || (parts.len() == 1 && stem == "mod")).then_some(parts)
}

/// The paths a file's code names through `crate::…`, `super::…` and `self::…` (groups
/// `a::{b, c::d}` expanded one level), resolved against the file's module `module`.
fn named_paths(text: &str, module: &[String]) -> Vec<Vec<String>> {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let bytes: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let rest: String = bytes[i..bytes.len().min(i + 8)].iter().collect();
        let starts = ["crate::", "super::", "self::"]
            .into_iter()
            .find(|k| rest.starts_with(k));
        let boundary = i == 0 || !(ident(bytes[i - 1]) || bytes[i - 1] == ':');
        let Some(_) = starts.filter(|_| boundary) else {
            i += 1;
            continue;
        };
        // Read `seg::seg::…`, stopping at anything else; a `{` opens a group.
        let mut segs: Vec<String> = Vec::new();
        let mut cur = String::new();
        let mut group = None;
        while i < bytes.len() {
            let c = bytes[i];
            if ident(c) {
                cur.push(c);
                i += 1;
            } else if c == ':' && bytes.get(i + 1) == Some(&':') {
                segs.push(std::mem::take(&mut cur));
                i += 2;
                if bytes.get(i) == Some(&'{') {
                    let mut depth = 0;
                    let start = i + 1;
                    while i < bytes.len() {
                        match bytes[i] {
                            '{' => depth += 1,
                            '}' => {
                                depth -= 1;
                                if depth == 0 {
                                    break;
                                }
                            }
                            _ => {}
                        }
                        i += 1;
                    }
                    group = Some(bytes[start..i.min(bytes.len())].iter().collect::<String>());
                    break;
                }
            } else {
                break;
            }
        }
        if !cur.is_empty() {
            segs.push(cur);
        }
        // Resolve the leading keywords against the file's module (`super` of `a/mod.rs` and
        // of `a/b.rs` alike is the module above the file's own).
        let mut base: Vec<String> = module.to_vec();
        let mut k = 0;
        match segs.first().map(String::as_str) {
            Some("crate") => {
                base.clear();
                k = 1;
            }
            Some("self") => k = 1,
            Some("super") => {
                while segs.get(k).map(String::as_str) == Some("super") {
                    base.pop();
                    k += 1;
                }
            }
            _ => {}
        }
        let mut path = base;
        path.extend(segs[k..].iter().cloned());
        match group {
            Some(g) => {
                let mut depth = 0;
                let mut item = String::new();
                for c in g.chars().chain(std::iter::once(',')) {
                    match c {
                        '{' => depth += 1,
                        '}' => depth -= 1,
                        ',' if depth == 0 => {
                            let first: Vec<String> = item
                                .trim()
                                .split("::")
                                .map(|s| s.trim().to_string())
                                .take_while(|s| !s.is_empty() && s.chars().all(ident))
                                .collect();
                            let mut p = path.clone();
                            p.extend(first);
                            out.push(p);
                            item.clear();
                            continue;
                        }
                        _ => {}
                    }
                    item.push(c);
                }
            }
            None => out.push(path),
        }
        i += 1;
    }
    out
}

/// The import cycles between the files of one stage under `src_dir`: each a list of module
/// paths. An edge is a file naming another file of its stage (`use super::run::…`,
/// `crate::study::design::Design`); a file naming its own parent module (`super::Item` of a
/// `mod.rs`) or a `mod.rs` naming its children (re-exports) is not an edge.
fn stage_import_cycles(src_dir: &Path) -> Vec<Vec<String>> {
    let mut files = Vec::new();
    rust_files(src_dir, &mut files);
    let modules: Vec<(Vec<String>, PathBuf)> = files
        .into_iter()
        .filter_map(|p| module_of(src_dir, &p).map(|m| (m, p)))
        .collect();
    let index = |m: &[String]| modules.iter().position(|(n, _)| n.as_slice() == m);
    let n = modules.len();
    let mut edges = vec![Vec::new(); n];
    for (a, (m, p)) in modules.iter().enumerate() {
        for named in named_paths(&code(p), m) {
            // The longest prefix that is a file of the same stage.
            let Some(b) = (1..=named.len()).rev().find_map(|l| index(&named[..l])) else {
                continue;
            };
            let other = &modules[b].0;
            let related = other.starts_with(m) || m.starts_with(other);
            if b != a && other[0] == m[0] && !related && !edges[a].contains(&b) {
                edges[a].push(b);
            }
        }
    }
    // Tarjan's strongly connected components; any of more than one file is a cycle.
    struct State {
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        sccs: Vec<Vec<usize>>,
    }
    fn visit(v: usize, edges: &[Vec<usize>], s: &mut State) {
        s.index[v] = Some(s.next);
        s.low[v] = s.next;
        s.next += 1;
        s.stack.push(v);
        s.on[v] = true;
        for &w in &edges[v] {
            match s.index[w] {
                None => {
                    visit(w, edges, s);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(iw) if s.on[w] => s.low[v] = s.low[v].min(iw),
                _ => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut scc = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on[w] = false;
                scc.push(w);
                if w == v {
                    break;
                }
            }
            s.sccs.push(scc);
        }
    }
    let mut s = State {
        index: vec![None; n],
        low: vec![0; n],
        on: vec![false; n],
        stack: Vec::new(),
        next: 0,
        sccs: Vec::new(),
    };
    for v in 0..n {
        if s.index[v].is_none() {
            visit(v, &edges, &mut s);
        }
    }
    let mut cycles: Vec<Vec<String>> = s
        .sccs
        .into_iter()
        .filter(|c| c.len() > 1)
        .map(|c| {
            let mut names: Vec<String> = c.iter().map(|&v| modules[v].0.join("::")).collect();
            names.sort();
            names
        })
        .collect();
    cycles.sort();
    cycles
}

/// No files of one stage (the binary's `cli` included) import each other in a circle: a
/// stage's files form layers too.
#[test]
fn no_import_cycle_inside_a_stage() {
    let cycles = stage_import_cycles(&root().join("src"));
    assert!(
        cycles.is_empty(),
        "files of one stage that import each other in a circle:\n{}",
        cycles
            .iter()
            .map(|c| c.join(", "))
            .collect::<Vec<_>>()
            .join("\n")
    );
}

#[test]
fn the_cycle_check_finds_a_cycle() {
    let dir = tempfile::tempdir().unwrap();
    let stage = dir.path().join("stage");
    std::fs::create_dir(&stage).unwrap();
    let write = |name: &str, text: &str| std::fs::write(stage.join(name), text).unwrap();
    write(
        "mod.rs",
        "//! s\npub mod a;\npub mod b;\npub mod c;\npub use a::A;\n",
    );
    write("a.rs", "//! a\nuse super::b::B;\npub struct A;\n");
    write(
        "b.rs",
        "//! b\nuse crate::stage::{c::C, a};\npub struct B;\n",
    );
    write(
        "c.rs",
        "//! c\npub struct C(super::A);\n#[cfg(test)]\nuse super::a::A;\n",
    );
    assert_eq!(
        stage_import_cycles(dir.path()),
        vec![vec!["stage::a".to_string(), "stage::b".to_string()]]
    );
}

/// The stage table of ARCHITECTURE.md has one row per stage folder, in pipeline order, then
/// the binary's `cli`; the order the data-flow invariant spells is [`STAGES`].
#[test]
fn the_stage_table_lists_every_stage_in_order() {
    let doc = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let rows: Vec<&str> = doc
        .lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|l| l.split('`').next())
        .collect();
    let mut want: Vec<&str> = STAGES.to_vec();
    want.push("cli");
    assert_eq!(rows, want, "ARCHITECTURE.md's stage table");
    let mut folders: Vec<String> = std::fs::read_dir(root().join("src"))
        .unwrap()
        .flatten()
        .filter(|e| e.path().is_dir())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    folders.sort();
    let mut listed: Vec<String> = want.iter().map(|s| s.to_string()).collect();
    listed.sort();
    assert_eq!(
        folders, listed,
        "a folder under src/ per stage, and no other"
    );
    let order = STAGES.join(", ");
    assert!(
        doc.replace("\n  ", " ").contains(&order),
        "the data-flow invariant names the stages in the order {order}"
    );
}

/// In the binary, rayon is used only by the commands ARCHITECTURE.md names (`atlas`,
/// `simulate`, `study` size the pool; `simulate` joins two tasks; `metrics` cuts a streamed
/// `.gsf` per thread), and no library code starts a thread of its own.
#[test]
fn threads_only_where_the_architecture_says() {
    let allowed = ["atlas.rs", "metrics.rs", "simulate.rs", "study.rs"];
    let mut files = Vec::new();
    rust_files(&root().join("src/cli"), &mut files);
    let bad: Vec<String> = files
        .iter()
        .filter(|p| code(p).contains("rayon::"))
        .filter(|p| !allowed.iter().any(|a| p.ends_with(a)))
        .map(|p| p.display().to_string())
        .collect();
    assert!(
        bad.is_empty(),
        "rayon in commands ARCHITECTURE.md does not name: {bad:?}"
    );
    let spawns: Vec<String> = library_files()
        .into_iter()
        .filter(|(p, _)| {
            let c = code(p);
            c.contains("thread::spawn")
                || c.contains("thread::scope")
                || c.contains("Builder::new().spawn")
        })
        .map(|(p, _)| p.display().to_string())
        .collect();
    assert!(
        spawns.is_empty(),
        "library code that starts threads: {spawns:?}"
    );
}

/// The types of the earlier stages (before `config`) that derive or implement
/// `Deserialize` are the ones ARCHITECTURE.md lists under "Serde only at the edge".
#[test]
fn only_the_listed_types_of_earlier_stages_deserialize() {
    let config = STAGES.iter().position(|s| *s == "config").unwrap();
    let mut found = Vec::new();
    for (path, stage) in library_files() {
        if STAGES.iter().position(|s| *s == stage).unwrap() >= config {
            continue;
        }
        let text = code(&path);
        let lines: Vec<&str> = text.lines().collect();
        for (i, l) in lines.iter().enumerate() {
            let t = l.trim_start();
            // The whole attribute (rustfmt breaks a long derive over lines).
            let attr: String = if t.starts_with("#[derive(") {
                let end = (i..lines.len())
                    .find(|&j| lines[j].contains(")]"))
                    .unwrap_or(i);
                lines[i..=end].concat()
            } else {
                String::new()
            };
            if attr.contains("Deserialize") {
                let item = lines[i + 1..]
                    .iter()
                    .map(|l| l.trim_start())
                    .find(|l| l.starts_with("pub struct") || l.starts_with("pub enum"));
                if let Some(item) = item {
                    let name = item.split_whitespace().nth(2).unwrap_or("");
                    found.push(name.trim_end_matches(['{', '(', ';']).to_string());
                }
            } else if let Some(rest) = t.split("Deserialize<'de> for ").nth(1) {
                found.push(rest.split_whitespace().next().unwrap_or("").to_string());
            }
        }
    }
    found.sort();
    let doc = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let doc = doc.replace("\n  ", " ");
    let para = doc
        .split("**Serde only at the edge.**")
        .nth(1)
        .and_then(|r| r.split("\n- ").next())
        .unwrap();
    let mut listed: Vec<String> = para
        .split('`')
        .skip(1)
        .step_by(2)
        .map(|s| s.rsplit("::").next().unwrap().to_string())
        .filter(|s| s.chars().next().is_some_and(char::is_uppercase))
        .filter(|s| s != "Deserialize" && s != "Serialize")
        .collect();
    listed.sort();
    assert_eq!(found, listed, "Deserialize in the stages before config");
}

/// miette's `fancy` renderer is the binary's: the library's dependency has no features, the
/// default `cli` feature (which the binary requires) turns it on, and the Python package
/// links the library without default features.
#[test]
fn miette_fancy_only_in_the_binary() {
    let manifest = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let dep = manifest.lines().find(|l| l.starts_with("miette")).unwrap();
    assert_eq!(dep.trim(), "miette = \"7\"", "the library's miette");
    assert!(manifest.contains("cli = [\"miette/fancy\"]"), "{manifest}");
    assert!(manifest.contains("default = [\"cli\"]"), "{manifest}");
    assert!(
        manifest.contains("required-features = [\"cli\"]"),
        "{manifest}"
    );
    let python = std::fs::read_to_string(root().join("python/Cargo.toml")).unwrap();
    assert!(
        python.contains("crest = { path = \"..\", default-features = false }"),
        "{python}"
    );
}

/// Library errors are typed: no function outside the binary returns `Result<_, String>`
/// (files still to convert would be listed in `pending`; none are).
/// Library errors are typed: no untyped report (`miette::Result`, `miette::Report`,
/// `miette!`, miette's `WrapErr` and `IntoDiagnostic`) anywhere in the library, its tests
/// included; only the binary (`src/cli/`, `src/main.rs`) builds reports.
#[test]
fn no_untyped_reports_in_the_library() {
    let mut files = Vec::new();
    rust_files(&root().join("src"), &mut files);
    let mut found = Vec::new();
    for path in files {
        let rel = path
            .strip_prefix(root())
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        if rel.starts_with("src/cli/") || rel == "src/main.rs" {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let code: Vec<&str> = text
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect();
        let code = code.join("\n");
        for k in [
            "miette::Result",
            "miette::Report",
            "ErrReport",
            "miette!(",
            "WrapErr",
            "IntoDiagnostic",
        ] {
            if code.contains(k) {
                found.push(format!("{rel}: {k}"));
            }
        }
    }
    assert!(found.is_empty(), "untyped library errors: {found:?}");
}

#[test]
fn library_errors_are_not_strings() {
    let pending: [&str; 0] = [];
    let mut bad = Vec::new();
    for (path, _) in library_files() {
        let rel = path
            .strip_prefix(root())
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        if pending.iter().any(|p| rel.starts_with(p)) {
            continue;
        }
        let text = code(&path).replace(char::is_whitespace, "");
        if result_types(&text)
            .iter()
            .any(|args| args.len() == 2 && args[1] == "String")
        {
            bad.push(rel);
        }
    }
    assert!(
        bad.is_empty(),
        "library files with Result<_, String>: {bad:?}"
    );
}

/// The type arguments of every `Result<…>` in `text` (whitespace removed), split at their
/// top-level commas.
fn result_types(text: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for (start, _) in text.match_indices("Result<") {
        if text[..start].ends_with(|c: char| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let mut depth = 0;
        let mut args = vec![String::new()];
        for c in text[start + "Result".len()..].chars() {
            match c {
                '<' | '(' | '[' => {
                    depth += 1;
                    if depth == 1 {
                        continue;
                    }
                }
                '>' | ')' | ']' => {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                ',' if depth == 1 => {
                    args.push(String::new());
                    continue;
                }
                _ => {}
            }
            args.last_mut().unwrap().push(c);
        }
        out.push(args);
    }
    out
}

/// One finite-or-null JSON number (`io::tables::json_number`): nobody else maps a float to
/// `null` by hand.
#[test]
fn one_finite_or_null_json_number() {
    let pending: [&str; 0] = [];
    let mut files = Vec::new();
    rust_files(&root().join("src"), &mut files);
    let bad: Vec<String> = files
        .iter()
        .filter(|p| !p.ends_with("src/io/tables.rs"))
        .filter(|p| !pending.iter().any(|f| p.ends_with(f)))
        .filter(|p| {
            let c = code(p).replace(char::is_whitespace, "");
            c.contains("Number::from_f64(") || c.contains("else{serde_json::Value::Null}")
        })
        .map(|p| p.display().to_string())
        .collect();
    assert!(
        bad.is_empty(),
        "floats mapped to JSON null by hand: {bad:?}"
    );
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

/// Library messages name request fields (`‹grid_um›`), which each front end spells its own
/// way (`pipeline::fields`); a command-line option (`--grid-um`) in a library string would
/// reach Python users as it is. Reports and plots (documents the command line writes) may
/// name options.
#[test]
fn library_messages_name_fields_not_options() {
    let mut bad = Vec::new();
    for (path, stage) in library_files() {
        if matches!(stage, "report" | "plot") {
            continue;
        }
        for line in code(&path).lines() {
            let b = line.as_bytes();
            let found = (0..b.len().saturating_sub(2)).any(|k| {
                b[k] == b'-'
                    && b[k + 1] == b'-'
                    && b[k + 2].is_ascii_lowercase()
                    && (k == 0 || !(b[k - 1].is_ascii_alphanumeric() || b"-_".contains(&b[k - 1])))
            });
            if found {
                bad.push(format!("{}: {}", path.display(), line.trim()));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "options named in library strings (write ‹field›):\n{}",
        bad.join("\n")
    );
}

/// One request per command, built once by each front end. The command line's values of the
/// library's choices (model, feed source, RTCP, moves, the teeth rule) are the library's own
/// enums, `clap::ValueEnum` derived on them: no enum of the CLI mirrors one and converts
/// with `From`. Python builds a `SimulateRequest` in one function
/// (`python/src/simulate.rs::request_of`, called by every function that simulates), so the
/// simulate keywords are spelled there only.
#[test]
fn one_request_per_command_one_builder_per_front_end() {
    let mut files = Vec::new();
    rust_files(&root().join("src/cli"), &mut files);
    let mut mirrors = Vec::new();
    for p in &files {
        let text = code(p);
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            if !line.contains("ValueEnum") || !line.trim_start().starts_with("#[derive") {
                continue;
            }
            let Some(name) = lines[i + 1..]
                .iter()
                .find_map(|l| l.trim_start().strip_prefix("pub enum "))
                .and_then(|rest| rest.split([' ', '{']).next())
            else {
                continue;
            };
            if text.contains(&format!("impl From<{name}> for")) {
                mirrors.push(format!("{}: {name}", p.display()));
            }
        }
    }
    assert!(
        mirrors.is_empty(),
        "CLI enums that mirror a library enum (derive clap::ValueEnum on the library's): {mirrors:?}"
    );
    let mut py = Vec::new();
    rust_files(&root().join("python/src"), &mut py);
    let mut builders = Vec::new();
    let mut spelled = Vec::new();
    for p in &py {
        let text = code(p);
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        builders.extend(std::iter::repeat_n(
            name.clone(),
            text.matches("SimulateRequest {").count(),
        ));
        // Keywords only `simulate` takes.
        if ["chord_tol_um", "band_um", "patch_near"]
            .iter()
            .any(|k| text.contains(k))
        {
            spelled.push(name);
        }
    }
    assert_eq!(
        builders,
        ["simulate.rs"],
        "where Python builds a SimulateRequest"
    );
    assert_eq!(
        spelled,
        ["simulate.rs"],
        "where Python spells simulate's keywords"
    );
}

/// The items of `text` (non-test code) that derive an error type (`thiserror::Error`), each
/// as its name and its body from the `struct`/`enum` line to the closing brace.
fn error_items(text: &str) -> Vec<(String, String)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut k = 0;
    while k < lines.len() {
        let l = lines[k].trim_start();
        if !(l.starts_with("#[derive(") && l.contains("Error")) {
            k += 1;
            continue;
        }
        // The item after its attributes (which may span lines).
        let is_item = |l: &str| {
            let t = l.trim_start();
            let t = t.strip_prefix("pub(crate) ").unwrap_or(t);
            let t = t.strip_prefix("pub ").unwrap_or(t);
            t.starts_with("struct ") || t.starts_with("enum ")
        };
        let mut i = k + 1;
        while i < lines.len() && !is_item(lines[i]) {
            i += 1;
        }
        // Its body: to the brace that closes it, or the `;` of a tuple or unit struct.
        let (mut depth, mut opened) = (0i64, false);
        let mut body = String::new();
        let mut j = i;
        while j < lines.len() {
            body.push_str(lines[j]);
            body.push('\n');
            depth += lines[j].matches('{').count() as i64;
            depth -= lines[j].matches('}').count() as i64;
            opened |= lines[j].contains('{');
            if depth <= 0 && (opened || lines[j].trim_end().ends_with(';')) {
                break;
            }
            j += 1;
        }
        let name = lines
            .get(i)
            .and_then(|l| {
                l.split_whitespace()
                    .skip_while(|w| *w != "struct" && *w != "enum")
                    .nth(1)
            })
            .map_or_else(String::new, |w| {
                w.chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect()
            });
        out.push((name, body));
        k = j.max(k + 1);
    }
    out
}

/// The error types of `text` that keep a line or a column of their own (an integer field
/// `line` or `column`), not a `parse::Span`.
fn errors_with_own_position(text: &str) -> Vec<String> {
    error_items(text)
        .into_iter()
        .filter(|(_, body)| {
            body.lines().any(|l| {
                let t = l.trim_start().trim_start_matches("pub ");
                ["line", "column"].iter().any(|field| {
                    ["u32", "u64", "usize"]
                        .iter()
                        .any(|ty| t.starts_with(&format!("{field}: {ty}")))
                })
            })
        })
        .map(|(name, _)| name)
        .collect()
}

/// Errors that name a posture by its source line (the number `toolpath::Posture::line`
/// carries), not a place a reader found in an input.
const POSTURE_LINE_ERRORS: [&str; 2] = ["KinematicsError", "ResampleError"];

/// One span type: every error that says where in an input something is carries a
/// `parse::Span` (inside a `parse::Located` or on its own), none a line or column of its
/// own. Only `src/parse/position.rs`, which defines the span, declares such fields, and the
/// errors about a posture keep its source line.
#[test]
fn errors_carry_a_span_not_their_own_line_and_column() {
    let mut files = Vec::new();
    rust_files(&root().join("src"), &mut files);
    let (mut bad, mut posture) = (Vec::new(), Vec::new());
    for p in files
        .iter()
        .filter(|p| !p.ends_with("src/parse/position.rs"))
    {
        for name in errors_with_own_position(&code(p)) {
            if POSTURE_LINE_ERRORS.contains(&name.as_str()) {
                posture.push(name);
            } else {
                bad.push(format!("{}: {name}", p.display()));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "error types with a line or column of their own (carry a parse::Span): {bad:?}"
    );
    posture.sort();
    assert_eq!(
        posture, POSTURE_LINE_ERRORS,
        "the list of posture-line errors is stale"
    );
}

#[test]
fn the_span_check_finds_an_error_with_its_own_line_or_column() {
    let text = r#"
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OldError {
    #[error("line {line}, column {column}: {message}")]
    At {
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        message: String,
    },
}

#[derive(Debug, thiserror::Error)]
#[error("{file}:{}:{}: {message}", at.line, at.column)]
pub struct NewError {
    pub file: String,
    pub at: Span,
    pub message: String,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub line: u32,
    pub column: u32,
}
"#;
    assert_eq!(errors_with_own_position(text), ["OldError"]);
    let tuple = "#[derive(Debug, thiserror::Error)]\n#[error(\"{0}\")]\npub struct E(pub Located);\n\n#[derive(thiserror::Error)]\nstruct F{\n    pub column: u32,\n}\n";
    assert_eq!(errors_with_own_position(tuple), ["F"]);
    let names: Vec<String> = error_items(tuple).into_iter().map(|(n, _)| n).collect();
    assert_eq!(names, ["E", "F"]);
    let line_only = "#[derive(Debug, thiserror::Error)]\n#[error(\"line {line}\")]\npub struct G {\n    line: u64,\n}\n";
    assert_eq!(errors_with_own_position(line_only), ["G"]);
}
