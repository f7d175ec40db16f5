//! Charts with plotters, as SVG or PNG, with text rendered from an embedded font (no
//! system fonts needed): cutter profiles, trochoids, run-out, height maps, profiles, feed, design effects
//! and regressions. Drawing only: what goes in a chart is computed by the earlier stages.
//! This file holds the output side every figure shares (fonts, the error type, rendering to
//! SVG or PNG bytes and files); [`chart`] holds the chart model and the one style.

use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
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

/// Rasterise an SVG document drawn by this module into PNG bytes, with the embedded font.
/// Every PNG of crest is its SVG rasterised here (resvg), so both show the same picture and
/// text is laid out by a text shaper (plotters' own bitmap text ran glyphs into each other).
pub fn svg_to_png(svg: &str) -> std::io::Result<Vec<u8>> {
    svg_pixmap(svg)?.encode_png().map_err(std::io::Error::other)
}

/// Rasterise an SVG document drawn by this module (see [`svg_to_png`]) into pixels, for a
/// caller that paints more onto them before encoding.
pub(crate) fn svg_pixmap(svg: &str) -> std::io::Result<resvg::tiny_skia::Pixmap> {
    use resvg::{tiny_skia, usvg};
    use std::sync::{Arc, OnceLock};
    static FONTS: OnceLock<(Arc<usvg::fontdb::Database>, String)> = OnceLock::new();
    let (db, family) = FONTS.get_or_init(|| {
        let mut db = usvg::fontdb::Database::new();
        db.load_font_data(epaint_default_fonts::UBUNTU_LIGHT.to_vec());
        let family = db
            .faces()
            .next()
            .and_then(|f| f.families.first().map(|(name, _)| name.clone()))
            .unwrap_or_else(|| "Ubuntu".to_string());
        db.set_sans_serif_family(family.clone());
        (Arc::new(db), family)
    });
    let opt = usvg::Options {
        font_family: family.clone(),
        fontdb: db.clone(),
        ..Default::default()
    };
    let tree = usvg::Tree::from_str(svg, &opt).map_err(std::io::Error::other)?;
    let size = tree.size().to_int_size();
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height())
        .ok_or_else(|| std::io::Error::other("picture has no pixels"))?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    Ok(pixmap)
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

/// Errors of the plots.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The output name has no `.svg` or `.png` extension.
    #[error("{}: unknown plot format (use .svg or .png)", .0.display())]
    Format(PathBuf),
    /// Nothing finite to draw.
    #[error("nothing to plot: {0}")]
    Empty(String),
    /// A parameter out of range.
    #[error("{0}")]
    Invalid(String),
    /// The drawing backend failed.
    #[error("drawing failed: {0}")]
    Draw(String),
    /// Writing the file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// Output file.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
}

/// Result of drawing on one backend.
pub(crate) type DrawResult<DB> =
    Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// Something that draws itself on any plotters backend.
pub(crate) trait Draw {
    /// Draw on `root` (already filled white).
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB>;
}

fn draw_err<E: std::fmt::Debug>(e: E) -> PlotError {
    PlotError::Draw(format!("{e:?}"))
}

/// Render `chart` at `size` pixels as SVG or PNG bytes, in memory.
pub(crate) fn render_bytes(
    format: Format,
    size: (u32, u32),
    chart: &impl Draw,
) -> Result<Vec<u8>, PlotError> {
    init_fonts();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        chart.draw(&root).map_err(draw_err)?;
        root.present().map_err(draw_err)?;
    }
    match format {
        Format::Svg => Ok(svg.into_bytes()),
        Format::Png => svg_to_png(&svg).map_err(|e| PlotError::Draw(e.to_string())),
    }
}

/// Render `chart` at `size` pixels to `path` (SVG or PNG by extension), atomically.
pub(crate) fn render(path: &Path, size: (u32, u32), chart: &impl Draw) -> Result<(), PlotError> {
    let format = Format::from_path(path).ok_or_else(|| PlotError::Format(path.to_path_buf()))?;
    let bytes = render_bytes(format, size, chart)?;
    crate::io::write_atomic(path, |w| w.write_all(&bytes)).map_err(|source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    })
}

pub mod atlas;
pub mod chart;
pub mod compare;
pub mod cutter;
pub mod effects;
pub mod feed;
pub mod heightmap;
pub mod profile;
pub mod regression;
pub mod runout;
pub mod trochoid;
