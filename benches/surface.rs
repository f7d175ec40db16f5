//! Surface engine benchmarks. B-SIM (issue 5): a 2 mm × 2 mm window at 1 µm (4.0 M nodes)
//! of a plane finished by a ball end R 5 mm, 4 teeth, helix 30°, lead 15°, stepover
//! 0.2 mm, fz 0.05 mm, run-out 10 µm, ICE with Δθ = 1°; plus scaling with window area
//! and with path length; and the N-buffer on a curved part (issue 15): the same tool and
//! raster mapped onto a convex cylinder of radius 20 mm (the design surface an STL-like
//! mesh), a 2 mm × 2 mm patch at 1 µm along the part's normals. Issue 19: the dome model
//! on the FreeCAD peer's 3-axis raster (ball Ø6, stepover 0.5 mm, fz 0.01 mm) on a coarse
//! 10 µm grid, where most triangles of the revolved body are smaller than a node cell.

use crest::math::{Point3, Vec3};
use crest::part::Part;
use crest::resample::Sample;
use crest::surface::{GridFrame, GridSpec, Model, Options, Reference, simulate, simulate_with};
use crest::tool::{Cutter, Shape};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

#[path = "../tests/integration/util/passes.rs"]
#[allow(dead_code)]
mod surface_common;

fn cutter() -> Cutter {
    let mut c = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
    c.runout.offset_mm = 0.010;
    c
}

/// Raster passes along +x at 15° lead, stepover 0.2 mm, covering y ∈ [y0, y1] and
/// x ∈ [x0, x1]; samples every 8° of spindle (the engine subdivides to Δθ).
fn raster(c: &Cutter, x0: f64, x1: f64, y0: f64, y1: f64) -> Vec<Sample> {
    let lead = 15f64.to_radians();
    let axis = Vec3::new(lead.sin(), 0.0, lead.cos());
    let fz = 0.05;
    let ds = 4.0 * fz * 8.0 / 360.0;
    let n = ((y1 - y0) / 0.2).round() as usize;
    let mut out = Vec::new();
    for k in 0..=n {
        let y = y0 + 0.2 * k as f64;
        out.extend(surface_common::pass(
            c,
            k,
            Point3::new(x0, y, 0.0),
            Vec3::x(),
            axis,
            x1 - x0,
            ds,
            fz,
            0.0,
        ));
    }
    out
}

fn run(samples: &[Sample], c: &Cutter, side_mm: f64, grid_mm: f64) -> usize {
    let grid = GridSpec::Window {
        x0_mm: 0.0,
        y0_mm: 0.0,
        x1_mm: side_mm,
        y1_mm: side_mm,
    };
    let opts = Options::new(
        Model::Ice {
            dtheta_rad: 1f64.to_radians(),
        },
        grid,
        grid_mm,
    );
    simulate(samples, c, &opts, &|_, _| {})
        .map(|s| s.nodes_cut)
        .unwrap_or(0)
}

/// The B-SIM raster on the convex cylinder z = √(R² − y²) − R (R = 20 mm, axis x): passes
/// along +x, 0.2 mm apart along the surface, the axis leaning 15° into the feed from the
/// normal, contact points every 8° of spindle.
fn raster_on_cylinder(c: &Cutter, x0: f64, x1: f64, a0: f64, a1: f64) -> Vec<Sample> {
    let r = 20.0;
    let lead = 15f64.to_radians();
    let fz = 0.05;
    let ds = 4.0 * fz * 8.0 / 360.0;
    let n = ((a1 - a0) / 0.2).round() as usize;
    let mut out = Vec::new();
    for k in 0..=n {
        let phi = (a0 + 0.2 * k as f64) / r;
        let normal = Vec3::new(0.0, phi.sin(), phi.cos());
        let axis = (Vec3::x() * lead.sin() + normal * lead.cos()).normalize();
        let m = ((x1 - x0) / ds).round() as usize;
        for i in 0..=m {
            let s = i as f64 * ds;
            let cc = Point3::new(x0 + s, r * phi.sin(), r * phi.cos() - r);
            out.push(Sample {
                run: k,
                s_mm: s,
                t_s: s / 1000.0,
                theta_rad: std::f64::consts::TAU * s / (4.0 * fz),
                position: crest::synth::tool_tip(c, &cc, &normal, &axis),
                axis,
                contact: Some(cc),
                normal: Some(normal),
                feed_dir: Vec3::x(),
                feed_mm_min: 1000.0,
            });
        }
    }
    out
}

