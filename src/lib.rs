//! crest: from Siemens NX CLSF tool paths to predicted 5-axis ball-end machined surfaces.
//!
//! The library is a pipeline of stages, one module each, in this order:
//!
//! ```text
//!  .cls / APT / contact12 ──parse──▶ records ──toolpath──▶ Toolpath ──resample──▶ Samples(s, θ, t, pose, frame)
//!  G-code ──parse──▶ blocks ──nc (machine FK)──▶ records ──toolpath──▶ Toolpath       │
//!                                                     │                        │
//!                                   machine.toml ──kinematics──▶ actual feed per pose
//!                                                                              │
//!  tool.toml ──tool──▶ Cutter (dome, edges, run-out) ──────────────▶ surface (z-map / N-buffer)
//!                                                                              │
//!                                                       HeightMap ──metrics──▶ Rz, Sa, Sq, Sz, …
//!                                                                              │
//!                                       measured table ──report──▶ Markdown + SVG/PNG, exit status
//! ```
//!
//! A stage imports only earlier stages and [`math`]. Only [`io`], [`plot`] and [`report`]
//! (and the binary's command line) touch files or the terminal; every other stage is pure.
//! See `ARCHITECTURE.md`.
//!
//! ```
//! use crest::tool::crest_height_mm;
//! // 002 Eq 14: fz = 0.05 mm on a ball of R = 5 mm leaves a 0.0625 µm crest.
//! let hc_um = crest_height_mm(5.0, 0.05) * 1000.0;
//! assert!((hc_um - 0.0625004).abs() < 1e-6);
//! ```

pub mod math;

pub mod kinematics;
pub mod metrics;
pub mod nc;
pub mod parse;
pub mod part;
pub mod resample;
pub mod study;
pub mod surface;
pub mod synth;
pub mod tool;
pub mod toolpath;

pub mod config;
pub mod io;
pub mod plot;
pub mod report;

pub mod pipeline;
