//! The figures of `crest compare`: the predicted and measured height maps on one colour scale,
//! the difference map, profiles through the centre along and across the feed, and the 1-D
//! spectra along and across it, in memory: the maps as PNG, the line charts as SVG.

use super::chart::{Chart, Series, finite_range, label_font, tick_font, title_font};
use super::chart::{tick_decimals, tick_label};
use super::heightmap::{colour_bar_with, diverging, viridis};
use super::{Draw, DrawResult, Format, PlotError, render_bytes};
use crate::metrics::LaySpectra;
use crate::surface::HeightMap;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::cell::RefCell;

/// Cells drawn along the longer side of a map at most.
const MAX_CELLS: usize = 200;

/// The colour of a cell without a valid node.
const MISSING: RGBColor = RGBColor(80, 80, 80);

struct MapFigure<'a> {
    title: &'a str,
    map: &'a HeightMap,
    range: (f64, f64),
    label: &'a str,
    /// A signed quantity: the diverging scale, white at zero.
    signed: bool,
    /// The map's cells in pixels, filled by [`Draw::draw`] for [`map_png`] to paint onto the
    /// rasterised frame: tens of thousands of cells as SVG rectangles took longer to write,
    /// parse and rasterise than the rest of `crest compare`'s figures together.
    cells: RefCell<Vec<Cell>>,
    /// Draw the cells as SVG rectangles instead (the reference the painted cells are tested
    /// against).
    #[cfg(test)]
    as_rects: bool,
}

/// A cell of a map in pixels of the picture: left, top, right, bottom, and its colour.
struct Cell {
    ltrb: (i32, i32, i32, i32),
    fill: RGBColor,
}

impl Draw for MapFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let root = root.titled(self.title, title_font())?;
        let (w, _) = root.dim_in_pixel();
        let (main, bar) = root.split_horizontally(w.saturating_sub(150));
        let m = self.map;
        let (x1, y1) = (m.nx as f64 * m.dx_um, m.ny as f64 * m.dy_um);
        let mut chart = ChartBuilder::on(&main)
            .margin(14)
            .x_label_area_size(55)
            .y_label_area_size(75)
            .build_cartesian_2d(0.0..x1, 0.0..y1)?;
        let (dx, dy) = (tick_decimals(x1), tick_decimals(y1));
        let (fx, fy) = (
            move |v: &f64| tick_label(*v, dx),
            move |v: &f64| tick_label(*v, dy),
        );
        chart
            .configure_mesh()
            .disable_mesh()
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .x_desc("x [µm]")
            .y_desc("y [µm]")
            .axis_desc_style(label_font())
            .label_style(tick_font())
            .draw()?;
        let b = m.nx.max(m.ny).div_ceil(MAX_CELLS).max(1);
        let (cx, cy) = (m.nx.div_ceil(b), m.ny.div_ceil(b));
        let (lo, hi) = self.range;
        let colour: &dyn Fn(f64) -> RGBColor = if self.signed { &diverging } else { &viridis };
        let mut cells = Vec::with_capacity(cx * cy);
        #[cfg(test)]
        let mut rects = Vec::new();
        for j in 0..cy {
            for i in 0..cx {
                let (mut s, mut n) = (0.0, 0usize);
                for r in j * b..((j + 1) * b).min(m.ny) {
                    for c in i * b..((i + 1) * b).min(m.nx) {
                        let v = m.z_um[r * m.nx + c];
                        if v.is_finite() {
                            s += v;
                            n += 1;
                        }
                    }
                }
                let (xa, ya) = ((i * b) as f64 * m.dx_um, (j * b) as f64 * m.dy_um);
                let (xb, yb) = (
                    (xa + b as f64 * m.dx_um).min(x1),
                    (ya + b as f64 * m.dy_um).min(y1),
                );
                // A cell without a valid node is missing: dark grey on either scale.
                let fill = if n > 0 {
                    colour((s / n as f64 - lo) / (hi - lo).max(1e-300))
                } else {
                    MISSING
                };
                #[cfg(test)]
                if self.as_rects {
                    rects.push(Rectangle::new([(xa, ya), (xb, yb)], fill.filled()));
                    continue;
                }
                // The corners exactly as plotters maps a rectangle's (absolute pixels).
                let (p, q) = (
                    chart.backend_coord(&(xa, ya)),
                    chart.backend_coord(&(xb, yb)),
                );
                cells.push(Cell {
                    ltrb: (p.0.min(q.0), p.1.min(q.1), p.0.max(q.0), p.1.max(q.1)),
                    fill,
                });
            }
        }
        #[cfg(test)]
        chart.draw_series(rects)?;
        *self.cells.borrow_mut() = cells;
        colour_bar_with(&bar, lo, hi, self.label, colour)?;
        Ok(())
    }
}

