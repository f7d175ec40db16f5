//! `crest study`: run a designed experiment (full factorial over tool orientation and
//! cutting parameters, 001 §4 and appendix) and its factor effects (001 Eqs 7-8).
//!
//! ```text
//! crest study design.toml -o DIR [--json] [--threads N]
//! ```
//!
//! Each run is simulated by [`crate::report::study::simulate_run`] (synthetic path →
//! resample → surface → areal parameters), the runs in parallel; the results do not depend
//! on the thread count. Nothing is written until every run has succeeded: then `DIR` is
//! created if needed and `runs.csv`, `effects.csv`, `effects.svg` (001 Fig 11) and, for each
//! factor with more than two levels, `effects-<factor>.svg` (001 Fig 12) are written, each
//! through [`crate::io::write_atomic`]. A progress bar is drawn on stderr when it is a
//! terminal.

use super::Outcome;
use crate::report::study::{
    Design, Effects, RunResult, design_effects, effects_chart, level_chart, run_design,
    simulate_run, write_effects_csv, write_runs_csv,
};
use miette::{IntoDiagnostic, WrapErr, miette};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
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
    let text = std::fs::read_to_string(&args.design)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot read design {}", args.design.display()))?;
    let file = args.design.display().to_string();
    let design = Design::parse(&text, &file)?;
    let tool_path = args
        .design
        .parent()
        .unwrap_or(Path::new("."))
        .join(&design.tool);
    let tool_text = std::fs::read_to_string(&tool_path)
        .into_diagnostic()
        .wrap_err_with(|| {
            format!(
                "{file}: cannot read tool file {} (the path is relative to the design file)",
                tool_path.display()
            )
        })?;
    let cutter = crate::tool::load_tool_toml(&tool_text).map_err(|e| {
        miette!(
            "{}:{}:{}: {}",
            tool_path.display(),
            e.line(),
            e.column(),
            e.message()
        )
    })?;
    if args.threads == Some(0) {
        return Err(miette!("--threads must be at least 1"));
    }
    let n_runs = design.runs().len();

    let bar = std::io::stderr().is_terminal().then(|| {
        let b = indicatif::ProgressBar::new(n_runs as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} study [{bar:40}] {pos}/{len} runs {elapsed_precise} eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let tick = || {
        if let Some(b) = &bar {
            b.inc(1);
        }
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .into_diagnostic()?;
    let results = pool.install(|| run_design(&design, |p| simulate_run(&design, &cutter, p), tick));
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let failed: Vec<String> = results
        .iter()
        .filter_map(|r| {
            r.error
                .as_ref()
                .map(|e| format!("run {}: {e}", r.point.run))
        })
        .collect();
    if !failed.is_empty() {
        return Err(miette!(
            "{file}: {} of {n_runs} runs failed, nothing written:\n  {}",
            failed.len(),
            failed.join("\n  ")
        ));
    }
    let effects = design_effects(&design, &results);

    // Every run succeeded: write the outputs.
    std::fs::create_dir_all(&args.output)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot create {}", args.output.display()))?;
    let runs_csv = args.output.join("runs.csv");
    let effects_csv = args.output.join("effects.csv");
    let chart_svg = args.output.join("effects.svg");
    let write = |path: &Path, f: &dyn Fn(&mut dyn std::io::Write) -> std::io::Result<()>| {
        crate::io::write_atomic(path, f)
            .into_diagnostic()
            .wrap_err_with(|| format!("cannot write {}", path.display()))
    };
    write(&runs_csv, &|w| write_runs_csv(&design, &results, w))?;
    write(&effects_csv, &|w| write_effects_csv(&design, &effects, w))?;
    crate::plot::init_fonts();
    let mut charts = Vec::new();
    let chart = effects_chart(&design, &effects);
    if !chart.series.is_empty() {
        crate::plot::profile::plot_lines(&chart, &chart_svg)
            .map_err(|e| miette!("cannot draw {}: {e}", chart_svg.display()))?;
        charts.push(chart_svg.clone());
    }
    for (i, f) in design.factors().iter().enumerate() {
        if f.levels.len() <= 2 {
            continue;
        }
        if let Some(c) = level_chart(&design, &effects, i) {
            let path = args.output.join(format!("effects-{}.svg", f.name));
            crate::plot::profile::plot_lines(&c, &path)
                .map_err(|e| miette!("cannot draw {}: {e}", path.display()))?;
            charts.push(path);
        }
    }
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
