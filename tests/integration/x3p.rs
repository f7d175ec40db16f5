//! ISO 25178-72 `.x3p` files (issue 34): crest reads what surfalize reads, heights and
//! spacing, for the files surfalize writes (float64, float32) and for files written by hand
//! for the point types and layouts it does not write (int16 and int32 with a validity mask,
//! heights listed in the XML); what crest writes reads back; damaged files are refused with
//! the field named and nothing written.

use std::io::Write;
use std::path::Path;

use crest::io::{ReadOptions, read_heightmap};
use md5::{Digest, Md5};

use crate::util::{crest, repo, tempdir};

fn fixtures() -> std::path::PathBuf {
    repo("samples/maps/x3p")
}

/// Heights and spacing equal surfalize's reading of every fixture (samples/maps/x3p/make.py):
/// integer point types exactly, floating-point ones to 1e-9 relative; spacing to 1e-12.
#[test]
fn fixtures_read_as_surfalize_reads_them() {
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixtures().join("expected.json")).unwrap())
            .unwrap();
    let files = expected.as_object().unwrap();
    assert_eq!(files.len(), 5);
    for (name, want) in files {
        let map = read_heightmap(&fixtures().join(name), &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(map.nx as u64, want["nx"].as_u64().unwrap(), "{name}");
        assert_eq!(map.ny as u64, want["ny"].as_u64().unwrap(), "{name}");
        for (got, key) in [(map.dx_um, "dx_um"), (map.dy_um, "dy_um")] {
            let w = want[key].as_f64().unwrap();
            assert!((got - w).abs() <= 1e-12 * w, "{name} {key}: {got} {w}");
        }
        let exact = name.contains("-i16") || name.contains("-i32");
        let z = want["z_um"].as_array().unwrap();
        assert_eq!(z.len(), map.z_um.len(), "{name}");
        for (k, (got, w)) in map.z_um.iter().zip(z).enumerate() {
            match w.as_f64() {
                None => assert!(got.is_nan(), "{name} point {k}: {got}, surfalize NaN"),
                Some(w) if exact => assert_eq!(*got, w, "{name} point {k}"),
                Some(w) => assert!(
                    (got - w).abs() <= 1e-9 * w.abs().max(1e-300),
                    "{name} point {k}: {got} {w}"
                ),
            }
        }
    }
    // The origin (CX/CY Offset, which surfalize does not keep): 0.001 m and -0.002 m.
    let m = read_heightmap(
        &fixtures().join("hand-i16-mask.x3p"),
        &ReadOptions::default(),
    )
    .unwrap();
    assert_eq!((m.x0_mm, m.y0_mm), (1.0, -2.0));
}

/// `crest convert` between formats, `metrics` on an x3p, the content told without the
/// extension; the heights survive gsf → x3p → csv as float32 values.
#[test]
fn convert_and_metrics_take_x3p() {
    let dir = tempdir();
    let p = dir.path();
    let src = fixtures().join("surfalize-d.x3p");
    for out in ["m.gsf", "m.sdf", "m.csv", "m.xyz", "m2.x3p"] {
        crest()
            .arg("convert")
            .arg(&src)
            .arg("-o")
            .arg(p.join(out))
            .assert()
            .success();
    }
    let a = read_heightmap(&src, &ReadOptions::default()).unwrap();
    let b = read_heightmap(&p.join("m2.x3p"), &ReadOptions::default()).unwrap();
    for (x, y) in a.z_um.iter().zip(&b.z_um) {
        assert!(
            x.is_nan() && y.is_nan() || (x - y).abs() <= 4e-16 * x.abs(),
            "{x} {y}"
        );
    }
    // The same file with no extension: told by its content.
    std::fs::copy(&src, p.join("noext")).unwrap();
    let metrics = |f: &Path| {
        crate::util::success_json(
            crest()
                .arg("metrics")
                .arg(f)
                .args(["--params", "Sa,Sq,Sz", "--json"]),
        )
    };
    let (x, y) = (metrics(&src), metrics(&p.join("noext")));
    for k in ["Sa", "Sq", "Sz"] {
        assert!(x[k].as_f64().is_some_and(|v| v > 0.0), "{k}: {x}");
        assert_eq!(x[k], y[k], "{k}: {x} {y}");
    }
    // The grid CSV of the same map (written by crest, its spacing in its header) measures alike.
    let c = metrics(&p.join("m.csv"));
    for k in ["Sa", "Sq", "Sz"] {
        let (u, v) = (x[k].as_f64().unwrap(), c[k].as_f64().unwrap());
        assert!((u - v).abs() <= 1e-12 * u, "{k}: {x} {c}");
    }
}

