//! `crest completions SHELL` and `crest man`: shell completions and man pages generated
//! from the clap definition of the command line (as ripgrep ships them), so they can never
//! disagree with what the binary accepts.

use std::path::PathBuf;

use clap::CommandFactory;
use miette::{IntoDiagnostic, WrapErr, miette};

use super::{Cli, Outcome};

/// Options of `crest completions`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Install, for example:
  bash:        crest completions bash > ~/.local/share/bash-completion/completions/crest
  zsh:         crest completions zsh > ~/.zfunc/_crest   (with fpath+=~/.zfunc before compinit)
  fish:        crest completions fish > ~/.config/fish/completions/crest.fish
  PowerShell:  crest completions powershell | Out-String | Invoke-Expression")]
pub struct CompletionsArgs {
    /// The shell to complete for.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
}

/// Options of `crest man`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Read it with `crest man | man -l -`; install with `crest man \
--out-dir ~/.local/share/man/man1`."
)]
pub struct ManArgs {
    /// The page of one command (`crest man simulate` is crest-simulate(1)); default crest(1).
    pub command: Option<String>,
    /// Write crest.1 and a crest-COMMAND.1 page for every command into this folder instead.
    #[arg(long, value_name = "DIR", conflicts_with = "command")]
    pub out_dir: Option<PathBuf>,
}

/// Run `crest completions`.
pub fn completions(args: CompletionsArgs) -> miette::Result<Outcome> {
    let mut out = Vec::new();
    clap_complete::generate(args.shell, &mut Cli::command(), "crest", &mut out);
    super::print_bytes(&out)?;
    Ok(Outcome::Ok)
}

/// The man page of `cmd` as roff; its title is the command's display name, which clap's
/// `build` makes `crest-simulate` for `simulate`.
fn page(cmd: clap::Command) -> miette::Result<Vec<u8>> {
    let mut out = Vec::new();
    clap_mangen::Man::new(cmd)
        .render(&mut out)
        .into_diagnostic()?;
    Ok(out)
}

/// Every page, named: crest(1), then crest-COMMAND(1) for each command and nested command.
fn pages() -> miette::Result<Vec<(String, Vec<u8>)>> {
    let mut root = Cli::command();
    root.build();
    let mut pages = Vec::new();
    let mut stack = vec![root];
    while let Some(cmd) = stack.pop() {
        let name = cmd.get_display_name().unwrap_or(cmd.get_name()).to_string();
        let mut subs: Vec<clap::Command> = cmd
            .get_subcommands()
            .filter(|c| c.get_name() != "help")
            .cloned()
            .collect();
        subs.reverse();
        stack.extend(subs);
        pages.push((name, page(cmd)?));
    }
    Ok(pages)
}

/// Run `crest man`.
pub fn man(args: ManArgs) -> miette::Result<Outcome> {
    let pages = pages()?;
    if let Some(dir) = args.out_dir {
        let files: Vec<(String, Vec<u8>)> = pages
            .into_iter()
            .map(|(name, roff)| (format!("{name}.1"), roff))
            .collect();
        crest::io::output::write_set(&dir, &files)
            .into_diagnostic()
            .wrap_err_with(|| format!("cannot write the man pages into {}", dir.display()))?;
        outln!("wrote {} man pages to {}", files.len(), dir.display());
        return Ok(Outcome::Ok);
    }
    let name = match &args.command {
        Some(c) => format!(
            "crest-{}",
            c.split_whitespace().collect::<Vec<_>>().join("-")
        ),
        None => "crest".to_string(),
    };
    let (_, roff) = pages
        .into_iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| miette!("no man page {name}: `crest help` lists the commands"))?;
    super::print_bytes(&roff)?;
    Ok(Outcome::Ok)
}
