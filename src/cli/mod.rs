//! The command line: clap commands, TOML configs, progress bars and exit codes.
//!
//! Exit status: 0 ok, 1 a check failed (a report beyond tolerance), 2 bad input or usage.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Print one line on stdout (like `println!`), returning an error instead of panicking when
/// stdout is closed (`crest … | head`); `main` turns that error into a quiet exit 0.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::print_line(format_args!($($arg)*))?
    };
}

mod atlas;
mod calibrate;
mod compare;
mod contact;
mod convert;
mod demo;
mod diagnostic;
mod feed;
mod inspect;
mod merge;
mod metrics;
mod plot;
mod progress;
mod reading;
mod report;
mod resample;
mod runout;
mod shell;
mod simulate;
mod study;
mod synth;
mod tool;
mod view;

/// crest: predict the surface a 5-axis ball-end finishing path leaves, from NX CLSF.
#[derive(Debug, Parser)]
#[command(name = "crest", version = env!("CREST_VERSION"), propagate_version = true, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the whole pipeline on an embedded default path and tool.
    Demo(demo::Args),
    /// Summarise the tool paths of a CLSF or contact12 file.
    Inspect(inspect::Args),
    /// Convert CLSF to contact12 CSV, or contact12 to CLSF with contact data.
    Convert(convert::Args),
    /// Contact points and normals of a centre-line path, from the part (or the path).
    Contact(contact::Args),
    /// Resample a path to even feed per tooth or a constant spindle step.
    Resample(resample::Args),
    /// Cutter analysis: effective radius, crest height, participating teeth.
    Tool(tool::Args),
    /// Run-out what-if study.
    Runout(runout::Args),
    /// Simulate the machined surface as a height map.
    Simulate(Box<simulate::Args>),
    /// Profile and ISO 25178 areal roughness parameters of a height map.
    Metrics(metrics::Args),
    /// Plots: trochoids, run-out, height maps, profiles, feed.
    Plot(plot::Args),
    /// Regression report against a measured table.
    Report(report::Args),
    /// Hold a predicted height map against a measured one (registered, same filters).
    Compare(compare::Args),
    /// Fit process parameters to a measured table (weighted least squares, leave-one-out).
    Calibrate(calibrate::Args),
    /// Predict the actual feed from the machine's axis limits.
    Feed(feed::Args),
    /// Write synthetic tool paths with contact data.
    Synth(synth::Args),
    /// Run a designed experiment and its factor effects.
    Study(study::Args),
    /// Assemble the shard files of `study --shard K/N` into the outputs of `study`.
    Merge(merge::Args),
    /// Write a height map or part map as a self-contained 3-D viewer page (HTML).
    View(view::Args),
    /// The roughness atlas of a part: a patch every D mm over every finishing region.
    Atlas(Box<atlas::Args>),
    /// Print shell completions (bash, zsh, fish, PowerShell, elvish).
    Completions(shell::CompletionsArgs),
    /// Print the man page (roff), or write every page into a folder.
    Man(shell::ManArgs),
}

/// How a command ended when it did not fail.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Everything ran and every check passed (exit 0).
    Ok,
    /// A check failed, e.g. a report beyond tolerance (exit 1).
    CheckFailed,
}

/// On SIGINT, SIGTERM or SIGHUP (a closed terminal, a dropped ssh): remove the temporary
/// files of outputs not yet in place, then exit with 128 + the signal's number, as a shell
/// would report it. (Unix signals; elsewhere the temporaries are removed on every error but
/// an interrupt.)
#[cfg(unix)]
fn clean_up_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    if let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
        std::thread::spawn(move || {
            if let Some(sig) = signals.forever().next() {
                crest::io::output::remove_temporaries();
                std::process::exit(128 + sig);
            }
        });
    }
}

#[cfg(not(unix))]
fn clean_up_on_signals() {}

/// Parse the process arguments, run the command, print errors, return the exit code.
pub fn main() -> ExitCode {
    clean_up_on_signals();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return match e.kind() {
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion => {
                    ExitCode::SUCCESS
                }
                _ => ExitCode::from(2),
            };
        }
    };
    match run(cli) {
        Ok(Outcome::Ok) => ExitCode::SUCCESS,
        Ok(Outcome::CheckFailed) => ExitCode::from(1),
        Err(e) => {
            if is_broken_pipe(&e) {
                return ExitCode::SUCCESS;
            }
            eprint!("{}", diagnostic::render(&e));
            ExitCode::from(2)
        }
    }
}

/// Stdout was closed by the reader (a broken pipe): not a failure of the command.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[error("stdout was closed")]
pub struct StdoutClosed;

/// Write one line on stdout and flush it; see [`outln!`].
pub(crate) fn print_line(args: std::fmt::Arguments<'_>) -> miette::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    // Library text names request fields (`‹grid_um›`); the command line shows options.
    let line = args.to_string();
    writeln!(out, "{}", crest::pipeline::fields::for_cli(&line))
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

/// Write bytes on stdout as they are (a generated file); a closed stdout as in [`outln!`].
pub(crate) fn print_bytes(bytes: &[u8]) -> miette::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_all(bytes)
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

/// A failed write to stdout: [`StdoutClosed`] for a broken pipe.
fn stdout_error(e: std::io::Error) -> miette::Report {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        miette::Report::new(StdoutClosed)
    } else {
        miette::miette!("cannot write to stdout: {e}")
    }
}

fn is_broken_pipe(e: &miette::Report) -> bool {
    e.downcast_ref::<StdoutClosed>().is_some()
        || e.chain().any(|c| {
            c.downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
        })
}

/// Refuse, before a command's work, output files that cannot be written (a folder in the
/// way, a missing folder, an input; `crest::io::output::check_file`). The outputs are
/// written later through `crest::io::output::Outputs`, all or none.
pub(crate) fn check_outputs<'a>(
    paths: impl IntoIterator<Item = &'a std::path::Path>,
) -> miette::Result<()> {
    for p in paths {
        crest::io::output::check_file(p).map_err(|e| miette::miette!("cannot write {e}"))?;
    }
    Ok(())
}

/// As [`check_outputs`] for the files `names` in the output folder `dir` (made if needed).
pub(crate) fn check_output_folder(dir: &std::path::Path, names: &[String]) -> miette::Result<()> {
    crest::io::output::check_folder(dir, names).map_err(|e| miette::miette!("cannot write {e}"))
}

/// Run one parsed command line.
pub fn run(cli: Cli) -> miette::Result<Outcome> {
    match cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Inspect(a) => inspect::run(a),
        Command::Convert(a) => convert::run(a),
        Command::Contact(a) => contact::run(a),
        Command::Resample(a) => resample::run(a),
        Command::Tool(a) => tool::run(a),
        Command::Runout(a) => runout::run(a),
        Command::Simulate(a) => simulate::run(*a),
        Command::Metrics(a) => metrics::run(a),
        Command::Plot(a) => plot::run(a),
        Command::Report(a) => report::run(a),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Feed(a) => feed::run(a),
        Command::Synth(a) => synth::run(a),
        Command::Study(a) => study::run(a),
        Command::Merge(a) => merge::run(a),
        Command::View(a) => view::run(a),
        Command::Atlas(a) => atlas::run(*a),
        Command::Completions(a) => shell::completions(a),
        Command::Man(a) => shell::man(a),
    }
}

/// Print a library warning on stderr, its request fields as options (`--grid-um`).
pub(crate) fn warn(w: &str) {
    eprintln!("warning: {}", crest::pipeline::fields::for_cli(w));
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_is_consistent() {
        Cli::command().debug_assert();
    }
}
