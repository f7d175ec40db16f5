//! Properties of the resampler on random 5-axis paths (issue 4 acceptance): samples lie on
//! the original path, spacing equals the step except the last of each run, tool axes and
//! normals are unit vectors, θ grows by exactly Δθ per sample in `dtheta` mode, and the
//! local frames (f, g = n × f, n) are orthonormal.

use crest::math::{Point3, Vec3};
use crest::resample::{AxisInterpolation, Mode, Options, Sample, resample, resample_with};
use crest::toolpath::{ArcMove, Contact, MotionKind, Posture, Toolpath};
use proptest::prelude::*;
use std::f64::consts::TAU;

/// A random step: displacement, axis (polar, azimuth), normal (polar, azimuth), rapid.
type Step = ([f64; 3], [f64; 2], [f64; 2], bool);

/// One random posture: a step from the previous one, a tool axis within 60° of +z, a
/// contact point below the tip, a normal within 45° of +z.
fn step() -> impl Strategy<Value = Step> {
    (
        [-2.0..2.0f64, -2.0..2.0f64, -0.5..0.5f64],
        [0.0..1.0f64, 0.0..TAU],
        [0.0..0.78f64, 0.0..TAU],
        prop::bool::weighted(0.1),
    )
}

fn unit(polar: f64, azimuth: f64) -> Vec3 {
    Vec3::new(
        polar.sin() * azimuth.cos(),
        polar.sin() * azimuth.sin(),
        polar.cos(),
    )
}

fn build(steps: &[Step], contact: bool) -> Toolpath {
    let mut position = Point3::origin();
    let mut postures = Vec::new();
    for (i, (d, a, n, rapid)) in steps.iter().enumerate() {
        position += Vec3::new(d[0], d[1], d[2]);
        let motion = if i == 0 || *rapid {
            MotionKind::Rapid
        } else {
            MotionKind::Cut
        };
        postures.push(Posture {
            position,
            axis: unit(a[0], a[1]),
            motion,
            arc: None,
            contact: contact.then(|| Contact {
                point: position + Vec3::new(0.3, -0.2, -1.0),
                normal: unit(n[0], n[1]),
                normal_derived: false,
            }),
            feed_mm_min: Some(1000.0 + 100.0 * (i % 3) as f64),
            spindle_rpm: None,
            line: i as u32 + 1,
        });
    }
    Toolpath {
        postures,
        ..Default::default()
    }
}

