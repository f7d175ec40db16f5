//! The `simulate` model of `crest report`: a z-map of one straight pass (crate::surface)
//! against the closed-form crest, on the 002 tool with the presetter radii.

use approx::assert_relative_eq;
use crest::study::measured::Side;
use crest::study::regression::{SimulateSpec, crest_model, simulate_case};
use crest::surface::ModelKind as SurfaceModel;
use crest::tool::Rule;
use crest::tool::{Cutter, Shape};

fn tool_002() -> Cutter {
    let mut c = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
    c.runout.tooth_radius_dev_mm = vec![-0.010, -0.015, -0.024, -0.025];
    c
}

#[test]
fn ice_pass_reproduces_the_exact_crest_and_ra() {
    let c = tool_002();
    let crest = crest_model(&c, 15.0, 0.4, 0.05, Rule::Exact, Side::Plane, None).unwrap();
    let spec = SimulateSpec {
        surface_model: SurfaceModel::Ice,
        grid_um: 2.0,
        dtheta_deg: 1.0,
    };
    let z = simulate_case(&c, 15.0, 0.4, 0.05, crest.fz_eff_mm, &spec).unwrap();
    // 5 sampling lengths of 0.8 mm (RSm = fz_eff = 0.2 mm).
    assert_relative_eq!(z.evaluation_length_mm, 4.0, epsilon = 1e-9);
    // Only tooth 1 cuts: marks 0.2 mm apart, crest 1.0021 µm (model.md R2/R3). The grid
    // (2 µm) and the spindle step (1°) cost at most a few per cent.
    assert!((z.rz_um - crest.crest_um).abs() < 0.03, "Rz {}", z.rz_um);
    assert!(
        (z.ra_um - crest.ra_um).abs() < 0.02,
        "Ra {} vs {}",
        z.ra_um,
        crest.ra_um
    );
}

#[test]
fn report_with_the_simulate_model() {
    let dir = tempfile::tempdir().unwrap();
    let root = env!("CARGO_MANIFEST_DIR");
    std::fs::write(
        dir.path().join("t.csv"),
        "lead_deg,side,sample,Ra_um,Rz_um\n15,concave,S1,0.418,2.20\n15,concave,S2,0.437,2.59\n",
    )
    .unwrap();
    let study = format!(
        "title = \"simulate\"\ntool = \"{root}/samples/tools/ball-r5-z4.toml\"\nmodel = \"simulate\"\n\
         fz_mm = 0.05\nap_mm = 0.4\n[simulate]\nsurface_model = \"ice\"\ngrid_um = 2.0\ndtheta_deg = 1.0\n\
         [[case]]\nlead_deg = 15.0\nside = \"concave\"\n"
    );
    std::fs::write(dir.path().join("s.toml"), &study).unwrap();
    let out = dir.path().join("out");
    let run = |tol: &str| {
        assert_cmd::Command::cargo_bin("crest")
            .unwrap()
            .current_dir(dir.path())
            .args(["report", "--measured", "t.csv", "--study", "s.toml", "-o"])
            .arg(&out)
            .args(["--tolerance-pct", tol, "--json"])
            .assert()
    };
    let a = run("20").code(1);
    let v: serde_json::Value =
        serde_json::from_slice(&a.get_output().stdout).expect("one JSON object");
    let z = &v["cases"][0]["zmap"];
    let rz = z["rz_um"].as_f64().unwrap();
    assert!((rz - 1.0).abs() < 0.03, "z-map Rz {rz}");
    assert_eq!(v["cases"][0]["comparisons"][0]["simulated_um"], z["rz_um"]);
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("simulate (ICE, grid 2 µm, Δθ 1°; teeth by the paper rule)"));
    assert!(md.contains(&format!("{rz:.4} / ")));
    // Within 65 % everything passes.
    run("65").code(0);
    // Unknown keys in [simulate] are rejected.
    std::fs::write(
        dir.path().join("s.toml"),
        study.replace("grid_um = 2.0", "grid_mm = 0.002"),
    )
    .unwrap();
    let bad = assert_cmd::Command::cargo_bin("crest")
        .unwrap()
        .current_dir(dir.path())
        .args([
            "report",
            "--measured",
            "t.csv",
            "--study",
            "s.toml",
            "-o",
            "bad",
        ])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&bad.get_output().stderr).to_string();
    assert!(err.contains("grid_mm"), "{err}");
    assert!(!dir.path().join("bad").exists());
}
