//! Machines and feed planning: the validation cases of kinematics.md §8 (K1, K1b, K2, K3,
//! K4, K6), its invariants and metamorphic checks on the Table I machines (T = 3 ms,
//! e = 0.01 mm / 0.01 deg); `predict_posture_feed` and `plan_path` on tool paths built here;
//! `crest feed` on real NX files; `--feed programmed|predicted --machine` on
//! `crest resample` and `crest simulate`.

use std::path::Path;

use approx::{abs_diff_eq, assert_abs_diff_eq, assert_relative_eq};
use crest::kinematics::{
    FeedPlan, KinematicsError, Level, Machine, PlanInput, Pose, plan_path, plan_poses,
    pose_tilt_azimuth, predict_posture_feed,
};
use crest::math::{Point3, Vec3};
use crest::toolpath::{MotionKind, Posture, Toolpath};
use predicates::prelude::*;

use crate::util::{
    RESAMPLE_HEADER, column, crest, external_samples, nx_sample, read_number_csv, repo_file,
    stdout_json, tempdir,
};

/// The Table I machine of 000 (A/C), and the same limits on a nutating table (A at 45°
/// carrying C).
const AC: &str = repo_file!("samples/machines/table1_ac.toml");
const NUT: &str = repo_file!("samples/machines/table1_nutating45.toml");
const AC_TOML: &str = include_str!(repo_file!("samples/machines/table1_ac.toml"));
const NUT_TOML: &str = include_str!(repo_file!("samples/machines/table1_nutating45.toml"));

// ---------------------------------------------------------------------------------------
// kinematics.md §8 validation cases
// ---------------------------------------------------------------------------------------

/// Interpolation cycle of the Table I machine, s.
const T: f64 = 0.003;

fn machine() -> Machine {
    Machine::from_toml_str(AC_TOML).unwrap()
}

fn vertical(tip: [f64; 3]) -> Pose {
    Pose {
        tip: Point3::new(tip[0], tip[1], tip[2]),
        axis: Vec3::z(),
    }
}

fn inputs(poses: &[Pose], feed_mm_min: f64) -> Vec<PlanInput> {
    poses
        .iter()
        .map(|&pose| PlanInput {
            pose,
            feed_mm_s: feed_mm_min / 60.0,
            exact_stop: false,
            line: 0,
        })
        .collect()
}

fn plan(m: &Machine, poses: &[Pose], feed_mm_min: f64) -> FeedPlan {
    plan_poses(&inputs(poses, feed_mm_min), m, Level::Jerk).unwrap()
}

/// §8 invariants: self-check, no fallback, t strictly increasing, rest at both ends, not
/// faster than Level 1.
fn check_invariants(p: &FeedPlan) {
    assert!(
        p.self_check_ok(),
        "axis {} ceiling {} fallbacks {}",
        p.max_axis_ratio,
        p.max_ceiling_ratio,
        p.fallbacks
    );
    assert_eq!(p.stop_recoveries, 0);
    for w in p.postures.windows(2) {
        assert!(
            w[1].t_s > w[0].t_s,
            "t not increasing: {} {}",
            w[0].t_s,
            w[1].t_s
        );
    }
    assert_eq!(p.postures[0].path_speed_mm_s, 0.0);
    assert_eq!(p.postures.last().unwrap().path_speed_mm_s, 0.0);
    assert!(
        p.total_time_s >= p.level1_time_s - 1e-12,
        "{} < L1 {}",
        p.total_time_s,
        p.level1_time_s
    );
}

fn within(got: f64, oracle: f64, below: f64, cycles_above: f64) {
    eprintln!(
        "time {got:.6} oracle {oracle:.6} diff {:+.3} ms",
        (got - oracle) * 1e3
    );
    assert!(
        got >= oracle - below && got <= oracle + cycles_above * T,
        "time {got} outside [{}, {}]",
        oracle - below,
        oracle + cycles_above * T
    );
}

/// The reference implementation's time: a port must match it within max(2 cycles, 0.2 %).
#[track_caller]
fn near_ref(got: f64, reference: f64) {
    assert_relative_eq!(got, reference, epsilon = 2.0 * T, max_relative = 0.002);
}

fn max_speed(p: &FeedPlan) -> f64 {
    p.postures
        .iter()
        .map(|q| q.path_speed_mm_s)
        .fold(0.0, f64::max)
}