/// Distance from `p` to the closest cutting move of run `run` of `path`.
fn distance_to_run(path: &Toolpath, run: usize, p: &Point3) -> f64 {
    let r = path.cutting_runs()[run].clone();
    let ps = &path.postures[r];
    ps.windows(2)
        .map(|w| {
            let (a, b) = (w[0].position, w[1].position);
            let d = b - a;
            let l2 = d.norm_squared();
            let u = if l2 > 0.0 {
                ((p - a).dot(&d) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (a + d * u - p).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

fn check_frame(s: &Sample) {
    let f = s.feed_dir;
    assert!((s.axis.norm() - 1.0).abs() < 1e-12, "axis {:?}", s.axis);
    assert!((f.norm() - 1.0).abs() < 1e-12, "f {f:?}");
    let n = s.normal.unwrap_or(s.axis);
    assert!((n.norm() - 1.0).abs() < 1e-12, "n {n:?}");
    assert!(f.dot(&n).abs() < 1e-12, "f·n {}", f.dot(&n));
    let g = n.cross(&f);
    assert!((g.norm() - 1.0).abs() < 1e-12);
    assert!(g.dot(&f).abs() < 1e-12 && g.dot(&n).abs() < 1e-12);
    assert!((f.cross(&g) - n).norm() < 1e-12);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn fz_mode_samples_lie_on_the_path_at_even_spacing(
        steps in prop::collection::vec(step(), 2..12),
        fz in 0.01..0.5f64,
        contact in any::<bool>(),
        nlerp in any::<bool>(),
    ) {
        let path = build(&steps, contact);
        let kind = if nlerp { AxisInterpolation::Nlerp } else { AxisInterpolation::Slerp };
        let opts = Options::new(Mode::FeedPerTooth, fz, 4).with_axis_interpolation(kind);
        let mut samples = Vec::new();
        let stats = resample_with(&path, &opts, |s| samples.push(s.clone())).unwrap();
        prop_assert_eq!(stats.samples as usize, samples.len());
        for s in &samples {
            prop_assert!(distance_to_run(&path, s.run, &s.position) < 1e-9);
            check_frame(s);
            prop_assert_eq!(s.contact.is_some(), contact);
        }
        for w in samples.windows(2) {
            if w[0].run != w[1].run {
                continue;
            }
            let ds = w[1].s_mm - w[0].s_mm;
            let chord = (w[1].position - w[0].position).norm();
            prop_assert!(chord <= ds + 1e-9, "chord {} > ds {}", chord, ds);
            prop_assert!(w[1].t_s > w[0].t_s && w[1].theta_rad > w[0].theta_rad);
            let last_of_run = samples
                .iter()
                .rfind(|s| s.run == w[1].run)
                .is_some_and(|l| std::ptr::eq(l, &w[1]));
            if last_of_run {
                prop_assert!(ds <= fz * (1.0 + 1e-6) + 1e-12, "last ds {} > fz {}", ds, fz);
            } else {
                prop_assert!((ds - fz).abs() < 1e-9, "ds {} vs fz {}", ds, fz);
            }
        }
        // Both ends of every run are kept.
        for (run, r) in path.cutting_runs().iter().enumerate() {
            let of_run: Vec<_> = samples.iter().filter(|s| s.run == run).collect();
            if let (Some(first), Some(last)) = (of_run.first(), of_run.last()) {
                prop_assert!((first.position - path.postures[r.start].position).norm() < 1e-9);
                prop_assert!((last.position - path.postures[r.end - 1].position).norm() < 1e-9);
                prop_assert_eq!(first.t_s, 0.0);
            }
        }
    }

    #[test]
    fn dtheta_mode_steps_theta_exactly(
        steps in prop::collection::vec(step(), 2..8),
        dtheta_deg in 2.0..30.0f64,
        fz in 0.02..0.2f64,
        teeth in 1usize..6,
        posture_feed in any::<bool>(),
    ) {
        let path = build(&steps, true);
        let dtheta = dtheta_deg.to_radians();
        let mut opts = Options::new(Mode::SpindleStep { dtheta_rad: dtheta }, fz, teeth);
        if posture_feed {
            let feeds = (0..path.postures.len()).map(|i| 300.0 + 250.0 * (i % 4) as f64).collect();
            opts = opts.with_rpm(6000.0).with_posture_feed_mm_min(feeds);
        }
        let samples = resample(&path, &opts).unwrap();
        // The spindle is derived from fz and the highest programmed cutting feed.
        let v_ref = path
            .cutting_runs()
            .iter()
            .flat_map(|r| (r.start + 1)..r.end)
            .filter_map(|i| path.postures[i].feed_mm_min)
            .fold(0.0, f64::max);
        for s in &samples {
            prop_assert!(distance_to_run(&path, s.run, &s.position) < 1e-9);
            check_frame(s);
        }
        for (i, w) in samples.windows(2).enumerate() {
            if w[0].run != w[1].run {
                continue;
            }
            let last_of_run = samples.get(i + 2).is_none_or(|n| n.run != w[1].run);
            let dth = w[1].theta_rad - w[0].theta_rad;
            if last_of_run {
                prop_assert!(dth > 0.0 && dth <= dtheta * (1.0 + 1e-6));
            } else {
                prop_assert!((dth - dtheta).abs() < 1e-12 * (1.0 + w[1].theta_rad), "dθ {}", dth);
                prop_assert!(w[1].s_mm >= w[0].s_mm);
            }
            let omega = w[1].theta_rad / w[1].t_s.max(1e-300);
            if w[1].t_s > 0.0 && !posture_feed {
                // θ = Ω t.
                let expected = v_ref / (teeth as f64 * fz) * TAU / 60.0;
                prop_assert!((omega - expected).abs() < 1e-9 * expected);
            }
        }
    }

    #[test]
    fn arcs_with_extra_turns_are_sampled_on_the_helix(
        r in 0.5..20.0f64,
        start in 0.0..TAU,
        sweep in 0.05..6.2f64,
        turns in 0u32..3,
        rise in -3.0..3.0f64,
        ccw in any::<bool>(),
        fz in 0.05..1.0f64,
    ) {
        let axis = if ccw { -Vec3::z() } else { Vec3::z() };
        let centre = Point3::new(1.0, 2.0, 3.0);
        // Clockwise about +z: the angle decreases.
        let sign = if ccw { 1.0 } else { -1.0 };
        let at = |phi: f64, h: f64| centre + Vec3::new(r * phi.cos(), r * phi.sin(), h);
        let p0 = at(start, 0.0);
        let p1 = at(start + sign * sweep, rise);
        let posture = |p: Point3, motion, arc| Posture {
            position: p,
            axis: Vec3::z(),
            motion,
            arc,
            contact: None,
            feed_mm_min: Some(800.0),
            spindle_rpm: None,
            line: 1,
        };
        let arc = ArcMove { centre, axis, radius_mm: r, extra_turns: turns };
        let path = Toolpath {
            postures: vec![posture(p0, MotionKind::Rapid, None), posture(p1, MotionKind::Cut, Some(arc))],
            ..Default::default()
        };
        let total = sweep + TAU * turns as f64;
        let len = total * (r * r + (rise / total).powi(2)).sqrt();
        let mut samples = Vec::new();
        let stats = resample_with(&path, &Options::new(Mode::FeedPerTooth, fz, 2), |s| samples.push(s.clone())).unwrap();
        prop_assert_eq!(stats.arcs, 1);
        prop_assert!((stats.length_mm - len).abs() < 1e-9 * len.max(1.0));
        // A grid sample within 1e-6 fz of the end is the end itself.
        prop_assert_eq!(samples.len() as f64, (len / fz - 1e-6).ceil() + 1.0);
        for s in &samples {
            let phi = start + sign * s.s_mm / len * total;
            let h = rise * s.s_mm / len;
            prop_assert!((s.position - at(phi, h)).norm() < 1e-9);
            check_frame(s);
        }
        prop_assert!((samples.last().unwrap().position - p1).norm() < 1e-9);
    }
}
