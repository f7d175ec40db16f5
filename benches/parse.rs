//! Parser and lowering throughput (bytes per second) on real and generated CLSF.
//!
//! `parse` = records only; `lower` = records + lowering to postures; `convert` = records +
//! lowering + contact12 rows into memory (the `crest convert` pipeline without the file);
//! `newlines` = a `memchr` count of the line ends, the limit of any line reader;
//! `write/contact12_rows` = the contact12 rows of lowered postures alone (bytes written).

use crest::parse::{ClsfReader, Contact12Reader};
use crest::toolpath::{Contact12Writer, LowerOptions, Lowerer, Posture, Toolpath};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

/// A real NX export that ships with the repository (Apache-2.0, 164 kB, 3-axis Z-level).
const ZLEVEL: &str = include_str!("../samples/nx/nx_zlevel_core_spindl.cls");

/// The large 5-axis NX export (804 kB) of the folder `CREST_EXTERNAL_SAMPLES` names, when it
/// is set (it has no licence to ship; `reports/benchmarks.md`'s figures are on it).
fn large() -> Option<String> {
    let dir = std::env::var_os("CREST_EXTERNAL_SAMPLES").filter(|v| !v.is_empty());
    let Some(dir) = dir else {
        eprintln!(
            "parse/*/nx_large_5axis not run: set CREST_EXTERNAL_SAMPLES to the folder of the real NX files"
        );
        return None;
    };
    let path = std::path::Path::new(&dir).join("nx_5axis_varcontour_ijk_large.cls");
    Some(std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())))
}

/// A 5-axis path with contact data (12-number GOTOs), about `bytes` long.
fn contact_clsf(bytes: usize) -> String {
    let mut s = String::from(
        "TOOL PATH/VC,TOOL,BALL\nTLDATA/MILL,10.0000,5.0000,75.0000,0.0000,0.0000\nFEDRAT/MMPM,1200.0000\n",
    );
    let mut k = 0u64;
    while s.len() < bytes {
        let x = (k % 2000) as f64 * 0.05;
        let y = (k / 2000) as f64 * 0.3;
        let z = (x / 20.0).sin() * 2.0;
        s += &format!(
            "GOTO/{:.4},{y:.4},{:.4},0.2588190,0.0000000,0.9659258,{x:.4},{y:.4},{z:.4},-0.0995037,0.0000000,0.9950372\n",
            x - 1.29,
            z + 0.17
        );
        k += 1;
    }
    s += "END-OF-PATH\n";
    s
}

fn lower_all(text: &str, out: Option<&mut Vec<u8>>) -> usize {
    let mut low = Lowerer::new(LowerOptions {
        keep_postures: false,
        ..Default::default()
    });
    let mut n = 0usize;
    let mut w = Contact12Writer::new(false);
    let mut buf = out;
    let mut sink = |_: &Toolpath, p: &Posture| {
        n += 1;
        match buf.as_deref_mut() {
            Some(b) => w.posture(p, b),
            None => Ok(()),
        }
    };
    for r in ClsfReader::new(text.as_bytes()) {
        let r = r.unwrap_or_else(|e| panic!("{e}"));
        low.push(&r, &mut sink).unwrap_or_else(|e| panic!("{e}"));
    }
    low.finish(&mut sink).unwrap_or_else(|e| panic!("{e}"));
    if let Some(b) = buf {
        w.flush(b).unwrap_or_else(|e| panic!("{e}"));
    }
    n
}

fn bench(c: &mut Criterion) {
    let contact = contact_clsf(4 << 20);
    let mut csv = Vec::new();
    lower_all(&contact, Some(&mut csv));
    let csv_text = String::from_utf8(csv).unwrap_or_default();

    let large = large();
    let mut inputs = vec![("nx_zlevel_3axis", ZLEVEL)];
    if let Some(text) = large.as_deref() {
        inputs.push(("nx_large_5axis", text));
    }
    inputs.push(("contact_5axis_4MiB", contact.as_str()));
    let mut g = c.benchmark_group("parse");
    for (name, text) in inputs {
        g.throughput(Throughput::Bytes(text.len() as u64));
        g.bench_function(format!("newlines/{name}"), |b| {
            b.iter(|| memchr::memchr_iter(b'\n', black_box(text).as_bytes()).count())
        });
        g.bench_function(format!("records/{name}"), |b| {
            b.iter(|| {
                ClsfReader::new(black_box(text).as_bytes())
                    .filter(|r| r.is_ok())
                    .count()
            })
        });
        g.bench_function(format!("lower/{name}"), |b| {
            b.iter(|| lower_all(black_box(text), None))
        });
        g.bench_function(format!("convert/{name}"), |b| {
            b.iter(|| {
                let mut out = Vec::with_capacity(text.len());
                lower_all(black_box(text), Some(&mut out));
                out.len()
            })
        });
    }
    g.throughput(Throughput::Bytes(csv_text.len() as u64));
    let mut postures = Vec::new();
    let mut low = Lowerer::new(LowerOptions {
        keep_postures: false,
        ..Default::default()
    });
    let mut keep = |_: &Toolpath, p: &Posture| {
        postures.push(p.clone());
        Ok(())
    };
    for r in ClsfReader::new(contact.as_bytes()) {
        let r = r.unwrap_or_else(|e| panic!("{e}"));
        low.push(&r, &mut keep).unwrap_or_else(|e| panic!("{e}"));
    }
    low.finish(&mut keep).unwrap_or_else(|e| panic!("{e}"));
    g.bench_function("write/contact12_rows", |b| {
        b.iter(|| {
            let mut out = Vec::with_capacity(csv_text.len());
            let mut w = Contact12Writer::new(false);
            for p in black_box(&postures) {
                w.posture(p, &mut out).unwrap_or_else(|e| panic!("{e}"));
            }
            w.flush(&mut out).unwrap_or_else(|e| panic!("{e}"));
            out.len()
        })
    });
    g.bench_function("records/contact12_csv", |b| {
        b.iter(|| {
            Contact12Reader::new(black_box(csv_text.as_str()).as_bytes())
                .filter(|r| r.is_ok())
                .count()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
