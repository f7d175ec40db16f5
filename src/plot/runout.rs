//! Plot: runout (built by its stage's owner).
