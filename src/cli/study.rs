//! `crest study`: run a designed experiment (full factorial over tool orientation and
//! cutting parameters, 001 §4 and appendix) and its factor effects (001 Eqs 7-8).
//!
//! ```text
//! crest study design.toml -o DIR [--json] [--threads N] [--shard K/N] [--monte-carlo N --seed S]
//! ```
//!
//! Each run is simulated by `crest::study::run::simulate_run` (synthetic path →
//! resample → surface → areal parameters), the runs in parallel; the results do not depend
//! on the thread count. Nothing is written until every run has succeeded: then `DIR` is
//! created if needed and `runs.csv`, `effects.csv`, `effects.svg` (001 Fig 11) and, for each
//! factor with more than two levels, `effects-<factor>.svg` (001 Fig 12) are written, all
//! or none (`crest::io::output::Outputs`); a blocked name (a folder in its place) is refused
//! before the first run. Progress goes to stderr (a bar on a terminal, plain lines
//! elsewhere once the run is long).
//!
//! With `--shard K/N` only runs K, K+N, … are simulated and their results written as JSON
//! lines (`crest::pipeline::tasks::TaskResult`) to `DIR/shard-K-of-N.jsonl`; `crest merge`
//! assembles the shards into the outputs above, byte for byte.
//!
//! With `--monte-carlo N` every run is also simulated N times with its inputs drawn from the
//! design's `[uncertainty]` (run-out, spindle phase of every pass; sample i from stream i of
//! the seed S, `crate::study::montecarlo::run_bands`), and `runs.csv` gets the columns
//! `X_p5`, `X_p50`, `X_p95` after each response `X` (`--json`: `bands` per run), and
//! `bands.svg` draws them (a panel per response: the band, its median and the deterministic
//! run); the deterministic columns and the effects are those of the run without it. Shards
//! carry the setting, so merged shards give the same bytes.

use super::Outcome;
use crest::io::tables::json_number;
use crest::pipeline::design::{DesignRun, effects_json, run_json};
use miette::{IntoDiagnostic, WrapErr, miette};
use std::path::PathBuf;
use std::time::Instant;

/// Options of `crest study`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Design file (TOML: surface, tool, rpm, grid, responses, [factors]).
    pub design: PathBuf,
    /// Output folder (created if needed) for runs.csv, effects.csv and the charts.
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub output: PathBuf,
    /// Print one JSON object (runs, effects, output paths) on stdout.
    #[arg(long)]
    pub json: bool,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Run only shard K of N (1 ≤ K ≤ N: runs K, K+N, K+2N, …) and write their results as
    /// JSON lines to DIR/shard-K-of-N.jsonl; `crest merge` assembles the shards.
    #[arg(long, value_name = "K/N", value_parser = crest::pipeline::tasks::parse_shard)]
    pub shard: Option<(usize, usize)>,
    /// Monte Carlo samples per run for P5/P50/P95 bands of every response (inputs from the
    /// design's [uncertainty]; 1 ≤ N ≤ 100000).
    #[arg(long, value_name = "N")]
    pub monte_carlo: Option<usize>,
    /// Seed of the Monte Carlo samples.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
}

/// Run `crest study`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let started = Instant::now();
    let file = args.design.display().to_string();
    let (design, cutter) = crest::pipeline::design::load_design(&args.design)?;
    if args.threads == Some(0) {
        return Err(miette!("--threads must be at least 1"));
    }
    let monte_carlo = args.monte_carlo.map(|n| (n, args.seed));
    if let Some(n) = args.monte_carlo {
        crest::study::uncertainty::check_samples(n).map_err(|e| miette!("{e}"))?;
    }
    // A blocked output is refused before the first run, not after the last.
    let names: Vec<String> = match args.shard {
        Some((k, n)) => vec![format!("shard-{k}-of-{n}.jsonl")],
        None => {
            let mut names = vec![
                "runs.csv".to_string(),
                "effects.csv".to_string(),
                "effects.svg".to_string(),
            ];
            if monte_carlo.is_some() {
                names.push("bands.svg".to_string());
            }
            for f in design.factors().iter().filter(|f| f.levels.len() > 2) {
                names.push(format!("effects-{}.svg", f.name));
            }
            names
        }
    };
    super::check_output_folder(&args.output, &names)?;
    if let Some((k, n)) = args.shard {
        return run_shard(&args, k, n, design.runs().len(), started);
    }
    let n_runs = design.runs().len();

    let progress = super::progress::Phases::new();
    let tick = progress.counter("study", "runs", n_runs as u64);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .into_diagnostic()?;
    let done = pool.install(|| {
        crest::pipeline::design::run_monte_carlo(design, cutter, &file, monte_carlo, &tick)
    });
    progress.finish();
    let done = done?;
    // Every run succeeded: render the outputs, then write them.
    write_outputs(&done, &file, &args.output, args.json, started)
}

