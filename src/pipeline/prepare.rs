//! The first steps of `crest simulate`, done once whatever the grid: check the request,
//! read the part and the path, resolve the cutter, the cutting data, the feed source and
//! the reference surface (deriving contacts when the heights need them), pick the tool
//! paths and plan the feed the machine reaches. [`crate::pipeline::atlas`] prepares once
//! and simulates every patch from the same [`Prepared`].

use super::contact::DerivedContacts;
use super::request::{
    CHORD_TOL_UM, Cutting, FeedSource, GridRequest, ReferenceSource, RequestError, SimulateRequest,
    default_grid_um, predicted_feed, resolve_cutting, resolve_feed_source,
};
use crate::config::ProcessConfig;
use crate::kinematics::Machine;
use crate::part::Part;
use crate::pipeline::{Error, Result};
use crate::tool::Cutter;
use crate::toolpath::{LowerOptions, MotionKind, Program};

/// Everything a simulation reads and resolves before it knows its grid.
#[derive(Debug)]
pub struct Prepared {
    /// The tool-path file, as given.
    pub file: String,
    /// The design surface, when given.
    pub part: Option<Part>,
    /// Process parameters.
    pub process: ProcessConfig,
    /// The program, cut moves as `--moves` says, contacts derived when needed.
    pub program: Program,
    /// The cut moves as the file gives them (before `--moves all`), per path and posture.
    pub cut_kinds: Vec<Vec<bool>>,
    /// The cutter.
    pub cutter: Cutter,
    /// Where the cutter came from.
    pub tool_source: String,
    /// Spindle speed and feeds.
    pub cutting: Cutting,
    /// The machine the feed was planned on, when it was.
    pub machine: Option<Machine>,
    /// Depth of cut, mm.
    pub ap_mm: f64,
    /// What the heights are measured from.
    pub reference: ReferenceSource,
    /// Contacts derived from the path, when they were.
    pub derived: Option<DerivedContacts>,
    /// The tool paths simulated (0-based).
    pub paths: Vec<usize>,
    /// The machine's feed per posture of each path simulated (same order as `paths`).
    pub posture_feeds: Vec<Option<Vec<f64>>>,
    /// The smallest chip the tool cuts, mm (from its file).
    pub min_chip_mm: Option<f64>,
    /// Non-fatal findings so far.
    pub warnings: Vec<String>,
}

impl Prepared {
    /// The grid spacing of `req`, µm: its own, else the default from the feed per tooth.
    pub fn grid_um(&self, req: &SimulateRequest) -> f64 {
        req.grid_um
            .unwrap_or_else(|| default_grid_um(self.cutting.fz_mm))
    }

    /// Whether posture `i` of path `pi` is a cut move.
    pub fn is_cut(&self, pi: usize, i: usize) -> bool {
        self.program.paths[pi].postures[i].motion == MotionKind::Cut
    }
}

/// Check the numbers of a request that do not need its files; the error names the
/// request's field (`grid_um`), which the command line shows as its flag.
pub fn check_request(req: &SimulateRequest) -> Result<(), RequestError> {
    let bad = |field: &'static str, message: String| Err(RequestError { field, message });
    if let Some(g) = req.grid_um
        && !(g.is_finite() && g > 0.0)
    {
        return bad("grid_um", format!("must be positive, got {g}"));
    }
    if let Some(t) = req.chord_tol_um
        && !(CHORD_TOL_UM.0..=CHORD_TOL_UM.1).contains(&t)
    {
        return bad(
            "chord_tol_um",
            format!(
                "must be between {} and {} µm, got {t}",
                CHORD_TOL_UM.0, CHORD_TOL_UM.1
            ),
        );
    }
    if let Some(b) = req.band_um
        && !(b.is_finite() && b >= 0.1)
    {
        return bad("band_um", format!("must be at least 0.1 µm, got {b}"));
    }
    let dmin = crate::math::limits::MIN_DTHETA_DEG;
    if !(req.dtheta_deg.is_finite() && req.dtheta_deg >= dmin && req.dtheta_deg <= 90.0) {
        return bad(
            "dtheta_deg",
            format!("must be in [{dmin}, 90], got {}", req.dtheta_deg),
        );
    }
    match req.grid {
        GridRequest::Window {
            x0_mm,
            y0_mm,
            x1_mm,
            y1_mm,
        } if x1_mm < x0_mm || y1_mm < y0_mm => bad(
            "window",
            format!("X0,Y0,X1,Y1 needs X0 ≤ X1 and Y0 ≤ Y1, got {x0_mm},{y0_mm},{x1_mm},{y1_mm}"),
        ),
        GridRequest::PatchNear { point, .. } if !point.iter().all(|v| v.is_finite()) => {
            bad("patch_near", "wants three finite numbers".to_string())
        }
        GridRequest::Map {
            region: Some(r), ..
        } if !(r.iter().all(|v| v.is_finite()) && r[3] >= r[0] && r[4] >= r[1] && r[5] >= r[2]) => {
            bad(
                "region",
                "X0,Y0,Z0,X1,Y1,Z1 needs finite numbers with X0 ≤ X1, Y0 ≤ Y1, Z0 ≤ Z1".to_string(),
            )
        }
        _ => Ok(()),
    }
}

