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

/// Synthetic profiles of known run-out (offset 1-20 µm at any phase, lead 0-25°, one to four
/// teeth cutting), irregularly sampled: the period and the cutting teeth exactly, and the
/// re-simulated Rz (exact-rule crest model with the identified deviations) within 5 %.
#[test]
fn runout_identification_recovers_period_teeth_and_rz() {
    use crest::math::rng::Rng;
    use crest::study::measured::Side;
    use crest::study::regression::crest_model;
    use crest::tool::{
        Cutter, Rule, Shape, generating_height_mm, mark_positions_mm, normal_deviation_mm,
    };
    let fz = 0.05;
    let mut rng = Rng::new(16);
    let mut seen = [false; 5];
    let cases: Vec<(f64, f64, f64)> = vec![
        (1.0, 0.0, 0.0),
        (20.0, 40.0, 25.0),
        (5.0, 200.0, 15.0),
        (2.0, 300.0, 10.0),
        (10.0, 100.0, 5.0),
        (3.0, 45.0, 25.0),
        (1.5, 10.0, 20.0),
        (12.0, 270.0, 2.0),
    ];
    for (e_um, phase_deg, lead_deg) in cases {
        let mut cutter = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        cutter.runout.offset_mm = e_um * 1e-3;
        cutter.runout.offset_phase_rad = phase_deg.to_radians();
        let lead = lead_deg.to_radians();
        let zc = generating_height_mm(&cutter, lead);
        let dev: Vec<f64> = (0..4)
            .map(|j| normal_deviation_mm(&cutter, j, zc, lead))
            .collect();
        let pos = mark_positions_mm(&cutter, fz);
        let period = 4.0 * fz;
        let r = 5.0;
        // (lowest height, its tooth, the lowest height of any other tooth)
        let env = |x: f64| -> (f64, usize, f64) {
            let mut best = (f64::INFINITY, 0, f64::INFINITY);
            for m in -2..=60i64 {
                for j in 0..4 {
                    let c = pos[j] + m as f64 * period;
                    let rr = r + dev[j];
                    let d = x - c;
                    if d.abs() < rr {
                        let v = rr - (rr * rr - d * d).sqrt() - dev[j];
                        if v < best.0 {
                            let second = if j == best.1 { best.2 } else { best.0 };
                            best = (v, j, second);
                        } else if v < best.2 && j != best.1 {
                            best.2 = v;
                        }
                    }
                }
            }
            best
        };
        // Irregular sampling over 8 turns.
        let (mut xs, mut zs) = (Vec::new(), Vec::new());
        let mut x = 0.3;
        let mut truth_cut = [false; 4];
        while x < 0.3 + 8.0 * period {
            let (z, j, second) = env(x);
            if second - z > 1e-6 {
                truth_cut[j] = true;
            }
            xs.push(x);
            zs.push(z * 1e3);
            x += 0.0005 * (0.2 + 1.6 * rng.uniform());
        }
        let id = crest::study::identify::identify(&xs, &zs, &cutter, fz, lead_deg).unwrap();
        // Truth, relabelled: tooth 1 = the deepest (largest deviation), then cutting order.
        let j1 = (0..4).max_by(|&a, &b| dev[a].total_cmp(&dev[b])).unwrap();
        let order: Vec<usize> = (0..4).map(|k| (j1 + k) % 4).collect();
        let want: Vec<usize> = (0..4)
            .filter(|k| truth_cut[order[*k]])
            .map(|k| k + 1)
            .collect();
        assert_eq!(
            id.teeth_cutting, want,
            "e {e_um} φ {phase_deg} lead {lead_deg}: {id:?}"
        );
        seen[want.len()] = true;
        let kmin = [1usize, 2, 4]
            .into_iter()
            .find(|&k| {
                (0..4).all(|i| {
                    let (p, q) = (order[i], order[(i + k) % 4]);
                    truth_cut[p] == truth_cut[q]
                        && (!truth_cut[p] || (dev[p] - dev[q]).abs() < 1e-7)
                })
            })
            .unwrap();
        assert!(
            (id.period_mm - kmin as f64 * fz).abs() < 1e-12,
            "{id:?} want {kmin}"
        );
        // Re-simulate with the identified deviations (tooth 1 = the deepest).
        let mut re = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        re.runout.tooth_radius_dev_mm = id.tooth_deviation_um.iter().map(|d| d * 1e-3).collect();
        let a = crest_model(&cutter, lead_deg, 0.4, fz, Rule::Exact, Side::Plane, None).unwrap();
        let b = crest_model(&re, lead_deg, 0.4, fz, Rule::Exact, Side::Plane, None).unwrap();
        assert!(
            (b.rz_um / a.rz_um - 1.0).abs() < 0.05,
            "e {e_um} φ {phase_deg} lead {lead_deg}: Rz {} against {}",
            b.rz_um,
            a.rz_um
        );
    }
    assert!(
        seen.iter().filter(|s| **s).count() >= 3,
        "cases cover several numbers of cutting teeth: {seen:?}"
    );
}
