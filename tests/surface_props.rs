//! Properties of the surface engine: thread-count independence, monotonicity, and an
//! untouched window when the tool never reaches it.

mod surface_common;

use crest::math::{Point3, Vec3};
use crest::surface::{GridSpec, Model, Options, Simulation, simulate};
use crest::tool::{Cutter, Shape};
use proptest::prelude::*;
use surface_common::pass;

fn no_progress(_: usize, _: usize) {}

fn runout_ball() -> Cutter {
    let mut c = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
    c.runout.offset_mm = 0.010;
    c.runout.offset_phase_rad = 0.4;
    c
}

fn raster(
    cutter: &Cutter,
    lead_deg: f64,
    ys: &[f64],
    x_start: f64,
    length: f64,
) -> Vec<crest::resample::Sample> {
    let l = lead_deg.to_radians();
    let axis = Vec3::new(l.sin(), 0.0, l.cos());
    let fz = 0.05;
    let ds = 4.0 * fz * 10.0 / 360.0;
    let mut out = Vec::new();
    for (run, y) in ys.iter().enumerate() {
        out.extend(pass(
            cutter,
            run,
            Point3::new(x_start, *y, 0.0),
            Vec3::x(),
            axis,
            length,
            ds,
            fz,
            0.3 * run as f64,
        ));
    }
    out
}

fn run(
    samples: &[crest::resample::Sample],
    cutter: &Cutter,
    model: Model,
    tile: usize,
) -> Simulation {
    let grid = GridSpec::Window {
        x0_mm: 0.0,
        y0_mm: -0.1,
        x1_mm: 0.3,
        y1_mm: 0.3,
    };
    let mut opts = Options::new(model, grid, 0.004);
    opts.tile = tile;
    simulate(samples, cutter, &opts, &no_progress).unwrap()
}

#[test]
fn identical_results_for_one_and_several_threads() {
    let cutter = runout_ball();
    let samples = raster(&cutter, 15.0, &[-0.2, 0.0, 0.2, 0.4], -1.0, 2.3);
    for model in [
        Model::Ice {
            dtheta_rad: 1f64.to_radians(),
        },
        Model::Dome,
    ] {
        let samples = if model == Model::Dome {
            // The dome wants one sample per feed per tooth.
            samples.iter().step_by(9).cloned().collect()
        } else {
            samples.clone()
        };
        let maps: Vec<Vec<u64>> = [1, 2, 3]
            .iter()
            .map(|&n| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .unwrap();
                let sim = pool.install(|| run(&samples, &cutter, model, 16));
                assert_eq!(sim.nodes_cut, sim.map.nx * sim.map.ny);
                sim.map.z_um.iter().map(|z| z.to_bits()).collect()
            })
            .collect();
        assert_eq!(maps[0], maps[1], "{model:?}: 1 vs 2 threads");
        assert_eq!(maps[0], maps[2], "{model:?}: 1 vs 3 threads");
        // The tile size is a memory knob only.
        let big = run(&samples, &cutter, model, 1000);
        let bits: Vec<u64> = big.map.z_um.iter().map(|z| z.to_bits()).collect();
        assert_eq!(maps[0], bits, "{model:?}: tile size changed the result");
    }
}

#[test]
fn a_tool_that_never_reaches_the_window_leaves_it_untouched() {
    let cutter = runout_ball();
    // Passes far away in y, and one lifted 1 mm above the window.
    let mut samples = raster(&cutter, 15.0, &[5.0], -1.0, 2.3);
    let mut lifted = raster(&cutter, 0.0, &[0.1], -1.0, 2.3);
    for s in &mut lifted {
        s.position.z += 1.0;
        s.run = 7;
    }
    samples.extend(lifted);
    let sim = run(
        &samples,
        &cutter,
        Model::Ice {
            dtheta_rad: 1f64.to_radians(),
        },
        64,
    );
    assert_eq!(sim.nodes_cut, 0);
    assert!(sim.map.z_um.iter().all(|z| z.is_nan()));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]

    /// Adding a pass (cutting more) never raises a height, and never un-cuts a node.
    #[test]
    fn cutting_more_never_raises_a_height(
        y_extra in -0.3f64..0.5,
        lead in 0.0f64..20.0,
        dz in -0.002f64..0.004,
    ) {
        let cutter = runout_ball();
        let base = raster(&cutter, lead, &[0.0, 0.2], -1.0, 2.3);
        let mut more = base.clone();
        let mut extra = raster(&cutter, lead, &[y_extra], -1.0, 2.3);
        for s in &mut extra {
            s.position.z += dz;
            s.run = 9;
        }
        more.extend(extra);
        let model = Model::Ice { dtheta_rad: 2f64.to_radians() };
        let a = run(&base, &cutter, model, 64);
        let b = run(&more, &cutter, model, 64);
        for (za, zb) in a.map.z_um.iter().zip(&b.map.z_um) {
            if za.is_finite() {
                prop_assert!(zb.is_finite() && *zb <= *za + 1e-12, "{za} -> {zb}");
            }
        }
    }
}
