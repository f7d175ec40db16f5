//! What `crest simulate` is asked ([`SimulateRequest`], [`GridRequest`], [`FeedSource`]) and
//! the first answers every step needs: the feed source and machine, the spindle speed,
//! feed and feed per tooth ([`Cutting`]), the machine's feed per posture, the default grid
//! spacing. [`super::simulate`] re-exports them.

use crate::config::ProcessConfig;
use crate::kinematics::Machine;
use crate::surface::ModelKind;
use crate::toolpath::{MotionKind, Moves, Posture, Program, Toolpath};
use miette::miette;
use std::path::{Path, PathBuf};

/// A request whose field is out of range: the field as the request names it (`grid_um`,
/// Python's keyword) and what is wrong with it.
#[derive(Debug, Clone, PartialEq, thiserror::Error, miette::Diagnostic)]
#[error("{field} {message}")]
pub struct RequestError {
    /// The field.
    pub field: &'static str,
    /// What is wrong, after the field's name.
    pub message: String,
}

impl RequestError {
    /// The message with the field as a command-line flag (`--grid-um`).
    pub fn with_flag(&self) -> String {
        format!("--{} {}", self.field.replace('_', "-"), self.message)
    }
}

/// Which feed moves the tool.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FeedSource {
    /// The programmed feed (FEDRAT, or the feed given).
    #[default]
    Programmed,
    /// The feed the machine really reaches (`crest feed`, kinematics.md §7).
    Predicted,
}

/// Resolve the feed source and the machine: the machine to plan on, or `None` for the
/// programmed feed. `Predicted` needs a machine; a machine alone means `Predicted`;
/// `Programmed` with a machine is refused (the machine would be ignored).
pub fn resolve_feed_source(
    feed: Option<FeedSource>,
    machine: Option<&Path>,
) -> miette::Result<Option<Machine>> {
    match (feed, machine) {
        (Some(FeedSource::Predicted), None) => Err(miette!(
            "‹feed› predicted needs the machine: add ‹machine› MACHINE.toml"
        )),
        (Some(FeedSource::Programmed), Some(m)) => Err(miette!(
            "‹machine› {} is only used with ‹feed› predicted (drop ‹feed› programmed or ‹machine›)",
            m.display()
        )),
        (Some(FeedSource::Predicted) | None, Some(m)) => Ok(Some(super::load_machine(m)?)),
        (Some(FeedSource::Programmed) | None, None) => Ok(None),
    }
}

/// Where to simulate.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum GridRequest {
    /// A window of the WCS xy plane, mm.
    Window {
        /// Lower x.
        x0_mm: f64,
        /// Lower y.
        y0_mm: f64,
        /// Upper x.
        x1_mm: f64,
        /// Upper y.
        y1_mm: f64,
    },
    /// A patch centred at the part point nearest `point` (the design surface of `--part`, or
    /// the surface derived from the path), `length_mm` along the local feed, `width_mm`
    /// across.
    PatchNear {
        /// The point, mm (the path's frame).
        point: [f64; 3],
        /// Along the feed, mm.
        length_mm: f64,
        /// Across, mm.
        width_mm: f64,
    },
    /// The whole part (or a region of it) at `spacing_mm`, as a point cloud (needs a part).
    Map {
        /// Node spacing, mm.
        spacing_mm: f64,
        /// X0, Y0, Z0, X1, Y1, Z1 of the region, mm (the part's bounds when `None`).
        region: Option<[f64; 6]>,
    },
    /// A patch on the tangent plane at the contact point at arc length `s_mm` of the path.
    PatchAt {
        /// Arc length, mm.
        s_mm: f64,
        /// Along the feed, mm.
        length_mm: f64,
        /// Across, mm.
        width_mm: f64,
    },
}

/// Accepted chord tolerances, µm: finer meshes take unbounded time, coarser ones are not a
/// model of the cutter any more.
pub const CHORD_TOL_UM: (f64, f64) = (0.001, 10.0);

