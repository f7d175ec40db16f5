//! `crest runout`.

use super::Outcome;

/// Options of `crest runout`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest runout`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest runout is not built yet"))
}
