//! Studies and reports: run-out what-if studies, regression reports against measured
//! confocal tables (Markdown and HTML), and their writers.

pub mod regression;
pub mod runout;
pub mod study;
