//! Real parts (issue 15): the design surface as input, contact data from the part or the
//! path, the N-buffer along the part's normals, patches and maps on real NX exports.

use crate::util::{ROOT, crest, external_samples, json};
use std::path::{Path, PathBuf};

const BALL: &str = "samples/synth/ball-r5.toml";

/// Write a synthetic path over `surface` (passes along x, contact points 0.4 mm apart along
/// the surface) and its design surface as STL; `three_axis` keeps the axis vertical.
fn synth(dir: &Path, surface: &str, three_axis: bool) -> (PathBuf, PathBuf) {
    let cls = dir.join(format!("{surface}-{three_axis}.cls"));
    let stl = dir.join(format!("{surface}.stl"));
    let mut c = crest();
    c.current_dir(ROOT).args([
        "synth",
        surface,
        "--tool",
        BALL,
        "--stepover-mm",
        "0.4",
        "--stepover-along-surface",
        "--size-mm",
        "4,4",
        "--point-step-mm",
        "0.05",
        "--feed-mm-min",
        "1000",
        "--rpm",
        "20000",
        "--part-tol-um",
        "0.01",
        "-o",
    ]);
    c.arg(&cls).arg("--part-stl").arg(&stl);
    if three_axis {
        c.args(["--axis", "0,0,1"]);
    }
    c.assert().success();
    (cls, stl)
}

/// The crest between two ball passes whose centres lie `phi` apart (radians) on a circle
/// about the cylinder axis (convex: radius Rs + R, material inside; concave: Rs − R,
/// material outside): the two-circle construction, µm.
fn two_circle_crest_um(rs: f64, r: f64, arc: f64, convex: bool) -> f64 {
    let half = 0.5 * arc / rs;
    if convex {
        let rc = rs + r;
        let d = rc * half.cos() - (r * r - (rc * half.sin()).powi(2)).sqrt();
        (d - rs) * 1e3
    } else {
        let rc = rs - r;
        let d = rc * half.cos() + (r * r - (rc * half.sin()).powi(2)).sqrt();
        (rs - d) * 1e3
    }
}

#[test]
fn two_circle_construction_gives_the_stated_crests() {
    // The figures: plane R − √(R² − ae²/4) = 4.0016 µm, convex ≈ 5.00, concave ≈ 3.00.
    let plane = (5.0 - (25.0f64 - 0.04).sqrt()) * 1e3;
    assert!((plane - 4.0016).abs() < 1e-4, "{plane}");
    let vex = two_circle_crest_um(20.0, 5.0, 0.4, true);
    let cave = two_circle_crest_um(20.0, 5.0, 0.4, false);
    assert!((vex - 5.00).abs() < 0.01, "{vex}");
    assert!((cave - 3.00).abs() < 0.01, "{cave}");
    // A very large radius tends to the plane.
    assert!((two_circle_crest_um(1e7, 5.0, 0.4, true) - plane).abs() < 1e-3);
}

#[test]
fn n_buffer_crests_on_plane_and_cylinders_match_the_closed_forms() {
    let dir = tempfile::tempdir().unwrap();
    let plane = (5.0 - (25.0f64 - 0.04).sqrt()) * 1e3;
    for (surface, want) in [
        ("plane", plane),
        ("convex-cylinder", two_circle_crest_um(20.0, 5.0, 0.4, true)),
        (
            "concave-cylinder",
            two_circle_crest_um(20.0, 5.0, 0.4, false),
        ),
    ] {
        for three_axis in [false, true] {
            let (cls, stl) = synth(dir.path(), surface, three_axis);
            let out = dir.path().join(format!("{surface}-{three_axis}.csv"));
            // fz 0.01 mm: the feed marks add 0.0025 µm to the crest (0.06 %).
            let a = crest()
                .current_dir(ROOT)
                .arg("simulate")
                .arg(&cls)
                .args(["--tool", BALL, "--part"])
                .arg(&stl)
                .args([
                    "--model",
                    "dome",
                    "--grid-um",
                    "1",
                    "--fz-mm",
                    "0.01",
                    "--patch-near",
                    "0,0,0",
                    "--patch-mm",
                    "0.05,0.5",
                    "--json",
                    "-o",
                ])
                .arg(&out)
                .assert()
                .success();
            let j = json(&a.get_output().stdout);
            assert_eq!(j["cut_fraction"], 1.0, "{surface}");
            assert_eq!(j["reference"], "design surface of the part");
            let max = j["heights_um"]["max"].as_f64().unwrap();
            let min = j["heights_um"]["min"].as_f64().unwrap();
            let dev = (max - want).abs() / want;
            assert!(
                dev < 0.03,
                "{surface} 3-axis {three_axis}: crest {max} µm, closed form {want} µm"
            );
            // No gouge: nothing below the design surface beyond its facets (0.01 µm).
            assert!(min > -0.02, "{surface} {three_axis}: lowest {min} µm");
        }
    }
}

