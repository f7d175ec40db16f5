//! Process effects (issue 16): the engine's ploughing against Brammertz's closed form,
//! effects off by default, texture independent of threads.

use crest::study::brammertz;

/// Brammertz (1961), via Weule et al., CIRP Annals 50/1 (2001) Eq 1: the engine's Rt on the
/// centre line of a one-tooth ball end imprinting every s matches
/// s²/(8R) + (h/2)(1 + R h/s²) within 2 % from the minimum s = √(2R h) (where Rt = h) up.
#[test]
fn engine_ploughing_matches_brammertz_within_two_percent() {
    for (r, h) in [(1.0, 0.002), (5.0, 0.001)] {
        let pts = brammertz::sweep(r, h, &[1.01, 1.3, 2.0, 3.0], 0.0005).unwrap();
        for p in &pts {
            let dev = p.engine_mm / p.closed_form_mm - 1.0;
            assert!(
                dev.abs() < 0.02,
                "R {r} h {h} s {}: engine {} closed form {} ({:.2} %)",
                p.s_mm,
                p.engine_mm,
                p.closed_form_mm,
                100.0 * dev
            );
        }
        // The minimum: Rt = h_min at s = √(2R h_min), rising beyond.
        assert!((pts[0].engine_mm / h - 1.0).abs() < 0.02, "{:?}", pts[0]);
        assert!(pts.windows(2).all(|w| w[1].engine_mm > w[0].engine_mm));
    }
}

/// Texture and ploughing give the same surface on one thread and on two.
#[test]
fn process_effects_do_not_depend_on_the_thread_count() {
    use crest::surface::{GridSpec, Model, Options, Process, Texture, simulate};
    use crest::tool::{Cutter, Shape};
    let cutter = Cutter::new(Shape::Ball, 1.0, 2, 0.0);
    let samples =
        crest::synth::pass::straight_pass(&cutter, 0.2, 0.05, -0.4, 0.9, 360.0 / 2.0).unwrap();
    let grid = GridSpec::Window {
        x0_mm: 0.0,
        y0_mm: -0.02,
        x1_mm: 0.1,
        y1_mm: 0.02,
    };
    let mut opts = Options::new(Model::Dome, grid, 0.002);
    opts.depth_mm = 0.05;
    opts.tile = 16;
    opts.process = Process {
        min_chip_mm: 0.001,
        recovery: 0.7,
        texture: Some(Texture {
            sq_mm: 0.0002,
            corr_mm: 0.01,
            seed: 9,
        }),
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| simulate(&samples, &cutter, &opts, &|_, _| {}).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(
        a.map.z_um.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        b.map.z_um.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );
    let plain = {
        let mut o = opts.clone();
        o.process = Process::default();
        simulate(&samples, &cutter, &o, &|_, _| {}).unwrap()
    };
    assert_ne!(plain.map.z_um, a.map.z_um);
}
