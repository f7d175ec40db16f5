//! Plot: profile (built by its stage's owner).
