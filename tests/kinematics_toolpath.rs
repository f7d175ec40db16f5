//! `predict_posture_feed` and `plan_path` on tool paths built in the test: the feed the
//! resampling and simulation stages take per posture.

use crest::kinematics::{KinematicsError, Level, Machine, plan_path, predict_posture_feed};
use crest::math::{Point3, Vec3};
use crest::toolpath::{MotionKind, Posture, Toolpath};

const AC: &str = include_str!("../samples/machines/table1_ac.toml");
const NUT: &str = include_str!("../samples/machines/table1_nutating45.toml");

fn posture(p: [f64; 3], axis: Vec3, motion: MotionKind, feed: Option<f64>, line: u32) -> Posture {
    Posture {
        position: Point3::new(p[0], p[1], p[2]),
        axis,
        motion,
        arc: None,
        contact: None,
        feed_mm_min: feed,
        spindle_rpm: Some(10_000.0),
        line,
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
    for text in [AC, NUT] {
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
    let m = Machine::from_toml_str(AC).unwrap();
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
    let m = Machine::from_toml_str(NUT).unwrap();
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
    let m = Machine::from_toml_str(AC).unwrap();
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
