//! Charts with plotters, as SVG or PNG, with text rendered from an embedded font (no
//! system fonts needed): cutter profiles, trochoids, run-out, height maps, profiles, feed, design effects
//! and regressions. Drawing only: what goes in a chart is computed by the earlier stages.

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

/// Encode an RGB8 buffer of `size` pixels as PNG, in memory (the same encoder and settings
/// plotters uses when it saves a bitmap to a path).
pub fn encode_png(rgb: &[u8], size: (u32, u32)) -> std::io::Result<Vec<u8>> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(rgb, size.0, size.1, image::ColorType::Rgb8)
        .map_err(std::io::Error::other)?;
    Ok(out)
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

pub mod chart;
pub mod cutter;
pub mod effects;
pub mod feed;
pub mod heightmap;
pub mod profile;
pub mod regression;
pub mod runout;
pub mod trochoid;
