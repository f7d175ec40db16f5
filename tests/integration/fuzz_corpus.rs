//! The fuzz corpora (`fuzz/corpus/<target>/`, minimised after the cargo-fuzz runs recorded in
//! reports/fuzzing.md) replayed on the stable toolchain: every input of every target goes
//! through the same function the fuzz target calls (`fuzz/entries.rs`) and must return.

#[path = "../../fuzz/entries.rs"]
mod entries;

use crate::util::ROOT;
use std::path::Path;

fn replay(target: &str, run: fn(&[u8])) {
    let dir = Path::new(ROOT).join("fuzz/corpus").join(target);
    let mut n = 0;
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .flatten()
        .map(|e| e.path())
        .collect();
    files.sort();
    for p in files {
        let data = std::fs::read(&p).unwrap();
        run(&data);
        n += 1;
    }
    assert!(n > 0, "{target}: empty corpus");
}

#[test]
fn clsf_corpus() {
    replay("clsf", entries::clsf);
}

#[test]
fn contact12_corpus() {
    replay("contact12", entries::contact12);
}

#[test]
fn gcode_corpus() {
    replay("gcode", entries::gcode);
}

#[test]
fn heightmap_corpus() {
    replay("heightmap", entries::heightmap);
}

#[test]
fn config_corpus() {
    replay("config", entries::config);
}

#[test]
fn measured_corpus() {
    replay("measured", entries::measured);
}

#[test]
fn mesh_corpus() {
    replay("mesh", entries::mesh);
}
