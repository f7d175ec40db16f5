//! `crest tool`.

use super::Outcome;

/// Options of `crest tool`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest tool`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest tool is not built yet"))
}
