//! `crest study`.

use super::Outcome;

/// Options of `crest study`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `crest study`.
pub fn run(_args: Args) -> miette::Result<Outcome> {
    Err(miette::miette!("crest study is not built yet"))
}
