//! What `crest simulate` is asked ([`SimulateRequest`], [`GridRequest`], [`FeedSource`]) and
//! the first answers every step needs: the feed source and machine, the spindle speed,
//! feed and feed per tooth ([`Cutting`]), the machine's feed per posture, the default grid
//! spacing. [`super::simulate`] re-exports them.

use crate::config::ProcessConfig;
use crate::kinematics::Machine;
use crate::pipeline::{Error, Result};
use crate::surface::ModelKind;
use crate::toolpath::{MotionKind, Moves, Posture, Program, Toolpath};
use std::path::{Path, PathBuf};

/// A request whose field is out of range: the field as the request names it (`grid_um`),
/// marked as [`super::fields`] spells it for each front end, and what is wrong with it.
#[derive(Debug, Clone, PartialEq, thiserror::Error, miette::Diagnostic)]
#[error("‹{field}› {message}")]
pub struct RequestError {
    /// The field.
    pub field: &'static str,
    /// What is wrong, after the field's name.
    pub message: String,
}

/// Which feed moves the tool; also the command line's values (the variants' lines are their
/// help). The predicted feed is kinematics.md §7.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum FeedSource {
    /// The programmed feed (FEDRAT, or the feed given).
    #[default]
    Programmed,
    /// The feed the machine really reaches (`crest feed`: the jerk-limited interpolator's
    /// tool-tip feed, on the machine given).
    Predicted,
}

/// Resolve the feed source and the machine: the machine to plan on, or `None` for the
/// programmed feed. `Predicted` needs a machine; a machine alone means `Predicted`;
/// `Programmed` with a machine is refused (the machine would be ignored).
pub fn resolve_feed_source(
    feed: Option<FeedSource>,
    machine: Option<&Path>,
) -> Result<Option<Machine>> {
    match (feed, machine) {
        (Some(FeedSource::Predicted), None) => Err(Error::Request(
            "‹feed› predicted needs the machine: add ‹machine› MACHINE.toml".into(),
        )),
        (Some(FeedSource::Programmed), Some(m)) => Err(Error::Request(format!(
            "‹machine› {} is only used with ‹feed› predicted (drop ‹feed› programmed or ‹machine›)",
            m.display()
        ))),
        (Some(FeedSource::Predicted) | None, Some(m)) => Ok(Some(super::load_machine(m)?)),
        (Some(FeedSource::Programmed) | None, None) => Ok(None),
    }
}

/// The placement options as both front ends take them (the command line's `--window`,
/// `--patch-near`, `--patch-at`, `--patch-mm`, `--map-mm`, `--region`; Python's keywords of
/// the same names): exactly one placement, resolved by [`GridChoice::resolve`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GridChoice {
    /// X0, Y0, X1, Y1 of a window of the WCS xy plane, mm.
    pub window: Option<[f64; 4]>,
    /// Arc length of a patch's contact point, mm.
    pub patch_at: Option<f64>,
    /// A point near which a patch is centred, mm.
    pub patch_near: Option<[f64; 3]>,
    /// Length along the feed and width across of a patch, mm.
    pub patch_mm: Option<[f64; 2]>,
    /// Node spacing of a part map, mm.
    pub map_mm: Option<f64>,
    /// X0, Y0, Z0, X1, Y1, Z1 of a part map's region, mm.
    pub region: Option<[f64; 6]>,
}

/// Placement options that give no one grid.
#[derive(Debug, Clone, PartialEq, thiserror::Error, miette::Diagnostic)]
pub enum GridChoiceError {
    /// None or several of the placements.
    #[error(
        "give exactly one of ‹window› X0,Y0,X1,Y1, ‹patch_near› X,Y,Z or ‹patch_at› S_MM with ‹patch_mm› L,W, or ‹map_mm› SPACING"
    )]
    NotOne,
    /// A patch without its size.
    #[error("a patch needs its size: give ‹patch_mm› LENGTH,WIDTH")]
    NoSize,
    /// A size without a patch.
    #[error("‹patch_mm› needs ‹patch_near› X,Y,Z or ‹patch_at› S_MM")]
    SizeWithoutPatch,
    /// A region without a part map.
    #[error("‹region› bounds a part map: give ‹map_mm› with it")]
    RegionWithoutMap,
    /// A map spacing that is not a positive number.
    #[error("‹map_mm› must be positive, got {0}")]
    MapSpacing(f64),
}

