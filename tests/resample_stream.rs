//! The incremental [`Resampler`] (postures pushed one at a time, as `crest resample`
//! streams a file) gives bit-identical samples and identical counts to [`resample_with`]
//! on the whole path: random paths with several cutting runs, rapids, arcs, zero-length
//! moves, FEDRAT changes, contact data or not, per-posture feeds, both modes, the spline.

use crest::math::{Point3, Vec3};
use crest::resample::{
    AxisInterpolation, Mode, Options, ResampleError, Resampler, Sample, SpindleScan, SpindleSource,
    Stats, resample_with,
};
use crest::toolpath::{ArcMove, Contact, MotionKind, Posture, Toolpath};
use proptest::prelude::*;
use std::f64::consts::TAU;

/// A random posture: displacement, axis (polar, azimuth), normal (polar, azimuth),
/// kind (0-6 cut, 7 rapid, 8 arc, 9 zero-length), feed index.
type Step = ([f64; 3], [f64; 2], [f64; 2], u8, u8);

fn step() -> impl Strategy<Value = Step> {
    (
        [-2.0..2.0f64, -2.0..2.0f64, -0.5..0.5f64],
        [0.0..1.0f64, 0.0..TAU],
        [0.0..0.78f64, 0.0..TAU],
        0u8..10,
        0u8..4,
    )
}

fn unit(polar: f64, azimuth: f64) -> Vec3 {
    Vec3::new(
        polar.sin() * azimuth.cos(),
        polar.sin() * azimuth.sin(),
        polar.cos(),
    )
}

fn build(steps: &[Step], contact: bool, feed_changes: bool) -> Toolpath {
    let mut position = Point3::origin();
    let mut postures: Vec<Posture> = Vec::new();
    for (i, (d, a, n, kind, feed)) in steps.iter().enumerate() {
        let start = position;
        let mut arc = None;
        match kind {
            9 => {}
            8 => {
                // An arc about a vertical axis through a centre beside the start.
                let centre = start + Vec3::new(d[0], d[1], 0.0);
                let r = (start - centre).norm();
                let phi = 0.3 + 0.5 * a[1];
                let v = start - centre;
                let (s, c) = phi.sin_cos();
                // Clockwise about +z by φ.
                let rot = Vec3::new(c * v.x + s * v.y, -s * v.x + c * v.y, 0.0);
                position = centre + rot + Vec3::new(0.0, 0.0, d[2]);
                arc = Some(ArcMove {
                    centre,
                    axis: Vec3::z(),
                    radius_mm: r,
                    extra_turns: u32::from(*feed == 3),
                });
            }
            _ => position += Vec3::new(d[0], d[1], d[2]),
        }
        let motion = if i == 0 || *kind == 7 {
            MotionKind::Rapid
        } else {
            MotionKind::Cut
        };
        postures.push(Posture {
            position,
            axis: unit(a[0], a[1]),
            motion,
            arc,
            contact: contact.then(|| Contact {
                point: position + Vec3::new(0.3, -0.2, -1.0),
                normal: unit(n[0], n[1]),
                normal_derived: false,
            }),
            feed_mm_min: Some(if feed_changes {
                400.0 + 300.0 * f64::from(*feed)
            } else {
                1200.0
            }),
            spindle_rpm: Some(9000.0),
            line: i as u32 + 1,
        });
    }
    Toolpath {
        postures,
        ..Default::default()
    }
}

/// Push the postures one by one; the spindle from a scan of the whole path when `scan`,
/// else resolved by the resampler at the first cutting move.
fn streamed(
    path: &Toolpath,
    opts: &Options,
    scan: bool,
) -> Result<(Vec<Sample>, Stats), ResampleError> {
    let mut r = Resampler::new(opts)?;
    if scan {
        let mut sc = SpindleScan::new();
        for p in &path.postures {
            sc.push(p);
        }
        if let Some((rpm, source)) = sc.resolve(opts)? {
            r = r.with_spindle(rpm, source);
        }
    }
    let mut out = Vec::new();
    for (i, p) in path.postures.iter().enumerate() {
        match &opts.posture_feed_mm_min {
            Some(f) => r.push_with_feed(p, f[i], |s| out.push(s.clone()))?,
            None => r.push(p, |s| out.push(s.clone()))?,
        }
    }
    let stats = r.finish(|s| out.push(s.clone()))?;
    Ok((out, stats))
}