#[test]
fn k1_single_block_rest_to_rest() {
    let m = machine();
    let p = plan(
        &m,
        &[vertical([0.0; 3]), vertical([100.0, 0.0, 0.0])],
        5000.0,
    );
    check_invariants(&p);
    // T = L/F + 2 sqrt(F/J) = 1.291287 s.
    let f = 5000.0 / 60.0;
    let oracle = 100.0 / f + 2.0 * (f / 40000.0f64).sqrt();
    assert_abs_diff_eq!(oracle, 1.291287, epsilon = 1e-6);
    within(p.total_time_s, oracle, 0.5e-3, 2.0);
    near_ref(p.total_time_s, 1.291305);
    // Level 1: 1.216667 s.
    assert_abs_diff_eq!(p.level1_time_s, 1.216667, epsilon = 1e-6);
}

#[test]
fn k1_peak_speed_is_the_programmed_feed() {
    // Sample the plateau with intermediate collinear postures (block-cycle rule off).
    let mut m = machine();
    m.min_block_cycles = 0.0;
    let poses: Vec<Pose> = (0..=100).map(|i| vertical([i as f64, 0.0, 0.0])).collect();
    let p = plan(&m, &poses, 5000.0);
    check_invariants(&p);
    let vmax = max_speed(&p);
    assert_relative_eq!(vmax, 5000.0 / 60.0, max_relative = 0.005);
    let mid = &p.postures[50];
    assert_abs_diff_eq!(mid.feed_mm_s * 60.0, 5000.0, epsilon = 25.0);
    let f = 5000.0 / 60.0;
    within(
        p.total_time_s,
        100.0 / f + 2.0 * (f / 40000.0f64).sqrt(),
        0.5e-3,
        2.0,
    );
}

#[test]
fn k1b_peak_limited_by_distance() {
    let m = machine();
    let p = plan(
        &m,
        &[vertical([0.0; 3]), vertical([100.0, 0.0, 0.0])],
        50_000.0,
    );
    check_invariants(&p);
    within(p.total_time_s, 0.430887, 0.5e-3, 2.0);
    near_ref(p.total_time_s, 0.430892);
    // Peak 27.8495 m/min, sampled with collinear postures.
    let poses: Vec<Pose> = (0..=200)
        .map(|i| vertical([0.5 * i as f64, 0.0, 0.0]))
        .collect();
    let mut m0 = machine();
    m0.min_block_cycles = 0.0;
    let q = plan(&m0, &poses, 50_000.0);
    let vmax = max_speed(&q) * 0.06;
    assert_relative_eq!(vmax, 27.8495, max_relative = 0.005);
    within(q.total_time_s, 0.430887, 0.5e-3, 2.0);
}

#[test]
fn k2_corner() {
    let m = machine();
    let poses = [
        vertical([0.0; 3]),
        vertical([50.0, 0.0, 0.0]),
        vertical([50.0, 50.0, 0.0]),
    ];
    let p = plan(&m, &poses, 5000.0);
    check_invariants(&p);
    // Junction speed sqrt(8·5000·0.01) = 20 mm/s.
    let vc = p.postures[1].path_speed_mm_s;
    assert_relative_eq!(vc, 20.0, max_relative = 0.005);
    within(p.total_time_s, 1.329543, 1e-3, 2.0);
    near_ref(p.total_time_s, 1.329201);
    assert_abs_diff_eq!(p.level1_time_s, 1.226293, epsilon = 1e-5);
}

#[test]
fn k3_ac_rotary_bound_block() {
    let m = machine();
    let poses = [
        pose_tilt_azimuth([0.0, 0.0, 0.0], 30.0, 0.0),
        pose_tilt_azimuth([0.0, 0.0, 20.0], 30.0, 120.0),
    ];
    let p = plan(&m, &poses, 5000.0);
    check_invariants(&p);
    let (q0, q1) = (p.postures[0].joints, p.postures[1].joints);
    let deg = |x: f64| x.to_degrees();
    assert_abs_diff_eq!(deg(q0[3]), 30.0, epsilon = 1e-9);
    assert_abs_diff_eq!(deg(q1[3]), 30.0, epsilon = 1e-9);
    assert_abs_diff_eq!(deg(q0[4]), 90.0, epsilon = 1e-9);
    assert_abs_diff_eq!(deg(q1[4]), -30.0, epsilon = 1e-9);
    assert_abs_diff_eq!(q1[1] - q0[1], -10.0, epsilon = 1e-9);
    assert_abs_diff_eq!(
        q1[2] - q0[2],
        20.0 * 30f64.to_radians().cos(),
        epsilon = 1e-9
    );
    let b = &p.blocks;
    assert_abs_diff_eq!(b.vbar[0], 50.0, epsilon = 1e-9);
    assert_abs_diff_eq!(b.abar[0], 180.0, epsilon = 1e-9);
    assert_abs_diff_eq!(b.jbar[0], 6000.0, epsilon = 1e-9);
    within(
        p.total_time_s,
        20.0 / 50.0 + 50.0 / 180.0 + 180.0 / 6000.0,
        0.5e-3,
        2.0,
    );
    near_ref(p.total_time_s, 0.707782);
}

