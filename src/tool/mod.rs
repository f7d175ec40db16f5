//! Cutters: ball-end, filleted (torus) and flat end mills; helical cutting edges of
//! infinitesimal elements (ICE); run-out; participating teeth; effective radius.
//!
//! Geometry follows `model.md` §2, §3, §6 and §7. The tool frame has its origin at the tool
//! tip, `z` along the axis towards the spindle; a spindle angle θ gives the edge direction
//! `d(θ) = sin θ x_t + cos θ y_t`.

mod cutter;

pub use cutter::{Cutter, Runout, Shape, crest_height_mm, direction};
