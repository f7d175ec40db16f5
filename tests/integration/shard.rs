//! `crest study --shard K/N` and `crest merge`: a design run as three shards in three
//! separate processes and merged gives the bytes of the single-process `crest study`;
//! merging refuses missing, repeated and foreign runs.

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