#[test]
fn k3_plateau_cl_feed_is_50_mm_s() {
    // Same move cut into 40 postures on the same linear joint path: the Eq 6 feed on the
    // plateau is 50 mm/s (the tip stays on the C axis).
    let mut m = machine();
    m.min_block_cycles = 0.0;
    let poses: Vec<Pose> = (0..=40)
        .map(|i| {
            let u = i as f64 / 40.0;
            pose_tilt_azimuth([0.0, 0.0, 20.0 * u], 30.0, 120.0 * u)
        })
        .collect();
    let p = plan(&m, &poses, 5000.0);
    check_invariants(&p);
    let mid = &p.postures[20];
    assert_abs_diff_eq!(mid.path_speed_mm_s, 50.0, epsilon = 0.25);
    assert_abs_diff_eq!(mid.feed_mm_s, 50.0, epsilon = 0.25);
    assert_eq!(mid.limit.label(&m.joint_names()), "vmax:C");
}

#[test]
fn k4_block_cycle_cap() {
    let m = machine();
    let poses: Vec<Pose> = (0..=100)
        .map(|i| vertical([0.1 * i as f64, 0.0, 0.0]))
        .collect();
    let p = plan(&m, &poses, 5000.0);
    check_invariants(&p);
    let cap = 0.1 / 0.003;
    let oracle = 10.0 / cap + 2.0 * (cap / 40000.0f64).sqrt();
    assert_abs_diff_eq!(oracle, 0.357735, epsilon = 1e-6);
    within(p.total_time_s, oracle, 0.5e-3, 2.0);
    near_ref(p.total_time_s, 0.358071);
    assert_relative_eq!(max_speed(&p), cap, max_relative = 0.005);
    assert_eq!(p.postures[50].limit.label(&m.joint_names()), "block_cycle");
}

fn k6_roundtrip(m: &Machine, tilts: &[f64]) {
    let tip = Point3::new(10.0, -5.0, 3.0);
    for &tilt in tilts {
        for az in (0..360).step_by(15) {
            let pose = pose_tilt_azimuth([10.0, -5.0, 3.0], tilt, az as f64);
            let sols = m.rotary_solutions(&pose.axis).expect("reachable");
            for s in sols {
                let mut q = [0.0, 0.0, 0.0, s[0].unwrap_or(0.0), s[1].unwrap_or(0.0)];
                m.linear_joints(&mut q, &tip);
                let f = m.forward(&q);
                assert!(
                    (f.tip - tip).norm() < 1e-12,
                    "tilt {tilt} az {az}: tip {:?}",
                    f.tip
                );
                assert!((f.axis - pose.axis).norm() < 1e-12, "tilt {tilt} az {az}");
            }
        }
    }
}

#[test]
fn k6_ac_roundtrip_and_example() {
    let m = machine();
    k6_roundtrip(&m, &[0.0, 5.0, 30.0, 60.0, 90.0, 110.0]);
}

#[test]
fn k6_nutating_table_roundtrip_and_example() {
    let m = Machine::from_toml_str(NUT_TOML).unwrap();
    k6_roundtrip(&m, &[0.0, 10.0, 45.0, 60.0, 89.0]);
    // Tilt 60 / azimuth 45 → A = ±90°, C = 99.736 / −9.736.
    let u = pose_tilt_azimuth([0.0; 3], 60.0, 45.0).axis;
    let mut got: Vec<(f64, f64)> = m
        .rotary_solutions(&u)
        .unwrap()
        .iter()
        .map(|s| {
            (
                crest::math::wrap_pi(s[0].unwrap()).to_degrees(),
                crest::math::wrap_pi(s[1].unwrap()).to_degrees(),
            )
        })
        .collect();
    got.sort_by(|a, b| b.0.total_cmp(&a.0));
    assert!(
        abs_diff_eq!(got[0].0, 90.0, epsilon = 1e-6)
            && abs_diff_eq!(got[1].0, -90.0, epsilon = 1e-6),
        "{got:?}"
    );
    let mut cs = [got[0].1, got[1].1];
    cs.sort_by(f64::total_cmp);
    assert!(
        abs_diff_eq!(cs[0], -9.736, epsilon = 1e-3) && abs_diff_eq!(cs[1], 99.736, epsilon = 1e-3),
        "{got:?}"
    );
    // Beyond 90° of tilt the nutating pair cannot reach.
    assert!(
        m.rotary_solutions(&pose_tilt_azimuth([0.0; 3], 100.0, 0.0).axis)
            .is_none()
    );
}

