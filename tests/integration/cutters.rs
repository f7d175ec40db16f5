//! General cutters (issue 23): round inserts, APT seven-parameter cutters, profiles and the
//! circle-segment families, axial run-out per tooth. The closed forms (a barrel's scallop
//! between passes, a round insert's marks along the feed, level and with a lifted insert),
//! synth's exact step with a barrel, `tool.toml` for every shape through `crest tool` and
//! `crest plot`, and APT files with `CUTTER/` of each family read and simulated.

use std::f64::consts::TAU;

use approx::assert_relative_eq;
use crest::math::{Point3, Vec3};
use crest::resample::Sample;
use crest::surface::{GridSpec, Model, Options, simulate};
use crest::synth::{CrossSection, axis_convention_a, exact_step_mm};
use crest::tool::{Cutter, Rule, Shape, analyse, meridian};

use crate::util::{crest, repo, stdout_json, tempdir};

fn no_progress(_: usize, _: usize) {}

fn tool(name: &str) -> Cutter {
    crest::pipeline::load_tool(&repo("samples/tools").join(name))
        .unwrap_or_else(|e| panic!("{e:?}"))
}

/// `Rs − √(Rs² − s²/4)`, mm.
fn sag(radius: f64, s: f64) -> f64 {
    radius - (radius * radius - 0.25 * s * s).sqrt()
}

// ---------------------------------------------------------------------------------------
// Barrel: the segment radius across the feed
// ---------------------------------------------------------------------------------------

#[test]
fn barrel_tangent_to_a_plane_leaves_the_segment_scallop() {
    // Rs = 250 mm, ae = 2 mm: 2.0 µm. The axis leans 89° across the feed (yaw 90°), so the
    // barrel's segment lies in the plane of the cross-section.
    let c = tool("barrel-r8-rs250.toml");
    let axis = axis_convention_a(89f64.to_radians(), 90f64.to_radians());
    let cs = CrossSection::new(&c, &axis).unwrap();
    let want = sag(250.0, 2.0);
    assert_relative_eq!(want * 1e3, 2.0, max_relative = 1e-3);
    let h = cs.scallop_mm(2.0).unwrap();
    assert_relative_eq!(h, want, max_relative = 0.02);
    // The exact step for a 2 µm scallop is the 2 mm of the closed form.
    let s = exact_step_mm(&c, &axis, want).unwrap();
    assert_relative_eq!(s, 2.0, max_relative = 0.02);
    // A ball of the barrel's radius would need a step 5.6 times smaller.
    let ball = Cutter::new(Shape::Ball, 8.0, 4, 0.0);
    let s_ball = exact_step_mm(&ball, &axis_convention_a(0.0, 0.0), want).unwrap();
    assert!(s / s_ball > 5.0, "{s} vs {s_ball}");
}

#[test]
fn synth_plane_with_a_barrel_steps_by_the_exact_envelope() {
    let dir = tempdir();
    let out = dir.path().join("barrel.cls");
    let a = crest()
        .args(["synth", "plane", "--tool"])
        .arg(repo("samples/tools/barrel-r8-rs250.toml"))
        .args(["--tilt-deg", "89", "--yaw-deg", "90", "--scallop-um", "2"])
        .args([
            "--feed-mm-min",
            "2000",
            "--rpm",
            "10000",
            "--size-mm",
            "6,8",
        ])
        .args(["--point-step-mm", "1", "-o"])
        .arg(&out)
        .arg("--json")
        .assert()
        .success();
    let v = stdout_json(&a);
    let step = v["plane_step_mm"].as_f64().unwrap();
    let stepover = v["stepover_mm"].as_f64().unwrap();
    assert_relative_eq!(step, 2.0, max_relative = 0.02);
    assert_relative_eq!(stepover, step, max_relative = 1e-9);
    let r_eff = v["r_eff_mm"].as_f64().unwrap();
    assert_relative_eq!(r_eff, 250.0, max_relative = 0.02);
    // The file reads back; its TLDATA cannot describe a barrel, so it has none.
    let p = crest::io::toolpath::read_program(&out).unwrap();
    assert!(p.paths[0].tool.is_none());
}

