//! `crest runout study.toml -o DIR`: a run-out what-if study (full factorial over run-out
//! offset, phase, axis tilt, lead and fz), written as `DIR/runout.csv` and SVG/PNG plots.
//! The study format is documented in `crest::config::runout` and
//! `samples/studies/runout.toml`.
//!
//! With `--shard K/N` only cases K-1, K-1+N, … (0-based) are evaluated and their rows
//! written as one JSON line (`crest::pipeline::tasks::runout::RunoutResult`) to
//! `DIR/shard-K-of-N.jsonl`; `crest merge` assembles the shards into the outputs above,
//! byte for byte.
//!
//! `crest runout identify (--profile PROFILE.csv | --map MEASURED [--channel NAME])
//! --tool TOOL.toml --fz-mm F [--lead-deg L] [--json] [--write-tool FILE]`: the run-out
//! identified from a measured profile (`crest::study::identify`) or from several profiles
//! along the feed of a height map (`crest::study::identify_map`).

use super::Outcome;
use miette::{IntoDiagnostic, WrapErr, miette};
use std::path::{Path, PathBuf};

/// Options of `crest runout`.
#[derive(Debug, clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Args {
    /// `identify`: the run-out from a measured profile.
    #[command(subcommand)]
    pub command: Option<Sub>,
    /// Study description (`study.toml`).
    #[arg(value_name = "STUDY.TOML", required = true)]
    pub study: Option<PathBuf>,
    /// Output folder (created if missing).
    #[arg(short = 'o', long = "out", value_name = "DIR", required = true)]
    pub out: Option<PathBuf>,
    /// Print one JSON object on stdout (the rows and the files written).
    #[arg(long)]
    pub json: bool,
    /// Evaluate only shard K of N (1 ≤ K ≤ N: cases K-1, K-1+N, … counted from 0) and write
    /// their rows as JSON lines to DIR/shard-K-of-N.jsonl; `crest merge` assembles the shards.
    #[arg(long, value_name = "K/N", value_parser = crest::pipeline::tasks::parse_shard)]
    pub shard: Option<(usize, usize)>,
}

/// Subcommands of `crest runout`.
#[derive(Debug, clap::Subcommand)]
pub enum Sub {
    /// Identify the run-out (mark period, teeth that cut, deviations, offset) from a profile.
    Identify(IdentifyArgs),
}

/// Options of `crest runout identify`.
#[derive(Debug, clap::Args)]
pub struct IdentifyArgs {
    /// Profile along the feed (CSV `x_mm,z_um`, any spacing).
    #[arg(
        long,
        value_name = "PROFILE.csv",
        required_unless_present = "map",
        conflicts_with = "map"
    )]
    pub profile: Option<PathBuf>,
    /// A measured height map, in any format `crest metrics` reads: the feed direction is
    /// found from its spectrum and the run-out identified from several profiles along it.
    #[arg(long, value_name = "MEASURED")]
    pub map: Option<PathBuf>,
    /// The channel of a Gwyddion `.gwy` map to read, by its title.
    #[arg(long, value_name = "NAME", requires = "map")]
    pub channel: Option<String>,
    /// Spacing along x of a grid-CSV map, µm (checked against the other formats).
    #[arg(long, value_name = "D", requires = "map")]
    pub dx_um: Option<f64>,
    /// Spacing along y of a grid-CSV map, µm (default: --dx-um).
    #[arg(long, value_name = "D", requires = "map")]
    pub dy_um: Option<f64>,
    /// The tool (shape, radius, teeth, pitch; its run-out is ignored).
    #[arg(long, value_name = "TOOL.toml")]
    pub tool: PathBuf,
    /// Programmed feed per tooth, mm.
    #[arg(long = "fz-mm", value_name = "F")]
    pub fz_mm: f64,
    /// Lead angle, degrees (default 0).
    #[arg(long = "lead-deg", value_name = "L", default_value_t = 0.0)]
    pub lead_deg: f64,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    /// Write the tool with the identified run-out (`offset_um`, `offset_phase_deg` when
    /// identified, `tooth_radius_deviation_um`) as this tool.toml.
    #[arg(long, value_name = "FILE")]
    pub write_tool: Option<PathBuf>,
}

/// Run `crest runout`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    if let Some(Sub::Identify(a)) = args.command {
        return identify(a);
    }
    let (Some(study_path), Some(out_dir)) = (args.study, args.out) else {
        return Err(miette!("crest runout needs STUDY.TOML and -o DIR"));
    };
    let names = match args.shard {
        Some((k, n)) => vec![format!("shard-{k}-of-{n}.jsonl")],
        None => vec!["runout.csv".to_string()],
    };
    super::check_output_folder(&out_dir, &names)?;
    if let Some((k, n)) = args.shard {
        return run_shard(&study_path, &out_dir, k, n, args.json);
    }
    let run = crest::pipeline::runout::runout(&study_path)?;
    write_outputs(&run, &study_path.display().to_string(), &out_dir, args.json)
}

