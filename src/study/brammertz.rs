//! The one-dimensional limit of ploughing: the surface engine with a minimum chip thickness
//! against Brammertz's closed form Rt = s²/(8R) + (h_min/2)(1 + R·h_min/s²).
//!
//! Source: H. Brammertz, "Die Entstehung der Oberflächenrauheit beim Feindrehen",
//! Industrie-Anzeiger 83 (1961) 25-32, as quoted in Weule, Hüntrup & Tritschler, "Micro-
//! cutting of steel to meet new requirements in miniaturization", CIRP Annals 50/1 (2001)
//! 61-64, Eq 1. Its derivation (each new arc cuts from its lowest point up to where the layer
//! above it thins to h_min, the thinner rest stays) holds for s ≥ √(2R·h_min), where Rt has
//! its minimum h_min; below it every other pass ploughs and the closed form does not apply.

use crate::surface::{GridSpec, Model, Options, Process, simulate};
use crate::tool::{Cutter, Shape};

/// Brammertz's Rt, mm, for arcs of radius `r_mm` spaced `s_mm` and minimum chip `h_mm`.
pub fn closed_form_mm(r_mm: f64, s_mm: f64, h_mm: f64) -> f64 {
    s_mm * s_mm / (8.0 * r_mm) + 0.5 * h_mm * (1.0 + r_mm * h_mm / (s_mm * s_mm))
}

/// The feed at the closed form's minimum, √(2R·h_min), mm.
pub fn optimum_feed_mm(r_mm: f64, h_mm: f64) -> f64 {
    (2.0 * r_mm * h_mm).sqrt()
}

/// Why the engine's Rt cannot be measured.
#[derive(Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EngineError {
    /// The straight pass would need too many samples.
    #[error("too many samples")]
    TooManySamples,
    /// The simulation failed.
    #[error(transparent)]
    Surface(#[from] crate::surface::SurfaceError),
    /// The measured line has nodes no pass reached.
    #[error("the centre line has nodes no pass reached")]
    NotReached,
}

/// Rt (mm) of the surface the engine leaves: a one-tooth ball end of radius `r_mm` at lead
/// 15° along one straight pass over a plane, one imprint (dome model) every `s_mm`, minimum
/// chip `h_mm`, on the centre line of a window two feeds long after 20 passes, grid
/// `grid_mm`.
pub fn engine_rt_mm(r_mm: f64, s_mm: f64, h_mm: f64, grid_mm: f64) -> Result<f64, EngineError> {
    let cutter = Cutter::new(Shape::Ball, r_mm, 1, 0.0);
    let depth = 0.02f64.max(10.0 * h_mm);
    let reach = (2.0 * r_mm * depth).sqrt();
    let margin = (20.0 * s_mm).max(reach) + s_mm;
    let samples = crate::synth::pass::straight_pass(
        &cutter,
        15f64.to_radians(),
        s_mm,
        -margin,
        margin + 2.0 * s_mm + reach,
        360.0,
    )
    .ok_or(EngineError::TooManySamples)?;
    let grid = GridSpec::Window {
        x0_mm: 0.0,
        y0_mm: -2.0 * grid_mm,
        x1_mm: 2.0 * s_mm,
        y1_mm: 2.0 * grid_mm,
    };
    let mut opts = Options::new(Model::Dome, grid, grid_mm);
    opts.depth_mm = depth;
    opts.process = Process {
        min_chip_mm: h_mm,
        ..Process::default()
    };
    let sim = simulate(&samples, &cutter, &opts, &|_, _| {})?;
    let row = sim.map.row(sim.map.ny / 2);
    if row.iter().any(|v| !v.is_finite()) {
        return Err(EngineError::NotReached);
    }
    let hi = row.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let lo = row.iter().copied().fold(f64::INFINITY, f64::min);
    Ok((hi - lo) * 1e-3)
}

/// One point of a sweep: feed, the engine's Rt and the closed form's, mm.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SweepPoint {
    /// Feed (arc spacing) s, mm.
    pub s_mm: f64,
    /// Rt of the engine, mm.
    pub engine_mm: f64,
    /// Brammertz's Rt, mm.
    pub closed_form_mm: f64,
}

/// The engine against the closed form at feeds `factors × √(2R·h_min)`.
pub fn sweep(
    r_mm: f64,
    h_mm: f64,
    factors: &[f64],
    grid_mm: f64,
) -> Result<Vec<SweepPoint>, EngineError> {
    let s0 = optimum_feed_mm(r_mm, h_mm);
    factors
        .iter()
        .map(|f| {
            let s = s0 * f;
            Ok(SweepPoint {
                s_mm: s,
                engine_mm: engine_rt_mm(r_mm, s, h_mm, grid_mm)?,
                closed_form_mm: closed_form_mm(r_mm, s, h_mm),
            })
        })
        .collect()
}