#[test]
fn simulated_barrel_passes_leave_the_closed_form_scallop() {
    // Dome model across three passes 2 mm apart: the cusps are 2.0 µm high.
    let c = tool("barrel-r8-rs250.toml");
    let axis = axis_convention_a(89f64.to_radians(), 90f64.to_radians());
    let fz = 0.05;
    let mut samples = Vec::new();
    for (run, y) in [-2.0, 0.0, 2.0].iter().enumerate() {
        let n = 40;
        for k in 0..=n {
            let s = -1.0 + 2.0 * k as f64 / n as f64;
            let cc = Point3::new(s, *y, 0.0);
            samples.push(Sample {
                run,
                s_mm: s,
                t_s: s,
                theta_rad: TAU * s / (4.0 * fz),
                position: crest::synth::tool_tip(&c, &cc, &Vec3::z(), &axis),
                axis,
                contact: Some(cc),
                normal: Some(Vec3::z()),
                feed_dir: Vec3::x(),
                feed_mm_min: 1000.0,
            });
        }
    }
    let grid = GridSpec::Window {
        x0_mm: -0.05,
        y0_mm: -0.4,
        x1_mm: 0.05,
        y1_mm: 2.4,
    };
    let mut opts = Options::new(Model::Dome, grid, 0.01);
    opts.chord_tol_mm = 1e-6;
    let sim = simulate(&samples, &c, &opts, &no_progress).unwrap();
    let m = &sim.map;
    assert_eq!(sim.nodes_cut, m.nx * m.ny);
    let col: Vec<f64> = (0..m.ny).map(|j| m.get(5, j)).collect();
    let top = col.iter().copied().fold(f64::MIN, f64::max);
    let low = col.iter().copied().fold(f64::MAX, f64::min);
    assert!(low.abs() < 0.05, "passes at 0: {low}");
    assert_relative_eq!(top - low, sag(250.0, 2.0) * 1e3, max_relative = 0.03);
}

// ---------------------------------------------------------------------------------------
// Round inserts along the feed
// ---------------------------------------------------------------------------------------

fn round_insert(lift_um: f64) -> Cutter {
    let mut c = tool("round-insert-r10-ri5.toml");
    c.runout.tooth_axial_dev_mm = vec![0.0, lift_um * 1e-3];
    c
}

#[test]
fn round_insert_marks_match_the_closed_forms() {
    // ri = 5, z = 2, fz = 0.4 at a lead of 1° (the back of the ring clears the surface):
    // level inserts leave marks fz apart of crest fz²/(8 ri) = 4.0 µm; an insert lifted by
    // more than (z fz)²/(8 ri) = 16 µm leaves one mark per revolution of that crest.
    let (ri, z, fz) = (5.0, 2.0, 0.4);
    for rule in [Rule::Paper, Rule::Exact] {
        let a = analyse(&round_insert(0.0), 1.0, 0.2, fz, rule).unwrap();
        assert_eq!(a.zc, 2, "{rule:?}");
        assert_relative_eq!(a.fz_effective_mm, fz, epsilon = 1e-12);
        assert_relative_eq!(
            a.crest_height_corrected_mm,
            fz * fz / (8.0 * ri),
            max_relative = 0.02
        );
        let a = analyse(&round_insert(20.0), 1.0, 0.2, fz, rule).unwrap();
        assert_eq!(a.zc, 1, "{rule:?}");
        assert!(!a.teeth[1].participates);
        assert_relative_eq!(a.fz_effective_mm, z * fz, epsilon = 1e-12);
        let one_per_rev = (z * fz) * (z * fz) / (8.0 * ri);
        assert_relative_eq!(
            a.crest_height_corrected_mm,
            one_per_rev,
            max_relative = 0.02
        );
    }
    // A lift below the one-mark crest leaves both inserts cutting, the crest in between.
    let a = analyse(&round_insert(9.0), 1.0, 0.2, fz, Rule::Exact).unwrap();
    assert_eq!(a.zc_exact, 2);
    assert!(a.crest_height_exact_mm > 0.004 && a.crest_height_exact_mm < 0.016);
    assert_relative_eq!(
        a.teeth[1].normal_deviation_mm,
        -0.009 * 1f64.to_radians().cos(),
        epsilon = 1e-12
    );
}

