//! `crest resample`.

use super::Outcome;

/// Options of `crest resample`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest resample`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest resample is not built yet"))
}
