//! `crest simulate`.

use super::Outcome;

/// Options of `crest simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest simulate`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest simulate is not built yet"))
}