#[test]
fn k6_c_table_b45_head_roundtrip() {
    let text = AC_TOML
        .replacen("name = \"A\"\nside = \"table\"", "name = \"C\"\nside = \"table\"", 1)
        .replacen("axis = [1.0, 0.0, 0.0]", "axis = [0.0, 0.0, 1.0]", 1)
        .replacen(
            "name = \"C\"\nside = \"table\"\naxis = [0.0, 0.0, 1.0]\npoint = [0.0, 0.0, 0.0]",
            "name = \"B\"\nside = \"head\"\naxis = [0.0, 0.70710678118654752, 0.70710678118654752]\npoint = [0.0, 0.0, 150.0]",
            1,
        )
        .replacen("tip_home = [0.0, 0.0, 0.0]", "tip_home = [0.0, 0.0, -80.0]", 1)
        .replacen("limits = [-120.0, 120.0]", "limits = []", 1);
    let m = Machine::from_toml_str(&text).unwrap();
    assert_eq!(m.joint_names(), ["X", "Y", "Z", "C", "B"]);
    k6_roundtrip(&m, &[0.0, 10.0, 45.0, 60.0, 89.0]);
}

#[test]
fn metamorphic_double_jerk_never_slower() {
    let m = machine();
    let mut m2 = machine();
    for l in m2.linear.iter_mut() {
        l.limits.jmax *= 2.0;
    }
    for r in m2.rotary.iter_mut() {
        r.limits.jmax *= 2.0;
    }
    let poses = [
        vertical([0.0; 3]),
        vertical([50.0, 0.0, 0.0]),
        vertical([50.0, 50.0, 0.0]),
    ];
    let a = plan(&m, &poses, 5000.0);
    let b = plan(&m2, &poses, 5000.0);
    check_invariants(&b);
    assert!(
        b.total_time_s <= a.total_time_s + 1e-9,
        "{} > {}",
        b.total_time_s,
        a.total_time_s
    );
}

#[test]
fn metamorphic_larger_tolerance_never_lowers_ceilings() {
    let m = machine();
    let mut m2 = machine();
    for l in m2.linear.iter_mut() {
        l.limits.tol *= 3.0;
    }
    let poses: Vec<Pose> = (0..=36)
        .map(|k| {
            let t = (10.0 * k as f64).to_radians();
            pose_tilt_azimuth([10.0 * t.cos(), 10.0 * t.sin(), 0.0], 20.0, 5.0 * k as f64)
        })
        .collect();
    let a = plan(&m, &poses, 5000.0);
    let b = plan(&m2, &poses, 5000.0);
    for (x, y) in a.blocks.ceil.iter().zip(&b.blocks.ceil) {
        assert!(y >= x, "{y} < {x}");
    }
    check_invariants(&a);
    check_invariants(&b);
}

#[test]
fn metamorphic_splitting_a_block_keeps_the_time() {
    let mut m = machine();
    m.min_block_cycles = 0.0;
    let one = plan(
        &m,
        &[vertical([0.0; 3]), vertical([30.0, 0.0, 0.0])],
        5000.0,
    );
    let two = plan(
        &m,
        &[
            vertical([0.0; 3]),
            vertical([13.0, 0.0, 0.0]),
            vertical([30.0, 0.0, 0.0]),
        ],
        5000.0,
    );
    check_invariants(&two);
    assert_abs_diff_eq!(one.total_time_s, two.total_time_s, epsilon = 2.0 * T);
}

// ---------------------------------------------------------------------------------------
// `predict_posture_feed` and `plan_path` on tool paths built here: the feed the
// resampling and simulation stages take per posture.
// ---------------------------------------------------------------------------------------

fn posture(p: [f64; 3], axis: Vec3, motion: MotionKind, feed: Option<f64>, line: u32) -> Posture {
    Posture {
        feed_mm_min: feed,
        spindle_rpm: Some(10_000.0),
        line,
        ..crate::util::posture(Point3::new(p[0], p[1], p[2]), axis, motion)
    }
}

