//! Metrics benches: quick Sa, the eight "whole process" parameters, every areal parameter,
//! a 5th-order form removal and an areal Gaussian filter on 1000 × 1000 maps; reading a
//! 2000 × 2000 `.gsf` (as `f64` and as stored, `f32`); the eight parameters on the `f32`
//! grid `crest metrics FILE.gsf --params Sa,Sq,Sp,Sv,Sz,Ssk,Sku,Sdr` uses (issue 19).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

use crest::io::{ReadOptions, open_gsf_rows, read_heightmap, write_heightmap};
use crest::metrics::{
    Grid, Level, ParamSet, Preprocess, areal_parameters, areal_parameters_of, gaussian_filter_map,
    preprocess_map,
};
use crest::surface::HeightMap;

/// A rough, anisotropic, deterministic surface (sum of incommensurate waves + hash noise).
fn surface(n: usize) -> HeightMap {
    let z = (0..n * n)
        .map(|k| {
            let (x, y) = ((k % n) as f64 * 0.5, (k / n) as f64 * 0.5);
            let h =
                ((k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f64 / (1u64 << 24) as f64;
            (x / 15.9).sin()
                + 0.4 * ((x + 2.0 * y) / 7.3).sin()
                + 0.2 * (y / 3.1).cos()
                + 0.1 * (h - 0.5)
        })
        .collect();
    HeightMap::from_rows(n, n, 0.5, 0.5, z).unwrap()
}

fn bench(c: &mut Criterion) {
    let m = surface(1000);
    let mut g = c.benchmark_group("metrics_1000x1000");
    g.sample_size(10);
    g.throughput(Throughput::Elements((m.nx * m.ny) as u64));
    let sa = ParamSet::parse("Sa", false).unwrap();
    g.bench_function("Sa", |b| {
        b.iter(|| areal_parameters(black_box(&m), &sa).unwrap())
    });
    let eight = ParamSet::parse("Sa,Sq,Sp,Sv,Sz,Ssk,Sku,Sdr", false).unwrap();
    g.bench_function("height_params_and_Sdr", |b| {
        b.iter(|| areal_parameters(black_box(&m), &eight).unwrap())
    });
    let z32: Vec<f32> = m.z_um.iter().map(|&v| v as f32).collect();
    let grid = Grid {
        nx: m.nx,
        ny: m.ny,
        dx_um: m.dx_um,
        dy_um: m.dy_um,
        z: &z32[..],
    };
    g.bench_function("height_params_and_Sdr_f32", |b| {
        b.iter(|| areal_parameters_of(black_box(grid), &eight).unwrap())
    });
    let all = ParamSet::all(false);
    g.bench_function("all_areal", |b| {
        b.iter(|| areal_parameters(black_box(&m), &all).unwrap())
    });
    let poly5 = Preprocess {
        level: Level::Poly(5),
        ..Preprocess::default()
    };
    g.bench_function("poly5_form_removal", |b| {
        b.iter(|| preprocess_map(black_box(&m), &poly5).unwrap())
    });
    g.bench_function("gaussian_lambda_25um", |b| {
        b.iter(|| gaussian_filter_map(black_box(&m), 25.0))
    });
    g.bench_function("gaussian_lambda_250um_fft", |b| {
        b.iter(|| gaussian_filter_map(black_box(&m), 250.0))
    });
    g.finish();

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("b.gsf");
    write_heightmap(&path, &surface(2000)).unwrap();
    let mut g = c.benchmark_group("io");
    g.sample_size(10);
    g.throughput(Throughput::Bytes(std::fs::metadata(&path).unwrap().len()));
    g.bench_function("read_gsf_2000x2000", |b| {
        b.iter(|| read_heightmap(black_box(&path), &ReadOptions::default()).unwrap())
    });
    g.bench_function("read_gsf_rows_2000x2000", |b| {
        b.iter(|| {
            let rows = open_gsf_rows(black_box(&path), &ReadOptions::default()).unwrap();
            let mut n = 0usize;
            rows.read_row_range(0..rows.ny, 256, |piece| n += piece.len())
                .unwrap();
            n
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
