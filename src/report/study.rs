//! Report: study.
