//! The cutter model: the reference values of model.md R1 (002 Table 3), R2 (Eq 14) and R3
//! (Eqs 7-8 and the exact one-dimensional check) with the tolerances model.md states;
//! properties (edges lie on the dome, zero run-out lets every tooth cut, raising one
//! tooth's radius never brings other teeth into the cut); `crest tool` end to end (JSON
//! keys and values, text output, rejected tool files that name the key, the file and the
//! line); `crest runout` (one CSV row per case and three plots; bad studies name the line).

use approx::{abs_diff_eq, assert_abs_diff_eq, assert_relative_eq};
use crest::tool::{Cutter, Rule, Shape, analyse, crest_height_mm, effective_radius};
use predicates::prelude::*;
use proptest::prelude::*;

use crate::util::{crest, read_csv, repo_file, success_json, tempdir, write};

// ---------------------------------------------------------------------------------------
// model.md R1-R3
// ---------------------------------------------------------------------------------------

const LEADS: [f64; 3] = [5.0, 15.0, 25.0];
const TOOTH_RADII: [f64; 4] = [4.990, 4.985, 4.976, 4.975];

fn ball(radius: f64) -> Cutter {
    Cutter::new(Shape::Ball, radius, 4, 30f64.to_radians())
}

fn r_ef(radius: f64, lead_deg: f64) -> f64 {
    effective_radius(&ball(radius), lead_deg.to_radians(), 0.4).max_mm
}

/// All 30 cells of 002 Table 3 against the printed values.
#[test]
fn r1_table3_all_thirty_cells_against_the_paper() {
    // Row "Vcef max (%)" and row "Ref max (5 mm)" (3 decimals).
    let vc_pct = [47.1, 61.7, 74.4];
    let ref_nominal = [2.353, 3.083, 3.720];
    // Rows z1..z4: R_ef and error %, for leads 5/15/25.
    let ref_teeth = [
        [2.3501, 3.0788, 3.714],
        [2.3487, 3.0765, 3.7109],
        [2.3461, 3.0724, 3.7054],
        [2.3458, 3.0720, 3.7048],
    ];
    // The 5°/z1 cell is printed as 0.0012, the fraction 0.00123, not the percentage
    // 0.1235 %: model.md R1 says to use 0.12350 %.
    let err_pct = [
        [0.12350, 0.1479, 0.1634],
        [0.1853, 0.2219, 0.2451],
        [0.2966, 0.3551, 0.3922],
        [0.3089, 0.3699, 0.4085],
    ];
    let mut cells = 0;
    for (l, &lead) in LEADS.iter().enumerate() {
        let c = ball(5.0);
        let a = analyse(&c, lead, 0.4, 0.05, Rule::Paper).unwrap();
        assert!(
            abs_diff_eq!(100.0 * a.cutting_speed_ratio, vc_pct[l], epsilon = 0.05),
            "Vc% at {lead}"
        );
        assert!(
            abs_diff_eq!(a.effective_radius_mm, ref_nominal[l], epsilon = 5e-4),
            "R_ef(5) at {lead}"
        );
        cells += 2;
        for (t, &rt) in TOOTH_RADII.iter().enumerate() {
            let e = r_ef(rt, lead);
            assert!(
                abs_diff_eq!(e, ref_teeth[t][l], epsilon = 6e-5),
                "R_ef({rt}) at {lead}: {e}"
            );
            let err = 100.0 * (a.effective_radius_mm - e) / a.effective_radius_mm;
            assert!(
                abs_diff_eq!(err, err_pct[t][l], epsilon = 6e-4),
                "error % ({rt}) at {lead}: {err}"
            );
            cells += 2;
        }
    }
    assert_eq!(cells, 30);
    // The inconsistent cell really is the fraction: 0.12350 % = 0.0012350.
    let frac = (r_ef(5.0, 5.0) - r_ef(4.990, 5.0)) / r_ef(5.0, 5.0);
    assert_abs_diff_eq!(frac, 0.0012, epsilon = 5e-5);
}