impl GridChoice {
    /// The one grid the options give.
    pub fn resolve(self) -> Result<GridRequest, GridChoiceError> {
        let placements = [
            self.window.is_some(),
            self.patch_at.is_some(),
            self.patch_near.is_some(),
            self.map_mm.is_some(),
        ];
        if placements.iter().filter(|b| **b).count() != 1 {
            return Err(
                if self.patch_mm.is_some() && !placements.iter().any(|b| *b) {
                    GridChoiceError::SizeWithoutPatch
                } else {
                    GridChoiceError::NotOne
                },
            );
        }
        if self.region.is_some() && self.map_mm.is_none() {
            return Err(GridChoiceError::RegionWithoutMap);
        }
        let patch = |size: Option<[f64; 2]>| size.ok_or(GridChoiceError::NoSize);
        Ok(if let Some([x0_mm, y0_mm, x1_mm, y1_mm]) = self.window {
            GridRequest::Window {
                x0_mm,
                y0_mm,
                x1_mm,
                y1_mm,
            }
        } else if let Some(spacing_mm) = self.map_mm {
            if !(spacing_mm.is_finite() && spacing_mm > 0.0) {
                return Err(GridChoiceError::MapSpacing(spacing_mm));
            }
            GridRequest::Map {
                spacing_mm,
                region: self.region,
            }
        } else if let Some(point) = self.patch_near {
            let [length_mm, width_mm] = patch(self.patch_mm)?;
            GridRequest::PatchNear {
                point,
                length_mm,
                width_mm,
            }
        } else {
            let [length_mm, width_mm] = patch(self.patch_mm)?;
            GridRequest::PatchAt {
                s_mm: self.patch_at.unwrap_or_default(),
                length_mm,
                width_mm,
            }
        })
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
) -> Result<Cutting> {
    for (name, v) in [
        ("rpm", req.rpm),
        ("feed_mm_min", req.feed_mm_min),
        ("fz_mm", req.fz_mm),
    ] {
        if let Some(v) = v
            && !(v.is_finite() && v > 0.0)
        {
            return Err(Error::field(
                name,
                format!("must be positive, got {}", crate::math::limits::shown(v)),
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
        return Err(Error::Request(format!(
            "no spindle speed: {} has no SPINDL; add ‹rpm› N (or rpm in ‹process› process.toml)",
            req.file.display()
        )));
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
                Some(line) => Error::Request(format!(
                    "{}:{line}: the cutting moves run at FEDRAT 0 mm/min; add ‹feed_mm_min› V or ‹fz_mm› F",
                    req.file.display()
                )),
                None => Error::Request(format!(
                    "no feed: {} has no FEDRAT; add ‹feed_mm_min› V or ‹fz_mm› F (or feed_mm_min / fz_mm in ‹process› process.toml)",
                    req.file.display()
                )),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_choice_gives_one_grid_or_says_what_is_missing() {
        let none = GridChoice::default();
        assert_eq!(none.resolve(), Err(GridChoiceError::NotOne));
        let size = GridChoice {
            patch_mm: Some([1.0, 2.0]),
            ..none
        };
        assert_eq!(size.resolve(), Err(GridChoiceError::SizeWithoutPatch));
        let near = GridChoice {
            patch_near: Some([1.0, 2.0, 3.0]),
            ..size
        };
        assert_eq!(
            near.resolve(),
            Ok(GridRequest::PatchNear {
                point: [1.0, 2.0, 3.0],
                length_mm: 1.0,
                width_mm: 2.0
            })
        );
        let at = GridChoice {
            patch_at: Some(7.5),
            ..none
        };
        assert_eq!(at.resolve(), Err(GridChoiceError::NoSize));
        let two = GridChoice {
            window: Some([0.0, 0.0, 1.0, 1.0]),
            ..near
        };
        assert_eq!(two.resolve(), Err(GridChoiceError::NotOne));
        let map = GridChoice {
            map_mm: Some(0.5),
            region: Some([0.0, 0.0, 0.0, 1.0, 1.0, 1.0]),
            ..none
        };
        assert!(matches!(
            map.resolve(),
            Ok(GridRequest::Map { spacing_mm, region: Some(_) }) if spacing_mm == 0.5
        ));
        for bad in [0.0, -1.0, f64::NAN] {
            let m = GridChoice {
                map_mm: Some(bad),
                ..none
            };
            assert!(matches!(m.resolve(), Err(GridChoiceError::MapSpacing(_))));
        }
        let stray = GridChoice {
            window: Some([0.0, 0.0, 1.0, 1.0]),
            region: Some([0.0; 6]),
            ..none
        };
        assert_eq!(stray.resolve(), Err(GridChoiceError::RegionWithoutMap));
        // The messages name fields, each front end spells them.
        let text = GridChoiceError::NotOne.to_string();
        assert!(super::super::fields::for_cli(&text).contains("--patch-near X,Y,Z"));
        assert!(super::super::fields::for_python(&text).contains("patch_near X,Y,Z"));
    }
}
