//! Plot: heightmap (built by its stage's owner).
