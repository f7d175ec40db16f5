//! Cutters: ball-end, filleted (torus) and flat end mills, round-insert face mills and any
//! profile (APT seven-parameter cutters, polylines and arc lists, the circle-segment
//! families) by its meridian; helical cutting edges of infinitesimal elements (ICE);
//! radial and axial run-out; participating teeth; effective radius.
//!
//! Geometry follows `model.md` §2, §3, §4, §6 and §7. The tool frame has its origin at the
//! tool tip, `z` along the axis towards the spindle; a spindle angle θ gives the edge
//! direction `d(θ) = sin θ x_t + cos θ y_t`.
//!
//! * [`cutter`](Cutter): the body of revolution, teeth (even or uneven pitch), straight or
//!   helical edges, run-out r_j(z) = r(z) + ρ_j(z);
//! * [`IceElement`]: the edges discretised at chosen heights;
//! * [`analyse`]: participating teeth ([`Rule::Paper`] or [`Rule::Exact`]), fz_eff, crest
//!   heights, effective radius and cutting-speed ratio for one engagement on a plane;
//!
//! The `tool.toml` file is read by [`crate::config::load_tool_toml`].
//!
//! ```
//! use crest::tool::{Cutter, Rule, Shape, analyse};
//! let mut c = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
//! c.runout.tooth_radius_dev_mm = vec![-0.010, -0.015, -0.024, -0.025];
//! let a = analyse(&c, 15.0, 0.4, 0.05, Rule::Paper).unwrap();
//! assert_eq!(a.zc, 1);
//! assert!((a.fz_effective_mm - 0.2).abs() < 1e-12);
//! ```

mod cutter;
mod effective;
mod ice;
pub mod meridian;
mod section;
mod teeth;
pub mod trochoid;

pub use cutter::{Cutter, Runout, Shape, crest_height_mm, direction};
pub use effective::{EffectiveRadius, cutting_speed_ratio, effective_radius};
pub use ice::IceElement;
pub use meridian::{Family, Meridian, ProfileError, Segment};
pub use section::{
    Envelope, FeedProfile, envelope, feed_profile, feed_profile_for, nominal_crest_mm,
};
pub use teeth::{
    Analysis, Rule, ToolError, ToothAnalysis, analyse, generating_height_mm, mark_positions_mm,
    normal_deviation_mm, normal_runout_spread_mm, paper_teeth,
};