/// A height map as a PNG colour map over `range` (µm); `signed` (a difference) takes a
/// diverging scale, white at zero. The frame (title, axes, colour bar) is drawn as SVG and
/// rasterised; the cells are painted straight onto its pixels, where plotters would have
/// put them as rectangles (the same picture, pixel for pixel: tested).
pub fn map_png(
    map: &HeightMap,
    title: &str,
    range: (f64, f64),
    label: &str,
    signed: bool,
) -> Result<Vec<u8>, PlotError> {
    let (fig, size) = map_figure(map, title, range, label, signed)?;
    paint(&fig, size)?
        .encode_png()
        .map_err(|e| PlotError::Draw(e.to_string()))
}

fn map_figure<'a>(
    map: &'a HeightMap,
    title: &'a str,
    range: (f64, f64),
    label: &'a str,
    signed: bool,
) -> Result<(MapFigure<'a>, (u32, u32)), PlotError> {
    if map.nx == 0 || map.ny == 0 {
        return Err(PlotError::Empty(title.to_string()));
    }
    let (wx, wy) = (map.nx as f64 * map.dx_um, map.ny as f64 * map.dy_um);
    let (pw, ph) = if wx >= wy {
        (600.0, (600.0 * wy / wx).max(200.0))
    } else {
        ((600.0 * wx / wy).max(200.0), 600.0)
    };
    let size = ((pw + 89.0 + 150.0) as u32, (ph + 69.0 + 54.0) as u32);
    let fig = MapFigure {
        title,
        map,
        range,
        label,
        signed,
        cells: RefCell::new(Vec::new()),
        #[cfg(test)]
        as_rects: false,
    };
    Ok((fig, size))
}

/// Draw `fig`'s frame, rasterise it, and paint its cells.
fn paint(fig: &MapFigure, size: (u32, u32)) -> Result<resvg::tiny_skia::Pixmap, PlotError> {
    use resvg::tiny_skia::{Paint, Rect, Transform};
    let draw = |e: std::io::Error| PlotError::Draw(e.to_string());
    let svg = render_bytes(Format::Svg, size, fig)?;
    let svg = std::str::from_utf8(&svg).map_err(|e| PlotError::Draw(e.to_string()))?;
    let mut pixmap = super::svg_pixmap(svg).map_err(draw)?;
    let mut paint = Paint::default();
    for c in fig.cells.borrow().iter() {
        let (l, t, r, b) = c.ltrb;
        // A cell narrower than a pixel has no area, as its SVG rectangle had none.
        if let Some(rect) = Rect::from_ltrb(l as f32, t as f32, r as f32, b as f32) {
            paint.set_color_rgba8(c.fill.0, c.fill.1, c.fill.2, 255);
            pixmap.fill_rect(rect, &paint, Transform::identity(), None);
        }
    }
    Ok(pixmap)
}

/// The common colour range of the predicted and measured maps, and a symmetric range for
/// the difference.
pub fn ranges(
    predicted: &HeightMap,
    measured: &HeightMap,
    difference: &HeightMap,
) -> ((f64, f64), (f64, f64)) {
    let r = |m: &HeightMap| finite_range(&m.z_um, 0.0).unwrap_or((0.0, 1.0));
    let (a, b) = (r(predicted), r(measured));
    let (dlo, dhi) = r(difference);
    let d = dlo.abs().max(dhi.abs()).max(1e-9);
    ((a.0.min(b.0), a.1.max(b.1)), (-d, d))
}

fn svg(chart: &Chart) -> Result<String, PlotError> {
    chart.check_finite()?;
    super::chart::render_svg(chart).map_err(|e| PlotError::Draw(e.to_string()))
}

