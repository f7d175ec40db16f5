//! Plot: trochoid (built by its stage's owner).
