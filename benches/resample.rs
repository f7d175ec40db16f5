//! Resampling speed: a 1,000,000-posture 5-axis zig-zag finishing path with contact data
//! (postures 0.1 mm apart on a wavy surface, the tool axis leading 15° and rolling),
//! resampled at fz = 0.05 mm (issue 4: under 1 s; 2 million samples) and at Δθ = 45°
//! (Z = 2, fz = 0.05: four samples a tooth, 8 million samples).

use crest::math::{Point3, Vec3};
use crest::resample::{Mode, Options, resample_with};
use crest::toolpath::{Contact, MotionKind, Posture, Toolpath};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

const POSTURES: usize = 1_000_000;
const STEP_MM: f64 = 0.1;
const LINE_POSTURES: usize = 500;

fn surface(x: f64, y: f64) -> (f64, Vec3) {
    let (a, k) = (2.0, 0.05);
    let z = a * (k * x).sin() * (k * y).cos();
    let dzdx = a * k * (k * x).cos() * (k * y).cos();
    let dzdy = -a * k * (k * x).sin() * (k * y).sin();
    (z, Vec3::new(-dzdx, -dzdy, 1.0).normalize())
}

fn path() -> Toolpath {
    let radius = 5.0;
    let lead = 15f64.to_radians();
    let postures = (0..POSTURES)
        .map(|i| {
            let line = i / LINE_POSTURES;
            let along = (i % LINE_POSTURES) as f64 * STEP_MM;
            let forward = line.is_multiple_of(2);
            let x = if forward {
                along
            } else {
                (LINE_POSTURES - 1) as f64 * STEP_MM - along
            };
            let y = line as f64 * 0.2;
            let (z, normal) = surface(x, y);
            let feed = if forward { Vec3::x() } else { -Vec3::x() };
            let roll = 0.2 * (0.01 * i as f64).sin();
            let axis = (normal * lead.cos() + feed * lead.sin() + Vec3::y() * roll).normalize();
            let cc = Point3::new(x, y, z);
            let centre = cc + normal * radius;
            Posture {
                position: centre - axis * radius,
                axis,
                motion: if i == 0 {
                    MotionKind::Rapid
                } else {
                    MotionKind::Cut
                },
                arc: None,
                contact: Some(Contact {
                    point: cc,
                    normal,
                    normal_derived: false,
                }),
                feed_mm_min: Some(2000.0),
                spindle_rpm: Some(10000.0),
                line: i as u32 + 1,
            }
        })
        .collect();
    Toolpath {
        postures,
        ..Default::default()
    }
}

fn bench(c: &mut Criterion) {
    let path = path();
    let mut group = c.benchmark_group("resample");
    group.sample_size(10);
    group.throughput(Throughput::Elements(POSTURES as u64));
    group.bench_function("fz_0.05mm_1M_postures", |b| {
        let opts = Options::new(Mode::FeedPerTooth, 0.05, 2);
        b.iter(|| {
            let mut acc = 0.0;
            let stats = resample_with(black_box(&path), &opts, |s| acc += s.position.z).unwrap();
            black_box((acc, stats.samples))
        })
    });
    group.bench_function("dtheta_45deg_1M_postures", |b| {
        let opts = Options::new(
            Mode::SpindleStep {
                dtheta_rad: 45f64.to_radians(),
            },
            0.05,
            2,
        );
        b.iter(|| {
            let mut acc = 0.0;
            let stats = resample_with(black_box(&path), &opts, |s| acc += s.position.z).unwrap();
            black_box((acc, stats.samples))
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
