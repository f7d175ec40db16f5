//! Planning speed: IKT, constraints, the Level 2 interpolator and the Eq 6 feed on a dense
//! 5-axis path (0.1 mm blocks, tilting tool axis, a zigzag with corners) on the Table I
//! AC machine. The target is 1,000,000 postures in under 2 s.

use crest::kinematics::{Level, Machine, PlanInput, plan_poses, pose_tilt_azimuth};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

const AC: &str = include_str!("../samples/machines/table1_ac.toml");

/// Raster passes 100 mm long in 0.1 mm blocks over a wavy surface, the tool axis tilting
/// with the slope, 1 mm stepover, 5 m/min.
fn dense_path(n: usize) -> Vec<PlanInput> {
    let per_pass = 1000;
    (0..n)
        .map(|i| {
            let pass = i / per_pass;
            let u = (i % per_pass) as f64 * 0.1;
            let x = if pass % 2 == 0 { u } else { 100.0 - u };
            let y = pass as f64;
            let z = 2.0 * (x / 10.0).sin() + 0.5 * (y / 7.0).cos();
            let slope = (0.2 * (x / 10.0).cos()).atan().to_degrees();
            PlanInput {
                pose: pose_tilt_azimuth(
                    [x, y, z],
                    10.0 + slope.abs(),
                    if slope >= 0.0 { 180.0 } else { 0.0 },
                ),
                feed_mm_s: 5000.0 / 60.0,
                exact_stop: false,
                line: i as u32,
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let m = Machine::from_toml_str(AC).expect("machine");
    let mut g = c.benchmark_group("kinematics");
    g.sample_size(10);
    for &n in &[100_000usize, 1_000_000] {
        let path = dense_path(n);
        g.throughput(Throughput::Elements(n as u64));
        g.bench_function(format!("plan_jerk_{n}"), |b| {
            b.iter(|| plan_poses(black_box(&path), &m, Level::Jerk).expect("plan"))
        });
    }
    let path = dense_path(1_000_000);
    g.bench_function("plan_acc_1000000", |b| {
        b.iter(|| plan_poses(black_box(&path), &m, Level::Acceleration).expect("plan"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