/// A rapid approach, then a zigzag of 0.5 mm blocks at 5 m/min with a tilting tool axis,
/// then a rapid retract.
fn zigzag() -> Toolpath {
    let mut ps = vec![
        posture([0.0, 0.0, 50.0], Vec3::z(), MotionKind::From, None, 1),
        posture([0.0, 0.0, 5.0], Vec3::z(), MotionKind::Rapid, None, 2),
    ];
    let mut line = 3;
    for pass in 0..3 {
        for i in 0..=80 {
            let x = if pass % 2 == 0 {
                0.5 * i as f64
            } else {
                40.0 - 0.5 * i as f64
            };
            let y = 2.0 * pass as f64;
            let tilt = (x / 40.0 * 20.0).to_radians();
            let axis = Vec3::new(tilt.sin(), 0.0, tilt.cos());
            ps.push(posture(
                [x, y, 0.1 * x],
                axis,
                MotionKind::Cut,
                Some(5000.0),
                line,
            ));
            line += 1;
        }
    }
    ps.push(posture(
        [40.0, 4.0, 50.0],
        Vec3::z(),
        MotionKind::Rapid,
        None,
        line,
    ));
    Toolpath {
        name: "zigzag".into(),
        postures: ps,
        ..Default::default()
    }
}

#[test]
fn predicted_feed_has_one_value_per_posture_and_respects_the_program() {
    for text in [AC_TOML, NUT_TOML] {
        let m = Machine::from_toml_str(text).unwrap();
        let path = zigzag();
        let feed = predict_posture_feed(&path, &m).unwrap();
        assert_eq!(feed.len(), path.postures.len());
        assert_eq!(feed[0], 0.0);
        assert_eq!(*feed.last().unwrap(), 0.0);
        // Exact stops where rapid and feed motion meet.
        assert_eq!(feed[1], 0.0);
        // Inside the passes: under 5 m/min plus the Eq 6 chord effect, and well above zero
        // somewhere.
        let cut = &feed[2..feed.len() - 1];
        assert!(cut.iter().all(|f| *f <= 5000.0 * 1.05), "{cut:?}");
        assert!(cut.iter().any(|f| *f > 1500.0), "{cut:?}");
        let plan = plan_path(&path, &m, Level::Jerk).unwrap();
        assert!(
            plan.self_check_ok(),
            "{} {} {}",
            plan.max_axis_ratio,
            plan.max_ceiling_ratio,
            plan.fallbacks
        );
        assert!(plan.total_time_s > plan.programmed_time_s);
        assert!(plan.total_time_s >= plan.level1_time_s);
        for w in plan.postures.windows(2) {
            assert!(w[1].t_s > w[0].t_s);
        }
    }
}