/// `crest study --shard K/N`: the shard's runs, written as JSON lines.
fn run_shard(
    args: &Args,
    k: usize,
    n: usize,
    total: usize,
    started: Instant,
) -> miette::Result<Outcome> {
    use crest::pipeline::tasks;
    let texts = crest::pipeline::design::load_design_texts(&args.design)?;
    let mine = (0..total).filter(|i| i % n + 1 == k).count();
    let progress = super::progress::Phases::new();
    let tick = progress.counter("study", "runs", mine as u64);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .into_diagnostic()?;
    let mc = tasks::MonteCarlo::of(args.monte_carlo.map(|n| (n, args.seed)));
    let results = pool.install(|| tasks::run_shard_with(&texts, k, n, mc, &tick));
    progress.finish();
    let results = results?;
    let mut text = Vec::new();
    for r in &results {
        serde_json::to_writer(&mut text, r).into_diagnostic()?;
        text.push(b'\n');
    }
    let name = format!("shard-{k}-of-{n}.jsonl");
    crest::io::write_files(&args.output, &[(name.clone(), text)])
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write into {}", args.output.display()))?;
    let path = args.output.join(&name);
    let failed = results.iter().filter(|r| r.error.is_some()).count();
    let elapsed = started.elapsed().as_secs_f64();
    if args.json {
        let j = serde_json::json!({
            "design": texts.design_file,
            "shard": [k, n],
            "runs": results.iter().map(|r| r.run).collect::<Vec<_>>(),
            "failed": failed,
            "output": path.display().to_string(),
            "time_s": json_number(elapsed),
        });
        outln!("{j}");
    } else {
        outln!(
            "{}: shard {k}/{n}, {} of {total} runs ({failed} failed) in {elapsed:.1} s; wrote {}",
            texts.design_file,
            results.len(),
            path.display()
        );
    }
    Ok(Outcome::Ok)
}

/// Render and write the outputs of a finished design into `output` and print its summary
/// (or, with `json`, its JSON object): `crest study` and `crest merge`.
pub(crate) fn write_outputs(
    done: &DesignRun,
    file: &str,
    output: &std::path::Path,
    json: bool,
    started: Instant,
) -> miette::Result<Outcome> {
    let files = crest::pipeline::design::render_outputs(done)?;
    let chart_names: Vec<String> = files
        .iter()
        .map(|(n, _)| n.clone())
        .filter(|n| n.ends_with(".svg"))
        .collect();
    crest::io::write_files(output, &files)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write into {}", output.display()))?;
    let DesignRun {
        design,
        results,
        effects,
        monte_carlo,
    } = done;
    let n_runs = results.len();
    let runs_csv = output.join("runs.csv");
    let effects_csv = output.join("effects.csv");
    let charts: Vec<PathBuf> = chart_names.iter().map(|n| output.join(n)).collect();
    let elapsed = started.elapsed().as_secs_f64();

    if json {
        let mut j = serde_json::json!({
            "design": file,
            "title": design.title,
            "runs": results.iter().map(|r| run_json(design, r)).collect::<Vec<_>>(),
            "effects": effects_json(design, effects),
            "outputs": {
                "runs_csv": runs_csv.display().to_string(),
                "effects_csv": effects_csv.display().to_string(),
                "charts": charts.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            },
            "time_s": json_number(elapsed),
        });
        if let Some((n, seed)) = monte_carlo {
            j["monte_carlo"] = serde_json::json!({
                "samples": n,
                "seed": seed,
                "uncertainty": {
                    "runout_offset_um": json_number(design.uncertainty.runout_offset_um),
                    "tooth_deviation_um": json_number(design.uncertainty.tooth_deviation_um),
                    "spindle_phase": design.uncertainty.spindle_phase,
                },
            });
        }
        outln!("{j}");
    } else {
        outln!(
            "{}: {n_runs} runs in {elapsed:.1} s; wrote {}, {} and {} chart(s)",
            file,
            runs_csv.display(),
            effects_csv.display(),
            charts.len()
        );
        for (name, e) in design.responses.iter().zip(effects.iter()) {
            let rel: Vec<String> = design
                .factors()
                .iter()
                .zip(&e.relative_first)
                .map(|(f, v)| format!("{} {:+.1} %", f.name, 100.0 * v))
                .collect();
            outln!("  {name}: mean {:.4}; EF_i1/M {}", e.mean, rel.join(", "));
        }
        if let Some((n, seed)) = monte_carlo {
            outln!("  Monte Carlo: {n} samples per run, seed {seed}; P95 − P5 over the runs:");
            for (k, name) in design.responses.iter().enumerate() {
                let w: Vec<f64> = results
                    .iter()
                    .filter_map(|r| r.bands.as_ref().map(|b| b[k].width()))
                    .collect();
                let lo = w.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = w.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                outln!("    {name}: {lo:.4} to {hi:.4}");
            }
        }
    }
    Ok(Outcome::Ok)
}
