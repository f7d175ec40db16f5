//! Every real NX sample in `../shared/samples-external/` parses and lowers; record counts
//! match an independent count of the lines; a summary of each is snapshotted.

use crest::parse::ClsfReader;
use crest::toolpath::{LowerOptions, Lowerer, MotionKind, Posture, Program, Toolpath};
use std::path::{Path, PathBuf};

fn samples() -> Vec<PathBuf> {
    let dir = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/samples-external"
    ));
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "cls"))
        .collect();
    v.sort();
    assert_eq!(v.len(), 12, "twelve NX samples expected");
    v
}

fn lower(text: &str, opts: LowerOptions) -> Program {
    let mut low = Lowerer::new(opts);
    let mut sink = |_: &Toolpath, _: &Posture| Ok(());
    for rec in ClsfReader::new(text.as_bytes()) {
        let rec = rec.unwrap_or_else(|e| panic!("{e}"));
        low.push(&rec, &mut sink).unwrap_or_else(|e| panic!("{e}"));
    }
    low.finish(&mut sink).unwrap_or_else(|e| panic!("{e}"))
}

fn count_lines(text: &str, prefix: &str) -> usize {
    text.lines().filter(|l| l.starts_with(prefix)).count()
}

fn fmt_p(p: &Posture) -> String {
    format!(
        "({:.4}, {:.4}, {:.4}) axis ({:.7}, {:.7}, {:.7}) {:?} line {}",
        p.position.x, p.position.y, p.position.z, p.axis.x, p.axis.y, p.axis.z, p.motion, p.line
    )
}

fn summary(program: &Program) -> String {
    let mut s = String::new();
    for t in &program.paths {
        let st = &t.stats;
        s += &format!("path {} tool {}\n", t.name, t.tool_name);
        s += &format!(
            "tldata {:?}\n",
            t.tool
                .as_ref()
                .map(|d| (&d.kind, d.diameter_mm, d.corner_radius_mm, d.length_mm))
        );
        s += &format!("msys {:?}\n", t.msys);
        s += &format!(
            "gotos {} rapids {} circles {} nurbs {} postures {}\n",
            st.gotos, st.rapids, st.circles, st.nurbs, st.postures
        );
        s += &format!(
            "length_mm {:.4} cutting_length_mm {:.4}\n",
            st.length_mm, st.cutting_length_mm
        );
        s += &format!(
            "feeds {:?} spindles {:?}\n",
            st.feeds_mm_min, st.spindles_rpm
        );
        let kinds = [
            MotionKind::From,
            MotionKind::Rapid,
            MotionKind::Cut,
            MotionKind::Cycle,
            MotionKind::GoHome,
        ];
        for k in kinds {
            let n = t.postures.iter().filter(|p| p.motion == k).count();
            s += &format!("{k:?} {n}  ");
        }
        s += &format!(
            "arcs {}\n",
            t.postures.iter().filter(|p| p.arc.is_some()).count()
        );
        if let (Some(a), Some(b)) = (t.postures.first(), t.postures.last()) {
            s += &format!("first {}\nlast  {}\n", fmt_p(a), fmt_p(b));
        }
        s += &format!("cutting runs {}\n", t.cutting_runs().len());
    }
    for w in &program.warnings {
        s += &format!("warning {}:{} {}\n", w.line, w.column, w.message);
    }
    s
}

