//! Reports: the regression report against a measured table as Markdown and HTML. Rendering
//! only: the numbers come from [`crate::study`], the charts from [`crate::plot`].

pub mod calibration;
pub mod regression;
