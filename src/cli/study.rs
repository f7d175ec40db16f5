//! `crest study`: run a designed experiment (full factorial over tool orientation and
//! cutting parameters, 001 §4 and appendix) and its factor effects (001 Eqs 7-8).
//!
//! ```text
//! crest study design.toml -o DIR [--json] [--threads N]
//! ```
//!
//! Each run is simulated by `crest::study::run::simulate_run` (synthetic path →
//! resample → surface → areal parameters), the runs in parallel; the results do not depend
//! on the thread count. Nothing is written until every run has succeeded: then `DIR` is
//! created if needed and `runs.csv`, `effects.csv`, `effects.svg` (001 Fig 11) and, for each
//! factor with more than two levels, `effects-<factor>.svg` (001 Fig 12) are written, each
//! through `crest::io::write_atomic`. A progress bar is drawn on stderr when it is a
//! terminal.

use super::Outcome;
use crest::io::tables::{write_effects_csv, write_runs_csv};
use crest::pipeline::design::DesignRun;
use crest::plot::effects::{effects_chart, level_chart};
use crest::plot::profile::line_chart_svg;
use crest::study::design::{Design, Effects, RunResult};
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
}

/// Run `crest study`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let started = Instant::now();
    let file = args.design.display().to_string();
    let (design, cutter) = crest::pipeline::design::load_design(&args.design)?;
    if args.threads == Some(0) {
        return Err(miette!("--threads must be at least 1"));
    }
    let n_runs = design.runs().len();

    let bar = super::progress::bar(n_runs as u64, "study", "runs");
    let tick = || {
        if let Some(b) = &bar {
            b.inc(1);
        }
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .into_diagnostic()?;
    let done = pool.install(|| crest::pipeline::design::run(design, cutter, &file, &tick));
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let DesignRun {
        design,
        results,
        effects,
        ..
    } = done?;

    // Every run succeeded: render the outputs, then write them.
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    let mut table = |name: &str, f: &dyn Fn(&mut Vec<u8>) -> std::io::Result<()>| {
        let mut buf = Vec::new();
        f(&mut buf).map_err(|e| miette!("cannot write {name}: {e}"))?;
        files.push((name.to_string(), buf));
        Ok::<(), miette::Report>(())
    };
    table("runs.csv", &|w| write_runs_csv(&design, &results, w))?;
    table("effects.csv", &|w| write_effects_csv(&design, &effects, w))?;
    crest::plot::init_fonts();
    let mut chart_names = Vec::new();
    let chart = effects_chart(&design, &effects);
    if !chart.series.is_empty() {
        files.push((
            "effects.svg".to_string(),
            crest::plot::effects::bar_chart_svg(&chart)
                .map_err(|e| miette!("cannot draw effects.svg: {e}"))?,
        ));
        chart_names.push("effects.svg".to_string());
    }
    for (i, f) in design.factors().iter().enumerate() {
        if f.levels.len() <= 2 {
            continue;
        }
        if let Some(c) = level_chart(&design, &effects, i) {
            let name = format!("effects-{}.svg", f.name);
            files.push((
                name.clone(),
                line_chart_svg(&c).map_err(|e| miette!("cannot draw {name}: {e}"))?,
            ));
            chart_names.push(name);
        }
    }
    crest::io::write_files(&args.output, &files)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write into {}", args.output.display()))?;
    let runs_csv = args.output.join("runs.csv");
    let effects_csv = args.output.join("effects.csv");
    let charts: Vec<PathBuf> = chart_names.iter().map(|n| args.output.join(n)).collect();
    let elapsed = started.elapsed().as_secs_f64();

    if args.json {
        let j = serde_json::json!({
            "design": file,
            "title": design.title,
            "runs": results.iter().map(|r| run_json(&design, r)).collect::<Vec<_>>(),
            "effects": effects_json(&design, &effects),
            "outputs": {
                "runs_csv": runs_csv.display().to_string(),
                "effects_csv": effects_csv.display().to_string(),
                "charts": charts.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            },
            "time_s": num(elapsed),
        });
        outln!("{j}");
    } else {
        outln!(
            "{}: {n_runs} runs in {elapsed:.1} s; wrote {}, {} and {} chart(s)",
            file,
            runs_csv.display(),
            effects_csv.display(),
            charts.len()
        );
        for (name, e) in design.responses.iter().zip(&effects) {
            let rel: Vec<String> = design
                .factors()
                .iter()
                .zip(&e.relative_first)
                .map(|(f, v)| format!("{} {:+.1} %", f.name, 100.0 * v))
                .collect();
            outln!("  {name}: mean {:.4}; EF_i1/M {}", e.mean, rel.join(", "));
        }
    }
    Ok(Outcome::Ok)
}

fn num(v: f64) -> serde_json::Value {
    serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

fn run_json(design: &Design, r: &RunResult) -> serde_json::Value {
    let factors: serde_json::Map<String, serde_json::Value> = design
        .factors()
        .iter()
        .zip(&r.point.values)
        .map(|(f, v)| (f.name.clone(), num(*v)))
        .collect();
    let responses: serde_json::Map<String, serde_json::Value> = design
        .responses
        .iter()
        .zip(&r.responses)
        .map(|(k, v)| (k.clone(), num(*v)))
        .collect();
    serde_json::json!({
        "run": r.point.run,
        "factors": factors,
        "tilt_deg": num(r.point.tilt_deg),
        "yaw_deg": num(r.point.yaw_deg),
        "feed_mm_min": num(r.point.feed_mm_min),
        "fz_mm": num(r.fz_mm),
        "stepover_mm": num(r.stepover_mm),
        "responses": responses,
        "error": r.error,
    })
}

fn effects_json(design: &Design, effects: &[Effects]) -> Vec<serde_json::Value> {
    let factors = design.factors();
    design
        .responses
        .iter()
        .zip(effects)
        .map(|(name, e)| {
            let per: Vec<serde_json::Value> = factors
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    serde_json::json!({
                        "factor": f.name,
                        "levels": f.levels.iter().map(|v| num(*v)).collect::<Vec<_>>(),
                        "effects": e.effects[i].iter().map(|v| num(*v)).collect::<Vec<_>>(),
                        "relative_first": num(e.relative_first[i]),
                    })
                })
                .collect();
            serde_json::json!({
                "response": name,
                "mean": num(e.mean),
                "factors": per,
            })
        })
        .collect()
}
