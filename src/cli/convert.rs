//! `crest convert`: CLSF → contact12 CSV, contact12 → CLSF with contact data, and any of
//! them (G-code included) → G-code through a machine's inverse kinematics; and height maps
//! between their formats (`crest convert MAP -o MAP.x3p|.gsf|.sdf|.csv|.xyz`).
//!
//! A height-map conversion is chosen when the input is a height map other than `.csv` or
//! `.xyz` (`.gsf`, `.sdf`, `.x3p` and the instruments' `.sur`, `.al3d`, `.gwy`, `.plu`,
//! `.plux`, `.opd`, `.vk4`) or the output is a `.gsf`, `.sdf`, `.x3p` or `.xyz` (a grid
//! `.csv` input needs `--dx-um`).
//!
//! The input kind is detected by content; the output kind by the extension of `-o`
//! (`.cls`, `.clsf`, `.cl`, `.apt` = CLSF; `.nc`, `.mpf`, `.spf`, `.tap`, `.gcode`, `.ngc`,
//! `.cnc` = G-code, which needs `--machine`; anything else = contact12 CSV). Conversion
//! streams posture by posture (constant memory); the output goes to a temporary file that
//! is renamed only when everything succeeded, so bad input leaves no output behind.

use super::Outcome;
use super::reading::read_options;
use crest::io::toolpath::{stream_from, stream_written_from};
use crest::nc::GcodeWriter;
use crest::nc::Rtcp;
use crest::parse::Written;
use crest::toolpath::{ClsfWriter, Contact12Writer, LowerOptions, Posture, Toolpath};
use std::io::Write;
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
    /// CLSF output: centre-line data only (GOTO x,y,z,i,j,k, as NX writes without "Output
    /// Contact Data"), dropping the contact points and normals.
    #[arg(long)]
    pub centre_line: bool,
    /// Machine description (`machine.toml`): reads G-code input through its forward
    /// kinematics and writes G-code output through its inverse kinematics.
    #[arg(long, value_name = "MACHINE.toml")]
    pub machine: Option<PathBuf>,
    /// Tool-centre-point control: for G-code input `auto` (as the program says), `on` or
    /// `off`; for G-code output `on` writes the tool tip in the part frame under G43.4,
    /// otherwise joint positions with inverse-time feed (G93).
    #[arg(long, value_enum, default_value = "auto")]
    pub rtcp: Rtcp,
    /// Height-map input as a grid `.csv`: its x spacing, µm.
    #[arg(long, value_name = "UM")]
    pub dx_um: Option<f64>,
    /// Height-map input as a grid `.csv`: its y spacing, µm (default: --dx-um).
    #[arg(long, value_name = "UM")]
    pub dy_um: Option<f64>,
    /// The channel of a Gwyddion `.gwy` to read, by its title (default: the first channel
    /// with heights in a length unit).
    #[arg(long, value_name = "NAME")]
    pub channel: Option<String>,
}

/// True when `args` converts a height map (see the module docs).
fn is_map_conversion(args: &Args) -> bool {
    use crest::io::HeightMapFormat as F;
    let input = F::from_path(&args.file);
    let output = F::from_path(&args.output);
    // `.txt` is also contact12's extension: only `.xyz` names a point-list map output.
    let xyz = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xyz"));
    matches!(input, Some(f) if !matches!(f, F::Csv | F::Xyz))
        || matches!(output, Some(F::Gsf | F::Sdf | F::X3p))
        || xyz
}

/// `crest convert MAP -o MAP2`: read a height map and write it in the output's format.
fn convert_map(args: &Args) -> miette::Result<Outcome> {
    use miette::IntoDiagnostic;
    let Some(format) =
        crest::io::HeightMapFormat::from_path(&args.output).filter(|f| f.is_written())
    else {
        return Err(miette::miette!(
            "{}: a height map converts to .csv, .xyz, .txt, .gsf, .sdf or .x3p",
            args.output.display()
        ));
    };
    if let (Ok(a), Ok(b)) = (args.file.canonicalize(), args.output.canonicalize())
        && a == b
    {
        return Err(miette::miette!(
            "{}: the output is the input; write the conversion to another file",
            args.output.display()
        ));
    }
    super::check_outputs([args.output.as_path()])?;
    let opts = crest::io::ReadOptions {
        dx_um: args.dx_um,
        dy_um: args.dy_um,
        channel: args.channel.clone(),
    };
    let map = crest::io::read_heightmap(&args.file, &opts).map_err(|e| miette::miette!("{e}"))?;
    crest::io::write_heightmap(&args.output, &map).into_diagnostic()?;
    let valid = map.z_um.iter().filter(|z| z.is_finite()).count();
    outln!(
        "{} ({} × {} nodes at {} × {} µm, {valid} measured) → {} ({format:?})",
        args.file.display(),
        map.nx,
        map.ny,
        map.dx_um,
        map.dy_um,
        args.output.display()
    );
    Ok(Outcome::Ok)
}

/// True when `path` names a CLSF output.
fn is_clsf_output(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| {
        ["cls", "clsf", "cl", "apt"]
            .iter()
            .any(|x| e.eq_ignore_ascii_case(x))
    })
}

/// True when `path` names a G-code output.
fn is_gcode_output(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| {
        ["nc", "mpf", "spf", "tap", "gcode", "ngc", "cnc"]
            .iter()
            .any(|x| e.eq_ignore_ascii_case(x))
    })
}