/// The heights (µm) along the feed through the ring's front, one pass at lead 1°.
fn round_insert_track(c: &Cutter) -> Vec<f64> {
    let lead = 1f64.to_radians();
    let axis = Vec3::new(lead.sin(), 0.0, lead.cos());
    let fz = 0.4;
    let samples = crate::util::pass(
        c,
        0,
        Point3::new(-1.0, 0.0, 0.0),
        Vec3::x(),
        axis,
        6.0,
        0.05,
        fz,
        0.0,
    );
    let grid = GridSpec::Window {
        x0_mm: 0.8,
        y0_mm: 0.0,
        x1_mm: 4.0,
        y1_mm: 0.0,
    };
    let opts = Options::new(
        Model::Ice {
            dtheta_rad: 0.1f64.to_radians(),
        },
        grid,
        0.002,
    );
    let sim = simulate(&samples, c, &opts, &no_progress).unwrap();
    assert_eq!(sim.nodes_cut, sim.map.nx);
    (0..sim.map.nx).map(|i| sim.map.get(i, 0)).collect()
}

/// Local minima of a track (mark bottoms), as node indices.
fn bottoms(z: &[f64]) -> Vec<usize> {
    (1..z.len() - 1)
        .filter(|&i| z[i] < z[i - 1] && z[i] <= z[i + 1])
        .collect()
}

#[test]
fn simulated_round_insert_marks_one_per_insert_then_one_per_revolution() {
    let level = round_insert_track(&round_insert(0.0));
    let rz = |z: &[f64]| {
        z.iter().copied().fold(f64::MIN, f64::max) - z.iter().copied().fold(f64::MAX, f64::min)
    };
    assert_relative_eq!(rz(&level), 4.0, max_relative = 0.02);
    let b = bottoms(&level);
    let spacing = (b[b.len() - 1] - b[0]) as f64 * 0.002 / (b.len() - 1) as f64;
    assert_relative_eq!(spacing, 0.4, max_relative = 0.01);
    // Lifted by 20 µm (> 16 µm): one mark per revolution, 0.8 mm apart, crest 16 µm.
    let lifted = round_insert_track(&round_insert(20.0));
    assert_relative_eq!(rz(&lifted), 16.0, max_relative = 0.02);
    let b = bottoms(&lifted);
    let spacing = (b[b.len() - 1] - b[0]) as f64 * 0.002 / (b.len() - 1) as f64;
    assert_relative_eq!(spacing, 0.8, max_relative = 0.01);
}

// ---------------------------------------------------------------------------------------
// Every shape through tool.toml, `crest tool` and `crest plot`
// ---------------------------------------------------------------------------------------

const SHAPES: [&str; 8] = [
    "round-insert-r10-ri5.toml",
    "round-insert-a2.toml",
    "barrel-r8-rs250.toml",
    "lens-r5-rs50.toml",
    "oval-r5-rs20.toml",
    "taper-barrel-r3-rs250.toml",
    "apt-taper-corner.toml",
    "profile-chamfer.toml",
];

#[test]
fn every_shape_goes_through_crest_tool() {
    for name in SHAPES {
        let v = stdout_json(
            &crest()
                .args(["tool", "--tool"])
                .arg(repo("samples/tools").join(name))
                .args([
                    "--lead-deg",
                    "10",
                    "--ap-mm",
                    "0.2",
                    "--fz-mm",
                    "0.1",
                    "--rule",
                    "exact",
                    "--json",
                ])
                .assert()
                .success(),
        );
        let crest_um = v["crest_height_um"].as_f64().unwrap();
        assert!(crest_um.is_finite() && crest_um >= 0.0, "{name}: {v}");
        let r_ef = v["effective_radius_mm"].as_f64().unwrap();
        assert!(
            r_ef > 0.0 && r_ef <= v["radius_mm"].as_f64().unwrap() + 1e-9,
            "{name}: {v}"
        );
    }
    // The lifted insert of case A2 is listed with its axial deviation.
    let v = stdout_json(
        &crest()
            .args(["tool", "--tool"])
            .arg(repo("samples/tools/round-insert-a2.toml"))
            .args([
                "--lead-deg",
                "0",
                "--ap-mm",
                "0.4",
                "--fz-mm",
                "0.4",
                "--json",
            ])
            .assert()
            .success(),
    );
    assert_eq!(v["shape"], "round_insert");
    assert_relative_eq!(
        v["teeth"][1]["axial_deviation_um"].as_f64().unwrap(),
        9.0,
        epsilon = 1e-9
    );
}

