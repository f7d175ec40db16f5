//! Plot: feed (built by its stage's owner).
