//! Validation cases of kinematics.md §8 (K1, K1b, K2, K3, K4, K6), the invariants and the
//! metamorphic checks, on the Table I machine (T = 3 ms, e = 0.01 mm / 0.01 deg).

use crest::kinematics::{FeedPlan, Level, Machine, PlanInput, Pose, plan_poses, pose_tilt_azimuth};
use crest::math::{Point3, Vec3};

const AC: &str = include_str!("../samples/machines/table1_ac.toml");
const NUT: &str = include_str!("../samples/machines/table1_nutating45.toml");
const T: f64 = 0.003;

fn machine() -> Machine {
    Machine::from_toml_str(AC).unwrap()
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
fn near_ref(got: f64, reference: f64) {
    let tol = (2.0 * T).max(0.002 * reference);
    assert!(
        (got - reference).abs() <= tol,
        "time {got} vs ref {reference}"
    );
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
    assert!((oracle - 1.291287).abs() < 1e-6);
    within(p.total_time_s, oracle, 0.5e-3, 2.0);
    near_ref(p.total_time_s, 1.291305);
    // Level 1: 1.216667 s.
    assert!(
        (p.level1_time_s - 1.216667).abs() < 1e-6,
        "{}",
        p.level1_time_s
    );
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
    assert!((vmax / (5000.0 / 60.0) - 1.0).abs() < 0.005, "{vmax}");
    let mid = &p.postures[50];
    assert!(
        (mid.feed_mm_s * 60.0 - 5000.0).abs() < 25.0,
        "{}",
        mid.feed_mm_s * 60.0
    );
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
    assert!((vmax / 27.8495 - 1.0).abs() < 0.005, "{vmax} m/min");
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
    assert!((vc / 20.0 - 1.0).abs() < 0.005, "corner speed {vc}");
    within(p.total_time_s, 1.329543, 1e-3, 2.0);
    near_ref(p.total_time_s, 1.329201);
    assert!(
        (p.level1_time_s - 1.226293).abs() < 1e-5,
        "{}",
        p.level1_time_s
    );
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
    assert!((deg(q0[3]) - 30.0).abs() < 1e-9 && (deg(q1[3]) - 30.0).abs() < 1e-9);
    assert!((deg(q0[4]) - 90.0).abs() < 1e-9 && (deg(q1[4]) + 30.0).abs() < 1e-9);
    assert!((q1[1] - q0[1] + 10.0).abs() < 1e-9);
    assert!((q1[2] - q0[2] - 20.0 * 30f64.to_radians().cos()).abs() < 1e-9);
    let b = &p.blocks;
    assert!((b.vbar[0] - 50.0).abs() < 1e-9);
    assert!((b.abar[0] - 180.0).abs() < 1e-9);
    assert!((b.jbar[0] - 6000.0).abs() < 1e-9);
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
    assert!(
        (mid.path_speed_mm_s - 50.0).abs() < 0.25,
        "{}",
        mid.path_speed_mm_s
    );
    assert!((mid.feed_mm_s - 50.0).abs() < 0.25, "{}", mid.feed_mm_s);
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
    assert!((oracle - 0.357735).abs() < 1e-6);
    within(p.total_time_s, oracle, 0.5e-3, 2.0);
    near_ref(p.total_time_s, 0.358071);
    assert!((max_speed(&p) / cap - 1.0).abs() < 0.005);
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
    let m = Machine::from_toml_str(NUT).unwrap();
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
        (got[0].0 - 90.0).abs() < 1e-6 && (got[1].0 + 90.0).abs() < 1e-6,
        "{got:?}"
    );
    let mut cs = [got[0].1, got[1].1];
    cs.sort_by(f64::total_cmp);
    assert!(
        (cs[0] + 9.736).abs() < 1e-3 && (cs[1] - 99.736).abs() < 1e-3,
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
    let text = AC
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
    assert!(
        (one.total_time_s - two.total_time_s).abs() <= 2.0 * T,
        "{} vs {}",
        one.total_time_s,
        two.total_time_s
    );
}
