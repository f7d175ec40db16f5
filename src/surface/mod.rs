//! Surface simulation: height maps on grids (WCS window or local patch along normals),
//! dome and cutting-edge (ICE) models, a kiddo index over contact points.
//!
//! This is the only stage that uses rayon; results are identical for any thread count
//! (tiles are independent and every node keeps an exact minimum, which does not depend on
//! the order in which cuts arrive).
//!
//! # How it works
//! The cutter is a meridian polyline (levels) with, per tooth, its edge elements (ICE) or
//! its revolved body (dome) at spindle angle 0 ([`profile`]). A pose (tool tip, tool frame,
//! spindle angle) becomes one 3×3 matrix into the grid frame ([`grid`]).
//! * **ICE**: between consecutive samples (subdivided so that Δθ ≤ the model's step) each
//!   tooth's edge polyline forms a ribbon of quads; the surface is the lower envelope of the
//!   ribbons, so it has no holes whatever the grid.
//! * **Dome**: at each sample the revolved body of each tooth (its own radius r_j(z),
//!   model.md Eq 5) is meshed in angle (chord error ≤ the tolerance) and imprinted.
//!
//! Triangles are rasterised into tiles of a z-buffer that keep the lowest height per node
//! ([`raster`]). Only triangles within a band above the nominal surface are generated; a
//! tile whose result is not provably inside that band is recomputed with a wider band,
//! up to the depth of cut, so the band only changes the speed, never the result.
//!
//! Process effects ([`process`]: minimum chip thickness, elastic recovery, texture) are off
//! by default; with ploughing on, each tile applies its tooth passes in cutting order.

pub mod cull;
mod engine;
mod envelope;
pub(crate) mod grid;
mod heightmap;
pub mod map;
pub mod process;
pub(crate) mod profile;
pub(crate) mod raster;
mod swept;

pub use engine::{simulate, simulate_with};
pub use grid::GridFrame;
pub use heightmap::HeightMap;
pub use map::{MapPoint, PartMap, map_part};
pub use process::{Process, Texture};

/// Which surface model imprints the tool.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Model {
    /// Instantaneous positions: every sample imprints the revolved body of each tooth.
    Dome,
    /// Pondered movement: the teeth's edges sweep between samples, subdivided so that the
    /// spindle turns at most `dtheta_rad` per step.
    Ice {
        /// Largest spindle step Δθ, rad.
        dtheta_rad: f64,
    },
    /// The ball swept continuously along the path, without teeth (no feed marks, no
    /// run-out): the scallops between passes at the speed of a z-map CAM simulator.
    Swept,
}

/// The surface model by name, as files, options and keywords write it (`"ice"`, `"dome"`,
/// `"swept"`); the command line's values too (the variants' lines are their help). ICE is
/// 002 §2.4.2, the dome 002 §2.4.1.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Deserialize,
    serde::Serialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum ModelKind {
    /// Pondered movement: the teeth's cutting edges swept at every Δθ.
    #[default]
    Ice,
    /// Instantaneous positions: the revolved body of each tooth at every fz.
    Dome,
    /// The ball swept continuously along the path: no teeth, no feed marks, no run-out
    /// (a tool's run-out is ignored); the scallops between passes, fast (ball end only).
    Swept,
}

impl ModelKind {
    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Ice => "ice",
            ModelKind::Dome => "dome",
            ModelKind::Swept => "swept",
        }
    }

    /// The model with the ICE step `dtheta_rad`, and the resampling it needs for feed per
    /// tooth `fz_mm` and `teeth`: one sample per feed per tooth for the dome; for ICE a
    /// sample every ≥ 8° of spindle and ≥ [`ICE_SAMPLE_STEP_MM`] of travel (a whole number
    /// of Δθ), which the engine subdivides to Δθ (poses interpolated straight between
    /// samples so close), so that memory stays small on long paths and tiny feeds. The
    /// discretisation is Δθ either way; where the sample spacing changes, the substeps at
    /// move ends fall differently, which moves heights by the model's Δθ error.
    pub fn with_resampling(
        self,
        dtheta_rad: f64,
        fz_mm: f64,
        teeth: usize,
    ) -> (Model, crate::resample::Mode) {
        match self {
            ModelKind::Dome => (Model::Dome, crate::resample::Mode::FeedPerTooth),
            ModelKind::Swept => (Model::Swept, crate::resample::Mode::FeedPerTooth),
            ModelKind::Ice => {
                let per_rev = fz_mm * teeth.max(1) as f64;
                let travel = if per_rev > 0.0 && per_rev.is_finite() {
                    std::f64::consts::TAU * ICE_SAMPLE_STEP_MM / per_rev
                } else {
                    0.0
                };
                let coarse_angle = 8f64.to_radians().max(travel.min(1e6));
                let coarse = dtheta_rad * (coarse_angle / dtheta_rad).floor().max(1.0);
                (
                    Model::Ice { dtheta_rad },
                    crate::resample::Mode::SpindleStep { dtheta_rad: coarse },
                )
            }
        }
    }
}

/// Largest travel between the ICE model's resampled poses that the engine subdivides, mm
/// (at tiny feeds per tooth 8° of spindle is far less).
pub const ICE_SAMPLE_STEP_MM: f64 = 0.005;