/// The same cells against the reference implementation's 5-6 digits, through the
/// per-tooth results of `analyse` (the presetter radii as deviations δ_j).
#[test]
fn r1_table3_against_the_oracle_via_tooth_deviations() {
    let nominal = [2.35305, 3.08339, 3.72004];
    let vc = [47.061, 61.668, 74.401];
    let teeth = [
        [
            (2.35015, 0.12350),
            (2.34869, 0.18529),
            (2.34607, 0.29656),
            (2.34578, 0.30893),
        ],
        [
            (3.07883, 0.14792),
            (3.07655, 0.22190),
            (3.07244, 0.35512),
            (3.07198, 0.36992),
        ],
        [
            (3.71396, 0.16336),
            (3.71092, 0.24506),
            (3.70545, 0.39216),
            (3.70484, 0.40850),
        ],
    ];
    let mut c = ball(5.0);
    c.runout.tooth_radius_dev_mm = TOOTH_RADII.iter().map(|r| r - 5.0).collect();
    for (l, &lead) in LEADS.iter().enumerate() {
        let a = analyse(&c, lead, 0.4, 0.05, Rule::Paper).unwrap();
        assert_relative_eq!(a.effective_radius_mm, nominal[l], epsilon = 6e-6);
        assert_relative_eq!(100.0 * a.cutting_speed_ratio, vc[l], epsilon = 6e-4);
        for (t, tooth) in a.teeth.iter().enumerate() {
            assert_relative_eq!(tooth.radius_mm, TOOTH_RADII[t], epsilon = 1e-12);
            assert_relative_eq!(tooth.effective_radius_mm, teeth[l][t].0, epsilon = 6e-6);
            assert_relative_eq!(
                tooth.effective_radius_error_pct,
                teeth[l][t].1,
                epsilon = 6e-5
            );
        }
        // Effective cutting speed at 80 m/min: 37.6 / 49.3 / 59.5 m/min.
        let v = 80.0 * a.cutting_speed_ratio;
        assert!(
            abs_diff_eq!(v, [37.6, 49.3, 59.5][l], epsilon = 0.05),
            "{v}"
        );
        // Radius of the generating point: R sin β = 0.436 / 1.294 / 2.113 mm.
        assert_abs_diff_eq!(
            a.contact_radius_mm,
            [0.436, 1.294, 2.113][l],
            epsilon = 5e-4
        );
    }
}

#[test]
fn r2_eq14_crest_heights() {
    for (fz, hc_um, tol) in [
        (0.05, 0.0625004, 1e-6),
        (0.2, 1.0001000, 1e-6),
        (0.1, 0.250006, 1e-6),
        // 0.13333 and 0.26667 in model.md are 0.4/3 and 0.8/3 (the oracle's values need the
        // unrounded feeds: 0.13333 exactly gives 0.44444 µm).
        (0.4 / 3.0, 0.44446, 1e-5),
        (0.8 / 3.0, 1.77810, 1e-5),
    ] {
        assert_relative_eq!(crest_height_mm(5.0, fz) * 1e3, hc_um, epsilon = tol);
    }
    // With Rt = 4.990 and fz 0.2 the exact profile gives 1.0021 µm.
    assert_abs_diff_eq!(crest_height_mm(4.990, 0.2) * 1e3, 1.0021, epsilon = 1e-4);
    // And `crest tool`'s nominal crest is Eq 14 at the nominal fz.
    let a = analyse(&ball(5.0), 15.0, 0.4, 0.05, Rule::Paper).unwrap();
    assert_relative_eq!(a.crest_height_mm * 1e3, 0.0625004, epsilon = 1e-6);
}

struct R3Row {
    name: &'static str,
    offset_um: f64,
    phase_deg: f64,
    dev_um: [f64; 4],
    rho_um: [f64; 4],
    paper: &'static [usize],
    fz_eff: f64,
    exact: &'static [usize],
    crest_um: f64,
}

