//! Report: runout.
