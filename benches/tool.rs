//! Cutter model throughput: ICE edge points, participating teeth (paper and exact rules),
//! the torus section envelope, and a run-out study case.

use crest::tool::{Cutter, Rule, Shape, analyse};
use criterion::{BenchmarkId, Criterion, Throughput, black_box, criterion_group, criterion_main};

fn runout_ball() -> Cutter {
    let mut c = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
    c.runout.offset_mm = 0.005;
    c.runout.offset_phase_rad = 30f64.to_radians();
    c.runout.tilt_rad = 0.02f64.to_radians();
    c.runout.tooth_radius_dev_mm = vec![0.0005, 0.0, -0.0005, 0.0];
    c
}

fn edges(c: &mut Criterion) {
    let cutter = runout_ball();
    let heights = cutter.ice_heights(64);
    let elements = cutter.ice_elements(&heights);
    let mut g = c.benchmark_group("tool/edge_points");
    g.throughput(Throughput::Elements((elements.len() * 360) as u64));
    g.bench_function("ice_point 4 teeth x 64 heights x 360 angles", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for step in 0..360 {
                let theta = (step as f64).to_radians();
                for e in &elements {
                    acc += cutter.ice_point(e, theta).x;
                }
            }
            black_box(acc)
        })
    });
    g.finish();
}

fn teeth(c: &mut Criterion) {
    let ball = runout_ball();
    let mut torus = Cutter::new(
        Shape::Torus {
            corner_radius_mm: 1.5,
        },
        5.0,
        4,
        0.0,
    );
    torus.runout = ball.runout.clone();
    let mut g = c.benchmark_group("tool/analyse");
    g.throughput(Throughput::Elements(1));
    for (name, cutter) in [("ball", &ball), ("torus", &torus)] {
        for rule in [Rule::Paper, Rule::Exact] {
            g.bench_with_input(BenchmarkId::new(name, rule.name()), &rule, |b, &rule| {
                b.iter(|| black_box(analyse(cutter, 15.0, 0.4, 0.05, rule).unwrap()))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, edges, teeth);
criterion_main!(benches);
