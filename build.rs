//! The version `crest --version` prints (as ripgrep does): `CREST_VERSION` is the package
//! version and, in brackets, the commit it is built from (the short hash of `git rev-parse
//! HEAD`, or `CREST_COMMIT` when that is set); outside a git checkout (a crate from
//! crates.io, a source tarball) the version alone.

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let text = String::from_utf8(out.stdout).ok()?;
    Some(text.trim().to_string())
}

/// Rerun the script when `path` changes (only if it exists: cargo reruns a script on every
/// build while a watched file is missing).
fn watch(path: Option<String>) {
    if let Some(p) = path.filter(|p| std::path::Path::new(p).exists()) {
        println!("cargo:rerun-if-changed={p}");
    }
}

fn main() {
    println!("cargo:rerun-if-env-changed=CREST_COMMIT");
    let commit = std::env::var("CREST_COMMIT").ok().or_else(|| {
        // Rebuild when HEAD moves: HEAD itself (a checkout) and the branch it names (a commit).
        for path in ["HEAD", "packed-refs"] {
            watch(git(&["rev-parse", "--git-path", path]));
        }
        if let Some(branch) = git(&["symbolic-ref", "-q", "HEAD"]) {
            watch(git(&["rev-parse", "--git-path", &branch]));
        }
        git(&["rev-parse", "--short=10", "HEAD"])
    });
    let version = std::env::var("CARGO_PKG_VERSION").unwrap_or_default();
    let long = match commit.filter(|c| !c.is_empty()) {
        Some(c) => format!("{version} (commit {c})"),
        None => version,
    };
    println!("cargo:rustc-env=CREST_VERSION={long}");
}
