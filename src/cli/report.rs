//! `crest report`.

use super::Outcome;

/// Options of `crest report`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest report`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest report is not built yet"))
}
