//! `crest feed`.

use super::Outcome;

/// Options of `crest feed`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest feed`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest feed is not built yet"))
}
