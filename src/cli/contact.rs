//! `crest contact`: contact data for a centre-line path, from the part's design surface (or
//! derived from the path), written as contact12 CSV or CLSF with contact data.
//!
//! ```text
//! crest contact FILE [--part PART.stl] [--tool TOOL.toml | --teeth N] -o OUT.csv|OUT.cls [--json]
//! ```

use super::Outcome;
use crest::pipeline::contact::{ContactRequest, DEFAULT_TOLERANCE_UM, contact};
use crest::toolpath::{ClsfWriter, Contact12Writer};
use miette::{IntoDiagnostic, WrapErr};
use std::path::PathBuf;

/// Options of `crest contact`.
///
/// The part must be in the frame of the path as crest reads it: the MCS of a CLSF (MSYS not
/// applied), or the absolute frame with --absolute.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Tool-path file (CLSF or contact12).
    pub file: PathBuf,
    /// The part's design surface (binary or ASCII STL, OBJ, PLY; mm); without it the
    /// contacts are derived from the path (the cutter's offset surface fitted over
    /// neighbouring passes).
    #[arg(long, value_name = "PART.STL")]
    pub part: Option<PathBuf>,
    /// Cutter description; default: the file's TLDATA with --teeth.
    #[arg(long, value_name = "TOOL.TOML", conflicts_with = "teeth")]
    pub tool: Option<PathBuf>,
    /// Teeth of a tool taken from TLDATA.
    #[arg(long, value_name = "N")]
    pub teeth: Option<usize>,
    /// Apply MSYS: the path (and the part) in the absolute frame.
    #[arg(long)]
    pub absolute: bool,
    /// A cutting posture whose cutter stays farther than this from the part gets no contact
    /// (an air cut), µm.
    #[arg(long, value_name = "UM", default_value_t = DEFAULT_TOLERANCE_UM)]
    pub tolerance_um: f64,
    /// Output: `.cls`/`.clsf` for CLSF with contact data; `.stl` for the surface the
    /// contacts describe as a binary STL mesh (neighbouring passes stitched, gaps left
    /// open), to give as `--part` where no CAD export is at hand; else contact12 CSV
    /// (x,y,z,i,j,k,cx,cy,cz,nx,ny,nz; contact columns empty where there is none).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub output: PathBuf,
    /// Which moves get contact data: `cut` (default: the cutting passes) or `all` (every
    /// feed move, engage and retract too).
    #[arg(long, value_enum, default_value = "cut")]
    pub moves: crest::toolpath::Moves,
    /// Print one JSON object: postures, with_contact, max_gouge_um, max_gap_um, ….
    #[arg(long)]
    pub json: bool,
}

/// Run `crest contact`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    super::check_outputs([args.output.as_path()])?;
    let req = ContactRequest {
        file: args.file.clone(),
        part: args.part.clone(),
        tool: args.tool.clone(),
        teeth: args.teeth,
        absolute: args.absolute,
        tolerance_um: args.tolerance_um,
        moves: args.moves,
    };
    let run = contact(&req)?;
    for w in &run.warnings {
        super::warn(w);
    }
    let clsf = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| {
            ["cls", "clsf", "cl", "apt"]
                .iter()
                .any(|x| e.eq_ignore_ascii_case(x))
        });
    let stl = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("stl"));
    let mesh = stl.then(|| crest::pipeline::contact::contact_mesh(&run.program));
    if let Some(m) = &mesh
        && m.mesh.triangles.is_empty()
    {
        return Err(miette::miette!(
            "{}: the contacts make no triangle (one pass, or no neighbouring passes): no surface to write to {}",
            args.file.display(),
            args.output.display()
        ));
    }
    crest::io::write_atomic(&args.output, |w| {
        if let Some(m) = &mesh {
            crest::io::mesh::write_stl(&m.mesh, w)?;
        } else if clsf {
            let mut cw = ClsfWriter::new();
            for path in &run.program.paths {
                cw.begin_path(path, w)?;
                for p in &path.postures {
                    cw.posture(p, w)?;
                }
                cw.end_path(w)?;
            }
        } else {
            let mut cw = Contact12Writer::new(true);
            cw.header(w)?;
            for p in run.program.paths.iter().flat_map(|t| t.postures.iter()) {
                cw.posture(p, w)?;
            }
            cw.flush(w)?;
        }
        Ok(())
    })
    .into_diagnostic()
    .wrap_err_with(|| format!("cannot write {}", args.output.display()))?;
    let without = run.postures - run.with_contact;
    if args.json {
        let j = serde_json::json!({
            "output": args.output.display().to_string(),
            "source": run.source,
            "tool": run.tool_source,
            "postures": run.postures,
            "with_contact": run.with_contact,
            "without_contact": without,
            "inconsistent": run.inconsistent,
            "triangles": mesh.as_ref().map(|m| m.mesh.triangles.len()),
            "triangles_left_out": mesh.as_ref().map(|m| m.left_out),
            "max_gouge_um": run.max_gouge_um,
            "max_gap_um": run.max_gap_um,
            "tolerance_um": args.tolerance_um,
            "moves": args.moves.name(),
            "move_kinds": super::reading::moves_json(
                run.program.paths.iter().flat_map(|t| t.postures.iter())
            ),
            "warnings": run.warnings,
        });
        outln!("{j}");
    } else {
        outln!(
            "{}: {} of {} cutting postures with contact ({}); deepest gouge {:.3} µm, largest gap {:.3} µm; tool {}",
            args.output.display(),
            run.with_contact,
            run.postures,
            run.source,
            run.max_gouge_um,
            run.max_gap_um,
            run.tool_source
        );
    }
    if run.with_contact == 0 {
        eprintln!(
            "crest contact: no cutting posture touches the part within {} µm: check the frame (--absolute) and the tool",
            args.tolerance_um
        );
        return Ok(Outcome::CheckFailed);
    }
    Ok(Outcome::Ok)
}