/// A zip with `main.xml` (and its checksum) and the given other entries.
fn x3p(xml: &str, entries: &[(&str, &[u8])], checksum: Option<&str>) -> Vec<u8> {
    let mut z = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let o = zip::write::SimpleFileOptions::default();
    z.start_file("main.xml", o).unwrap();
    z.write_all(xml.as_bytes()).unwrap();
    for (n, b) in entries {
        z.start_file(*n, o).unwrap();
        z.write_all(b).unwrap();
    }
    let sum = checksum.map_or_else(
        || {
            Md5::digest(xml.as_bytes())
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect()
        },
        str::to_string,
    );
    z.start_file("md5checksum.hex", o).unwrap();
    z.write_all(format!("{sum} *main.xml\n").as_bytes())
        .unwrap();
    z.finish().unwrap().into_inner()
}

fn xml(axes: bool, size_x: usize, record3_data: &str) -> String {
    let axes = if axes {
        "<Axes><CX><AxisType>I</AxisType><DataType>D</DataType><Increment>1e-6</Increment><Offset>0</Offset></CX>\
         <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>1e-6</Increment><Offset>0</Offset></CY>\
         <CZ><AxisType>A</AxisType><DataType>D</DataType><Increment>1</Increment><Offset>0</Offset></CZ></Axes>"
    } else {
        ""
    };
    format!(
        "<?xml version=\"1.0\"?>\n<p:ISO5436_2 xmlns:p=\"http://www.opengps.eu/2008/ISO5436_2\">\n<Record1><Revision>ISO5436 - 2000</Revision><FeatureType>SUR</FeatureType>{axes}</Record1>\n<Record3><MatrixDimension><SizeX>{size_x}</SizeX><SizeY>2</SizeY><SizeZ>1</SizeZ></MatrixDimension>{record3_data}</Record3>\n</p:ISO5436_2>\n"
    )
}

#[test]
fn damaged_x3p_files_are_refused_with_the_field_named() {
    let dir = tempdir();
    let p = dir.path();
    let link = "<DataLink><PointDataLink>bindata/data.bin</PointDataLink></DataLink>";
    let data: Vec<u8> = [1e-6f64, 2e-6, 3e-6, 4e-6]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let nan: Vec<u8> = [f64::NAN; 4].iter().flat_map(|v| v.to_le_bytes()).collect();
    let good = x3p(&xml(true, 2, link), &[("bindata/data.bin", &data)], None);
    let mut truncated = good.clone();
    truncated.truncate(good.len() / 2);
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("ok.x3p", good.clone(), ""),
        ("corrupt.x3p", truncated, "zip"),
        ("notzip.x3p", b"PK\x03\x04 but no archive".to_vec(), "zip"),
        (
            "checksum.x3p",
            x3p(
                &xml(true, 2, link),
                &[("bindata/data.bin", &data)],
                Some("00ff"),
            ),
            "md5checksum.hex",
        ),
        (
            "noaxes.x3p",
            x3p(&xml(false, 2, link), &[("bindata/data.bin", &data)], None),
            "Record1/Axes/CX",
        ),
        (
            "sizes.x3p",
            x3p(&xml(true, 3, link), &[("bindata/data.bin", &data)], None),
            "bindata/data.bin holds 32 bytes",
        ),
        (
            "nodata.x3p",
            x3p(&xml(true, 2, link), &[], None),
            "the archive has no bindata/data.bin",
        ),
        (
            "allnan.x3p",
            x3p(&xml(true, 2, link), &[("bindata/data.bin", &nan)], None),
            "not measured",
        ),
        (
            "datamd5.x3p",
            x3p(
                &xml(
                    true,
                    2,
                    "<DataLink><PointDataLink>bindata/data.bin</PointDataLink><MD5ChecksumPointData>0123456789abcdef0123456789abcdef</MD5ChecksumPointData></DataLink>",
                ),
                &[("bindata/data.bin", &data)],
                None,
            ),
            "MD5ChecksumPointData",
        ),
        (
            "datum.x3p",
            x3p(
                &xml(
                    true,
                    2,
                    "<DataList><Datum>1e-6</Datum><Datum>x</Datum><Datum>1e-6</Datum><Datum>1e-6</Datum></DataList>",
                ),
                &[],
                None,
            ),
            "Datum 2 at main.xml line 4",
        ),
    ];
    for (name, bytes, needle) in cases {
        let f = p.join(name);
        std::fs::write(&f, bytes).unwrap();
        let out = p.join(format!("{name}.gsf"));
        let o = crest()
            .arg("convert")
            .arg(&f)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        if needle.is_empty() {
            assert!(o.status.success(), "{name}: {err}");
            continue;
        }
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(name), "{name}: {err}");
        assert!(err.contains(needle), "{name}: {needle:?} not in {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert!(!out.exists(), "{name}: output written");
    }
}
