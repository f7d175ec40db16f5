//! `crest synth`.

use super::Outcome;

/// Options of `crest synth`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest synth`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest synth is not built yet"))
}
