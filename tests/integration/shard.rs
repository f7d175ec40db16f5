//! `crest study --shard K/N`, `crest runout … --shard K/N`, `crest simulate --map-mm …
//! --shard K/N` and `crest merge`: a design (a run-out sweep, a part map) run as three shards
//! in three separate processes and merged gives the bytes of the single-process `crest
//! study` (`crest runout`, `crest simulate`); merging refuses missing, repeated and foreign
//! runs (shards) and results of mixed kinds.

use std::path::{Path, PathBuf};

use crate::util::{crest, output_json, read, repo, tempdir, write};

/// Six runs (three feeds, so `effects-feed_mm_min.svg` is drawn too) on a coarse grid.
fn design(dir: &Path, title: &str) -> PathBuf {
    let text = format!(
        "title = \"{title}\"\n\
         surface = \"plane\"\n\
         tool = \"{}\"\n\
         rpm = 15000.0\n\
         grid_um = 4.0\n\
         dtheta_deg = 1.0\n\
         responses = [\"Sz\", \"Sq\", \"Sa\", \"Ssk\"]\n\
         [factors]\n\
         tilt_deg = [5.0, 10.0]\n\
         stepover_mm = [0.05]\n\
         feed_mm_min = [2000.0, 3000.0, 4000.0]\n",
        repo("samples/tools/torus-r5-rc1.5.toml").display()
    );
    write(dir, &format!("{title}.toml"), text)
}

