//! `crest convert`.

use super::Outcome;

/// Options of `crest convert`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest convert`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest convert is not built yet"))
}
