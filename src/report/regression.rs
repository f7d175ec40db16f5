//! Report: regression.
