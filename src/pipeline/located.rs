//! The place an error names: the one [`Located`] a front end's error carries, found in a
//! report's chain whatever the reader (tool paths, TOML files, study files), for the front
//! ends that show it apart from the message (the Python package's `CrestError.file`,
//! `.line`, `.column`).

use crate::config::ConfigError;
use crate::io::toolpath::InputError;
use crate::parse::{Located, ParseError};
use crate::pipeline::inputs::ToolFileError;
use crate::pipeline::runout::StudyFileError;
use crate::toolpath::LowerError;

/// The located diagnostic of `e` itself (none when it names no place in an input).
pub fn of_error<'a>(e: &'a (dyn std::error::Error + 'static)) -> Option<&'a Located> {
    if let Some(l) = e.downcast_ref::<Located>() {
        return Some(l);
    }
    if let Some(InputError(l)) = e.downcast_ref::<InputError>() {
        return Some(l);
    }
    if let Some(ToolFileError(l)) = e.downcast_ref::<ToolFileError>() {
        return Some(l);
    }
    if let Some(StudyFileError(l)) = e.downcast_ref::<StudyFileError>() {
        return Some(l);
    }
    if let Some(ConfigError(l)) = e.downcast_ref::<ConfigError>() {
        return Some(l.as_ref());
    }
    if let Some(ParseError::Syntax(l)) = e.downcast_ref::<ParseError>() {
        return Some(l);
    }
    if let Some(LowerError::Invalid(l)) = e.downcast_ref::<LowerError>() {
        return Some(l);
    }
    None
}

/// The first located diagnostic in `e`'s chain of causes, from the outermost.
pub fn of_report(e: &miette::Report) -> Option<&Located> {
    e.chain().find_map(of_error)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse::Span;

    #[test]
    fn a_report_gives_the_place_its_error_names() {
        let text = "shape = \"ball\"\nradius_mm = -5.0\nteeth = 2\nhelix_deg = 0.0\n";
        let e = crate::pipeline::tool_from_text(text, "t.toml").unwrap_err();
        let l = of_report(&e).unwrap();
        assert_eq!(l.file.as_deref(), Some("t.toml"));
        assert_eq!((l.span.line, l.span.column), (2, 13));
        let e = miette::Report::new(ConfigError::whole("d.toml", "bad")).wrap_err("context");
        assert_eq!(of_report(&e).map(|l| l.span), Some(Span::NONE));
        assert!(of_report(&miette::miette!("no place")).is_none());
    }
}
