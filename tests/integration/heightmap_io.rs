//! Height-map files: round trips through every format (NaN kept), and malformed files
//! rejected with the file name, the place and what was wrong.

use std::path::Path;

use approx::{assert_abs_diff_eq, relative_eq};
use crest::io::{HeightMapError, ReadOptions, read_heightmap, write_heightmap};
use crest::surface::HeightMap;
use proptest::prelude::*;

use crate::util::tempdir;

fn sample_map() -> HeightMap {
    let (nx, ny) = (7, 5);
    let mut z: Vec<f64> = (0..nx * ny)
        .map(|k| ((k as f64) * 0.37).sin() * 1.75 + 0.001 * k as f64)
        .collect();
    z[3] = f64::NAN;
    z[nx * ny - 1] = f64::NAN;
    let mut m = HeightMap::from_rows(nx, ny, 0.5, 0.25, z).unwrap();
    m.x0_mm = 1.5;
    m.y0_mm = -2.0;
    m
}

/// Same grid, NaN where `a` has NaN, heights within `rel` relative (absolute below 1 µm).
fn same_heights(a: &HeightMap, b: &HeightMap, rel: f64) {
    assert_eq!((a.nx, a.ny), (b.nx, b.ny));
    for (k, (x, y)) in a.z_um.iter().zip(&b.z_um).enumerate() {
        if x.is_nan() {
            assert!(y.is_nan(), "node {k}: NaN became {y}");
        } else {
            assert!(
                relative_eq!(*x, *y, epsilon = rel, max_relative = rel),
                "node {k}: {x} vs {y}"
            );
        }
    }
}

fn roundtrip(ext: &str, opts: ReadOptions) -> HeightMap {
    let dir = tempdir();
    let path = dir.path().join(format!("map.{ext}"));
    let m = sample_map();
    write_heightmap(&path, &m).unwrap();
    read_heightmap(&path, &opts).unwrap()
}

#[test]
fn csv_roundtrip_is_exact() {
    let opts = ReadOptions {
        dx_um: Some(0.5),
        dy_um: Some(0.25),
        ..Default::default()
    };
    let back = roundtrip("csv", opts);
    same_heights(&sample_map(), &back, 0.0);
    assert_eq!((back.dx_um, back.dy_um), (0.5, 0.25));
}

#[test]
fn xyz_roundtrip_keeps_spacing_and_origin() {
    let back = roundtrip("xyz", ReadOptions::default());
    same_heights(&sample_map(), &back, 0.0);
    assert_abs_diff_eq!(back.dx_um, 0.5, epsilon = 1e-12);
    assert_abs_diff_eq!(back.dy_um, 0.25, epsilon = 1e-12);
    assert_abs_diff_eq!(back.x0_mm, 1.5, epsilon = 1e-12);
    assert_abs_diff_eq!(back.y0_mm, -2.0, epsilon = 1e-12);
}

#[test]
fn gsf_roundtrip_float32() {
    let back = roundtrip("gsf", ReadOptions::default());
    same_heights(&sample_map(), &back, 1e-7);
    assert_abs_diff_eq!(back.dx_um, 0.5, epsilon = 1e-9);
    assert_abs_diff_eq!(back.dy_um, 0.25, epsilon = 1e-9);
    assert_abs_diff_eq!(back.x0_mm, 1.5, epsilon = 1e-9);
    assert_abs_diff_eq!(back.y0_mm, -2.0, epsilon = 1e-9);
}

#[test]
fn sdf_roundtrip() {
    let back = roundtrip("sdf", ReadOptions::default());
    same_heights(&sample_map(), &back, 1e-12);
    assert_abs_diff_eq!(back.dx_um, 0.5, epsilon = 1e-9);
    assert_abs_diff_eq!(back.dy_um, 0.25, epsilon = 1e-9);
}

#[test]
fn gsf_header_is_gwyddion_simple_field() {
    let dir = tempdir();
    let path = dir.path().join("m.gsf");
    write_heightmap(&path, &sample_map()).unwrap();
    let b = std::fs::read(&path).unwrap();
    let text = String::from_utf8_lossy(&b[..b.iter().position(|&c| c == 0).unwrap()]).to_string();
    assert!(text.starts_with("Gwyddion Simple Field 1.0\n"));
    assert!(text.contains("XRes = 7\n") && text.contains("YRes = 5\n"));
    assert!(text.contains("XReal = 3.5e-6\n"), "{text}");
    assert_eq!((b.len() - 7 * 5 * 4) % 4, 0);
}