/// Profiles of both maps through the centre, along (`along`) or across the feed.
pub fn profiles_svg(
    predicted: &LaySpectra,
    measured: &LaySpectra,
    along: bool,
) -> Result<String, PlotError> {
    let pick = |l: &LaySpectra| {
        if along {
            l.along_profile_um.clone()
        } else {
            l.across_profile_um.clone()
        }
    };
    let line = |label: &str, l: &LaySpectra, i: usize| {
        let z = pick(l);
        let pts: Vec<(f64, f64)> = l
            .position_um
            .iter()
            .zip(&z)
            .filter(|(_, z)| z.is_finite())
            .map(|(x, z)| (*x, *z))
            .collect();
        let (x, y): (Vec<f64>, Vec<f64>) = pts.into_iter().unzip();
        Series::line(label, &x, &y, i)
    };
    let what = if along { "along" } else { "across" };
    svg(&Chart::lines(
        format!("Profiles through the centre, {what} the feed"),
        format!("distance {what} the feed from the centre [µm]"),
        "height [µm]",
        vec![
            line("predicted", predicted, 0),
            line("measured", measured, 1),
        ],
    ))
}

/// The 1-D spectra of both maps along (`along`) or across the feed, log10 of the power,
/// up to four times the higher peak frequency.
pub fn spectra_svg(
    predicted: &LaySpectra,
    measured: &LaySpectra,
    along: bool,
) -> Result<String, PlotError> {
    let spec = |l: &LaySpectra| {
        if along {
            l.along.clone()
        } else {
            l.across.clone()
        }
    };
    let (sp, sm) = (spec(predicted), spec(measured));
    let fmax = 4.0
        / [sp.peak_period_um, sm.peak_period_um]
            .iter()
            .filter(|p| p.is_finite())
            .fold(f64::INFINITY, |a, &b| a.min(b));
    let line = |label: &str, s: &crate::metrics::LineSpectrum, i: usize| {
        let (x, y): (Vec<f64>, Vec<f64>) = s
            .freq_per_um
            .iter()
            .zip(&s.power)
            .skip(1)
            .filter(|(f, p)| (!fmax.is_finite() || **f <= fmax) && **p > 0.0)
            .map(|(f, p)| (*f, p.log10()))
            .unzip();
        Series::line(label, &x, &y, i)
    };
    let what = if along {
        "along the feed (feed marks)"
    } else {
        "across the feed (stepover)"
    };
    svg(&Chart::lines(
        format!("1-D spectra {what}"),
        "spatial frequency [1/µm]",
        "log10 power [µm²]",
        vec![line("predicted", &sp, 0), line("measured", &sm, 1)],
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A map of pseudo-random heights with missing nodes scattered in it.
    fn map(nx: usize, ny: usize, dx_um: f64, dy_um: f64, seed: u64) -> HeightMap {
        let mut state = seed;
        let z_um = (0..nx * ny)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                if u < 0.03 { f64::NAN } else { 40.0 * u - 13.0 }
            })
            .collect();
        let mut m = HeightMap::new_nan(nx, ny, dx_um, dy_um);
        m.z_um = z_um;
        m
    }

    /// The painted cells give the picture plotters' rectangles gave, pixel for pixel: maps
    /// wider and taller than long, with more nodes than cells (and not a multiple of them),
    /// with fewer nodes than cells, signed and not.
    #[test]
    fn painted_cells_are_the_rectangles_plotters_drew() {
        let cases = [
            // nx, ny, dx, dy, signed, cells (blocks of ceil(longer side / 200) nodes)
            (437, 251, 0.7, 1.3, false, 146 * 84),
            (251, 437, 2.0, 0.5, true, 84 * 146),
            (13, 7, 10.0, 10.0, false, 13 * 7),
            (2000, 1999, 0.4, 0.4, true, 200 * 200),
            (3, 450, 1.0, 1.0, false, 150),
        ];
        for (k, &(nx, ny, dx, dy, signed, n_cells)) in cases.iter().enumerate() {
            let m = map(nx, ny, dx, dy, k as u64 + 1);
            let range = if signed { (-20.0, 20.0) } else { (-13.0, 27.0) };
            let (fig, size) = map_figure(&m, "Map", range, "height [µm]", signed).unwrap();
            let painted = paint(&fig, size).unwrap();
            let (mut reference, _) = map_figure(&m, "Map", range, "height [µm]", signed).unwrap();
            reference.as_rects = true;
            let svg = render_bytes(Format::Svg, size, &reference).unwrap();
            assert!(reference.cells.borrow().is_empty());
            let drawn = crate::plot::svg_pixmap(std::str::from_utf8(&svg).unwrap()).unwrap();
            assert_eq!((painted.width(), painted.height()), size);
            let differ = painted
                .pixels()
                .iter()
                .zip(drawn.pixels())
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(differ, 0, "case {k}: {differ} pixels differ");
            assert_eq!(fig.cells.borrow().len(), n_cells, "case {k}");
        }
    }
}