fn r3_rows() -> Vec<R3Row> {
    let s = 1.0 / 2f64.sqrt();
    let mut rows = vec![R3Row {
        name: "presetter radii",
        offset_um: 0.0,
        phase_deg: 0.0,
        dev_um: [-10.0, -15.0, -24.0, -25.0],
        rho_um: [-10.0, -15.0, -24.0, -25.0],
        paper: &[1],
        fz_eff: 0.2,
        exact: &[1],
        crest_um: 1.0021,
    }];
    for (e0, crest) in [(5.0, 0.9998), (10.0, 0.9996), (15.0, 0.9993)] {
        rows.push(R3Row {
            name: "offset at phase 0",
            offset_um: e0,
            phase_deg: 0.0,
            dev_um: [0.0; 4],
            rho_um: [e0, 0.0, -e0, 0.0],
            paper: &[1],
            fz_eff: 0.2,
            exact: &[1],
            crest_um: crest,
        });
    }
    for (e0, crest) in [(5.0, 0.5624), (10.0, 0.5623), (15.0, 0.5622)] {
        rows.push(R3Row {
            name: "offset at phase 45",
            offset_um: e0,
            phase_deg: 45.0,
            dev_um: [0.0; 4],
            rho_um: [e0 * s, -e0 * s, -e0 * s, e0 * s],
            paper: &[1, 4],
            fz_eff: 0.1,
            exact: &[1, 4],
            crest_um: crest,
        });
    }
    rows.push(R3Row {
        name: "offset 5 at phase 30 (the paper rule under-counts)",
        offset_um: 5.0,
        phase_deg: 30.0,
        dev_um: [0.0; 4],
        rho_um: [4.330127, -2.5, -4.330127, 2.5],
        paper: &[1],
        fz_eff: 0.2,
        exact: &[1, 4],
        crest_um: 0.8242,
    });
    rows.push(R3Row {
        name: "offset 0.05",
        offset_um: 0.05,
        phase_deg: 0.0,
        dev_um: [0.0; 4],
        rho_um: [0.05, 0.0, -0.05, 0.0],
        paper: &[1, 2, 4],
        fz_eff: 0.05 * 4.0 / 3.0,
        exact: &[1, 2, 3, 4],
        crest_um: 0.0821,
    });
    rows
}

fn set(teeth: &[crest::tool::ToothAnalysis], exact: bool) -> Vec<usize> {
    teeth
        .iter()
        .filter(|t| {
            if exact {
                t.participates_exact
            } else {
                t.participates_paper
            }
        })
        .map(|t| t.index)
        .collect()
}

/// model.md R3: Z = 4, fz = 0.05, R = 5, lead 15°. The table's ρ_j are the run-out at the
/// teeth's tip angles, so the cutter here has straight edges (helix 0): with a 30° helix
/// the edges at z_c lag 1.13° and the phase-45° rows would split teeth 1 and 4.
#[test]
fn r3_participating_teeth_and_exact_crests() {
    for row in r3_rows() {
        let mut c = Cutter::new(Shape::Ball, 5.0, 4, 0.0);
        c.runout.offset_mm = row.offset_um * 1e-3;
        c.runout.offset_phase_rad = row.phase_deg.to_radians();
        c.runout.tilt_phase_rad = row.phase_deg.to_radians();
        c.runout.tooth_radius_dev_mm = row.dev_um.iter().map(|d| d * 1e-3).collect();
        // The table's ρ_j.
        for j in 0..4 {
            assert_relative_eq!(c.runout_mm(j, 0.1) * 1e3, row.rho_um[j], epsilon = 1e-5);
        }
        let paper = analyse(&c, 15.0, 0.4, 0.05, Rule::Paper).unwrap();
        assert_eq!(
            set(&paper.teeth, false),
            row.paper,
            "{}: paper teeth",
            row.name
        );
        assert_eq!(paper.zc, row.paper.len(), "{}", row.name);
        assert_relative_eq!(paper.fz_effective_mm, row.fz_eff, epsilon = 1e-12);
        let exact = analyse(&c, 15.0, 0.4, 0.05, Rule::Exact).unwrap();
        assert_eq!(
            set(&exact.teeth, true),
            row.exact,
            "{}: exact teeth",
            row.name
        );
        assert_eq!(exact.zc, row.exact.len(), "{}", row.name);
        assert_eq!(set(&exact.teeth, false), row.paper, "{}", row.name);
        let crest = exact.crest_height_corrected_mm * 1e3;
        assert!(
            abs_diff_eq!(crest, row.crest_um, epsilon = 1e-4),
            "{}: exact crest {crest} µm, expected {}",
            row.name,
            row.crest_um
        );
        assert_relative_eq!(exact.crest_height_exact_mm, paper.crest_height_exact_mm);
        // The paper rule's corrected crest is Eq 14 at fz_eff.
        assert_relative_eq!(
            paper.crest_height_corrected_mm,
            crest_height_mm(5.0, row.fz_eff),
            epsilon = 1e-15
        );
    }
}