/// Everything `crest simulate` is asked (serde data: a part-map task carries it).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulateRequest {
    /// Tool-path file (CLSF or contact12).
    pub file: PathBuf,
    /// Cutter description (`tool.toml` file or text); the file's TLDATA when `None`.
    pub tool: Option<super::inputs::ToolSource>,
    /// Teeth of a tool taken from TLDATA.
    pub teeth: Option<usize>,
    /// Helix angle of a tool taken from TLDATA, degrees.
    pub helix_deg: Option<f64>,
    /// The design surface (STL, OBJ, PLY) in the path's frame.
    pub part: Option<PathBuf>,
    /// Apply MSYS: read the path in the absolute frame (the part must be in it too).
    pub absolute: bool,
    /// Process parameters (`process.toml`).
    pub process: Option<PathBuf>,
    /// Spindle speed, rpm.
    pub rpm: Option<f64>,
    /// Feed, mm/min.
    pub feed_mm_min: Option<f64>,
    /// Feed per tooth, mm.
    pub fz_mm: Option<f64>,
    /// Programmed or predicted feed.
    pub feed: Option<FeedSource>,
    /// Machine description for the predicted feed (and to read G-code through).
    pub machine: Option<PathBuf>,
    /// Tool-centre-point control of G-code input.
    pub rtcp: crate::nc::Rtcp,
    /// Surface model.
    pub model: ModelKind,
    /// Spindle step of the ICE model, degrees.
    pub dtheta_deg: f64,
    /// Grid spacing, µm; by default a tenth of the feed per tooth (see [`default_grid_um`]).
    pub grid_um: Option<f64>,
    /// Chord tolerance of the meshes, µm (default [`surface::Options`]'s 0.01 µm; see
    /// [`CHORD_TOL_UM`]).
    #[serde(default)]
    pub chord_tol_um: Option<f64>,
    /// First rasterised band above the reference, µm (speed only; default 5 µm).
    #[serde(default)]
    pub band_um: Option<f64>,
    /// Grid placement.
    pub grid: GridRequest,
    /// Depth of cut, mm (default: process.toml, else 0.5).
    pub ap_mm: Option<f64>,
    /// Only this tool path (1-based).
    pub path: Option<usize>,
    /// Which moves cut (define the reference surface, are simulated, give the feed).
    #[serde(default)]
    pub moves: Moves,
}

/// Spindle speed, feed and feed per tooth after resolving options, process.toml and file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cutting {
    /// Spindle speed, rpm.
    pub rpm: f64,
    /// Feed given by the user (None = the file's FEDRAT, per posture).
    pub feed_mm_min: Option<f64>,
    /// Representative feed, mm/min.
    pub feed_nominal: f64,
    /// Feed per tooth, mm.
    pub fz_mm: f64,
}

/// Where the heights are measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReferenceSource {
    /// The contact data of the file.
    File,
    /// Contact data derived from the centre-line path (offset-surface fit).
    Derived,
    /// The design surface of the part.
    Part,
    /// None: a window measures WCS z.
    None,
}

impl ReferenceSource {
    /// The name used in output.
    pub fn name(self) -> &'static str {
        match self {
            ReferenceSource::File => "contact data of the file",
            ReferenceSource::Derived => "surface derived from the path",
            ReferenceSource::Part => "design surface of the part",
            ReferenceSource::None => "z = 0 (no contact data)",
        }
    }
}

fn first_in_cut<T>(program: &Program, pick: impl Fn(&Posture) -> Option<T>) -> Option<T> {
    program
        .paths
        .iter()
        .flat_map(|p| p.postures.iter())
        .filter(|p| p.motion == MotionKind::Cut)
        .find_map(pick)
}