fn bytes(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn three_shards_in_three_processes_merge_to_the_single_process_bytes() {
    let dir = tempdir();
    let d = design(dir.path(), "six");
    let single = dir.path().join("single");
    crest()
        .arg("study")
        .arg(&d)
        .arg("-o")
        .arg(&single)
        .assert()
        .success();

    // Three processes at once, as a batch scheduler would start them.
    let shards = dir.path().join("shards");
    let children: Vec<std::process::Child> = (1..=3)
        .map(|k| {
            std::process::Command::new(env!("CARGO_BIN_EXE_crest"))
                .arg("study")
                .arg(&d)
                .arg("--shard")
                .arg(format!("{k}/3"))
                .arg("--threads")
                .arg("1")
                .arg("-o")
                .arg(&shards)
                .stdout(std::process::Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut c in children {
        assert!(c.wait().unwrap().success());
    }
    // Shard k holds runs k, k+3.
    for k in 1..=3 {
        let text = read(&shards.join(format!("shard-{k}-of-3.jsonl")));
        let runs: Vec<u64> = text
            .lines()
            .map(|l| crate::util::json(l.as_bytes())["run"].as_u64().unwrap())
            .collect();
        assert_eq!(runs, vec![k, k + 3]);
    }

    let merged = dir.path().join("merged");
    let files: Vec<PathBuf> = (1..=3)
        .rev()
        .map(|k| shards.join(format!("shard-{k}-of-3.jsonl")))
        .collect();
    let o = crest()
        .arg("merge")
        .args(&files)
        .arg("-o")
        .arg(&merged)
        .arg("--json")
        .output()
        .unwrap();
    let j = output_json(&o);
    assert_eq!(j["runs"].as_array().unwrap().len(), 6);
    for name in [
        "runs.csv",
        "effects.csv",
        "effects.svg",
        "effects-feed_mm_min.svg",
    ] {
        assert_eq!(
            bytes(&merged.join(name)),
            bytes(&single.join(name)),
            "{name} differs"
        );
    }
    // And the JSON of the runs is the single-process one, to the last bit.
    let s = crest()
        .arg("study")
        .arg(&d)
        .arg("-o")
        .arg(dir.path().join("again"))
        .arg("--json")
        .output()
        .unwrap();
    assert_eq!(output_json(&s)["runs"], j["runs"]);
    assert_eq!(output_json(&s)["effects"], j["effects"]);
}

#[test]
fn merge_refuses_missing_repeated_and_foreign_runs() {
    let dir = tempdir();
    let d = design(dir.path(), "six");
    let other = design(dir.path(), "other");
    let shards = dir.path().join("shards");
    for (design, k) in [(&d, "1/2"), (&d, "2/2"), (&other, "2/2")] {
        let out = if design == &d {
            shards.clone()
        } else {
            dir.path().join("other")
        };
        crest()
            .arg("study")
            .arg(design)
            .arg("--shard")
            .arg(k)
            .arg("-o")
            .arg(&out)
            .assert()
            .success();
    }
    let one = shards.join("shard-1-of-2.jsonl");
    let two = shards.join("shard-2-of-2.jsonl");
    let foreign = dir.path().join("other").join("shard-2-of-2.jsonl");
    let merged = dir.path().join("merged");
    let fails = |files: &[&Path], want: &str| {
        let o = crest()
            .arg("merge")
            .args(files)
            .arg("-o")
            .arg(&merged)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(want), "wanted '{want}' in: {err}");
        assert!(!merged.exists(), "nothing is written");
    };
    fails(&[&one], "3 of 6 runs are missing: 2, 4, 6");
    fails(&[&one, &two, &two], "run 2 is given twice");
    fails(&[&one, &foreign], "the results are of different designs");
    let bad = write(dir.path(), "bad.jsonl", "{\"kind\": \"design-run\"}\n");
    fails(&[&bad], "bad.jsonl:1:");

    let o = crest()
        .arg("study")
        .arg(&d)
        .arg("--shard")
        .arg("4/3")
        .arg("-o")
        .arg(&merged)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("is not a shard K/N"));
}

/// A plane part and its path (4 × 4 mm, as `real_parts.rs` makes them), and the options of a
/// map of a 0.6 × 0.6 mm region at 4 µm: cells of 0.512 mm, so four cells.
fn map_job(dir: &Path) -> Vec<std::ffi::OsString> {
    let cls = dir.join("plane.cls");
    let stl = dir.join("plane.stl");
    let ball = repo("samples/synth/ball-r5.toml");
    crest()
        .arg("synth")
        .arg("plane")
        .arg("--tool")
        .arg(&ball)
        .args([
            "--stepover-mm",
            "0.4",
            "--stepover-along-surface",
            "--size-mm",
            "4,4",
        ])
        .args([
            "--point-step-mm",
            "0.05",
            "--feed-mm-min",
            "1000",
            "--rpm",
            "20000",
        ])
        .args(["--part-tol-um", "0.01", "-o"])
        .arg(&cls)
        .arg("--part-stl")
        .arg(&stl)
        .assert()
        .success();
    let mut v: Vec<std::ffi::OsString> = vec!["simulate".into(), cls.into(), "--tool".into()];
    v.push(ball.into());
    v.push("--part".into());
    v.push(stl.into());
    for a in [
        "--model",
        "dome",
        "--grid-um",
        "10",
        "--fz-mm",
        "0.05",
        "--map-mm",
        "0.004",
        "--region=-0.3,-0.3,-0.5,0.3,0.3,0.5",
    ] {
        v.push(a.into());
    }
    v
}

#[test]
fn a_part_map_in_three_processes_merges_to_the_single_process_ply() {
    let dir = tempdir();
    let job = map_job(dir.path());
    let single = dir.path().join("single.ply");
    let s = crest()
        .args(&job)
        .arg("-o")
        .arg(&single)
        .arg("--json")
        .output()
        .unwrap();
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    assert_eq!(output_json(&s)["cells"], 4);

    let shards = dir.path().join("shards");
    let children: Vec<std::process::Child> = (1..=3)
        .map(|k| {
            std::process::Command::new(env!("CARGO_BIN_EXE_crest"))
                .args(&job)
                .arg("--shard")
                .arg(format!("{k}/3"))
                .arg("--threads")
                .arg("1")
                .arg("-o")
                .arg(&shards)
                .stdout(std::process::Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut c in children {
        assert!(c.wait().unwrap().success());
    }
    // Shard k holds cells k-1, k+2 (0-based) of the four.
    for k in 1..=3usize {
        let text = read(&shards.join(format!("shard-{k}-of-3.jsonl")));
        let j = crate::util::json(text.trim().as_bytes());
        assert_eq!(j["kind"], "map-tiles");
        let cells: Vec<usize> = j["cells"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["cell"].as_u64().unwrap() as usize)
            .collect();
        let want: Vec<usize> = [k - 1, k + 2].into_iter().filter(|c| *c < 4).collect();
        assert_eq!(cells, want);
    }
    let merged = dir.path().join("merged.ply");
    let files: Vec<PathBuf> = (1..=3)
        .rev()
        .map(|k| shards.join(format!("shard-{k}-of-3.jsonl")))
        .collect();
    let m = crest()
        .arg("merge")
        .args(&files)
        .arg("-o")
        .arg(&merged)
        .arg("--json")
        .output()
        .unwrap();
    let j = output_json(&m);
    assert_eq!(j["nodes"], output_json(&s)["nodes"]);
    assert_eq!(j["heights_um"], output_json(&s)["heights_um"]);
    assert_eq!(bytes(&merged), bytes(&single), "the merged PLY differs");

    // A missing or repeated shard, or a shard of another map, is refused.
    let fails = |files: &[PathBuf], want: &str| {
        let out = dir.path().join("bad.ply");
        let o = crest()
            .arg("merge")
            .args(files)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(want), "wanted '{want}' in: {err}");
        assert!(!out.exists(), "nothing is written");
    };
    fails(&files[..2], "1 of 3 shards are missing: 1");
    fails(
        &[files[0].clone(), files[0].clone()],
        "shard 3 of 3 is given twice",
    );
    let other = dir.path().join("other");
    crest()
        .args(&job)
        .args(["--ap-mm", "0.4", "--shard", "1/3", "-o"])
        .arg(&other)
        .assert()
        .success();
    let mut mixed = files[..2].to_vec();
    mixed.push(other.join("shard-1-of-3.jsonl"));
    fails(&mixed, "the results are of different part maps");
    // A study's results do not mix with a map's.
    let d = design(dir.path(), "six");
    crest()
        .arg("study")
        .arg(&d)
        .args(["--shard", "1/9", "-o"])
        .arg(&other)
        .assert()
        .success();
    let mut mixed = files.clone();
    mixed.push(other.join("shard-1-of-9.jsonl"));
    fails(&mixed, "among results of kind");
    // --shard splits part maps only.
    let o = crest()
        .args(&job[..job.len() - 3])
        .args(["--window", "0,0,0.1,0.1", "--shard", "1/2", "-o"])
        .arg(dir.path().join("w"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}

/// The run-out sample study (78 cases) and its tool, or a copy beside `dir` with other
/// offsets.
fn runout_study(dir: &Path, other: bool) -> PathBuf {
    let sample = repo("samples/studies/runout.toml");
    if !other {
        return sample;
    }
    let text = read(&sample)
        .replace(
            "tool = \"../tools/",
            &format!("tool = \"{}/", repo("samples/tools").display()),
        )
        .replace("offset_um = [0.0, 0.25,", "offset_um = [0.1, 0.25,");
    write(dir, "other-runout.toml", text)
}

#[test]
fn a_runout_sweep_in_three_processes_merges_to_the_single_process_bytes() {
    let dir = tempdir();
    let study = runout_study(dir.path(), false);
    let single = dir.path().join("single");
    let s = crest()
        .arg("runout")
        .arg(&study)
        .arg("-o")
        .arg(&single)
        .arg("--json")
        .output()
        .unwrap();
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    let total = output_json(&s)["cases"].as_u64().unwrap() as usize;
    assert_eq!(total, 78);

    let shards = dir.path().join("shards");
    let children: Vec<std::process::Child> = (1..=3)
        .map(|k| {
            std::process::Command::new(env!("CARGO_BIN_EXE_crest"))
                .arg("runout")
                .arg(&study)
                .arg("--shard")
                .arg(format!("{k}/3"))
                .arg("-o")
                .arg(&shards)
                .stdout(std::process::Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut c in children {
        assert!(c.wait().unwrap().success());
    }
    // Shard k holds cases k-1, k+2, … (0-based).
    for k in 1..=3usize {
        let text = read(&shards.join(format!("shard-{k}-of-3.jsonl")));
        assert_eq!(text.lines().count(), 1);
        let j = crate::util::json(text.trim().as_bytes());
        assert_eq!(j["kind"], "runout-cases");
        let cases: Vec<usize> = j["cases"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["case"].as_u64().unwrap() as usize)
            .collect();
        let want: Vec<usize> = (k - 1..total).step_by(3).collect();
        assert_eq!(cases, want);
    }
    let merged = dir.path().join("merged");
    let files: Vec<PathBuf> = (1..=3)
        .rev()
        .map(|k| shards.join(format!("shard-{k}-of-3.jsonl")))
        .collect();
    let m = crest()
        .arg("merge")
        .args(&files)
        .arg("-o")
        .arg(&merged)
        .arg("--json")
        .output()
        .unwrap();
    assert!(m.status.success(), "{}", String::from_utf8_lossy(&m.stderr));
    let (j, sj) = (output_json(&m), output_json(&s));
    for key in ["study", "tool", "rule", "x", "cases", "rows"] {
        assert_eq!(j[key], sj[key], "{key} differs");
    }
    let names: Vec<String> = std::fs::read_dir(&single)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 7, "{names:?}");
    for name in &names {
        assert_eq!(
            bytes(&merged.join(name)),
            bytes(&single.join(name)),
            "{name} differs"
        );
    }

    // A missing or repeated shard, a shard of another study, or a study's results among a
    // run-out study's, are refused.
    let fails = |files: &[PathBuf], want: &str| {
        let out = dir.path().join("bad");
        let o = crest()
            .arg("merge")
            .args(files)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(want), "wanted '{want}' in: {err}");
        assert!(!out.exists(), "nothing is written");
    };
    fails(&files[..2], "1 of 3 shards are missing: 1");
    fails(
        &[files[0].clone(), files[1].clone(), files[0].clone()],
        "shard 3 of 3 is given twice",
    );
    let other = dir.path().join("other");
    crest()
        .arg("runout")
        .arg(runout_study(dir.path(), true))
        .args(["--shard", "1/3", "-o"])
        .arg(&other)
        .assert()
        .success();
    let mut mixed = files[..2].to_vec();
    mixed.push(other.join("shard-1-of-3.jsonl"));
    fails(&mixed, "the results are of different run-out studies");
    let d = design(dir.path(), "six");
    crest()
        .arg("study")
        .arg(&d)
        .args(["--shard", "1/9", "-o"])
        .arg(&other)
        .assert()
        .success();
    let mut mixed = files.clone();
    mixed.push(other.join("shard-1-of-9.jsonl"));
    fails(&mixed, "among results of kind");
    let mut mixed = vec![other.join("shard-1-of-9.jsonl")];
    mixed.extend(files.iter().cloned());
    fails(&mixed, "among results of kind");
    let o = crest()
        .arg("runout")
        .arg(&study)
        .args(["--shard", "4/3", "-o"])
        .arg(dir.path().join("x"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("is not a shard K/N"));
}

/// Two runs with Monte Carlo bands (run-out offset and tooth radius uncertain, spindle
/// phase drawn per pass).
fn mc_design(dir: &Path) -> PathBuf {
    let text = format!(
        "title = \"mc\"\n\
         surface = \"plane\"\n\
         tool = \"{}\"\n\
         rpm = 15000.0\n\
         grid_um = 4.0\n\
         dtheta_deg = 2.0\n\
         responses = [\"Sz\", \"Sa\"]\n\
         [factors]\n\
         tilt_deg = [10.0]\n\
         stepover_mm = [0.05]\n\
         feed_mm_min = [2000.0, 4000.0]\n\
         [uncertainty]\n\
         runout_offset_um = 1.0\n\
         tooth_deviation_um = 0.5\n",
        repo("samples/tools/torus-r5-rc1.5.toml").display()
    );
    write(dir, "mc.toml", text)
}

#[test]
fn monte_carlo_shards_in_two_processes_merge_to_the_single_process_bytes() {
    let dir = tempdir();
    let d = mc_design(dir.path());
    let mc = ["--monte-carlo", "5", "--seed", "7"];
    let single = dir.path().join("single");
    let s = crest()
        .arg("study")
        .arg(&d)
        .args(mc)
        .arg("-o")
        .arg(&single)
        .arg("--json")
        .output()
        .unwrap();
    let s = output_json(&s);
    let shards = dir.path().join("shards");
    let children: Vec<std::process::Child> = (1..=2)
        .map(|k| {
            std::process::Command::new(env!("CARGO_BIN_EXE_crest"))
                .arg("study")
                .arg(&d)
                .args(mc)
                .arg("--shard")
                .arg(format!("{k}/2"))
                .arg("--threads")
                .arg("1")
                .arg("-o")
                .arg(&shards)
                .stdout(std::process::Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut c in children {
        assert!(c.wait().unwrap().success());
    }
    let merged = dir.path().join("merged");
    let files: Vec<PathBuf> = (1..=2)
        .map(|k| shards.join(format!("shard-{k}-of-2.jsonl")))
        .collect();
    let o = crest()
        .arg("merge")
        .args(&files)
        .arg("-o")
        .arg(&merged)
        .arg("--json")
        .output()
        .unwrap();
    let j = output_json(&o);
    for name in ["runs.csv", "effects.csv", "bands.svg"] {
        assert_eq!(
            bytes(&merged.join(name)),
            bytes(&single.join(name)),
            "{name} differs"
        );
    }
    // The bands' figure: a panel per response, the band, its median and the deterministic run.
    let svg = read(&single.join("bands.svg"));
    for text in [
        "mc: Monte Carlo bands of every run",
        ">\nSz\n<",
        ">\nSa\n<",
        "P5 / P95",
        "P50",
        "deterministic run",
        "5 Monte Carlo samples per run",
    ] {
        assert!(svg.contains(text), "bands.svg lacks {text}");
    }
    assert_eq!(s["runs"], j["runs"]);
    assert_eq!(s["monte_carlo"], j["monte_carlo"]);
    assert_eq!(s["monte_carlo"]["samples"], 5);
    assert_eq!(s["monte_carlo"]["seed"], 7);
    assert_eq!(
        s["monte_carlo"]["uncertainty"],
        serde_json::json!({"runout_offset_um": 1.0, "tooth_deviation_um": 0.5, "spindle_phase": true})
    );
    let csv = read(&single.join("runs.csv"));
    assert_eq!(
        csv.lines().next().unwrap(),
        "run,tilt_deg,stepover_mm,feed_mm_min,fz_mm,step_mm,Sz,Sz_p5,Sz_p50,Sz_p95,Sa,Sa_p5,Sa_p50,Sa_p95,error"
    );

    // Without --monte-carlo: the deterministic values, to the last bit, and no bands.
    let plain = crest()
        .arg("study")
        .arg(&d)
        .arg("-o")
        .arg(dir.path().join("plain"))
        .arg("--json")
        .output()
        .unwrap();
    let plain = output_json(&plain);
    assert!(plain.get("monte_carlo").is_none());
    assert!(!dir.path().join("plain").join("bands.svg").exists());
    assert!(dir.path().join("plain").join("runs.csv").exists());
    for (p, m) in plain["runs"]
        .as_array()
        .unwrap()
        .iter()
        .zip(s["runs"].as_array().unwrap())
    {
        assert_eq!(p["responses"], m["responses"]);
        assert!(p.get("bands").is_none());
        for k in ["Sz", "Sa"] {
            let b = &m["bands"][k];
            let (p5, p95) = (b["p5"].as_f64().unwrap(), b["p95"].as_f64().unwrap());
            assert!(p5 <= b["p50"].as_f64().unwrap() && b["p50"].as_f64().unwrap() <= p95);
            // The spindle phase between passes and the run-out move the marks.
            assert!(p95 > p5, "{k}: {b}");
        }
    }

    // Shards of different Monte Carlo settings do not merge.
    let other = dir.path().join("other");
    crest()
        .arg("study")
        .arg(&d)
        .args(["--monte-carlo", "5", "--seed", "8", "--shard", "2/2"])
        .arg("-o")
        .arg(&other)
        .assert()
        .success();
    let o = crest()
        .arg("merge")
        .arg(&files[0])
        .arg(other.join("shard-2-of-2.jsonl"))
        .arg("-o")
        .arg(dir.path().join("bad"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("different Monte Carlo"), "{err}");
}

#[test]
fn monte_carlo_needs_one_to_a_hundred_thousand_samples() {
    let dir = tempdir();
    let d = mc_design(dir.path());
    for n in ["0", "100001"] {
        let o = crest()
            .arg("study")
            .arg(&d)
            .args(["--monte-carlo", n])
            .arg("-o")
            .arg(dir.path().join("out"))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{n}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("--monte-carlo"), "{err}");
        assert!(!dir.path().join("out").exists());
    }
    let bad = read(&d).replace("tooth_deviation_um = 0.5", "parameter_scale = 2.0");
    let b = write(dir.path(), "bad.toml", bad);
    let o = crest()
        .arg("study")
        .arg(&b)
        .arg("-o")
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.toml:14:19") && err.contains("parameter_scale"),
        "{err}"
    );
}
