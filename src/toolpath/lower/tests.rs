//! Unit tests of lowering: modal state, units and feeds, MSYS, contact forms and derived normals, arcs and cycles, positioned errors.

use super::*;
use crate::parse::clsf::parse_str;
use approx::assert_relative_eq;

fn lower(text: &str, apply_msys: bool) -> Program {
    let recs = parse_str(text).unwrap_or_else(|e| panic!("{e}"));
    lower_records(
        &recs,
        LowerOptions {
            apply_msys,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn modal_state_rapid_axis_and_feed() {
    let p = lower(
        "TOOL PATH/OP,TOOL,T\nTLDATA/MILL,10,5,50,0,0\nRAPID\nGOTO/0,0,10,0,0,1\nFEDRAT/MMPM,500\nSPINDL/RPM,8000,CLW\nGOTO/0,0,0\nGOTO/3,4,0,0,1,0\nGOTO/3,4,1\nEND-OF-PATH\n",
        false,
    );
    let t = &p.paths[0];
    let ps = &t.postures;
    assert_eq!(ps.len(), 4);
    assert_eq!(ps[0].motion, MotionKind::Rapid);
    assert_eq!(ps[0].feed_mm_min, None);
    assert_eq!(ps[1].motion, MotionKind::Cut);
    assert_eq!(ps[1].feed_mm_min, Some(500.0));
    assert_eq!(ps[1].spindle_rpm, Some(8000.0));
    assert_eq!(ps[1].axis, Vec3::z());
    assert_eq!(ps[3].axis, Vec3::y());
    // The rapid starts the path (no length); the cuts are 10, 5 and 1 mm.
    assert_relative_eq!(t.stats.length_mm, 16.0, epsilon = 1e-12);
    assert_relative_eq!(t.stats.cutting_length_mm, 16.0, epsilon = 1e-12);
    assert_eq!((t.stats.gotos, t.stats.rapids), (4, 1));
}

#[test]
fn inches_and_feed_units() {
    let p = lower(
        "UNITS/INCH\nTOOL PATH/OP,TOOL,T\nSPINDL/RPM,1000\nFEDRAT/IPR,0.01\nGOTO/1,0,0\nFEDRAT/IPM,10\nGOTO/2,0,0\nEND-OF-PATH\n",
        false,
    );
    let ps = &p.paths[0].postures;
    assert_relative_eq!(ps[0].position.x, 25.4, epsilon = 1e-12);
    assert_relative_eq!(ps[0].feed_mm_min.unwrap_or(0.0), 254.0, epsilon = 1e-9);
    assert_relative_eq!(ps[1].feed_mm_min.unwrap_or(0.0), 254.0, epsilon = 1e-9);
}

#[test]
fn msys_applied_only_on_request() {
    let text = "TOOL PATH/OP,TOOL,T\nMSYS/10,20,30,0,1,0,1,0,0\nGOTO/1,2,3,0,0,1\nEND-OF-PATH\n";
    let kept = lower(text, false);
    assert_eq!(
        kept.paths[0].postures[0].position,
        Point3::new(1.0, 2.0, 3.0)
    );
    let abs = lower(text, true);
    let q = &abs.paths[0].postures[0];
    // X_mcs = +y_acs, Y_mcs = +x_acs, Z_mcs = X × Y = −z_acs.
    assert_relative_eq!(q.position, Point3::new(12.0, 21.0, 27.0), epsilon = 1e-12);
    assert_relative_eq!(q.axis, -Vec3::z(), epsilon = 1e-12);
    assert!(abs.paths[0].msys_applied);
}

#[test]
fn contact_forms_and_derived_normals() {
    // Ball R = 5, axis +Z, tip at origin: ball centre (0,0,5). CC at 45° on the ball.
    let c = 5.0 - 5.0 * 0.5f64.sqrt();
    let text = format!(
        "TOOL PATH/OP,TOOL,BALL\nTLDATA/MILL,10,5,50,0,0\nGOTO/0,0,0,0,0,1,{x},0,{c}\nGOTO/1,0,0\n$$ CONTACT/1,0,0,0,0,2\nGOTO/2,0,0\nCONTACT/{x2},0,{c}\nEND-OF-PATH\n",
        x = 5.0 * 0.5f64.sqrt(),
        x2 = 2.0 + 5.0 * 0.5f64.sqrt(),
    );
    let p = lower(&text, false);
    let ps = &p.paths[0].postures;
    let n0 = ps[0].contact.as_ref().unwrap_or_else(|| panic!("contact"));
    assert!(n0.normal_derived);
    assert_relative_eq!(
        n0.normal,
        Vec3::new(-1.0, 0.0, 1.0).normalize(),
        epsilon = 1e-12
    );
    let n1 = ps[1].contact.as_ref().unwrap_or_else(|| panic!("contact"));
    assert!(!n1.normal_derived);
    assert_eq!(n1.normal, Vec3::z());
    let n2 = ps[2].contact.as_ref().unwrap_or_else(|| panic!("contact"));
    assert_relative_eq!(
        n2.normal,
        Vec3::new(-1.0, 0.0, 1.0).normalize(),
        epsilon = 1e-12
    );
}

#[test]
fn torus_normal_points_to_the_corner_circle() {
    let tool = ToolData {
        kind: "MILL".into(),
        diameter_mm: 20.0,
        corner_radius_mm: 2.0,
        ..Default::default()
    };
    // Corner circle centre ring: radius 8 at height 2. CC straight out at radius 10.
    let n = derive_normal(
        &tool,
        &Point3::origin(),
        &Vec3::z(),
        &Point3::new(10.0, 0.0, 2.0),
    );
    assert_relative_eq!(n.unwrap_or_else(Vec3::zeros), -Vec3::x(), epsilon = 1e-12);
}

#[test]
fn arcs_cycles_and_times() {
    let p = lower(
        "TOOL PATH/OP,TOOL,T\nGOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10,0.06,0.5,10,0,TIMES,2\nGOTO/0,-10,0\nCYCLE/DRILL,RAPTO,3\nGOTO/5,5,0\nCYCLE/OFF\nGOTO/5,5,1\nEND-OF-PATH\n",
        false,
    );
    let t = &p.paths[0];
    let arc = t.postures[1].arc.as_ref().unwrap_or_else(|| panic!("arc"));
    assert_eq!(arc.extra_turns, 1);
    assert_eq!(t.postures[2].motion, MotionKind::Cycle);
    assert_eq!(t.postures[3].motion, MotionKind::Cut);
    let quarter = 10.0 * std::f64::consts::FRAC_PI_2;
    let hole = (Point3::new(5.0, 5.0, 0.0) - Point3::new(0.0, -10.0, 0.0)).norm();
    assert_relative_eq!(
        t.stats.length_mm,
        quarter + 20.0 * std::f64::consts::PI + hole + 1.0,
        epsilon = 1e-9
    );
    assert_relative_eq!(
        t.stats.cutting_length_mm,
        quarter + 20.0 * std::f64::consts::PI + 1.0,
        epsilon = 1e-9
    );
}

#[test]
fn several_paths_reset_state() {
    let p = lower(
        "TOOL PATH/A,TOOL,T\nFEDRAT/100\nGOTO/0,0,0,1,0,0\nEND-OF-PATH\nTOOL PATH/B,TOOL,T\nGOTO/1,0,0\nEND-OF-PATH\n",
        false,
    );
    assert_eq!(p.paths.len(), 2);
    assert_eq!(p.paths[1].postures[0].axis, Vec3::z());
    assert_eq!(p.paths[1].postures[0].feed_mm_min, None);
}

#[test]
fn bad_geometry_is_an_error_with_position() {
    let recs = parse_str("TOOL PATH/A,TOOL,T\nGOTO/0,0,0,0,0,0\n").unwrap_or_default();
    match lower_records(&recs, LowerOptions::default()) {
        Err(LowerError::Invalid(e)) => assert_eq!((e.span.line, e.span.column), (2, 1)),
        other => panic!("{other:?}"),
    }
}