#[test]
fn contact_from_the_part_is_within_a_micrometre_and_a_tenth_of_a_degree() {
    let dir = tempfile::tempdir().unwrap();
    for (surface, convex) in [("convex-cylinder", true), ("concave-cylinder", false)] {
        let (cls, stl) = synth(dir.path(), surface, true);
        let out = dir.path().join(format!("{surface}-contact.csv"));
        let a = crest()
            .current_dir(ROOT)
            .arg("contact")
            .arg(&cls)
            .args(["--tool", BALL, "--part"])
            .arg(&stl)
            .arg("--json")
            .arg("-o")
            .arg(&out)
            .assert()
            .success();
        let j = json(&a.get_output().stdout);
        assert_eq!(j["postures"], j["with_contact"], "{j}");
        assert!(j["max_gouge_um"].as_f64().unwrap() < 0.05, "{j}");
        let text = std::fs::read_to_string(&out).unwrap();
        let mut checked = 0;
        for line in text.lines().skip(1) {
            let v: Vec<&str> = line.split(',').collect();
            if v[6].is_empty() {
                continue;
            }
            let f: Vec<f64> = v.iter().map(|s| s.parse().unwrap()).collect();
            // The ball centre of a 3-axis posture, and the exact contact on the cylinder of
            // radius 20 about x (convex axis at z = −20, concave at z = +20).
            let (cy, cz) = (f[1], f[2] + 5.0);
            let (ay, az, rs) = (0.0, if convex { -20.0 } else { 20.0 }, 20.0);
            let (dy, dz) = (cy - ay, cz - az);
            let d = dy.hypot(dz);
            let (ey, ez) = (dy / d, dz / d);
            let exact = [f[0], ay + rs * ey, az + rs * ez];
            let normal = if convex {
                [0.0, ey, ez]
            } else {
                [0.0, -ey, -ez]
            };
            let err =
                ((f[6] - exact[0]).powi(2) + (f[7] - exact[1]).powi(2) + (f[8] - exact[2]).powi(2))
                    .sqrt();
            assert!(err < 1e-3, "{surface}: contact {:?} vs {exact:?}", &f[6..9]);
            let dot = f[9] * normal[0] + f[10] * normal[1] + f[11] * normal[2];
            assert!(
                dot.clamp(-1.0, 1.0).acos().to_degrees() < 0.1,
                "{surface}: normal {:?}",
                &f[9..12]
            );
            checked += 1;
        }
        assert!(checked > 500, "{checked}");
    }
}

#[test]
fn patches_on_real_centre_line_exports_cut_most_of_their_nodes() {
    let Some(ext) = external_samples() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    // The large export's point lies on the lead-in and lead-out arcs, about 8.5 mm above
    // the floor (issue 33): refused with that distance by default, simulated from every
    // feed move with `--moves all` (with a warning, exit 1).
    let large = ext.join("nx_5axis_varcontour_ijk_large.cls");
    let a = crest()
        .arg("simulate")
        .arg(&large)
        .args([
            "--teeth",
            "2",
            "--rpm",
            "8000",
            "--model",
            "dome",
            "--grid-um",
            "10",
            "--patch-near",
            "472.0,224.4,-65.8",
            "--patch-mm",
            "4,4",
            "-o",
        ])
        .arg(dir.path().join("air.gsf"))
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).replace('│', " ");
    let err = err.split_whitespace().collect::<Vec<_>>().join(" ");
    let d: f64 = err
        .split(" mm from the surface")
        .next()
        .and_then(|h| h.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no distance in: {err}"));
    assert!((7.5..9.5).contains(&d), "{d}: {err}");
    for (file, near, moves, code) in [
        (
            "nx_5axis_varcontour_ijk_large.cls",
            "472.0,224.4,-65.8",
            "all",
            1,
        ),
        // A 4 mm patch across a 14.6 mm stepover: its areal parameters do not cover one
        // scallop period (a sanity check, exit 1).
        ("nx_fixed_contour_nurbs.cls", "-94.4,101,253", "cut", 1),
    ] {
        let out = dir.path().join(format!("{file}.gsf"));
        let a = crest()
            .arg("simulate")
            .arg(ext.join(file))
            .args([
                "--teeth",
                "2",
                "--rpm",
                "8000",
                "--model",
                "dome",
                "--grid-um",
                "10",
                "--patch-near",
                near,
                "--patch-mm",
                "4,4",
                "--json",
                "--moves",
                moves,
                "-o",
            ])
            .arg(&out)
            .assert()
            .code(code);
        let j = json(&a.get_output().stdout);
        if moves == "all" {
            assert!(
                j["warnings"]
                    .to_string()
                    .contains("engage and retract moves only"),
                "{j}"
            );
        } else {
            assert!(
                j["warnings"]
                    .to_string()
                    .contains("narrower than the local stepover 14.59"),
                "{j}"
            );
        }
        assert!(j["cut_fraction"].as_f64().unwrap() >= 0.8, "{file}: {j}");
        assert_eq!(j["reference"], "surface derived from the path", "{file}");
        assert!(j["tool"].as_str().unwrap().contains("TLDATA"), "{file}");
        // Culling: only the samples near the patch are simulated.
        assert!(j["samples"].as_u64().unwrap() * 10 < j["samples_total"].as_u64().unwrap());
    }
}