#[test]
fn travel_limits_give_an_error_with_the_line() {
    let m = Machine::from_toml_str(AC_TOML).unwrap();
    let t = 130f64.to_radians();
    let path = Toolpath {
        postures: vec![
            posture([0.0; 3], Vec3::z(), MotionKind::From, None, 7),
            posture(
                [1.0, 0.0, 0.0],
                Vec3::new(t.sin(), 0.0, t.cos()),
                MotionKind::Cut,
                Some(1000.0),
                8,
            ),
        ],
        ..Default::default()
    };
    let e = predict_posture_feed(&path, &m).unwrap_err();
    assert_eq!(e, KinematicsError::Travel { index: 1, line: 8 });
    assert!(e.to_string().starts_with("line 8:"));
    // Far into a long path (the IKT works in chunks of postures): the same error, with
    // the index and line of the first bad posture, before a non-finite one further on.
    let mut long: Vec<_> = (0..40_000)
        .map(|i| {
            let kind = if i == 0 {
                MotionKind::From
            } else {
                MotionKind::Cut
            };
            posture(
                [i as f64 * 0.01, 0.0, 0.0],
                Vec3::z(),
                kind,
                Some(1000.0),
                10 + i,
            )
        })
        .collect();
    long[33_333].axis = Vec3::new(t.sin(), 0.0, t.cos());
    long[39_000].position.x = f64::NAN;
    let long = Toolpath {
        postures: long,
        ..Default::default()
    };
    let e = predict_posture_feed(&long, &m).unwrap_err();
    assert_eq!(
        e,
        KinematicsError::Travel {
            index: 33_333,
            line: 33_343
        }
    );
    // The nutating pair cannot tilt beyond 90°.
    let m = Machine::from_toml_str(NUT_TOML).unwrap();
    let e = predict_posture_feed(&path, &m).unwrap_err();
    assert!(
        matches!(
            e,
            KinematicsError::Unreachable {
                index: 1,
                line: 8,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn degenerate_paths_do_not_panic() {
    let m = Machine::from_toml_str(AC_TOML).unwrap();
    let empty = Toolpath::default();
    assert!(predict_posture_feed(&empty, &m).unwrap().is_empty());
    let one = Toolpath {
        postures: vec![posture(
            [1.0, 2.0, 3.0],
            Vec3::z(),
            MotionKind::From,
            None,
            1,
        )],
        ..Default::default()
    };
    assert_eq!(predict_posture_feed(&one, &m).unwrap(), vec![0.0]);
    // Repeated postures and a pure re-orientation.
    let t = 10f64.to_radians();
    let rep = Toolpath {
        postures: vec![
            posture([0.0; 3], Vec3::z(), MotionKind::From, None, 1),
            posture([5.0, 0.0, 0.0], Vec3::z(), MotionKind::Cut, Some(3000.0), 2),
            posture([5.0, 0.0, 0.0], Vec3::z(), MotionKind::Cut, Some(3000.0), 3),
            posture(
                [5.0, 0.0, 0.0],
                Vec3::new(t.sin(), 0.0, t.cos()),
                MotionKind::Cut,
                Some(3000.0),
                4,
            ),
            posture(
                [10.0, 0.0, 0.0],
                Vec3::new(t.sin(), 0.0, t.cos()),
                MotionKind::Cut,
                Some(3000.0),
                5,
            ),
        ],
        ..Default::default()
    };
    let plan = plan_path(&rep, &m, Level::Jerk).unwrap();
    assert!(
        plan.postures
            .iter()
            .all(|p| p.t_s.is_finite() && p.feed_mm_s.is_finite())
    );
    assert!(plan.fallbacks == 0);
    let nan = Toolpath {
        postures: vec![
            posture([0.0; 3], Vec3::z(), MotionKind::From, None, 1),
            posture(
                [f64::NAN, 0.0, 0.0],
                Vec3::z(),
                MotionKind::Cut,
                Some(3000.0),
                2,
            ),
        ],
        ..Default::default()
    };
    assert!(matches!(
        predict_posture_feed(&nan, &m),
        Err(KinematicsError::BadPosture { line: 2, .. })
    ));
}

// ---------------------------------------------------------------------------------------
// `crest feed` end to end on real NX files: JSON contract keys, CSV output, exit codes and
// machine-file errors that name the file and the line.
// ---------------------------------------------------------------------------------------

const CIRCLE: &str = "nx_circle_times_from.cls";
const VARC: &str = "nx_5axis_varcontour_ijk_small.cls";

#[test]
fn json_has_the_contract_keys() {
    let Some(ext) = external_samples() else {
        return;
    };
    let v = stdout_json(
        &crest()
            .arg("feed")
            .arg(ext.join(CIRCLE))
            .args(["--machine", AC, "--json"])
            .assert()
            .success(),
    );
    let total = v["total_time_s"].as_f64().unwrap();
    let programmed = v["programmed_time_s"].as_f64().unwrap();
    let ratio = v["time_ratio"].as_f64().unwrap();
    assert!(total >= programmed && programmed > 0.0);
    assert_abs_diff_eq!(ratio, total / programmed, epsilon = 1e-12);
    let path = &v["paths"][0];
    let postures = path["postures"].as_array().unwrap();
    assert!(postures.len() > 5);
    let mut last_t = -1.0;
    for p in postures {
        let t = p["t_s"].as_f64().unwrap();
        assert!(t > last_t);
        last_t = t;
        assert!(p["feed_mm_min"].as_f64().unwrap() >= 0.0);
        assert!(p["limit"].is_string());
        for j in ["X", "Y", "Z", "A", "C"] {
            assert!(p["joints"][j].is_number(), "{j}");
        }
    }
    assert_abs_diff_eq!(
        last_t,
        path["total_time_s"].as_f64().unwrap(),
        epsilon = 1e-9
    );
    assert_eq!(path["fallbacks"], 0);
}

#[test]
fn five_axis_file_on_both_machines_with_csv() {
    let Some(ext) = external_samples() else {
        return;
    };
    let dir = tempdir();
    for m in [AC, NUT] {
        let csv = dir.path().join("poses.csv");
        crest()
            .arg("feed")
            .arg(ext.join(VARC))
            .args(["--machine", m, "--absolute", "-o"])
            .arg(&csv)
            .assert()
            .success()
            .stdout(predicate::str::contains("VARIABLE_CONTOUR"));
        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines = text.lines();
        assert!(lines.next().unwrap().starts_with(
            "path,index,line,t_s,feed_mm_min,path_speed_mm_min,programmed_feed_mm_min,limit,branch,X,Y,Z,"
        ));
        assert_eq!(lines.count(), 546);
    }
    // In the MCS the tool points along −Z: beyond A's ±120° travel.
    crest()
        .arg("feed")
        .arg(ext.join(VARC))
        .args(["--machine", AC])
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "nx_5axis_varcontour_ijk_small.cls:11:1",
        ));
}

#[test]
fn feed_poses_chain_into_plot_feed() {
    let Some(ext) = external_samples() else {
        return;
    };
    let dir = tempdir();
    let csv = dir.path().join("poses.csv");
    crest()
        .arg("feed")
        .arg(ext.join(CIRCLE))
        .args(["--machine", AC, "-o"])
        .arg(&csv)
        .assert()
        .success();
    let svg = dir.path().join("feed.svg");
    let v = stdout_json(
        &crest()
            .args(["plot", "feed"])
            .arg(ext.join(CIRCLE))
            .args(["--json", "--actual"])
            .arg(&csv)
            .arg("-o")
            .arg(&svg)
            .assert()
            .success(),
    );
    let points = v["points"].as_u64().unwrap();
    assert!(points > 5);
    // Every cutting posture finds its planned feed by its source line.
    assert_eq!(v["actual_points"].as_u64().unwrap(), points);
    assert!(
        std::fs::read_to_string(&svg)
            .unwrap()
            .contains("actual (planned)")
    );
}

#[test]
fn bad_machine_names_file_key_and_line() {
    let dir = tempdir();
    let bad = dir.path().join("m.toml");
    let text = std::fs::read_to_string(AC)
        .unwrap()
        .replacen("amax = 5000.0", "amax = 5.0", 1);
    let line = text[..text.find("amax = 5.0").unwrap()].lines().count() + 1;
    std::fs::write(&bad, text).unwrap();
    crest()
        .arg("feed")
        .arg(nx_sample("nx_iso_header_units_mm.cls"))
        .arg("--machine")
        .arg(&bad)
        .assert()
        .code(2)
        .stderr(predicate::str::contains(format!("m.toml:{line}:1")))
        .stderr(predicate::str::contains("amax"));
}

// ---------------------------------------------------------------------------------------
// `--feed programmed|predicted --machine machine.toml` on `crest resample` and
// `crest simulate` (issue 8): on the 000 hyperbolic-paraboloid path at 5 m/min the Table I
// AC machine must slow down where the tool axis passes near the C pole, so the predicted
// feed, time stamps and cutting time differ from the programmed ones; the JSON says which
// feed was used; the option combinations that make no sense are refused.
// ---------------------------------------------------------------------------------------

const PARABOLOID: &str = repo_file!("samples/synth/hyperbolic-paraboloid.cls");
const TORUS: &str = repo_file!("samples/synth/torus-r5-rc1.5.toml");

/// `crest resample PARABOLOID --path 1 --mode fz …` with `extra`; the JSON and the (t_s,
/// feed_mm_min) columns.
fn resample(extra: &[&str]) -> (serde_json::Value, Vec<(f64, f64)>) {
    let dir = tempdir();
    let out = dir.path().join("r.csv");
    let a = crest()
        .args(["resample", PARABOLOID, "--path", "1", "--mode", "fz"])
        .args(["--fz-mm", "0.2", "--teeth", "1", "--json", "-o"])
        .arg(&out)
        .args(extra)
        .assert()
        .success();
    let json = stdout_json(&a);
    let (ti, fi) = (
        column(RESAMPLE_HEADER, "t_s"),
        column(RESAMPLE_HEADER, "feed_mm_min"),
    );
    let rows = read_number_csv(&out, RESAMPLE_HEADER)
        .iter()
        .map(|c| (c[ti].unwrap(), c[fi].unwrap()))
        .collect();
    (json, rows)
}

/// Cutting time of a resampled path: t restarts at 0 at every run, so add the runs' ends.
fn cut_time(rows: &[(f64, f64)]) -> f64 {
    let mut total = 0.0;
    for w in rows.windows(2) {
        if w[1].0 < w[0].0 {
            total += w[0].0;
        }
    }
    total + rows.last().map_or(0.0, |r| r.0)
}

#[test]
fn resample_predicted_feed_is_slower_than_programmed() {
    let (jp, prog) = resample(&[]);
    let (jm, pred) = resample(&["--feed", "predicted", "--machine", AC]);
    assert_eq!(jp["feed"], "programmed");
    assert_eq!(jm["feed"], "predicted");
    assert_eq!(jm["machine"], AC);
    // Programmed: 5000 mm/min everywhere in the cut.
    assert!(
        prog.iter()
            .all(|r| abs_diff_eq!(r.1, 5000.0, epsilon = 1e-6))
    );
    // Predicted: starting from rest, well below the programmed feed somewhere mid-path (the
    // C axis near its pole), and the run takes longer. The Eq 6 feed of the tool tip may
    // exceed F by a little: the planner bounds the speed along the chord between postures,
    // the tip follows the joint interpolation, which is a bit longer where A and C turn.
    let fmax = pred.iter().map(|r| r.1).fold(0.0, f64::max);
    let fmin_mid = pred[pred.len() / 4..3 * pred.len() / 4]
        .iter()
        .map(|r| r.1)
        .fold(f64::INFINITY, f64::min);
    assert!(fmax <= 5000.0 * 1.03, "{fmax}");
    assert!(pred[0].1 < 1e-6);
    assert!(fmin_mid < 0.8 * 5000.0, "{fmin_mid}");
    let (tp, tm) = (cut_time(&prog), cut_time(&pred));
    assert!(tm > tp * 1.05, "predicted {tm} s vs programmed {tp} s");
    // The plunges start and end at rest; they still take a finite, planned time (the whole
    // plan, rapids included, is 2.5x the programmed time).
    assert!(tm < tp * 4.0, "predicted {tm} s vs programmed {tp} s");
    // Time stamps increase inside every cutting run (t restarts at 0 at each run).
    assert!(pred.windows(2).all(|w| w[1].0 >= w[0].0 || w[1].0 == 0.0));
    // `--machine` alone means predicted, with the same result.
    let (jalone, alone) = resample(&["--machine", AC]);
    assert_eq!(jalone["feed"], "predicted");
    assert_eq!(alone, pred);
}

#[test]
fn resample_refuses_inconsistent_feed_options() {
    let dir = tempdir();
    let out = dir.path().join("r.csv");
    let base = |c: &mut assert_cmd::Command| {
        c.args(["resample", PARABOLOID, "--mode", "fz", "--fz-mm", "0.2"])
            .args(["--teeth", "1", "-o"])
            .arg(&out);
    };
    let mut c = crest();
    base(&mut c);
    let a = c.args(["--feed", "predicted"]).assert().code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("--machine"), "{err}");
    let mut c = crest();
    base(&mut c);
    let a = c
        .args(["--feed", "programmed", "--machine", AC])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("--feed predicted"), "{err}");
    assert!(!Path::new(&out).exists());
}