/// Convert `args.file` to `args.output` (streaming).
/// What a conversion wrote: postures read, and data rows written to a contact12 CSV
/// (`None` for CLSF and G-code outputs).
pub struct Converted {
    postures: usize,
    rows: Option<usize>,
}

pub fn convert(args: &Args) -> miette::Result<Converted> {
    let (input, output, all_moves, absolute) =
        (&args.file, &args.output, args.all_moves, args.absolute);
    super::check_outputs([output.as_path()])?;
    let (kind, reader) = crest::io::toolpath::open_detected(input)?;
    let lower = LowerOptions {
        apply_msys: absolute,
        keep_postures: false,
        ..Default::default()
    };
    let opts = read_options(kind, lower, args.machine.as_deref(), args.rtcp)?;
    let to_gcode = is_gcode_output(output);
    let machine = match (&opts.machine, &args.machine, to_gcode) {
        (_, _, false) => None,
        (Some(m), _, true) => Some(m.clone()),
        (None, Some(m), true) => Some(crest::pipeline::load_machine(m)?),
        (None, None, true) => {
            return Err(miette::miette!(
                "{}: G-code is written through the machine's inverse kinematics: give --machine MACHINE.toml",
                output.display()
            ));
        }
    };
    let mut gcode = match &machine {
        Some(m) => Some(GcodeWriter::new(m, args.rtcp == Rtcp::On).map_err(|e| {
            miette::miette!(
                "{}: {e}",
                args.machine
                    .as_deref()
                    .unwrap_or(Path::new("machine"))
                    .display()
            )
        })?),
        None => None,
    };
    let gcode_out = gcode.is_some();
    let mut failure: Option<crest::io::toolpath::ReadError> = None;
    let mut rows = 0usize;
    let mut postures = 0usize;
    let to_clsf = is_clsf_output(output);
    let written = crest::io::write_atomic(output, |w| {
        let result = if let Some(gw) = gcode.as_mut() {
            let mut open = false;
            let mut sink = |path: &Toolpath, p: &Posture| -> std::io::Result<()> {
                if path.stats.postures == 1 {
                    if open {
                        gw.end_path(w)?;
                    }
                    gw.begin_path(path, w)?;
                    open = true;
                }
                gw.posture(p, w)
            };
            let r = stream_from(input, kind, reader, opts, &mut sink);
            if r.is_ok() {
                if open {
                    gw.end_path(w)?;
                }
                gw.finish(w)?;
            }
            r
        } else if to_clsf {
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
                if args.centre_line && p.contact.is_some() {
                    let mut q = p.clone();
                    q.contact = None;
                    cw.posture(&q, w)
                } else {
                    cw.posture(p, w)
                }
            };
            let r = stream_from(input, kind, reader, opts, &mut sink);
            if r.is_ok() && open {
                cw.end_path(w)?;
            }
            r
        } else {
            let mut cw = Contact12Writer::new(all_moves);
            cw.header(w)?;
            // Rows whose numbers print as the CLSF wrote them are copied from its lines.
            let mut sink = |_: &Toolpath, p: &Posture, written: Option<&Written>| {
                if all_moves
                    || (p.contact.is_some() && p.motion == crest::toolpath::MotionKind::Cut)
                {
                    rows += 1;
                }
                cw.posture_written(p, written, w)
            };
            let r = stream_written_from(input, kind, reader, opts, &mut sink);
            // The rows collected so far are handed on even when the input fails later, as a
            // `BufWriter` would: a FIFO or device gets every row before the bad line (a file
            // is not kept on failure anyway).
            let flushed = cw.flush(w);
            if r.is_ok() {
                flushed?;
            }
            r
        };
        match result {
            Ok(program) => {
                postures = program.paths.iter().map(|p| p.stats.postures).sum();
                Ok(())
            }
            Err(e) => {
                failure = Some(e);
                Err(std::io::Error::other("conversion failed"))
            }
        }
    });
    if let Some(e) = failure {
        return Err(crest::io::toolpath::name_output(e, output).into());
    }
    written.map_err(|e| miette::miette!("{}: cannot write: {e}", output.display()))?;
    let csv = !to_clsf && !gcode_out;
    Ok(Converted {
        postures,
        rows: csv.then_some(rows),
    })
}

/// Run `crest convert`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    if is_map_conversion(&args) {
        return convert_map(&args);
    }
    if args.dx_um.is_some() || args.dy_um.is_some() || args.channel.is_some() {
        return Err(miette::miette!(
            "--dx-um, --dy-um and --channel are for height maps; {} converts a tool path",
            args.file.display()
        ));
    }
    let c = convert(&args)?;
    let _ = std::io::stderr().flush();
    if c.postures == 0 {
        eprintln!(
            "crest convert: {} has no motion: nothing was converted",
            args.file.display()
        );
        return Ok(Outcome::CheckFailed);
    }
    if c.rows == Some(0) {
        eprintln!(
            "crest convert: no cutting posture of {} has contact data, so {} holds only its header: give --all-moves to write every posture, or compute the contact data with `crest contact`",
            args.file.display(),
            args.output.display()
        );
        return Ok(Outcome::CheckFailed);
    }
    Ok(Outcome::Ok)
}
