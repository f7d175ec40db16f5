//! Charts with plotters, as SVG or PNG, with text rendered from an embedded font (no
//! system fonts needed): trochoids, run-out, height maps, profiles, feed.

use std::path::Path;
use std::sync::Once;

/// Font family name registered for every chart.
pub const FONT: &str = "sans-serif";

/// Register the embedded font with plotters (idempotent). Call before drawing text.
pub fn init_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        use plotters::style::{FontStyle, register_font};
        for style in [
            FontStyle::Normal,
            FontStyle::Bold,
            FontStyle::Italic,
            FontStyle::Oblique,
        ] {
            // The Ubuntu font is a valid TrueType file; registration cannot fail on it.
            let _ = register_font(FONT, style, epaint_default_fonts::UBUNTU_LIGHT);
        }
    });
}

/// Output kind chosen from a file name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Scalable vector graphics.
    Svg,
    /// Portable network graphics.
    Png,
}

impl Format {
    /// The format for `path` by extension (`.svg` or `.png`), or `None`.
    pub fn from_path(path: &Path) -> Option<Format> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "svg" => Some(Format::Svg),
            "png" => Some(Format::Png),
            _ => None,
        }
    }
}

pub mod feed;
pub mod heightmap;
pub mod profile;
pub mod runout;
pub mod trochoid;
