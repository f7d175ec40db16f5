//! The roughness atlas as a map: one square per patch at its x, y on the part, coloured
//! (viridis, with a scale bar) by one of its number columns; patches without a number are
//! drawn as grey crosses, so refused patches show where they are, and patches whose checks
//! failed (a warning) as red crosses: their numbers are not on the colour scale, so one
//! wrong patch cannot flatten the others. A square is as wide as the spacing to the nearest
//! other patch (at most the atlas spacing), so squares do not overlap.

use super::chart::{label_font, tick_decimals, tick_font, tick_label, title_font};
use super::heightmap::viridis;
use super::{Draw, DrawResult, PlotError};
use crate::study::atlas::{AtlasRow, NUMBER_COLUMNS};
use plotters::coord::Shift;
use plotters::prelude::*;

struct AtlasChart<'a> {
    title: &'a str,
    label: &'a str,
    /// x, y, the value (NaN: none), whether a check failed.
    pts: Vec<(f64, f64, f64, bool)>,
    range: (f64, f64),
    bounds: (f64, f64, f64, f64),
    mark: f64,
}

impl Draw for AtlasChart<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let root = root.titled(self.title, title_font())?;
        let (w, _) = root.dim_in_pixel();
        let (main, bar) = root.split_horizontally(w.saturating_sub(150));
        let (x0, y0, x1, y1) = self.bounds;
        let mut chart = ChartBuilder::on(&main)
            .margin(14)
            .x_label_area_size(55)
            .y_label_area_size(75)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        let (dx, dy) = (tick_decimals(x1 - x0), tick_decimals(y1 - y0));
        let fx = move |v: &f64| tick_label(*v, dx);
        let fy = move |v: &f64| tick_label(*v, dy);
        chart
            .configure_mesh()
            .disable_mesh()
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .x_desc("x [mm]")
            .y_desc("y [mm]")
            .axis_desc_style(label_font())
            .label_style(tick_font())
            .draw()?;
        let (lo, hi) = self.range;
        let h = 0.5 * self.mark;
        chart.draw_series(self.pts.iter().filter(|p| p.2.is_finite() && !p.3).map(
            |&(x, y, v, _)| {
                let t = if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
                Rectangle::new([(x - h, y - h), (x + h, y + h)], viridis(t).filled())
            },
        ))?;
        chart.draw_series(self.pts.iter().filter(|p| !p.2.is_finite() || p.3).map(
            |&(x, y, v, warned)| {
                let colour = if warned && v.is_finite() {
                    RGBColor(200, 30, 30)
                } else {
                    RGBColor(150, 150, 150)
                };
                Cross::new((x, y), 4, colour.stroke_width(1))
            },
        ))?;
        super::heightmap::colour_bar(&bar, lo, hi.max(lo + 1e-9), self.label)?;
        Ok(())
    }
}

/// The atlas `rows` coloured by `column` (one of [`NUMBER_COLUMNS`]) over the part's x, y,
/// as SVG or PNG bytes (`png`); patches are squares `every_mm` wide.
pub fn atlas_map(
    rows: &[AtlasRow],
    column: &str,
    title: &str,
    every_mm: f64,
    png: bool,
) -> Result<Vec<u8>, PlotError> {
    let Some(c) = NUMBER_COLUMNS.iter().position(|n| *n == column) else {
        return Err(PlotError::Invalid(format!(
            "no atlas column '{column}' (one of {})",
            NUMBER_COLUMNS.join(", ")
        )));
    };
    let pts: Vec<(f64, f64, f64, bool)> = rows
        .iter()
        .map(|r| {
            (
                r.point[0],
                r.point[1],
                r.numbers()[c],
                !r.warnings.is_empty(),
            )
        })
        .collect();
    // The colour scale spans the patches whose checks passed (all of them if none did).
    let trusted: Vec<f64> = pts
        .iter()
        .filter(|p| !p.3)
        .map(|p| p.2)
        .filter(|v| v.is_finite())
        .collect();
    let vals: Vec<f64> = if trusted.is_empty() {
        pts.iter().map(|p| p.2).filter(|v| v.is_finite()).collect()
    } else {
        trusted
    };
    if vals.is_empty() {
        return Err(PlotError::Empty(format!(
            "no patch has a value of {column}"
        )));
    }
    // Squares as wide as a patch's nearest neighbour is far (in x or y), the median over
    // the patches (one pair of patches that nearly coincide, on two regions or passes, must
    // not shrink every square to nothing), at most `every_mm`.
    let mut nearest: Vec<f64> = pts
        .iter()
        .map(|a| {
            pts.iter()
                .map(|b| (a.0 - b.0).abs().max((a.1 - b.1).abs()))
                .filter(|d| *d > 1e-9)
                .fold(f64::INFINITY, f64::min)
        })
        .filter(|d| d.is_finite())
        .collect();
    nearest.sort_by(f64::total_cmp);
    let mark = nearest
        .get(nearest.len() / 2)
        .map_or(every_mm, |d| d.min(every_mm));
    let lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let m = 0.5 * every_mm;
    let x0 = pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min) - m;
    let x1 = pts.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max) + m;
    let y0 = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min) - m;
    let y1 = pts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max) + m;
    let (wx, wy) = (x1 - x0, y1 - y0);
    let (pw, ph) = if wx >= wy {
        (800.0, (800.0 * wy / wx).max(260.0))
    } else {
        ((800.0 * wx / wy).max(260.0), 800.0)
    };
    let size = ((pw + 89.0 + 150.0) as u32, (ph + 69.0 + 14.0 + 40.0) as u32);
    let label = format!("{column} (× grey: no number, red: check failed)");
    let chart = AtlasChart {
        title,
        label: &label,
        pts,
        range: (lo, hi),
        bounds: (x0, y0, x1, y1),
        mark,
    };
    let format = if png {
        super::Format::Png
    } else {
        super::Format::Svg
    };
    super::render_bytes(format, size, &chart)
}