#[test]
fn a_tool_from_tldata_needs_its_tooth_count_by_name() {
    let Some(ext) = external_samples() else {
        return;
    };
    let a = crest()
        .arg("simulate")
        .arg(ext.join("nx_fixed_contour_nurbs.cls"))
        .args([
            "--rpm",
            "8000",
            "--model",
            "dome",
            "--grid-um",
            "10",
            "--patch-near",
            "-94.4,101,253",
            "--patch-mm",
            "1,1",
            "-o",
            "x.gsf",
        ])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr);
    assert!(err.contains("--teeth") && err.contains("TLDATA"), "{err}");
}

#[test]
fn a_patch_away_from_the_path_is_refused_and_a_thin_cut_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let (cls, stl) = synth(dir.path(), "plane", false);
    let out = dir.path().join("far.csv");
    // 30 mm from a 4 × 4 mm field.
    let a = crest()
        .current_dir(ROOT)
        .arg("simulate")
        .arg(&cls)
        .args(["--tool", BALL, "--part"])
        .arg(&stl)
        .args([
            "--model",
            "dome",
            "--grid-um",
            "10",
            "--patch-near",
            "30,0,0",
            "--patch-mm",
            "1,1",
            "-o",
        ])
        .arg(&out)
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr);
    assert!(
        err.contains("does not cut there") || err.contains("within reach"),
        "{err}"
    );
    assert!(!out.exists());
    // A window that the field covers only at one edge: exit 1, said on stderr and in JSON.
    let out = dir.path().join("thin.csv");
    let a = crest()
        .current_dir(ROOT)
        .arg("simulate")
        .arg(&cls)
        .args([
            "--tool",
            BALL,
            "--model",
            "dome",
            "--grid-um",
            "100",
            "--window",
            "2.5,-2,60,2",
            "--json",
            "-o",
        ])
        .arg(&out)
        .assert()
        .code(1);
    let j = json(&a.get_output().stdout);
    assert!(j["cut_fraction"].as_f64().unwrap() < 0.1, "{j}");
    assert!(j["warning"].as_str().unwrap().contains("were cut"), "{j}");
    assert!(String::from_utf8_lossy(&a.get_output().stderr).contains("were cut"));
}

