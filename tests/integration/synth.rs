//! `crest synth`: stepover and pass count in --json, CLSF and contact12 outputs, errors.

use std::path::Path;

use approx::{abs_diff_eq, assert_abs_diff_eq};

use crate::util::{crest, output_json, read, synth_sample, tempdir, write};

fn synth(args: &[&str], tool: &str, out: &Path) -> std::process::Output {
    crest()
        .arg("synth")
        .args(args)
        .arg("--tool")
        .arg(synth_sample(tool))
        .arg("-o")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn r6_trials_give_the_exact_steps() {
    // model.md R6 (R = 5, rc = 1.5): exact steps 2.7850, 1.3115, 1.2385 mm.
    let dir = tempdir();
    let out = dir.path().join("p.cls");
    for (tilt, yaw, h, step, passes) in [
        ("1", "0", "5", 2.7850, 5),
        ("10", "0", "10", 1.3115, 9),
        ("10", "20", "10", 1.2385, 10),
    ] {
        let o = synth(
            &[
                "plane",
                "--tilt-deg",
                tilt,
                "--yaw-deg",
                yaw,
                "--scallop-um",
                h,
                "--feed-mm-min",
                "4000",
                "--rpm",
                "15000",
                "--size-mm",
                "20,10",
                "--json",
            ],
            "torus-r5-rc1.5.toml",
            &out,
        );
        let v = output_json(&o);
        let s = v["stepover_mm"].as_f64().unwrap();
        assert!(abs_diff_eq!(s, step, epsilon = 1e-3), "{s} vs {step}");
        assert_eq!(v["passes"], passes);
        let text = read(&out);
        for word in [
            "TOOL PATH/",
            "TLDATA/MILL",
            "FEDRAT/",
            "SPINDL/",
            "RAPID",
            "GOTO/",
        ] {
            assert!(text.contains(word), "no {word} in the CLSF");
        }
        assert_eq!(text.matches("RAPID").count(), 2 * passes);
    }
}

#[test]
fn feed_end_writes_one_fedrat_per_move() {
    // 001 Fig 6: the feed falls linearly from 4000 to 500 mm/min along each 10 mm pass.
    let dir = tempdir();
    let out = dir.path().join("p.cls");
    let v = output_json(&synth(
        &[
            "plane",
            "--tilt-deg",
            "1",
            "--stepover-mm",
            "3",
            "--size-mm",
            "10,3",
            "--point-step-mm",
            "2",
            "--feed-mm-min",
            "4000",
            "--feed-end-mm-min",
            "500",
            "--rpm",
            "15000",
            "--json",
        ],
        "torus-r5-rc1.5.toml",
        &out,
    ));
    assert_eq!(v["passes"], 2);
    assert_eq!(v["feed_end_mm_min"], 500.0);
    let text = read(&out);
    let feeds: Vec<f64> = text
        .lines()
        .filter_map(|l| l.strip_prefix("FEDRAT/MMPM,"))
        .map(|f| f.trim().parse().unwrap())
        .collect();
    // Per pass: 4000 (engage and first point), 3300, 2600, 1900, 1200, 500; the second
    // pass starts again at 4000.
    let pass = [4000.0, 3300.0, 2600.0, 1900.0, 1200.0, 500.0];
    let want: Vec<f64> = pass.iter().chain(pass.iter()).copied().collect();
    assert_eq!(feeds.len(), want.len(), "{feeds:?}");
    for (f, w) in feeds.iter().zip(&want) {
        assert!(abs_diff_eq!(f, w, epsilon = 1e-6), "{feeds:?}");
    }
}

#[test]
fn contact12_has_one_line_per_contact_point() {
    let dir = tempdir();
    let out = dir.path().join("p.txt");
    let v = output_json(&synth(
        &[
            "extruded-parabola",
            "--lead-deg",
            "15",
            "--stepover-mm",
            "2",
            "--pass-angle-deg",
            "45",
            "--zigzag",
            "--feed-mm-min",
            "5000",
            "--rpm",
            "15000",
            "--json",
        ],
        "ball-r5.toml",
        &out,
    ));
    // 10 × 10 mm field, 2 mm apart: 6 passes of 21 points (0.5 mm step).
    assert_eq!(v["passes"], 6);
    assert_eq!(v["points_per_pass"], 21);
    let text = read(&out);
    let rows: Vec<Vec<f64>> = text
        .lines()
        .filter_map(|l| {
            let f: Option<Vec<f64>> = l.split(',').map(|x| x.trim().parse().ok()).collect();
            f
        })
        .collect();
    assert_eq!(rows.len(), 6 * 21);
    for r in rows {
        assert_eq!(r.len(), 12);
        // CC on z = −0.004 x² + 0.1; ball: CL = CC + R n − R a.
        assert_abs_diff_eq!(r[8], 0.1 - 0.004 * r[6] * r[6], epsilon = 2e-4);
        for k in 0..3 {
            assert_abs_diff_eq!(
                r[k],
                r[6 + k] + 5.0 * r[9 + k] - 5.0 * r[3 + k],
                epsilon = 5e-4
            );
        }
    }
}

#[test]
fn bad_requests_exit_2() {
    let dir = tempdir();
    let out = dir.path().join("p.cls");
    let base = ["--feed-mm-min", "4000", "--rpm", "15000"];
    // Lead and tilt together.
    let o = synth(
        &[
            &[
                "plane",
                "--lead-deg",
                "3",
                "--tilt-deg",
                "3",
                "--stepover-mm",
                "1",
            ][..],
            &base,
        ]
        .concat(),
        "ball-r5.toml",
        &out,
    );
    assert_eq!(o.status.code(), Some(2));
    // Neither scallop nor stepover.
    let o = synth(&[&["plane"][..], &base].concat(), "ball-r5.toml", &out);
    assert_eq!(o.status.code(), Some(2));
    // A concave region tighter than R_eff = 202 mm.
    let o = synth(
        &[
            &["blade-patch", "--tilt-deg", "1", "--scallop-um", "5"][..],
            &base,
        ]
        .concat(),
        "torus-r5-rc1.5.toml",
        &out,
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("gouge"));
    // Unknown output extension.
    let o = synth(
        &[&["plane", "--stepover-mm", "1"][..], &base].concat(),
        "ball-r5.toml",
        &dir.path().join("p.nc"),
    );
    assert_eq!(o.status.code(), Some(2));
    // A bad tool file names the file.
    let bad = write(
        dir.path(),
        "bad.toml",
        "shape = \"ball\"\nradius_mm = \"five\"\n",
    );
    let o = crest()
        .args([
            "synth",
            "plane",
            "--stepover-mm",
            "1",
            "--feed-mm-min",
            "1",
            "--rpm",
            "1",
            "--tool",
        ])
        .arg(&bad)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("bad.toml"));
    assert!(!out.exists());
}