/// `crest simulate` on a 2 × 2 mm window at the saddle point; the JSON summary.
fn simulate(extra: &[&str]) -> serde_json::Value {
    let dir = tempdir();
    let out = dir.path().join("h.csv");
    let a = crest()
        .args(["simulate", PARABOLOID, "--tool", TORUS, "--model", "dome"])
        .args(["--grid-um", "50", "--window=-1,-1,1,1", "--json", "-o"])
        .arg(&out)
        .args(extra)
        .assert()
        .success();
    stdout_json(&a)
}

#[test]
fn simulate_with_predicted_feed_takes_longer_and_feeds_less() {
    let p = simulate(&["--feed", "programmed"]);
    let m = simulate(&["--feed", "predicted", "--machine", AC]);
    assert_eq!(p["feed"]["source"], "programmed");
    assert_eq!(m["feed"]["source"], "predicted");
    assert_eq!(m["feed"]["machine"], AC);
    let f = |v: &serde_json::Value, k: &str| v["feed"]["sample_feed_mm_min"][k].as_f64().unwrap();
    assert_abs_diff_eq!(f(&p, "min"), 5000.0, epsilon = 1e-6);
    assert_abs_diff_eq!(f(&p, "max"), 5000.0, epsilon = 1e-6);
    assert!(f(&m, "max") <= 5000.0 * 1.03);
    assert!(f(&m, "min") < 0.8 * 5000.0);
    assert!(f(&m, "mean") < f(&p, "mean"));
    let (tp, tm) = (
        p["feed"]["cut_time_s"].as_f64().unwrap(),
        m["feed"]["cut_time_s"].as_f64().unwrap(),
    );
    assert!(
        tm > tp * 1.05 && tm < tp * 4.0,
        "predicted {tm} s vs programmed {tp} s"
    );
    // Same spindle speed (from the file), so the surface is cut with a finer feed per
    // tooth where the machine is slow: the window is still cut.
    assert_eq!(p["rpm"], m["rpm"]);
    assert!(m["nodes_cut"].as_u64().unwrap() > 0);
    // Without a machine, `--feed predicted` is an error.
    let dir = tempdir();
    crest()
        .args(["simulate", PARABOLOID, "--tool", TORUS, "--model", "dome"])
        .args([
            "--grid-um",
            "50",
            "--window=-1,-1,1,1",
            "--feed",
            "predicted",
            "-o",
        ])
        .arg(dir.path().join("h.csv"))
        .assert()
        .code(2);
}
