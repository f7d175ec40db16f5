//! `crest runout study.toml -o DIR`: a run-out what-if study (full factorial over run-out
//! offset, phase, axis tilt, lead and fz), written as `DIR/runout.csv` and SVG/PNG plots.
//! The study format is documented in `crest::config::runout` and
//! `samples/studies/runout.toml`.

use super::Outcome;
use std::path::PathBuf;

/// Options of `crest runout`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Study description (`study.toml`).
    #[arg(value_name = "STUDY.TOML")]
    pub study: PathBuf,
    /// Output folder (created if missing).
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    pub out: PathBuf,
    /// Print one JSON object on stdout (the rows and the files written).
    #[arg(long)]
    pub json: bool,
}

/// Run `crest runout`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let run = crest::pipeline::runout::runout(&args.study)?;
    let (study, cutter, rows, tool_path) = (&run.study, &run.cutter, &run.rows, &run.tool_path);
    let mut csv = Vec::new();
    crest::io::tables::write_runout_csv(rows, cutter.teeth(), &mut csv)
        .map_err(|e| miette::miette!("cannot write runout.csv: {e}"))?;
    let mut files = vec![("runout.csv".to_string(), csv)];
    files.extend(
        crest::plot::runout::figures(rows, study, cutter.teeth(), &run.lateral, &run.tool_name())
            .map_err(|e| miette::miette!("cannot draw the run-out charts: {e}"))?,
    );
    let written = crest::io::write_files(&args.out, &files)
        .map_err(|e| miette::miette!("{}: cannot write the outputs: {e}", args.out.display()))?;
    if args.json {
        let out = serde_json::json!({
            "study": args.study.display().to_string(),
            "tool": tool_path.display().to_string(),
            "rule": study.rule.name(),
            "x": study.x.key(),
            "cases": rows.len(),
            "files": written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "rows": rows,
        });
        outln!("{out}");
    } else {
        let min_zc = rows.iter().map(|r| r.zc).min().unwrap_or(0);
        let max_zc = rows.iter().map(|r| r.zc).max().unwrap_or(0);
        outln!(
            "{} cases ({} rule, tool {}): zc from {min_zc} to {max_zc} of {} teeth",
            rows.len(),
            study.rule.name(),
            tool_path.display(),
            cutter.teeth()
        );
        for p in &written {
            outln!("wrote {}", p.display());
        }
    }
    Ok(Outcome::Ok)
}
