//! Property tests: printed records parse back to the same values; arbitrary bytes never
//! panic the readers or the lowering; written postures read back to the printed digits.

use crest::math::{Point3, Vec3};
use crest::parse::clsf::parse_line;
use crest::parse::{Arg, ClsfReader, Contact12Reader, FeedUnit, LengthUnit, Numbers, RecordKind};
use crest::toolpath::{
    Contact, LowerOptions, Lowerer, MotionKind, Posture, Program, Toolpath, write_clsf,
    write_contact12,
};
use proptest::prelude::*;

fn finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1.0e4..1.0e4f64,
        (-100_000_000i64..100_000_000).prop_map(|v| v as f64 / 10_000.0),
        any::<f64>().prop_filter("finite", |v| v.is_finite()),
    ]
}

fn nums(counts: &'static [usize]) -> impl Strategy<Value = Numbers> {
    prop::sample::select(counts).prop_flat_map(|n| {
        prop::collection::vec(finite(), n)
            .prop_map(|v| Numbers::from_slice(&v).unwrap_or_else(|| unreachable!()))
    })
}

fn name() -> impl Strategy<Value = String> {
    "[A-Z0-9_][A-Z0-9_-]{0,20}"
}

fn record() -> impl Strategy<Value = RecordKind> {
    prop_oneof![
        nums(&[3, 6, 9, 12]).prop_map(RecordKind::Goto),
        nums(&[3, 6]).prop_map(RecordKind::From),
        nums(&[3, 6]).prop_map(RecordKind::GoHome),
        nums(&[3, 6]).prop_map(RecordKind::Contact),
        (nums(&[7, 8, 9, 10, 11]), prop::option::of(1u32..1000))
            .prop_map(|(numbers, times)| RecordKind::Circle { numbers, times }),
        prop::collection::vec(finite(), 1..30).prop_map(RecordKind::Knot),
        (finite(), finite(), finite()).prop_map(|(a, b, c)| RecordKind::Cntrl([a, b, c])),
        prop::collection::vec(finite(), 9).prop_map(|v| {
            let mut m = [0.0; 9];
            m.copy_from_slice(&v);
            RecordKind::Msys(m)
        }),
        (
            prop::option::of(prop::sample::select(vec![
                FeedUnit::Mmpm,
                FeedUnit::Ipm,
                FeedUnit::Mmpr,
                FeedUnit::Ipr
            ])),
            finite()
        )
            .prop_map(|(unit, value)| RecordKind::Fedrat { unit, value }),
        (name(), name()).prop_map(|(name, tool)| RecordKind::ToolPath { name, tool }),
        (0.0..100_000.0f64).prop_map(|v| RecordKind::Spindl(vec![
            Arg::Word("RPM".into()),
            Arg::Num(v),
            Arg::Word("CLW".into())
        ])),
        Just(RecordKind::Units(LengthUnit::Inch)),
        Just(RecordKind::Rapid),
        Just(RecordKind::Nurbs),
        Just(RecordKind::EndOfPath),
    ]
}

