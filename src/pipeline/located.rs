//! The place an error names: the one [`Located`] a front end's error carries, found in an
//! error's chain of causes whatever the reader (tool paths, TOML files, study files,
//! tables), for the front ends that show it apart from the message (the Python package's
//! `CrestError.file`, `.line`, `.column`).

use crate::config::ConfigError;
use crate::io::measured::MeasuredError;
use crate::io::series::SeriesError;
use crate::io::table_error::TableError;
use crate::io::toolpath::{InputError, ReadError};
use crate::parse::{Located, ParseError};
use crate::pipeline::Error;
use crate::pipeline::inputs::ToolFileError;
use crate::pipeline::runout::StudyFileError;
use crate::toolpath::LowerError;

/// The located diagnostic of `e` itself (none when it names no place in an input).
pub fn of_error<'a>(e: &'a (dyn std::error::Error + 'static)) -> Option<&'a Located> {
    if let Some(l) = e.downcast_ref::<Located>() {
        return Some(l);
    }
    // The error a step's own line wraps is a cause as its box.
    let pipeline = e
        .downcast_ref::<Error>()
        .or_else(|| e.downcast_ref::<Box<Error>>().map(Box::as_ref));
    if let Some(e) = pipeline {
        return e.transparent().and_then(of_error);
    }
    if let Some(InputError(l)) = e.downcast_ref::<InputError>() {
        return Some(l);
    }
    if let Some(ReadError::Located(located)) = e.downcast_ref::<ReadError>() {
        return Some(&located.0);
    }
    if let Some(TableError(l)) = e.downcast_ref::<TableError>() {
        return Some(l.as_ref());
    }
    if let Some(MeasuredError::At(TableError(l))) = e.downcast_ref::<MeasuredError>() {
        return Some(l.as_ref());
    }
    if let Some(SeriesError::At(TableError(l))) = e.downcast_ref::<SeriesError>() {
        return Some(l.as_ref());
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

/// The first located diagnostic in the chain of causes of `e`, from `e` itself outward.
pub fn of_chain<'a>(e: &'a (dyn std::error::Error + 'static)) -> Option<&'a Located> {
    let mut next = Some(e);
    while let Some(e) = next {
        if let Some(l) = of_error(e) {
            return Some(l);
        }
        next = e.source();
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse::Span;

    #[test]
    fn an_error_gives_the_place_it_names() {
        let text = "shape = \"ball\"\nradius_mm = -5.0\nteeth = 2\nhelix_deg = 0.0\n";
        let e = crate::pipeline::tool_from_text(text, "t.toml").unwrap_err();
        let l = of_chain(&e).unwrap();
        assert_eq!(l.file.as_deref(), Some("t.toml"));
        assert_eq!((l.span.line, l.span.column), (2, 13));
        // Under a step's line of its own: found among the causes.
        let e = Error::DesignTool {
            design: "d.toml".into(),
            tool: "t.toml".into(),
            source: Box::new(ConfigError::whole("t.toml", "bad").into()),
        };
        assert!(of_error(&e).is_none());
        assert_eq!(of_chain(&e).map(|l| l.span), Some(Span::NONE));
        assert!(of_chain(&Error::Input("no place".into())).is_none());
        // A table's line or field.
        let text = "lead_deg,side,sample,Ra_um\n1,concave,S1,x\n";
        let e = crate::io::measured::parse_measured(text, "m.csv").unwrap_err();
        let e = Error::from(e);
        let l = of_chain(&e).unwrap();
        assert_eq!(l.file.as_deref(), Some("m.csv"));
        assert_eq!((l.span.line, l.span.column), (2, 14));
    }
}