/// Read and resolve everything of `req` but its grid (after [`check_request`]).
pub fn prepare(req: &SimulateRequest, progress: &dyn super::Progress) -> Result<Prepared> {
    check_request(req)?;
    let mut warnings = Vec::new();
    let part = match &req.part {
        Some(p) => {
            progress.phase(&format!("reading {}", p.display()), "");
            let f = crate::io::mesh::read_part(p)?;
            warnings.extend(f.warnings);
            Some(f.part)
        }
        None => None,
    };
    if matches!(req.grid, GridRequest::Map { .. }) && part.is_none() {
        return Err(Error::Request(
            "‹map_mm› maps the design surface of a part: give ‹part› PART.stl".into(),
        ));
    }
    let process = match &req.process {
        Some(p) => super::load_process(p)?,
        None => ProcessConfig::default(),
    };
    let (mut program, read_machine, gcode) = read_program(req, progress)?;
    // The cut moves as the file gives them, before `--moves all` makes every feed move one.
    let cut_kinds: Vec<Vec<bool>> = program
        .paths
        .iter()
        .map(|p| {
            p.postures
                .iter()
                .map(|q| q.motion == MotionKind::Cut)
                .collect()
        })
        .collect();
    req.moves.apply(&mut program);
    let (cutter, tool_source, tool_warnings) = super::inputs::resolve_cutter(
        req.tool.as_ref(),
        &program,
        &req.file,
        req.teeth,
        req.helix_deg,
    )?;
    warnings.extend(tool_warnings);
    let cutting = resolve_cutting(req, &process, &program, cutter.teeth())?;
    let machine = match (gcode, req.feed) {
        (true, Some(FeedSource::Predicted)) => read_machine,
        (true, _) => None,
        (false, _) => resolve_feed_source(req.feed, req.machine.as_deref())?,
    };
    let ap_mm = req.ap_mm.or(process.ap_mm).unwrap_or(0.5);
    if !(ap_mm.is_finite() && ap_mm > 0.0) {
        return Err(Error::field(
            "ap_mm",
            format!("must be positive, got {ap_mm}"),
        ));
    }
    let file = req.file.display().to_string();
    let (reference, derived) = reference(req, part.is_some(), &mut program, &cutter, progress)?;
    if let Some(w) = derived.as_ref().and_then(DerivedContacts::summary) {
        warnings.push(w);
    }
    let paths = super::inputs::select_paths(&req.file, req.path, program.paths.len())?;
    let mut posture_feeds = Vec::with_capacity(paths.len());
    for &i in &paths {
        let path = &program.paths[i];
        posture_feeds.push(match &machine {
            Some(m) => Some(predicted_feed(path, m, cutting.feed_mm_min).map_err(|e| {
                Error::within(
                    format_args!(
                        "{file}: tool path {} ({}): feed prediction",
                        i + 1,
                        path.name
                    ),
                    e,
                )
            })?),
            None => None,
        });
    }
    let min_chip_mm = match &req.tool {
        Some(t) => t.min_chip()?,
        None => None,
    };
    Ok(Prepared {
        file,
        part,
        process,
        program,
        cut_kinds,
        cutter,
        tool_source,
        cutting,
        machine,
        ap_mm,
        reference,
        derived,
        paths,
        posture_feeds,
        min_chip_mm,
        warnings,
    })
}

/// Read the path (G-code through the machine, which then predicts the feed only when
/// asked): the program, the machine it was read with, and whether it was G-code.
fn read_program(
    req: &SimulateRequest,
    progress: &dyn super::Progress,
) -> Result<(Program, Option<Machine>, bool)> {
    let gcode = crate::io::toolpath::detect(&req.file)? == crate::io::toolpath::InputKind::Gcode;
    let read = crate::io::toolpath::ReadOptions {
        lower: LowerOptions {
            apply_msys: req.absolute,
            ..Default::default()
        },
        machine: match (&req.machine, gcode) {
            (Some(m), true) => Some(super::load_machine(m)?),
            _ => None,
        },
        rtcp: req.rtcp,
    };
    let machine = read.machine.clone();
    progress.phase(&format!("reading {}", req.file.display()), "");
    let program = crate::io::toolpath::read_program_with(&req.file, read)?;
    Ok((program, machine, gcode))
}

/// Where the heights are measured from: the part, the file's contact data, or contacts
/// derived from the path (into `program`) when the grid needs them.
fn reference(
    req: &SimulateRequest,
    has_part: bool,
    program: &mut Program,
    cutter: &Cutter,
    progress: &dyn super::Progress,
) -> Result<(ReferenceSource, Option<DerivedContacts>)> {
    let patch_at = matches!(req.grid, GridRequest::PatchAt { .. });
    let map = matches!(req.grid, GridRequest::Map { .. });
    if has_part && !patch_at {
        return Ok((ReferenceSource::Part, None));
    }
    let from_file = program
        .paths
        .iter()
        .flat_map(|p| p.postures.iter())
        .any(|p| p.motion == MotionKind::Cut && p.contact.is_some());
    if from_file {
        return Ok((ReferenceSource::File, None));
    }
    if !((!has_part && !map) || patch_at) {
        return Ok((ReferenceSource::None, None));
    }
    progress.phase("deriving contact points from the path", "");
    let found = super::contact::derive_contacts(program, cutter);
    if found.with_contact > 0 {
        return Ok((ReferenceSource::Derived, Some(found)));
    }
    match req.grid {
        GridRequest::Window { .. } => Ok((ReferenceSource::None, Some(found))),
        _ => Err(Error::Request(format!(
            "{}: the path has no contact data and none can be derived from it (a single pass has no neighbour to fit the surface to); give ‹part› PART.stl",
            req.file.display()
        ))),
    }
}