/// 002's own correction: with the presetter radii and the 30° helix of the real tool,
/// only the largest tooth cuts at every lead and fz becomes 0.2 mm/tooth.
#[test]
fn r3_paper_case_with_the_real_helix() {
    let mut c = ball(5.0);
    c.runout.tooth_radius_dev_mm = vec![-0.010, -0.015, -0.024, -0.025];
    for lead in LEADS {
        for rule in [Rule::Paper, Rule::Exact] {
            let a = analyse(&c, lead, 0.4, 0.05, rule).unwrap();
            assert_eq!(a.zc, 1);
            assert_relative_eq!(a.fz_effective_mm, 0.2, epsilon = 1e-12);
            assert!(a.teeth[0].participates);
        }
    }
}

// ---------------------------------------------------------------------------------------
// Properties of the cutter model
// ---------------------------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Without run-out every ICE point of a ball end lies on the dome (002 Eq 1), whatever
    /// the helix, tooth and spindle angle; on a torus it lies on the torus.
    #[test]
    fn edges_lie_on_the_dome(
        radius in 0.5f64..12.0,
        teeth in 1usize..9,
        helix_deg in 0.0f64..50.0,
        u in 0.0f64..=1.0,
        theta in -10.0f64..10.0,
        tooth_seed in 0usize..64,
        corner_share in 0.05f64..0.95,
    ) {
        let j = tooth_seed % teeth;
        let ball = Cutter::new(Shape::Ball, radius, teeth, helix_deg.to_radians());
        let z = u * radius;
        let p = ball.edge_point(j, z, theta);
        let centre_distance = (p - nalgebra::Vector3::new(0.0, 0.0, radius)).norm();
        prop_assert!(abs_diff_eq!(centre_distance, radius, epsilon = 1e-10 * radius.max(1.0)));
        prop_assert!(abs_diff_eq!(p.z, z, epsilon = 1e-12));
        let rc = corner_share * radius;
        let torus = Cutter::new(Shape::Torus { corner_radius_mm: rc }, radius, teeth, helix_deg.to_radians());
        let zt = u * rc;
        let q = torus.edge_point(j, zt, theta);
        let rho = q.xy().norm() - (radius - rc);
        let on_torus = rho * rho + (zt - rc) * (zt - rc);
        prop_assert!(abs_diff_eq!(on_torus, rc * rc, epsilon = 1e-9 * radius.max(1.0)));
    }

    /// With zero run-out every tooth cuts under both rules and the marks are fz apart.
    #[test]
    fn zero_runout_every_tooth_participates(
        radius in 1.0f64..10.0,
        teeth in 1usize..9,
        helix_deg in 0.0f64..45.0,
        lead_deg in -60.0f64..60.0,
        fz in 0.005f64..0.3,
        torus in any::<bool>(),
    ) {
        let shape = if torus { Shape::Torus { corner_radius_mm: 0.3 * radius } } else { Shape::Ball };
        let c = Cutter::new(shape, radius, teeth, helix_deg.to_radians());
        for rule in [Rule::Paper, Rule::Exact] {
            let a = analyse(&c, lead_deg, 0.3, fz, rule).unwrap();
            prop_assert_eq!(a.zc, teeth);
            prop_assert!(a.teeth.iter().all(|t| t.participates));
            prop_assert!(abs_diff_eq!(a.fz_effective_mm, fz, epsilon = 1e-12));
        }
    }

    /// Raising one tooth's radius never brings another tooth into the cut (either rule),
    /// and when that tooth already cut, zc does not grow.
    #[test]
    fn raising_one_tooth_never_adds_teeth(
        teeth in 2usize..7,
        offset_um in 0.0f64..20.0,
        phase_deg in 0.0f64..360.0,
        devs in proptest::collection::vec(-20.0f64..20.0, 6),
        raise_um in 0.001f64..30.0,
        tooth_seed in 0usize..64,
        lead_deg in 1.0f64..40.0,
        fz in 0.01f64..0.2,
        helix_deg in 0.0f64..40.0,
    ) {
        let j = tooth_seed % teeth;
        let mut c = Cutter::new(Shape::Ball, 5.0, teeth, helix_deg.to_radians());
        c.runout.offset_mm = offset_um * 1e-3;
        c.runout.offset_phase_rad = phase_deg.to_radians();
        c.runout.tooth_radius_dev_mm = devs[..teeth].iter().map(|d| d * 1e-3).collect();
        let mut raised = c.clone();
        raised.runout.tooth_radius_dev_mm[j] += raise_um * 1e-3;
        for rule in [Rule::Paper, Rule::Exact] {
            let before = analyse(&c, lead_deg, 0.4, fz, rule).unwrap();
            let after = analyse(&raised, lead_deg, 0.4, fz, rule).unwrap();
            for i in (0..teeth).filter(|&i| i != j) {
                prop_assert!(
                    !after.teeth[i].participates || before.teeth[i].participates,
                    "{:?}: tooth {} joined after raising tooth {}", rule, i + 1, j + 1
                );
            }
            if before.teeth[j].participates {
                prop_assert!(after.zc <= before.zc);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// `crest tool` end to end
// ---------------------------------------------------------------------------------------

const BALL: &str = repo_file!("samples/tools/ball-r5-z4.toml");
const TORUS: &str = repo_file!("samples/tools/torus-r5-rc1.5.toml");

fn json(args: &[&str]) -> serde_json::Value {
    success_json(crest().args(args))
}

#[test]
fn json_has_the_contract_keys_and_table3_values() {
    let v = json(&[
        "tool",
        "--tool",
        BALL,
        "--lead-deg",
        "25",
        "--ap-mm",
        "0.4",
        "--fz-mm",
        "0.05",
        "--rule",
        "paper",
        "--json",
    ]);
    for key in [
        "effective_radius_mm",
        "cutting_speed_ratio",
        "crest_height_um",
        "teeth",
        "zc",
        "fz_effective_mm",
        "crest_height_corrected_um",
    ] {
        assert!(v.get(key).is_some(), "missing {key}: {v}");
    }
    assert_abs_diff_eq!(
        v["effective_radius_mm"].as_f64().unwrap(),
        3.72004,
        epsilon = 6e-6
    );
    let ratio = v["cutting_speed_ratio"].as_f64().unwrap();
    assert_abs_diff_eq!(ratio, 0.74401, epsilon = 6e-6);
    assert_abs_diff_eq!(
        v["crest_height_um"].as_f64().unwrap(),
        0.0625004,
        epsilon = 1e-6
    );
    assert_eq!(v["zc"], 1);
    assert_abs_diff_eq!(v["fz_effective_mm"].as_f64().unwrap(), 0.2, epsilon = 1e-12);
    assert_abs_diff_eq!(
        v["crest_height_corrected_um"].as_f64().unwrap(),
        1.0001,
        epsilon = 1e-4
    );
    assert_eq!(v["rule"], "paper");
    let teeth = v["teeth"].as_array().unwrap();
    assert_eq!(teeth.len(), 4);
    for (i, t) in teeth.iter().enumerate() {
        assert_eq!(t["index"], i + 1);
        assert!(t["radius_mm"].is_f64());
        assert_eq!(t["participates"], i == 0);
    }
    assert_abs_diff_eq!(
        teeth[3]["radius_mm"].as_f64().unwrap(),
        4.975,
        epsilon = 1e-12
    );
    assert_abs_diff_eq!(
        teeth[3]["effective_radius_mm"].as_f64().unwrap(),
        3.70484,
        epsilon = 6e-6
    );
}

#[test]
fn exact_rule_and_torus() {
    let v = json(&[
        "tool",
        "--tool",
        BALL,
        "--lead-deg",
        "15",
        "--ap-mm",
        "0.4",
        "--fz-mm",
        "0.05",
        "--rule",
        "exact",
        "--json",
    ]);
    assert_eq!(v["rule"], "exact");
    assert_abs_diff_eq!(
        v["crest_height_corrected_um"].as_f64().unwrap(),
        1.0021,
        epsilon = 1e-4
    );
    let v = json(&[
        "tool",
        "--tool",
        TORUS,
        "--lead-deg",
        "10",
        "--ap-mm",
        "0.2",
        "--fz-mm",
        "0.26667",
        "--json",
    ]);
    assert_eq!(v["shape"], "torus");
    assert_eq!(v["zc"], 1);
    // Generating radius rc on both sides at 10°: 1.5 − √(1.5² − s²/4).
    let hc = (1.5 - (2.25f64 - 0.26667f64.powi(2) / 4.0).sqrt()) * 1e3;
    assert_abs_diff_eq!(v["crest_height_um"].as_f64().unwrap(), hc, epsilon = 1e-6);
}

#[test]
fn text_output_lists_teeth() {
    crest()
        .args([
            "tool",
            "--tool",
            BALL,
            "--lead-deg",
            "5",
            "--ap-mm",
            "0.4",
            "--fz-mm",
            "0.05",
        ])
        .assert()
        .success()
        .stdout(predicate::str::contains("2.35305"))
        .stdout(predicate::str::contains("zc = 1 of 4"));
}

fn rejected(body: &str, key: &str, line: usize) {
    let dir = tempdir();
    let path = write(dir.path(), "tool.toml", body);
    let p = path.to_str().unwrap();
    crest()
        .args([
            "tool",
            "--tool",
            p,
            "--lead-deg",
            "15",
            "--ap-mm",
            "0.4",
            "--fz-mm",
            "0.05",
        ])
        .assert()
        .code(2)
        .stdout(predicate::str::is_empty())
        .stderr(predicate::str::contains(format!("tool.toml:{line}:")))
        .stderr(predicate::str::contains(key));
}

#[test]
fn bad_tool_files_name_key_and_line() {
    let head = "shape = \"ball\"\nradius_mm = 5.0\nteeth = 4\nhelix_deg = 30.0\n";
    rejected(&format!("{head}flutes = 4\n"), "flutes", 5);
    rejected(
        "shape = \"ball\"\nradius_mm = -5.0\nteeth = 4\nhelix_deg = 30.0\n",
        "radius_mm",
        2,
    );
    rejected(
        "shape = \"ball\"\nradius_mm = 5.0\nteeth = 0\nhelix_deg = 30.0\n",
        "teeth",
        3,
    );
    rejected(
        "shape = \"torus\"\nradius_mm = 5.0\ncorner_radius_mm = 5.5\nteeth = 2\nhelix_deg = 0\n",
        "corner_radius_mm",
        3,
    );
    rejected(
        &format!("{head}\n[runout]\noffset_um = 5\ntooth_radius_deviation_um = [1, 2, 3]\n"),
        "tooth_radius_deviation_um",
        8,
    );
    rejected(&format!("{head}[runout]\nphase_deg = 5\n"), "phase_deg", 6);
    rejected(
        "shape = \"ball\"\nteeth = 4\nhelix_deg = 30.0\n",
        "radius_mm",
        1,
    );
}

#[test]
fn missing_file_and_bad_numbers_exit_2() {
    crest()
        .args([
            "tool",
            "--tool",
            "/nonexistent/tool.toml",
            "--lead-deg",
            "5",
            "--ap-mm",
            "0.4",
            "--fz-mm",
            "0.05",
        ])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("/nonexistent/tool.toml"));
    crest()
        .args([
            "tool",
            "--tool",
            BALL,
            "--lead-deg",
            "5",
            "--ap-mm",
            "0.4",
            "--fz-mm",
            "-1",
        ])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("feed per tooth"));
}

// ---------------------------------------------------------------------------------------
// `crest runout`: the sample study writes one CSV row per case and three plots (SVG and
// PNG); bad study files name the line.
// ---------------------------------------------------------------------------------------

const RUNOUT_STUDY: &str = repo_file!("samples/studies/runout.toml");

#[test]
fn sample_study_writes_csv_and_plots() {
    let dir = tempdir();
    let v = success_json(
        crest()
            .args(["runout", RUNOUT_STUDY, "-o"])
            .arg(dir.path())
            .arg("--json"),
    );
    // 3 leads × 1 fz × 13 offsets × 2 phases.
    assert_eq!(v["cases"], 78);
    let mut rows = read_csv(&dir.path().join("runout.csv"));
    let header = rows.remove(0);
    assert_eq!(rows.len(), 78);
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (zc, offset, phase) = (col("zc"), col("offset_um"), col("offset_phase_deg"));
    let (fz_eff, teeth) = (col("fz_effective_mm"), col("participating_teeth"));
    for r in &rows {
        let n: usize = r[zc].parse().unwrap();
        assert_eq!(r[teeth].split(';').count(), n);
        let f: f64 = r[fz_eff].parse().unwrap();
        assert_abs_diff_eq!(f, 0.2 * 4.0 / n as f64, epsilon = 1e-12);
        // Zero offset leaves only the tool's sub-micron deviations: every tooth cuts at 1 µm crests.
        if r[offset] == "0" {
            assert_eq!(n, 4, "{r:?}");
        }
        // A 5 µm offset at phase 45° leaves teeth 1 and 4 (model.md R3 pattern).
        if r[offset] == "5" && r[phase] == "45" {
            assert_eq!(r[teeth], "1;4", "{r:?}");
        }
    }
    for name in [
        "runout-teeth.svg",
        "runout-teeth.png",
        "runout-crest.svg",
        "runout-crest.png",
        "runout-lateral.svg",
        "runout-lateral.png",
    ] {
        let bytes = std::fs::read(dir.path().join(name)).unwrap();
        assert!(bytes.len() > 1000, "{name} is too small");
        if name.ends_with(".png") {
            assert_eq!(&bytes[..4], b"\x89PNG");
        } else {
            let text = String::from_utf8(bytes).unwrap();
            assert!(text.contains("run-out"), "{name} lacks its axis label");
        }
    }
}

#[test]
fn bad_study_names_line() {
    let dir = tempdir();
    let study = write(
        dir.path(),
        "study.toml",
        "tool = \"x.toml\"\nap_mm = 0.4\n[sweep]\nlead_deg = [5, 95]\nfz_mm = [0.05]\n",
    );
    crest()
        .args(["runout"])
        .arg(&study)
        .arg("-o")
        .arg(dir.path().join("out"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("study.toml:4:"))
        .stderr(predicate::str::contains("lead_deg"));
    assert!(!dir.path().join("out").exists());
}