/// `crest runout --shard K/N`: the shard's rows, written as one JSON line.
fn run_shard(
    study_path: &Path,
    out_dir: &Path,
    k: usize,
    n: usize,
    json: bool,
) -> miette::Result<Outcome> {
    use crest::pipeline::tasks::runout::{run_runout_task, runout_tasks};
    let texts = crest::pipeline::runout::load_runout_texts(study_path)?;
    let task = runout_tasks(&texts, Some(n))?.swap_remove(k - 1);
    let result = run_runout_task(&task)?;
    let mut text = serde_json::to_vec(&result).into_diagnostic()?;
    text.push(b'\n');
    let name = format!("shard-{k}-of-{n}.jsonl");
    crest::io::write_files(out_dir, &[(name.clone(), text)])
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write into {}", out_dir.display()))?;
    let path = out_dir.join(&name);
    let cases: Vec<usize> = result.cases.iter().map(|c| c.case).collect();
    if json {
        let j = serde_json::json!({
            "study": texts.study_file,
            "shard": [k, n],
            "cases": cases,
            "cases_total": result.cases_total,
            "output": path.display().to_string(),
        });
        outln!("{j}");
    } else {
        outln!(
            "{}: shard {k}/{n}, {} of {} cases; wrote {}",
            texts.study_file,
            cases.len(),
            result.cases_total,
            path.display()
        );
    }
    Ok(Outcome::Ok)
}

/// Render and write the outputs of a finished run-out study into `out_dir` and print its
/// summary (or, with `json`, its JSON object): `crest runout` and `crest merge`.
pub(crate) fn write_outputs(
    run: &crest::pipeline::runout::RunoutRun,
    study_file: &str,
    out_dir: &Path,
    json: bool,
) -> miette::Result<Outcome> {
    let (study, cutter, rows, tool_path) = (&run.study, &run.cutter, &run.rows, &run.tool_path);
    let files = crest::pipeline::runout::render_outputs(run)?;
    let written = crest::io::write_files(out_dir, &files)
        .map_err(|e| miette::miette!("{}: cannot write the outputs: {e}", out_dir.display()))?;
    if json {
        let out = serde_json::json!({
            "study": study_file,
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

/// A library error as the command line says it: the options it names, the file it is about.
fn identify_error(e: &crest::study::identify::IdentifyError, file: &Path) -> miette::Report {
    use crest::study::identify::IdentifyError;
    match e {
        IdentifyError::Feed(v) => miette!("--fz-mm must be positive, got {v}"),
        IdentifyError::Lead(v) => miette!("--lead-deg must lie within ±90 degrees, got {v}"),
        e => miette!("{}: {e}", file.display()),
    }
}

fn identify(a: IdentifyArgs) -> miette::Result<Outcome> {
    use crest::study::identify_map::MapIdentifyError;
    if let Some(out) = &a.write_tool {
        super::check_outputs([out.as_path()])?;
    }
    let tool_text = crest::io::text::read_text(&a.tool, "tool file", crest::io::input::CONFIG)?;
    let cutter = crest::pipeline::tool_from_text(&tool_text, &a.tool.display().to_string())?;
    let (id, feed_deg) = match (&a.profile, &a.map) {
        (Some(profile), _) => {
            let (xs, zs) = crest::io::profile_csv::read_profile_csv(profile)?;
            let id = crest::study::identify::identify(&xs, &zs, &cutter, a.fz_mm, a.lead_deg)
                .map_err(|e| identify_error(&e, profile))?;
            (id, None)
        }
        (None, Some(path)) => {
            let opts = crest::io::ReadOptions {
                dx_um: a.dx_um,
                dy_um: a.dy_um,
                channel: a.channel.clone(),
            };
            let map = crest::io::read_heightmap(path, &opts).map_err(|e| miette!("{e}"))?;
            let m = crest::study::identify_map::identify_map(&map, &cutter, a.fz_mm, a.lead_deg)
                .map_err(|e| match e {
                    MapIdentifyError::Profiles { source, feed_deg } => {
                        identify_error(&source, path).wrap_err(format!(
                            "{}: the profiles along the feed at {feed_deg:.2}°",
                            path.display()
                        ))
                    }
                    e => miette!("{}: {e}", path.display()),
                })?;
            (m.identification, Some(m.feed_deg))
        }
        (None, None) => return Err(miette!("crest runout identify needs --profile or --map")),
    };
    if let Some(out) = &a.write_tool {
        let r = &id.runout;
        let text = crest::config::tool::with_runout(
            &tool_text,
            r.offset_um.zip(r.offset_phase_deg),
            &r.tooth_radius_deviation_um,
        );
        crest::io::write_atomic(out, |w| w.write_all(text.as_bytes()))
            .into_diagnostic()
            .wrap_err_with(|| format!("cannot write {}", out.display()))?;
    }
    if a.json {
        let mut v = serde_json::to_value(&id).into_diagnostic()?;
        if let (Some(f), Some(obj)) = (feed_deg, v.as_object_mut()) {
            obj.insert("feed_deg".into(), crest::io::tables::json_number(f));
        }
        outln!("{v}");
    } else {
        if let Some(f) = feed_deg {
            outln!(
                "feed direction {f:.2}° (from +x); {} profiles along it",
                id.profiles
            );
        }
        outln!(
            "marks {:.4} mm apart, pattern period {:.4} mm (revolution {:.4} mm); teeth cutting {:?} of {}; residual {:.3} µm",
            id.mark_spacing_mm,
            id.period_mm,
            id.revolution_mm,
            id.teeth_cutting,
            cutter.teeth(),
            id.residual_um
        );
        let devs: Vec<String> = id
            .tooth_deviation_um
            .iter()
            .map(|d| format!("{d:.3}"))
            .collect();
        outln!(
            "tooth deviations (µm, tooth 1 = deepest): {}",
            devs.join(" / ")
        );
        match (id.offset_um, id.phase_deg) {
            (Some(e), Some(p)) => outln!("offset {e:.3} µm at offset_phase_deg {p:.1}°"),
            _ => outln!("offset and phase: not identifiable from this profile"),
        }
        for n in &id.identifiable.notes {
            outln!("{n}");
        }
        if let Some(out) = &a.write_tool {
            outln!("wrote {}", out.display());
        }
    }
    Ok(Outcome::Ok)
}
