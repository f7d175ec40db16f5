//! `crest metrics`.

use super::Outcome;

/// Options of `crest metrics`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest metrics`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest metrics is not built yet"))
}
