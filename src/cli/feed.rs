//! `crest feed`: predict the feed the machine really reaches along every tool path of a
//! file (kinematics.md §7), from the machine's axis limits, cycle time and look-ahead.
//!
//! Every tool path of the file is planned on its own, rapids included, starting and ending
//! at rest; `t_s` restarts at 0 for each path and the totals add the paths up. Exit status
//! 1 when a path fails the §7 self-check (an interpolator fallback was needed).

use super::Outcome;
use crest::io::tables::json_number;
use crest::kinematics::{FeedPlan, Level};
use crest::pipeline::feed::PlannedPath;
use std::io::Write;
use std::path::PathBuf;

/// Options of `crest feed`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Tool-path file (CLSF, contact12 or G-code).
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Machine description (`machine.toml`: axis chain, velocity/acceleration/jerk limits,
    /// interpolation cycle; see the README's configuration reference).
    #[arg(long, value_name = "MACHINE.TOML")]
    pub machine: PathBuf,
    /// Planner: `jerk` (jerk-limited look-ahead interpolator at the cycle time) or `acc`
    /// (acceleration-limited look-ahead).
    #[arg(long, value_enum, default_value_t = LevelArg::Jerk)]
    pub level: LevelArg,
    /// Print one JSON object on stdout (totals, per path and per posture).
    #[arg(long)]
    pub json: bool,
    /// Apply MSYS: plan in the absolute frame instead of the MCS (the machine's part frame
    /// is then the CLSF's absolute system).
    #[arg(long)]
    pub absolute: bool,
    /// Write the per-posture table as CSV.
    #[arg(short = 'o', long = "output", value_name = "POSES.CSV")]
    pub output: Option<PathBuf>,
    /// Tool-centre-point control of G-code input: `auto` (as the program says), `on` or
    /// `off` (the program is read through the kinematics of `--machine`).
    #[arg(long, value_enum, default_value = "auto")]
    pub rtcp: crest::nc::Rtcp,
}

/// The `--level` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LevelArg {
    /// Jerk-limited look-ahead interpolator at the cycle time.
    Jerk,
    /// Acceleration-limited look-ahead (no jerk).
    Acc,
}

/// Run `crest feed`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    super::check_outputs(args.output.as_deref())?;
    let machine = crest::pipeline::load_machine(&args.machine)?;
    let level = match args.level {
        LevelArg::Jerk => Level::Jerk,
        LevelArg::Acc => Level::Acceleration,
    };
    let file = args.file.display().to_string();
    let plans =
        crest::pipeline::feed::plan_file(&args.file, &machine, level, args.absolute, args.rtcp)?;
    let names = machine.joint_names();
    if let Some(out) = &args.output {
        crest::io::write_atomic(out, |w| write_csv(w, &plans, &names))
            .map_err(|e| miette::miette!("{}: cannot write: {e}", out.display()))?;
    }
    let total: f64 = plans.iter().map(|p| p.plan.total_time_s).sum();
    let programmed: f64 = plans.iter().map(|p| p.plan.programmed_time_s).sum();
    let ratio = if programmed > 0.0 {
        total / programmed
    } else {
        f64::NAN
    };
    let all_ok = plans.iter().all(|p| p.plan.self_check_ok());
    if args.json {
        let paths: Vec<serde_json::Value> = plans
            .iter()
            .map(|p| path_json(&p.name, &p.input, &p.plan, &names))
            .collect();
        let v = serde_json::json!({
            "file": file,
            "machine": machine.name,
            "level": match level { Level::Jerk => "jerk", Level::Acceleration => "acc" },
            "total_time_s": total,
            "programmed_time_s": programmed,
            "time_ratio": json_number(ratio),
            "self_check_ok": all_ok,
            "paths": paths,
        });
        outln!("{v}");
    } else {
        let mut lines = String::new();
        lines.push_str(&format!("{file} on \"{}\"\n", machine.name));
        for PlannedPath { name, plan, .. } in &plans {
            let feeds: Vec<f64> = plan.postures.iter().map(|p| p.feed_mm_s * 60.0).collect();
            let fmax = feeds.iter().copied().fold(0.0, f64::max);
            lines.push_str(&format!(
                "  {:<24} {:>7} postures  time {:>10.3} s  programmed {:>10.3} s  ratio {:>6.3}  max feed {:>8.0} mm/min  switches {}  recoveries {}  fallbacks {}\n",
                name,
                plan.postures.len(),
                plan.total_time_s,
                plan.programmed_time_s,
                plan.total_time_s / plan.programmed_time_s,
                fmax,
                plan.branch_switches,
                plan.stop_recoveries,
                plan.fallbacks,
            ));
        }
        lines.push_str(&format!(
            "total {total:.3} s, programmed {programmed:.3} s, ratio {ratio:.3}\n"
        ));
        outln!("{}", lines.trim_end_matches('\n'));
    }
    Ok(if all_ok {
        Outcome::Ok
    } else {
        Outcome::CheckFailed
    })
}