/// Resolve spindle speed, feed and feed per tooth: the options first, then `process.toml`,
/// then the file (first cutting SPINDL and FEDRAT); fz defaults to feed / (Z · rpm).
pub fn resolve_cutting(
    req: &SimulateRequest,
    process: &ProcessConfig,
    program: &Program,
    teeth: usize,
) -> miette::Result<Cutting> {
    for (name, v) in [
        ("rpm", req.rpm),
        ("feed-mm-min", req.feed_mm_min),
        ("fz-mm", req.fz_mm),
    ] {
        if let Some(v) = v
            && !(v.is_finite() && v > 0.0)
        {
            return Err(miette!(
                "--{name} must be positive, got {}",
                crate::math::limits::shown(v)
            ));
        }
    }
    let rpm = req
        .rpm
        .or(process.rpm)
        .or_else(|| first_in_cut(program, |p| p.spindle_rpm.filter(|r| *r > 0.0)));
    let feed_user = req.feed_mm_min.or(process.feed_mm_min);
    let fz_user = req.fz_mm.or(process.fz_mm);
    let feed_file = first_in_cut(program, |p| p.feed_mm_min.filter(|f| *f > 0.0));
    let Some(rpm) = rpm else {
        return Err(miette!(
            "no spindle speed: {} has no SPINDL; add ‹rpm› N (or rpm in ‹process› process.toml)",
            req.file.display()
        ));
    };
    let z = teeth as f64;
    let (feed_mm_min, feed_nominal, fz_mm) = match (feed_user, fz_user, feed_file) {
        (Some(f), Some(fz), _) => (Some(f), f, fz),
        (Some(f), None, _) => (Some(f), f, f / (z * rpm)),
        (None, Some(fz), Some(ff)) => (None, ff, fz),
        (None, Some(fz), None) => (Some(fz * z * rpm), fz * z * rpm, fz),
        (None, None, Some(ff)) => (None, ff, ff / (z * rpm)),
        (None, None, None) => {
            // A FEDRAT of 0 is not "no FEDRAT": name its line.
            let zero = first_in_cut(program, |p| {
                p.feed_mm_min.filter(|f| *f == 0.0).map(|_| p.line)
            });
            return Err(match zero {
                Some(line) => miette!(
                    "{}:{line}: the cutting moves run at FEDRAT 0 mm/min; add ‹feed_mm_min› V or ‹fz_mm› F",
                    req.file.display()
                ),
                None => miette!(
                    "no feed: {} has no FEDRAT; add ‹feed_mm_min› V or ‹fz_mm› F (or feed_mm_min / fz_mm in ‹process› process.toml)",
                    req.file.display()
                ),
            });
        }
    };
    Ok(Cutting {
        rpm,
        feed_mm_min,
        feed_nominal,
        fz_mm,
    })
}

/// The predicted feed per posture (mm/min) of `path` on `machine`; with a feed override
/// the machine is planned at that programmed feed.
pub fn predicted_feed(
    path: &Toolpath,
    machine: &Machine,
    feed_override: Option<f64>,
) -> Result<Vec<f64>, crate::kinematics::KinematicsError> {
    match feed_override {
        Some(f) => {
            let mut p = path.clone();
            for q in &mut p.postures {
                q.feed_mm_min = Some(f);
            }
            crate::kinematics::predict_posture_feed(&p, machine)
        }
        None => crate::kinematics::predict_posture_feed(path, machine),
    }
}

/// The default grid spacing: a tenth of the feed per tooth (so that each feed mark spans ten
/// nodes), rounded down to 1, 2 or 5 × 10ⁿ µm, within 0.5 … 20 µm.
pub fn default_grid_um(fz_mm: f64) -> f64 {
    let target = (fz_mm * 1e3 / 10.0).clamp(0.5, 20.0);
    let decade = 10f64.powf(target.log10().floor());
    let m = target / decade;
    let nice = if m >= 5.0 {
        5.0
    } else if m >= 2.0 {
        2.0
    } else {
        1.0
    };
    nice * decade
}