#[test]
fn every_shape_draws_trochoids_and_its_profile() {
    let dir = tempdir();
    for name in SHAPES {
        let t = repo("samples/tools").join(name);
        let out = dir.path().join(format!("{name}.svg"));
        crest()
            .args(["plot", "trochoid", "--tool"])
            .arg(&t)
            .args(["--heights-mm", "0.5", "-o"])
            .arg(&out)
            .assert()
            .success();
        let out = dir.path().join(format!("{name}-profile.svg"));
        crest()
            .args(["plot", "cutter", "--tool"])
            .arg(&t)
            .arg("-o")
            .arg(&out)
            .assert()
            .success();
        assert!(std::fs::read_to_string(&out).unwrap().contains("<svg"));
    }
}

#[test]
fn profile_tools_simulate_with_the_ice_and_dome_models() {
    // One straight pass at lead 10° for every profile: the models agree on the marks.
    for name in SHAPES {
        let c = tool(name);
        let lead = 10f64.to_radians();
        let axis = Vec3::new(lead.sin(), 0.0, lead.cos());
        let fz = 0.1;
        let n = 60;
        let samples: Vec<Sample> = (0..=n)
            .map(|k| {
                let s = -1.5 + 3.0 * k as f64 / n as f64;
                let cc = Point3::new(s, 0.0, 0.0);
                Sample {
                    run: 0,
                    s_mm: s,
                    t_s: s,
                    theta_rad: TAU * s / (c.teeth() as f64 * fz),
                    position: crest::synth::tool_tip(&c, &cc, &Vec3::z(), &axis),
                    axis,
                    contact: Some(cc),
                    normal: Some(Vec3::z()),
                    feed_dir: Vec3::x(),
                    feed_mm_min: 1000.0,
                }
            })
            .collect();
        let grid = GridSpec::Window {
            x0_mm: -0.5,
            y0_mm: -0.02,
            x1_mm: 0.5,
            y1_mm: 0.02,
        };
        let a = crest::tool::analyse(&c, 10.0, 0.2, fz, Rule::Exact).unwrap();
        // The dome model stamps every tooth's body at every sample (0.05 mm apart here).
        let profile = crest::tool::feed_profile_for(&c, lead);
        let dome = crest::tool::nominal_crest_mm(&profile, 0.05) * 1e3;
        for model in [
            Model::Dome,
            Model::Ice {
                dtheta_rad: 0.5f64.to_radians(),
            },
        ] {
            let sim = simulate(
                &samples,
                &c,
                &Options::new(model, grid, 0.002),
                &no_progress,
            )
            .unwrap_or_else(|e| panic!("{name}: {e}"));
            let m = &sim.map;
            assert_eq!(sim.nodes_cut, m.nx * m.ny, "{name}");
            let row: Vec<f64> = (0..m.nx).map(|i| m.get(i, m.ny / 2)).collect();
            let lo = row.iter().copied().fold(f64::MAX, f64::min);
            let hi = row.iter().copied().fold(f64::MIN, f64::max);
            assert!(lo.abs() < 0.05, "{name} {model:?}: bottom {lo}");
            // The marks along the feed: the 1-D envelope's crest for ICE, the nominal crest
            // of the sample spacing for the dome.
            let want = match model {
                Model::Dome => dome,
                _ => a.crest_height_exact_mm * 1e3,
            };
            assert!(
                (hi - lo - want).abs() < 0.05 + 0.03 * want,
                "{name} {model:?}: {} vs {want}",
                hi - lo,
            );
        }
    }
}

#[test]
fn tool_toml_rejects_what_a_shape_does_not_use() {
    let dir = tempdir();
    let bad = [
        (
            "shape = \"barrel\"\nradius_mm = 8\nsegment_radius_mm = 250\ncorner_radius_mm = 1\nteeth = 2\nhelix_deg = 0\n",
            "segment_height_mm",
        ),
        (
            "shape = \"ball\"\nradius_mm = 5\ntaper_deg = 3\nteeth = 2\nhelix_deg = 0\n",
            "taper_deg",
        ),
        (
            "shape = \"apt\"\napt = [10, 1, 4, 1, 0]\nteeth = 2\nhelix_deg = 0\n",
            "apt",
        ),
        (
            "shape = \"profile\"\nprofile_mm = [[0, 1], [5, 1]]\nteeth = 2\nhelix_deg = 0\n",
            "z = 0",
        ),
        (
            "shape = \"round_insert\"\nradius_mm = 5\ncorner_radius_mm = 6\nteeth = 2\nhelix_deg = 0\n",
            "corner_radius_mm",
        ),
        (
            "shape = \"ball\"\nradius_mm = 5\nteeth = 2\nhelix_deg = 0\n[runout]\ntooth_axial_deviation_um = [1]\n",
            "tooth_axial_deviation_um",
        ),
    ];
    for (i, (text, word)) in bad.iter().enumerate() {
        let t = crate::util::write(dir.path(), &format!("t{i}.toml"), text);
        let a = crest()
            .args(["tool", "--tool"])
            .arg(&t)
            .args(["--lead-deg", "0", "--ap-mm", "0.1", "--fz-mm", "0.1"])
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
        assert!(err.contains(word), "{text}: {err}");
    }
}