/// Joint value in interface units: mm for linear joints, degrees for rotary ones.
fn joint_out(i: usize, q: f64) -> f64 {
    if i < 3 { q } else { q.to_degrees() }
}

fn path_json(
    name: &str,
    input: &[crest::kinematics::PlanInput],
    plan: &FeedPlan,
    names: &[&str; 5],
) -> serde_json::Value {
    let postures: Vec<serde_json::Value> = plan
        .postures
        .iter()
        .zip(input)
        .enumerate()
        .map(|(i, (p, inp))| {
            let mut joints = serde_json::Map::new();
            for (k, n) in names.iter().enumerate() {
                joints.insert(n.to_string(), serde_json::json!(joint_out(k, p.joints[k])));
            }
            serde_json::json!({
                "index": i,
                "line": inp.line,
                "t_s": p.t_s,
                "feed_mm_min": p.feed_mm_s * 60.0,
                "path_speed_mm_min": p.path_speed_mm_s * 60.0,
                "programmed_feed_mm_min": json_number(inp.feed_mm_s * 60.0),
                "limit": p.limit.label(names),
                "branch": p.branch,
                "joints": joints,
            })
        })
        .collect();
    serde_json::json!({
        "name": name,
        "total_time_s": plan.total_time_s,
        "programmed_time_s": plan.programmed_time_s,
        "time_ratio": json_number(plan.total_time_s / plan.programmed_time_s),
        "level1_time_s": plan.level1_time_s,
        "cycles": plan.cycles,
        "fallbacks": plan.fallbacks,
        "stop_recoveries": plan.stop_recoveries,
        "branch_switches": plan.branch_switches,
        "self_check": {
            "max_axis_ratio": plan.max_axis_ratio,
            "max_ceiling_ratio": json_number(plan.max_ceiling_ratio),
            "ok": plan.self_check_ok(),
        },
        "postures": postures,
    })
}

fn write_csv(w: &mut dyn Write, plans: &[PlannedPath], names: &[&str; 5]) -> std::io::Result<()> {
    let mut csv = csv::Writer::from_writer(w);
    let mut head = vec![
        "path",
        "index",
        "line",
        "t_s",
        "feed_mm_min",
        "path_speed_mm_min",
        "programmed_feed_mm_min",
        "limit",
        "branch",
    ];
    head.extend(names);
    csv.write_record(&head)?;
    for PlannedPath { name, input, plan } in plans {
        for (i, (p, inp)) in plan.postures.iter().zip(input).enumerate() {
            let f = inp.feed_mm_s * 60.0;
            let f = if f.is_finite() {
                f.to_string()
            } else {
                String::new()
            };
            let mut row = vec![
                name.clone(),
                i.to_string(),
                inp.line.to_string(),
                p.t_s.to_string(),
                (p.feed_mm_s * 60.0).to_string(),
                (p.path_speed_mm_s * 60.0).to_string(),
                f,
                p.limit.label(names).to_string(),
                p.branch.to_string(),
            ];
            row.extend((0..5).map(|k| joint_out(k, p.joints[k]).to_string()));
            csv.write_record(&row)?;
        }
    }
    csv.flush()
}