fn bench(cr: &mut Criterion) {
    let c = cutter();
    let mut g = cr.benchmark_group("surface");
    g.sample_size(10);
    // B-SIM: passes reach 1.2 mm beyond the window on every side.
    let bsim = raster(&c, -1.2, 3.2, -1.2, 3.2);
    g.bench_function("bsim_2mm_1um_ice", |b| {
        b.iter(|| black_box(run(&bsim, &c, 2.0, 0.001)))
    });
    // Window area at a fixed path (the B-SIM raster): 0.5, 1 and 2 mm squares at 1 µm.
    for side in [0.5, 1.0] {
        g.bench_function(format!("area_{side}mm_1um_ice"), |b| {
            b.iter(|| black_box(run(&bsim, &c, side, 0.001)))
        });
    }
    // Path length at a fixed window (2 mm at 2 µm): raster extended beyond the window.
    for extra in [2.0, 6.0] {
        let long = raster(&c, -1.2 - extra, 3.2 + extra, -1.2, 3.2);
        g.bench_function(format!("path_plus{extra}mm_2um_ice"), |b| {
            b.iter(|| black_box(run(&long, &c, 2.0, 0.002)))
        });
    }
    // Dome model, 3-axis ball Ø6 raster (stepover 0.5 mm, one stamp per fz = 0.01 mm) over a
    // 2 mm × 2 mm window at 10 µm (the FreeCAD peer's grid, benches/peers/freecad).
    let mut ball = Cutter::new(Shape::Ball, 3.0, 2, 0.0);
    ball.runout.offset_mm = 0.0;
    let mut flat3 = Vec::new();
    for k in 0..=6 {
        flat3.extend(surface_common::pass(
            &ball,
            k,
            Point3::new(-4.0, -0.5 + 0.5 * k as f64, 0.0),
            Vec3::x(),
            Vec3::z(),
            10.0,
            0.01,
            0.01,
            0.0,
        ));
    }
    let dome = Options::new(
        Model::Dome,
        GridSpec::Window {
            x0_mm: 0.0,
            y0_mm: 0.0,
            x1_mm: 2.0,
            y1_mm: 2.0,
        },
        0.01,
    );
    g.bench_function("dome_ball_r3_2mm_10um", |b| {
        b.iter(|| {
            black_box(
                simulate(&flat3, &ball, &dome, &|_, _| {})
                    .map(|s| s.nodes_cut)
                    .unwrap_or(0),
            )
        })
    });
    // N-buffer on the design surface of a convex cylinder (B-SIM tool and raster).
    let cyl = raster_on_cylinder(&c, -1.2, 3.2, -2.2, 2.2);
    let surface = crest::synth::Surface::ConvexCylinder { radius_mm: 20.0 };
    let mesh = crest::synth::mesh::surface_mesh(&surface, (8.0, 8.0), 0.0, 0.0, 1e-5).unwrap();
    let part = Part::new(mesh).unwrap();
    let patch = Options::new(
        Model::Ice {
            dtheta_rad: 1f64.to_radians(),
        },
        GridSpec::Oriented {
            frame: GridFrame {
                origin: Point3::new(1.0, 0.0, 0.0),
                u: Vec3::x(),
                v: Vec3::y(),
                w: Vec3::z(),
            },
            length_mm: 2.0,
            width_mm: 2.0,
        },
        0.001,
    );
    g.bench_function("nbuffer_cylinder_2mm_1um_ice", |b| {
        b.iter(|| {
            black_box(
                simulate_with(&cyl, &c, &patch, Reference::Part(&part), &|_, _| {})
                    .map(|s| s.nodes_cut)
                    .unwrap_or(0),
            )
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