/// Where the grid lies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GridSpec {
    /// A window of the WCS xy plane, heights along +z. Corners in mm.
    Window {
        /// Lower x, mm.
        x0_mm: f64,
        /// Lower y, mm.
        y0_mm: f64,
        /// Upper x, mm.
        x1_mm: f64,
        /// Upper y, mm.
        y1_mm: f64,
    },
    /// A patch centred on `frame.origin` in the plane of `frame.u` (columns, `length_mm`)
    /// and `frame.v` (rows, `width_mm`), heights along `frame.w` (the surface normal there)
    /// and then along the local surface normals.
    Oriented {
        /// The patch frame (origin on the surface, w its normal).
        frame: GridFrame,
        /// Extent along u, mm.
        length_mm: f64,
        /// Extent along v, mm.
        width_mm: f64,
    },
    /// A patch on the tangent plane at the contact point nearest arc length `s_mm`, centred
    /// there: `length_mm` along the feed f (columns), `width_mm` along g = n × f (rows);
    /// heights along the local surface normals.
    Patch {
        /// Arc length of the CL point along the path, mm.
        s_mm: f64,
        /// Extent along f, mm.
        length_mm: f64,
        /// Extent along g, mm.
        width_mm: f64,
    },
}

/// What heights are measured from.
#[derive(Debug, Clone, Copy, Default)]
pub enum Reference<'a> {
    /// The surface through the samples' contact points and normals (a window without
    /// contact data measures from z = 0).
    #[default]
    Contacts,
    /// The design surface of the part: heights along its normal, 0 on the surface, positive
    /// where material is left, negative where the tool gouged.
    Part(&'a crate::part::Part),
}

/// Options of a simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Surface model.
    pub model: Model,
    /// Grid placement.
    pub grid: GridSpec,
    /// Node spacing, mm (the same along both axes).
    pub spacing_mm: f64,
    /// Depth of cut ap, mm: stock ends this far above the nominal surface, so a node whose
    /// cut height would be higher is not reached (NaN).
    pub depth_mm: f64,
    /// First band above the nominal surface that is rasterised, mm (speed only).
    pub band_mm: f64,
    /// Chord tolerance of the meridian polyline and of the dome's angular mesh, mm.
    pub chord_tol_mm: f64,
    /// Nodes per tile side (memory per tile = side² × 8 bytes).
    pub tile: usize,
    /// Process effects (ploughing, elastic recovery, texture); off by default.
    pub process: Process,
}

impl Options {
    /// Defaults: depth 0.5 mm, band 5 µm, chord tolerance 0.01 µm, tiles of 256 × 256.
    pub fn new(model: Model, grid: GridSpec, spacing_mm: f64) -> Options {
        Options {
            model,
            grid,
            spacing_mm,
            depth_mm: 0.5,
            band_mm: 0.005,
            chord_tol_mm: 1e-5,
            tile: 256,
            process: Process::default(),
        }
    }
}

/// A finished simulation.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// Heights above the nominal surface, µm (NaN = not reached).
    pub map: HeightMap,
    /// The grid frame (for a window: the WCS).
    pub frame: GridFrame,
    /// Nodes with a finite height.
    pub nodes_cut: usize,
    /// Ribbon strips generated (all passes).
    pub strips: usize,
    /// Tiles recomputed with a wider band.
    pub tiles_widened: usize,
    /// True when the nominal surface came from contact data or a part; false when the
    /// samples carry none and a window's heights are WCS z (nominal z = 0).
    pub nominal_from_contacts: bool,
    /// The reference surface over the grid (for [`Simulation::node_point`]).
    pub(crate) nominal: grid::Nominal,
}

impl Simulation {
    /// The reference-surface point under node (`i` column, `j` row) and the surface's unit
    /// normal there, in the WCS.
    pub fn node_point(&self, i: usize, j: usize) -> (crate::math::Point3, crate::math::Vec3) {
        let f = &self.frame;
        let d = self.map.dx_um * 1e-3;
        let (q, gu, gv) = self.nominal.q_grad(i, j);
        let p = f.origin
            + f.u * (self.map.x0_mm + i as f64 * d)
            + f.v * (self.map.y0_mm + j as f64 * d)
            + f.w * q;
        let n = (f.w - f.u * gu - f.v * gv).normalize();
        (p, n)
    }
}

/// Why a simulation cannot run.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SurfaceError {
    /// A non-positive or non-finite option.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// The grid would hold no node or too many.
    #[error("grid of {nx} × {ny} nodes is empty or too large")]
    BadGrid {
        /// Columns.
        nx: usize,
        /// Rows.
        ny: usize,
    },
    /// No samples to simulate.
    #[error("the path has no samples")]
    NoSamples,
    /// A patch needs contact points and normals.
    #[error("a patch needs contact data (CC points and normals) in the path")]
    NoContactData,
    /// The part has no surface facing the tool under the grid.
    #[error("the part has no surface facing the tool under the grid")]
    NoPartSurface,
    /// A sample holds a non-finite number.
    #[error("sample {0} has a non-finite position, axis or angle")]
    BadSample(usize),
}