// ---------------------------------------------------------------------------------------
// APT files with CUTTER/ of each family
// ---------------------------------------------------------------------------------------

/// (file, V-groove end angle a in degrees, stepover mm): when the end is a cone of that
/// angle under the passes, the highest point between two passes and two stamps of the
/// body (fz = 0.05 mm apart: 1000 mm/min, 10000 rpm, 2 teeth) is `tan a √((s/2)² + (fz/2)²)`.
const APT_FILES: [(&str, f64, f64); 3] = [
    ("cone.apt", 30.0, 0.2),
    ("dished-bull-nose.apt", 5.0, 1.0),
    ("taper-corner.apt", 0.0, 1.0),
];

#[test]
fn apt_files_of_each_family_read_and_simulate() {
    let dir = tempdir();
    for (name, a_deg, step) in APT_FILES {
        let file = repo("samples/apt/cutters").join(name);
        let p = crest::io::toolpath::read_program(&file).unwrap();
        assert!(p.warnings.is_empty(), "{name}: {:?}", p.warnings);
        let t = p.paths[0].tool.as_ref().unwrap();
        let apt = t.apt.unwrap();
        assert!(t.apt_profile().is_some(), "{name}: read as a classic shape");
        let (m, warning) = meridian::apt([
            apt[0],
            apt[1],
            apt[2],
            apt[3],
            apt[4].to_degrees(),
            apt[5].to_degrees(),
            apt[6],
        ])
        .unwrap();
        assert!(warning.is_none(), "{name}: {warning:?}");
        assert!(m.is_convex());
        let out = dir.path().join(format!("{name}.csv"));
        let v = stdout_json(
            &crest()
                .arg("simulate")
                .arg(&file)
                .args([
                    "--teeth",
                    "2",
                    "--rpm",
                    "10000",
                    "--model",
                    "dome",
                    "--grid-um",
                    "5",
                ])
                .args(["--window", "0.5,-0.6,1.5,0.6", "-o"])
                .arg(&out)
                .arg("--json")
                .assert()
                .success(),
        );
        assert!(
            v["tool"].as_str().unwrap().contains("APT cutter"),
            "{name}: {v}"
        );
        let sz = v["heights_um"]["sz"].as_f64().unwrap();
        let want = a_deg.to_radians().tan() * (0.25 * step * step + 0.025f64.powi(2)).sqrt() * 1e3;
        assert!(
            (sz - want).abs() < 0.02 * want + 0.2,
            "{name}: Sz {sz} µm vs {want} µm"
        );
    }
}

#[test]
fn tldata_with_seven_values_is_an_apt_cutter() {
    let dir = tempdir();
    let text = "TOOL PATH/OP,TOOL,CONE\nTLDATA/MILL,10.0,0.0,20.0,0.0,30.0,5.0,2.886751346\n\
                FEDRAT/MMPM,1000\nGOTO/0,0,0,0,0,1\nGOTO/1,0,0\nEND-OF-PATH\n";
    let f = crate::util::write(dir.path(), "cone.cls", text);
    let p = crest::io::toolpath::read_program(&f).unwrap();
    let t = p.paths[0].tool.as_ref().unwrap();
    let apt = t.apt.unwrap();
    assert_relative_eq!(apt[2], 5.0);
    assert_relative_eq!(apt[3], 2.886751346);
    assert_relative_eq!(apt[4].to_degrees(), 30.0, epsilon = 1e-12);
    let (c, what, warnings) =
        crest::pipeline::inputs::resolve_cutter(None, &p, &f, Some(2), None).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert!(what.contains("APT cutter"), "{what}");
    assert!(matches!(c.shape, Shape::Profile(_)));
    assert_relative_eq!(
        c.profile_height(2.0).unwrap(),
        2.0 * 30f64.to_radians().tan(),
        epsilon = 1e-6
    );
}