proptest! {
    #[test]
    fn fixed_point_printing_is_close_and_idempotent(x in -1.0..1.0f64, unit in any::<bool>()) {
        use crest::toolpath::write::{fixed, LENGTH_DECIMALS, UNIT_DECIMALS};
        // Unit-vector components within ±10, lengths within ±1e8 mm.
        let (d, v) = if unit { (UNIT_DECIMALS, x * 10.0) } else { (LENGTH_DECIMALS, x * 1.0e8) };
        let s = fixed(v, d);
        let decimals = s.split('.').nth(1).map(str::len).unwrap_or(0) as u32;
        prop_assert!(decimals >= d.0 && decimals <= d.1, "{}", s);
        let back: f64 = s.parse().map_err(|e| TestCaseError::fail(format!("{s}: {e:?}")))?;
        prop_assert!((back - v).abs() <= 0.5 * 10f64.powi(-(d.1 as i32)) * (1.0 + 1e-6) + v.abs() * 1e-15, "{} vs {}", s, v);
        prop_assert_eq!(fixed(back, d), s);
    }

    #[test]
    fn numbers_agree_with_std(s in "[+-]?[0-9]{0,25}(\\.[0-9]{0,25})?([eE][+-]?[0-9]{1,3})?") {
        let std: Result<f64, _> = s.parse();
        match crest::parse::number::scan_number(s.as_bytes()) {
            Some((v, n)) => {
                prop_assert_eq!(n, s.len());
                let want = std.map_err(|e| TestCaseError::fail(format!("{s}: {e}")))?;
                prop_assert_eq!(v.to_bits(), want.to_bits(), "{}", s);
            }
            None => prop_assert!(s.trim_start_matches(['+', '-']).starts_with(['.', 'e', 'E']) || s.trim_start_matches(['+', '-']).is_empty(), "{}", s),
        }
    }

    #[test]
    fn printed_records_parse_back(r in record(), pad in 0usize..3) {
        let text = format!("{}{}", " ".repeat(pad), r);
        let back = parse_line(&text, 7).map_err(|e| TestCaseError::fail(format!("{text}: {e}")))?;
        prop_assert_eq!(&back.kind, &r, "{}", text);
        prop_assert_eq!((back.line, back.column), (7, pad as u32 + 1));
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let mut low = Lowerer::new(LowerOptions::default());
        let mut sink = |_: &Toolpath, _: &Posture| Ok(());
        for r in ClsfReader::new(&bytes[..]) {
            match r {
                Ok(r) => { if low.push(&r, &mut sink).is_err() { break; } }
                Err(e) => { let s = e.syntax().map(|s| s.line).unwrap_or(1); prop_assert!(s >= 1); break; }
            }
        }
        let _ = low.finish(&mut sink);
        let mut low = Lowerer::new(LowerOptions::default());
        for r in Contact12Reader::new(&bytes[..]) {
            match r {
                Ok(r) => { if low.push_contact12(&r, &mut sink).is_err() { break; } }
                Err(_) => break,
            }
        }
        let _ = low.finish(&mut sink);
    }

    #[test]
    fn clsf_like_text_never_panics(lines in prop::collection::vec(prop_oneof![
        Just("TOOL PATH/A,TOOL,B".to_string()),
        Just("END-OF-PATH".to_string()),
        Just("RAPID".to_string()),
        Just("NURBS/".to_string()),
        Just("$$ CONTACT/1,2,3".to_string()),
        "(GOTO|FROM|GOHOME|CIRCLE|KNOT|CNTRL|CONTACT|MSYS|FEDRAT|SPINDL|TLDATA|CYCLE|UNITS|PAINT)/[-0-9.,A-Z $]{0,40}",
        "[ -~]{0,30}",
    ], 0..30)) {
        let text = lines.join("\n");
        let mut low = Lowerer::new(LowerOptions { apply_msys: true, ..Default::default() });
        let mut sink = |_: &Toolpath, p: &Posture| {
            assert!(p.position.coords.iter().all(|v| v.is_finite() || v.is_nan()));
            Ok(())
        };
        for r in ClsfReader::new(text.as_bytes()) {
            match r {
                Ok(r) => { if low.push(&r, &mut sink).is_err() { break; } }
                Err(_) => break,
            }
        }
        let _ = low.finish(&mut sink);
    }

    #[test]
    fn written_postures_read_back_to_the_printed_digits(
        pts in prop::collection::vec((
            (-1000i64..1000, -1000i64..1000, -1000i64..1000),
            (-1.0..1.0f64, -1.0..1.0f64, 0.1..1.0f64),
            prop::option::of(((-1000i64..1000, -1000i64..1000, -1000i64..1000), (-1.0..1.0f64, -1.0..1.0f64, 0.1..1.0f64))),
        ), 1..20)
    ) {
        let postures: Vec<Posture> = pts.iter().map(|((x, y, z), (i, j, k), c)| Posture {
            position: Point3::new(*x as f64 / 1000.0, *y as f64 / 1000.0, *z as f64 / 1000.0),
            axis: Vec3::new(*i, *j, *k).normalize(),
            motion: if c.is_some() { MotionKind::Cut } else { MotionKind::Rapid },
            arc: None,
            contact: c.map(|((a, b, d), (p, q, r))| Contact {
                point: Point3::new(a as f64 / 100.0, b as f64 / 100.0, d as f64 / 100.0),
                normal: Vec3::new(p, q, r).normalize(),
                normal_derived: false,
            }),
            feed_mm_min: None,
            spindle_rpm: None,
            line: 0,
        }).collect();
        let path = Toolpath { name: "P".into(), postures, ..Default::default() };
        let mut csv1 = Vec::new();
        write_contact12(&path, true, &mut csv1).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let mut cls = Vec::new();
        write_clsf(&Program { paths: vec![path], warnings: vec![] }, &mut cls).map_err(|e| TestCaseError::fail(e.to_string()))?;
        // CLSF → postures → contact12 gives the same text as the direct write.
        let mut low = Lowerer::new(LowerOptions::default());
        let mut sink = |_: &Toolpath, _: &Posture| Ok(());
        for r in ClsfReader::new(&cls[..]) {
            let r = r.map_err(|e| TestCaseError::fail(e.to_string()))?;
            low.push(&r, &mut sink).map_err(|e| TestCaseError::fail(e.to_string()))?;
        }
        let prog = low.finish(&mut sink).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let mut csv2 = Vec::new();
        write_contact12(&prog.paths[0], true, &mut csv2).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(String::from_utf8_lossy(&csv1), String::from_utf8_lossy(&csv2));
        // contact12 → postures → contact12 is a fixed point too.
        let mut low = Lowerer::new(LowerOptions::default());
        low.begin_path("P", "", &mut sink).map_err(|e| TestCaseError::fail(e.to_string()))?;
        for r in Contact12Reader::new(&csv1[..]) {
            let r = r.map_err(|e| TestCaseError::fail(e.to_string()))?;
            low.push_contact12(&r, &mut sink).map_err(|e| TestCaseError::fail(e.to_string()))?;
        }
        let prog = low.finish(&mut sink).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let mut csv3 = Vec::new();
        write_contact12(&prog.paths[0], true, &mut csv3).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(String::from_utf8_lossy(&csv1), String::from_utf8_lossy(&csv3));
    }
}