fn whole(path: &Toolpath, opts: &Options) -> Result<(Vec<Sample>, Stats), ResampleError> {
    let mut out = Vec::new();
    let stats = resample_with(path, opts, |s| out.push(s.clone()))?;
    Ok((out, stats))
}

/// Bit-identical samples (f64 `==` on every field, NaN excluded by the resampler).
fn assert_same(a: &[Sample], b: &[Sample]) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x, y);
        assert_eq!(x.s_mm.to_bits(), y.s_mm.to_bits());
        assert_eq!(x.theta_rad.to_bits(), y.theta_rad.to_bits());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn streaming_equals_whole_path(
        steps in prop::collection::vec(step(), 1..16),
        contact in any::<bool>(),
        feed_changes in any::<bool>(),
        spline in any::<bool>(),
        nlerp in any::<bool>(),
        dtheta in any::<bool>(),
        posture_feed in any::<bool>(),
        fz in 0.05..0.5f64,
    ) {
        let path = build(&steps, contact, feed_changes);
        let mode = if dtheta {
            Mode::SpindleStep { dtheta_rad: 20f64.to_radians() }
        } else {
            Mode::FeedPerTooth
        };
        let kind = if nlerp { AxisInterpolation::Nlerp } else { AxisInterpolation::Slerp };
        let mut opts = Options::new(mode, fz, 3)
            .with_axis_interpolation(kind)
            .with_spline(spline);
        if posture_feed {
            let feeds = (0..path.postures.len()).map(|i| 300.0 + 250.0 * (i % 4) as f64).collect();
            opts = opts.with_posture_feed_mm_min(feeds);
        }
        let reference = whole(&path, &opts);
        let scanned = streamed(&path, &opts, true);
        match (&reference, &scanned) {
            (Ok((a, sa)), Ok((b, sb))) => {
                assert_same(a, b);
                prop_assert_eq!(sa, sb);
                prop_assert_eq!(sa.samples as usize, a.len());
            }
            (Err(a), Err(b)) => prop_assert_eq!(a, b),
            _ => prop_assert!(false, "{:?} vs {:?}", reference.as_ref().err(), scanned.as_ref().err()),
        }
        // Resolved at the first cutting move: the same whenever no later cutting move is
        // faster than the first (always with a constant FEDRAT).
        if !feed_changes && !posture_feed {
            let lazy = streamed(&path, &opts, false);
            match (&reference, &lazy) {
                (Ok((a, sa)), Ok((b, sb))) => {
                    assert_same(a, b);
                    prop_assert_eq!(sa, sb);
                }
                (Err(a), Err(b)) => prop_assert_eq!(a, b),
                _ => prop_assert!(false, "{:?} vs {:?}", reference.as_ref().err(), lazy.as_ref().err()),
            }
        }
    }
}

#[test]
fn lazy_spindle_is_the_first_cutting_feed_and_the_scan_the_highest() {
    let posture = |x: f64, motion, feed: f64| Posture {
        position: Point3::new(x, 0.0, 0.0),
        axis: Vec3::z(),
        motion,
        arc: None,
        contact: None,
        feed_mm_min: Some(feed),
        spindle_rpm: None,
        line: 1,
    };
    let ps = [
        posture(0.0, MotionKind::Rapid, 250.0),
        posture(1.0, MotionKind::Cut, 250.0),
        posture(2.0, MotionKind::Cut, 1000.0),
    ];
    let opts = Options::new(Mode::FeedPerTooth, 0.05, 4);
    let mut r = Resampler::new(&opts).unwrap();
    let mut scan = SpindleScan::new();
    for p in &ps {
        scan.push(p);
        r.push(p, |_| {}).unwrap();
    }
    // 250/(4·0.05) = 1250 rpm at the first cutting move; 1000/(4·0.05) = 5000 over all.
    assert_eq!(r.spindle(), Some((1250.0, SpindleSource::DerivedFromFeed)));
    assert_eq!(
        scan.resolve(&opts).unwrap(),
        Some((5000.0, SpindleSource::DerivedFromFeed))
    );
    let path = Toolpath {
        postures: ps.to_vec(),
        ..Default::default()
    };
    let stats = resample_with(&path, &opts, |_| {}).unwrap();
    assert_eq!(stats.spindle_rpm, Some(5000.0));
    // Nothing cut yet: nothing resolved; the option wins over everything.
    assert_eq!(SpindleScan::new().resolve(&opts).unwrap(), None);
    assert_eq!(
        scan.resolve(&opts.clone().with_rpm(777.0)).unwrap(),
        Some((777.0, SpindleSource::Option))
    );
}
