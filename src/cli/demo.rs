//! `crest demo`.

use super::Outcome;

/// Options of `crest demo`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest demo`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest demo is not built yet"))
}
