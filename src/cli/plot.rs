//! `crest plot`.

use super::Outcome;

/// Options of `crest plot`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest plot`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest plot is not built yet"))
}
