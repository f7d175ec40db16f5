//! Surface simulation: height maps on grids (WCS window or local patch along normals),
//! dome and cutting-edge (ICE) models, a kiddo index over contact points.
//!
//! This is the only stage that uses rayon; results are identical for any thread count.

mod heightmap;

pub use heightmap::HeightMap;
