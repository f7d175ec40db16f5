//! `crest merge`: assemble the shard files of `crest study --shard K/N` into the outputs
//! `crest study` writes on one machine (the same bytes).
//!
//! ```text
//! crest merge OUT/shard-*.jsonl -o DIR [--json]
//! ```
//!
//! Every line of every shard file is one task result (`crest::pipeline::tasks::TaskResult`);
//! the results must be of one design and cover each run exactly once. As in `crest study`,
//! nothing is written unless every run succeeded.

use super::Outcome;
use crest::pipeline::tasks::TaskResult;
use miette::miette;
use std::path::PathBuf;
use std::time::Instant;

/// Options of `crest merge`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Shard files written by `crest study --shard K/N` (JSON lines).
    #[arg(required = true, value_name = "SHARD_FILES")]
    pub shards: Vec<PathBuf>,
    /// Output folder (created if needed) for runs.csv, effects.csv and the charts.
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub output: PathBuf,
    /// Print one JSON object (runs, effects, output paths) on stdout, as `crest study --json`.
    #[arg(long)]
    pub json: bool,
}

/// Run `crest merge`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let started = Instant::now();
    let mut results: Vec<TaskResult> = Vec::new();
    for path in &args.shards {
        let file = path.display().to_string();
        let text = crest::io::text::read_text(path, "shard file")?;
        for (i, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let r: TaskResult = serde_json::from_str(line).map_err(|e| {
                miette!(
                    "{file}:{}:{}: not a task result: {e}",
                    i + 1,
                    e.column().max(1)
                )
            })?;
            results.push(r);
        }
    }
    let design_file = results
        .first()
        .map(|r| r.design_file.clone())
        .unwrap_or_default();
    let done = crest::pipeline::tasks::merge(results)?;
    super::study::write_outputs(&done, &design_file, &args.output, args.json, started)
}
