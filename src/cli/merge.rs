//! `crest merge`: assemble the shard files of `crest study --shard K/N` (of `crest
//! runout … --shard K/N`, of `crest simulate --map-mm … --shard K/N`) into the outputs the
//! command writes on one machine (the same bytes).
//!
//! ```text
//! crest merge OUT/shard-*.jsonl -o DIR [--json]        (a study: DIR gets runs.csv, …)
//! crest merge OUT/shard-*.jsonl -o DIR [--json]        (a run-out study: runout.csv, …)
//! crest merge OUT/shard-*.jsonl -o MAP.ply [--json]    (a part map)
//! ```
//!
//! Every line of every shard file is one task result (`crest::pipeline::tasks`); the results
//! must be of one design (covering each run exactly once), of one run-out study or of one
//! part map (every shard exactly once). As in `crest study`, nothing is written unless every run succeeded.

use super::Outcome;
use crest::pipeline::tasks::Merged;
use crest::surface::PartMap;
use miette::{IntoDiagnostic, WrapErr, miette};
use std::path::PathBuf;
use std::time::Instant;

/// Options of `crest merge`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Shard files written by `crest study --shard K/N`, `crest runout … --shard K/N` or
    /// `crest simulate --map-mm … --shard K/N` (JSON lines).
    #[arg(required = true, value_name = "SHARD_FILES")]
    pub shards: Vec<PathBuf>,
    /// A study's output folder (created if needed) for runs.csv, effects.csv and the
    /// charts (a run-out study's for runout.csv and its charts); for a part map, the PLY
    /// file.
    #[arg(short = 'o', long = "output", value_name = "DIR|MAP.ply")]
    pub output: PathBuf,
    /// Print one JSON object (runs, effects, output paths) on stdout, as `crest study --json`.
    #[arg(long)]
    pub json: bool,
}

/// Run `crest merge`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let started = Instant::now();
    let mut results: Vec<(String, serde_json::Value)> = Vec::new();
    for path in &args.shards {
        let file = path.display().to_string();
        let text = crest::io::text::read_text(path, "shard file", crest::io::input::SHARD)?;
        for (i, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let v: serde_json::Value = serde_json::from_str(line).map_err(|e| {
                miette!(
                    "{file}:{}:{}: not a task result: {e}",
                    i + 1,
                    e.column().max(1)
                )
            })?;
            results.push((format!("{file}:{}:1", i + 1), v));
        }
    }
    let name = |k: &str| {
        results
            .first()
            .and_then(|(_, v)| v.get(k))
            .and_then(|f| f.as_str().map(str::to_string))
            .unwrap_or_default()
    };
    let design_file = name("design_file");
    let study_file = name("study_file");
    match crest::pipeline::tasks::merge_any(results)? {
        Merged::Design(done) => {
            super::study::write_outputs(&done, &design_file, &args.output, args.json, started)
        }
        Merged::Runout(run) => {
            super::runout::write_outputs(&run, &study_file, &args.output, args.json)
        }
        Merged::Map(m) => write_map(&m, &args, started),
        Merged::Atlas(a) => {
            let outputs = vec![args.output.clone()];
            super::atlas::check_names(&outputs, None)?;
            super::atlas::write_outputs(&a, &outputs, None, args.json, started)
        }
    }
}

/// Write a merged part map as the PLY `crest simulate --map-mm` writes, and its summary.
fn write_map(m: &PartMap, args: &Args, started: Instant) -> miette::Result<Outcome> {
    let out = &args.output;
    if !out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"))
    {
        return Err(miette!(
            "{}: the shards are of a part map: -o names the PLY file to write (OUT.ply)",
            out.display()
        ));
    }
    crest::io::write_atomic(out, |w| crest::io::mesh::write_map_ply(&m.points, w))
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write {}", out.display()))?;
    let heights: Vec<f64> = m.points.iter().map(|p| p.height_um).collect();
    let st = crest::metrics::height_stats(&heights);
    let elapsed = started.elapsed().as_secs_f64();
    let nan = f64::NAN;
    if args.json {
        let num = crest::io::tables::json_number;
        let stat =
            |pick: fn(&crest::metrics::HeightStats) -> f64| num(st.as_ref().map_or(nan, pick));
        let j = serde_json::json!({
            "output": out.display().to_string(),
            "grid": "map",
            "nodes": m.points.len(),
            "nodes_cut": m.nodes_cut,
            "cells": m.tiles,
            "heights_um": {
                "min": stat(|s| s.min),
                "max": stat(|s| s.max),
                "mean": stat(|s| s.mean),
                "sz": stat(|s| s.sz()),
                "sq": stat(|s| s.sq),
                "sa": stat(|s| s.sa),
            },
            "time_s": num(elapsed),
        });
        outln!("{j}");
    } else {
        outln!(
            "{}: {} part points in {} cells, {} cut; heights {:.4}..{:.4} µm (Sq {:.4} µm); {:.2} s",
            out.display(),
            m.points.len(),
            m.tiles,
            m.nodes_cut,
            st.as_ref().map_or(nan, |s| s.min),
            st.as_ref().map_or(nan, |s| s.max),
            st.as_ref().map_or(nan, |s| s.sq),
            elapsed
        );
    }
    Ok(Outcome::Ok)
}
