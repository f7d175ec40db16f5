//! The project's own contact-data samples (`samples/clsf/`): the CC points lie on the
//! ball of a tool-tip CL point (model.md §1.1), derived normals match the written ones,
//! and the CLSF and contact12 forms of the same path agree.

use crest::parse::{ClsfReader, Contact12Reader};
use crest::toolpath::{
    LowerOptions, Lowerer, MotionKind, Posture, Program, Toolpath, write_contact12,
};

const CLS: &str = include_str!("../samples/clsf/ball_lead15_contact.cls");
const C12: &str = include_str!("../samples/clsf/ball_lead15_contact12.txt");
const R: f64 = 5.0;

fn lower_clsf(text: &str) -> Program {
    let mut low = Lowerer::new(LowerOptions::default());
    let mut sink = |_: &Toolpath, _: &Posture| Ok(());
    for r in ClsfReader::new(text.as_bytes()) {
        let r = r.unwrap_or_else(|e| panic!("{e}"));
        low.push(&r, &mut sink).unwrap_or_else(|e| panic!("{e}"));
    }
    low.finish(&mut sink).unwrap_or_else(|e| panic!("{e}"))
}

fn lower_c12(text: &str) -> Program {
    let mut low = Lowerer::new(LowerOptions::default());
    let mut sink = |_: &Toolpath, _: &Posture| Ok(());
    low.begin_path("c12", "", &mut sink)
        .unwrap_or_else(|e| panic!("{e}"));
    for r in Contact12Reader::new(text.as_bytes()) {
        let r = r.unwrap_or_else(|e| panic!("{e}"));
        low.push_contact12(&r, &mut sink)
            .unwrap_or_else(|e| panic!("{e}"));
    }
    low.finish(&mut sink).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn cc_points_lie_on_the_ball_of_a_tip_cl_point() {
    let p = lower_clsf(CLS);
    let t = &p.paths[0];
    let cutting: Vec<&Posture> = t
        .postures
        .iter()
        .filter(|q| q.motion == MotionKind::Cut)
        .collect();
    assert_eq!(cutting.len(), 3 * 41);
    for q in cutting {
        let c = q
            .contact
            .as_ref()
            .unwrap_or_else(|| panic!("line {}", q.line));
        assert!(!c.normal_derived);
        let centre = q.position + q.axis * R;
        // |C − (P + R n_t)| = R: P is the tool tip (4-decimal rounding of the file).
        assert!(
            ((c.point - centre).norm() - R).abs() < 3e-4,
            "line {}",
            q.line
        );
        // The normal points from C to the ball centre.
        assert!(
            (c.normal - (centre - c.point) / R).norm() < 1e-4,
            "line {}",
            q.line
        );
    }
}

#[test]
fn derived_normals_match_the_written_ones() {
    // Drop the normals: 9-number GOTOs and `$$ CONTACT/` records with 3 numbers.
    let mut nine = String::new();
    let mut records = String::new();
    for line in CLS.lines() {
        let fields: Vec<&str> = line.split(',').collect();
        if line.starts_with("GOTO/") && fields.len() == 12 {
            nine += &fields[..9].join(",");
            nine.push('\n');
            records += &fields[..6].join(",");
            records += &format!("\n$$ CONTACT/{}\n", fields[6..9].join(","));
        } else {
            nine += line;
            nine.push('\n');
            records += line;
            records.push('\n');
        }
    }
    let full = lower_clsf(CLS);
    for text in [nine, records] {
        let derived = lower_clsf(&text);
        let (a, b) = (&full.paths[0].postures, &derived.paths[0].postures);
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            match (&x.contact, &y.contact) {
                (Some(cx), Some(cy)) => {
                    assert!(cy.normal_derived);
                    assert_eq!(cx.point, cy.point);
                    assert!((cx.normal - cy.normal).norm() < 1e-4, "line {}", y.line);
                }
                (None, None) => {}
                _ => panic!("contact mismatch at line {}", y.line),
            }
        }
        assert!(derived.warnings.is_empty(), "{:?}", derived.warnings);
    }
}

#[test]
fn clsf_and_contact12_forms_agree() {
    let a = lower_clsf(CLS);
    let b = lower_c12(C12);
    let (mut x, mut y) = (Vec::new(), Vec::new());
    write_contact12(&a.paths[0], true, &mut x).unwrap_or_else(|e| panic!("{e}"));
    write_contact12(&b.paths[0], true, &mut y).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(String::from_utf8_lossy(&x), String::from_utf8_lossy(&y));
    assert_eq!(a.paths[0].postures.len(), 3 * 42 + 3);
    assert!((a.paths[0].stats.cutting_length_mm - b.paths[0].stats.cutting_length_mm).abs() < 1e-9);
}
