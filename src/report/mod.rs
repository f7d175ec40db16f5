//! Reports: the regression report against a measured table as Markdown and HTML, and the
//! 3-D viewer page of a height map or a part map. Rendering only: the numbers come from
//! [`crate::study`] and [`crate::metrics`], the charts from [`crate::plot`].

pub mod calibration;
pub mod compare;
pub mod regression;
pub mod view;

/// Text from the input as one Markdown table cell: `|` escaped (`\|`), line breaks as
/// blanks, so a label cannot split or end the row.
pub(crate) fn md_cell(text: &str) -> String {
    text.replace('|', "\\|").replace(['\r', '\n'], " ")
}