#[test]
fn every_sample_parses_with_independent_counts() {
    for path in samples() {
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
        let program = lower(&text, LowerOptions::default());
        assert_eq!(
            program.paths.len(),
            count_lines(&text, "TOOL PATH/"),
            "{path:?}"
        );
        let gotos: usize = program.paths.iter().map(|t| t.stats.gotos).sum();
        let circles: usize = program.paths.iter().map(|t| t.stats.circles).sum();
        let rapids: usize = program.paths.iter().map(|t| t.stats.rapids).sum();
        let nurbs: usize = program.paths.iter().map(|t| t.stats.nurbs).sum();
        assert_eq!(gotos, count_lines(&text, "GOTO/"), "{path:?}");
        assert_eq!(circles, count_lines(&text, "CIRCLE/"), "{path:?}");
        assert_eq!(
            rapids,
            text.lines().filter(|l| l.trim() == "RAPID").count(),
            "{path:?}"
        );
        assert_eq!(nurbs, count_lines(&text, "NURBS/"), "{path:?}");
        // Postures: one per GOTO/FROM/GOHOME, plus the NURBS samples.
        let point_records = count_lines(&text, "GOTO/")
            + count_lines(&text, "FROM/")
            + count_lines(&text, "GOHOME/");
        let postures: usize = program.paths.iter().map(|t| t.postures.len()).sum();
        if nurbs == 0 {
            assert_eq!(postures, point_records, "{path:?}");
        } else {
            assert!(
                postures > point_records + count_lines(&text, "CNTRL/") / 2,
                "{path:?}"
            );
        }
        assert!(
            program.warnings.is_empty(),
            "{path:?}: {:?}",
            program.warnings
        );
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("x")
            .to_string();
        insta::assert_snapshot!(name, summary(&program));
    }
}

#[test]
fn the_published_facts_of_the_samples_hold() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/samples-external/");
    let read =
        |n: &str| std::fs::read_to_string(format!("{dir}{n}")).unwrap_or_else(|e| panic!("{e}"));
    // SOURCES.md: 20 057 GOTOs, 4 660 with i,j,k in the large 5-axis file.
    let large = read("nx_5axis_varcontour_ijk_large.cls");
    let p = lower(&large, LowerOptions::default());
    assert_eq!(p.paths[0].stats.gotos, 20_057);
    let with_axis = large
        .lines()
        .filter(|l| l.starts_with("GOTO/") && l.split(',').count() == 6)
        .count();
    assert_eq!(with_axis, 4_660);
    // The axis is carried over: every posture's axis equals the last written one.
    let axis_changes = p.paths[0]
        .postures
        .windows(2)
        .filter(|w| w[0].axis != w[1].axis)
        .count();
    assert!(axis_changes < with_axis);
    // A path without any i,j,k keeps the default +Z.
    let slot = lower(
        &read("nx_slot_multilevel_arcs.cls"),
        LowerOptions::default(),
    );
    assert!(
        slot.paths[0]
            .postures
            .iter()
            .all(|q| q.axis == crest::math::Vec3::z())
    );
    // Arcs end on their circle (radius as written, within the 4-decimal rounding).
    for q in slot.paths[0].postures.iter().filter(|q| q.arc.is_some()) {
        let a = q.arc.as_ref().unwrap_or_else(|| unreachable!());
        let d = q.position - a.centre;
        let radial = (d - a.axis * a.axis.dot(&d)).norm();
        assert!(
            (radial - a.radius_mm).abs() < 2e-3,
            "{radial} vs {}",
            a.radius_mm
        );
    }
    // The NURBS samples pass through the last control point of each block.
    let nurbs_text = read("nx_fixed_contour_nurbs.cls");
    let nurbs = lower(&nurbs_text, LowerOptions::default());
    let last_cntrl: Vec<&str> = nurbs_text
        .lines()
        .filter(|l| l.starts_with("CNTRL/"))
        .collect();
    let end = last_cntrl
        .last()
        .map(|l| l.trim_start_matches("CNTRL/"))
        .unwrap_or("");
    let xyz: Vec<f64> = end
        .split(',')
        .map(|v| v.parse().unwrap_or(f64::NAN))
        .collect();
    let hit = nurbs.paths[0].postures.iter().any(|q| {
        (q.position.x - xyz[0]).abs() < 1e-9
            && (q.position.y - xyz[1]).abs() < 1e-9
            && (q.position.z - xyz[2]).abs() < 1e-9
    });
    assert!(hit, "last CNTRL point reached");
}
