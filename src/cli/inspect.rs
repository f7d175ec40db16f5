//! `crest inspect`.

use super::Outcome;

/// Options of `crest inspect`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest inspect`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest inspect is not built yet"))
}