#[test]
fn unknown_extension_is_refused_and_writes_nothing() {
    let dir = tempdir();
    let path = dir.path().join("m.png");
    assert!(write_heightmap(&path, &sample_map()).is_err());
    assert!(!path.exists());
    let e = read_heightmap(&path, &ReadOptions::default()).unwrap_err();
    assert!(matches!(e, HeightMapError::UnknownFormat { .. }));
}

fn read_text(name: &str, content: &[u8], opts: ReadOptions) -> String {
    let dir = tempdir();
    let path = dir.path().join(name);
    std::fs::write(&path, content).unwrap();
    let e = read_heightmap(&path, &opts).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains(name), "error does not name the file: {msg}");
    msg
}

#[test]
fn malformed_files_name_place_and_problem() {
    let dx = ReadOptions {
        dx_um: Some(1.0),
        ..Default::default()
    };
    let m = read_text("a.csv", b"1,2,3\n4,5,6\n7,8\n", dx.clone());
    assert!(m.contains("a.csv:3") && m.contains("2 fields"), "{m}");
    let m = read_text("b.csv", b"1,2,3\n4,five,6\n", dx.clone());
    assert!(m.contains("b.csv:2: field 2") && m.contains("five"), "{m}");
    let m = read_text(
        "c.xyz",
        b"x,y,z\n0,0,1\n1,0,1\n0.4,0,1\n",
        ReadOptions::default(),
    );
    assert!(
        m.contains("c.xyz:3: field 1") && m.contains("not on the grid"),
        "{m}"
    );
    let m = read_text(
        "d.gsf",
        b"Gwyddion Simple Field 1.0\nXRes = 2\nYRes = 2\n\0\0\0\0\0\0",
        ReadOptions::default(),
    );
    assert!(m.contains("d.gsf: byte") && m.contains("needs 16"), "{m}");
    let m = read_text("e.gsf", b"GIF89a", ReadOptions::default());
    assert!(m.contains("e.gsf: byte 0"), "{m}");
    let m = read_text("f.sdf", b"aBCR-1.0\nNumPoints = 2\nNumProfiles = 1\nXscale = 1e-6\nYscale = 1e-6\nZscale = 1e-6\n*\n1\n*\n", ReadOptions::default());
    assert!(m.contains("f.sdf:") && m.contains("after 1 of"), "{m}");
    let m = read_text("g.csv", b"", dx.clone());
    assert!(m.contains("no data"), "{m}");
}

#[test]
fn missing_file_names_it() {
    let e = read_heightmap(Path::new("/nonexistent/z.gsf"), &ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/z.gsf"));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn every_format_roundtrips(nx in 1usize..9, ny in 1usize..6, seed in 0u64..1000,
                               dx in 0.05f64..20.0, dy in 0.05f64..20.0) {
        let z: Vec<f64> = (0..nx * ny).map(|k| {
            let v = ((k as u64 * 2654435761 + seed) % 10007) as f64 / 10007.0;
            if v < 0.1 { f64::NAN } else { (v - 0.5) * 100.0 }
        }).collect();
        let m = HeightMap::from_rows(nx, ny, dx, dy, z).unwrap();
        let dir = tempdir();
        for ext in ["csv", "gsf", "sdf", "xyz", "x3p"] {
            let path = dir.path().join(format!("p.{ext}"));
            write_heightmap(&path, &m).unwrap();
            // An x3p with no measured point is refused (the instrument measured nothing).
            if ext == "x3p" && m.z_um.iter().all(|v| v.is_nan()) {
                prop_assert!(read_heightmap(&path, &ReadOptions::default()).is_err());
                continue;
            }
            let opts = ReadOptions { dx_um: Some(dx), dy_um: Some(dy), ..Default::default() };
            // xyz with one row or column cannot know the other spacing: skip the check there.
            if ext == "xyz" && (nx == 1 || ny == 1 || m.z_um.iter().all(|v| v.is_nan())) {
                continue;
            }
            let back = read_heightmap(&path, &opts).unwrap();
            let rel = if ext == "gsf" { 1e-6 } else { 1e-12 };
            same_heights(&m, &back, rel);
            prop_assert!(relative_eq!(back.dx_um, dx, epsilon = 0.0, max_relative = 1e-6));
        }
    }
}
