//! `crest convert`: CLSF → contact12 CSV, or contact12 → CLSF with contact data.
//!
//! The input kind is detected by content; the output kind by the extension of `-o`
//! (`.cls`, `.clsf`, `.cl`, `.apt` = CLSF, anything else = contact12 CSV). Conversion
//! streams posture by posture (constant memory); the output goes to a temporary file that
//! is renamed only when everything succeeded, so bad input leaves no output behind.

use super::Outcome;
use crest::io::toolpath::{detect, stream_from};
use crest::toolpath::{ClsfWriter, Contact12Writer, LowerOptions, Posture, Toolpath};
use std::fs::File;
use std::io::{BufReader, Write};
use std::path::{Path, PathBuf};

/// Options of `crest convert`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// CLSF or contact12 file (detected by content).
    pub file: PathBuf,
    /// Output: `.cls`/`.clsf` for CLSF with contact data, else contact12 CSV.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// contact12: one row per posture (CC and normal empty where there is no contact)
    /// instead of cutting moves with contact data only.
    #[arg(long)]
    pub all_moves: bool,
    /// Apply MSYS: write coordinates in the absolute frame instead of the MCS.
    #[arg(long)]
    pub absolute: bool,
}

/// True when `path` names a CLSF output.
fn is_clsf_output(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| {
        ["cls", "clsf", "cl", "apt"]
            .iter()
            .any(|x| e.eq_ignore_ascii_case(x))
    })
}

/// Convert `input` to `output` (streaming).
pub fn convert(input: &Path, output: &Path, all_moves: bool, absolute: bool) -> miette::Result<()> {
    let kind = detect(input)?;
    let file =
        File::open(input).map_err(|e| miette::miette!("{}: cannot open: {e}", input.display()))?;
    let reader = BufReader::with_capacity(1 << 16, file);
    let opts = LowerOptions {
        apply_msys: absolute,
        keep_postures: false,
        ..Default::default()
    };
    let mut failure: Option<miette::Report> = None;
    let to_clsf = is_clsf_output(output);
    let written = crest::io::write_atomic(output, |w| {
        let result = if to_clsf {
            let mut cw = ClsfWriter::new();
            let mut open = false;
            let mut sink = |path: &Toolpath, p: &Posture| -> std::io::Result<()> {
                if path.stats.postures == 1 {
                    if open {
                        cw.end_path(w)?;
                    }
                    cw.begin_path(path, w)?;
                    open = true;
                }
                cw.posture(p, w)
            };
            let r = stream_from(input, kind, reader, opts, &mut sink);
            if r.is_ok() && open {
                cw.end_path(w)?;
            }
            r
        } else {
            let mut cw = Contact12Writer::new(all_moves);
            cw.header(w)?;
            let mut sink = |_: &Toolpath, p: &Posture| cw.posture(p, w);
            stream_from(input, kind, reader, opts, &mut sink)
        };
        match result {
            Ok(_) => Ok(()),
            Err(e) => {
                failure = Some(e);
                Err(std::io::Error::other("conversion failed"))
            }
        }
    });
    if let Some(e) = failure {
        return Err(e);
    }
    written.map_err(|e| miette::miette!("{}: cannot write: {e}", output.display()))
}

/// Run `crest convert`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    convert(&args.file, &args.output, args.all_moves, args.absolute)?;
    let _ = std::io::stderr().flush();
    Ok(Outcome::Ok)
}