#[test]
fn a_part_map_is_a_point_cloud_with_heights() {
    let dir = tempfile::tempdir().unwrap();
    let (cls, stl) = synth(dir.path(), "convex-cylinder", false);
    let out = dir.path().join("map.ply");
    let a = crest()
        .current_dir(ROOT)
        .arg("simulate")
        .arg(&cls)
        .args(["--tool", BALL, "--part"])
        .arg(&stl)
        .args([
            "--model",
            "dome",
            "--grid-um",
            "10",
            "--fz-mm",
            "0.05",
            "--map-mm",
            "0.05",
            "--region",
            "-1,-1,-1,1,1,1",
            "--json",
            "-o",
        ])
        .arg(&out)
        .assert()
        .success();
    let j = json(&a.get_output().stdout);
    assert_eq!(j["grid"], "map");
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.starts_with("ply\nformat ascii 1.0\n"));
    assert!(text.contains("property float height_um"));
    let pts: Vec<Vec<f64>> = text
        .lines()
        .skip_while(|l| *l != "end_header")
        .skip(1)
        .map(|l| {
            l.split_whitespace()
                .map(|t| t.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    // A 2 × 2 mm region at 0.05 mm: about 40 × 40 points, all on the cylinder, all cut,
    // heights between 0 and the crest.
    assert!(pts.len() > 1200 && pts.len() < 2200, "{}", pts.len());
    for p in &pts {
        let r = p[1].hypot(p[2] + 20.0);
        assert!((r - 20.0).abs() < 1e-3, "{p:?}");
        assert!(p[6] > -0.05 && p[6] < 5.3, "{p:?}");
    }
}

#[test]
fn bad_meshes_exit_2_naming_file_and_triangle() {
    let dir = tempfile::tempdir().unwrap();
    let (cls, stl) = synth(dir.path(), "plane", false);
    let bytes = std::fs::read(&stl).unwrap();
    let cut = dir.path().join("cut.stl");
    std::fs::write(&cut, &bytes[..bytes.len() - 10]).unwrap();
    let a = crest()
        .current_dir(ROOT)
        .arg("contact")
        .arg(&cls)
        .args(["--tool", BALL, "--part"])
        .arg(&cut)
        .args(["-o"])
        .arg(dir.path().join("c.csv"))
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr);
    assert!(
        err.contains("cut.stl:1:") && err.contains("header says"),
        "{err}"
    );
    let bad = dir.path().join("bad.obj");
    std::fs::write(
        &bad,
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 nan\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let a = crest()
        .current_dir(ROOT)
        .arg("contact")
        .arg(&cls)
        .args(["--tool", BALL, "--part"])
        .arg(&bad)
        .args(["-o"])
        .arg(dir.path().join("c.csv"))
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr);
    assert!(err.contains("bad.obj:4:"), "{err}");
}

mod properties {
    use crest::math::{Point3, Vec3};
    use crest::part::{Mesh, Part};
    use crest::surface::{GridSpec, Model, Options, Reference, simulate_with};
    use crest::tool::{Cutter, Shape};
    use proptest::prelude::*;

    /// The plane z = `z` as two triangles over ±20 mm.
    fn plane_part(z: f64) -> Part {
        let p = |x: f64, y: f64| Point3::new(x, y, z);
        Part::new(Mesh {
            vertices: vec![
                p(-20.0, -20.0),
                p(20.0, -20.0),
                p(20.0, 20.0),
                p(-20.0, 20.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        })
        .unwrap()
    }

    fn pass() -> (Cutter, Vec<crest::resample::Sample>) {
        let c = Cutter::new(Shape::Ball, 5.0, 2, 0.0);
        let s = crest::synth::pass::straight_pass(&c, 10f64.to_radians(), 0.05, -2.0, 4.0, 10.0)
            .unwrap();
        (c, s)
    }

    fn window(y0: f64) -> Options {
        let mut o = Options::new(
            Model::Dome,
            GridSpec::Window {
                x0_mm: -0.3,
                y0_mm: y0,
                x1_mm: 0.3,
                y1_mm: y0 + 0.6,
            },
            0.01,
        );
        o.depth_mm = 0.05;
        o
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(6))]

        /// Raising the plane part by d (the path unchanged) lowers every reached height by
        /// exactly 1000·d µm, and the same nodes are reached. (The ICE model: its triangles
        /// do not depend on the band; the dome's angular mesh follows the levels in the band,
        /// so it agrees only to its 0.01 µm chord tolerance.)
        #[test]
        fn raising_the_part_lowers_every_height_by_d(d in -0.003f64..0.003, y0 in -0.5f64..0.0) {
            let (c, s) = pass();
            let mut o = window(y0);
            o.model = Model::Ice { dtheta_rad: 2f64.to_radians() };
            let a = simulate_with(&s, &c, &o, Reference::Part(&plane_part(0.0)), &|_, _| {}).unwrap();
            let b = simulate_with(&s, &c, &o, Reference::Part(&plane_part(d)), &|_, _| {}).unwrap();
            prop_assert!(a.nodes_cut > 0);
            for (ha, hb) in a.map.z_um.iter().zip(&b.map.z_um) {
                prop_assert_eq!(ha.is_nan(), hb.is_nan());
                if ha.is_finite() {
                    prop_assert!((ha - hb - 1000.0 * d).abs() < 1e-6, "{} {} {}", ha, hb, d);
                }
            }
        }
    }

    /// Nodes the tool never reaches are reported as not reached (NaN), never as zero; the
    /// result is the same for one and two threads.
    #[test]
    fn unreached_nodes_are_nan_and_threads_do_not_matter() {
        let (c, s) = pass();
        // The pass runs along y = 0; the window reaches 3 mm across, beyond the ball's reach
        // within the 0.05 mm depth (√(2 R ap) ≈ 0.71 mm).
        let mut o = window(0.0);
        o.grid = GridSpec::Window {
            x0_mm: -0.2,
            y0_mm: -0.2,
            x1_mm: 0.2,
            y1_mm: 3.0,
        };
        let part = plane_part(0.0);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| simulate_with(&s, &c, &o, Reference::Part(&part), &|_, _| {}).unwrap())
        };
        let one = run(1);
        let two = run(2);
        assert_eq!(
            one.map.z_um.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            two.map.z_um.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        let m = &one.map;
        for j in 0..m.ny {
            let y = m.y0_mm + j as f64 * m.dy_um * 1e-3;
            for &h in m.row(j) {
                if y > 1.0 {
                    assert!(h.is_nan(), "y {y}: {h}");
                } else if y < 0.5 {
                    assert!(h.is_finite(), "y {y}: {h}");
                }
            }
        }
        assert!(m.z_um.iter().all(|h| h.is_nan() || *h > -1e-9));
        let _ = Vec3::z();
    }
}
