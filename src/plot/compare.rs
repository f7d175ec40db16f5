//! The figures of `crest compare`: the predicted and measured height maps on one colour scale,
//! the difference map, profiles through the centre along and across the feed, and the 1-D
//! spectra along and across it, as SVG documents in memory.

use super::chart::{Chart, Series, finite_range, label_font, tick_font, title_font};
use super::chart::{tick_decimals, tick_label};
use super::heightmap::{colour_bar_with, diverging, viridis};
use super::{Draw, DrawResult, Format, PlotError, render_bytes};
use crate::metrics::LaySpectra;
use crate::surface::HeightMap;
use plotters::coord::Shift;
use plotters::prelude::*;

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
        let mut cells = Vec::new();
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
                cells.push(Rectangle::new([(xa, ya), (xb, yb)], fill.filled()));
            }
        }
        chart.draw_series(cells)?;
        colour_bar_with(&bar, lo, hi, self.label, colour)?;
        Ok(())
    }
}

/// A height map as an SVG colour map over `range` (µm); `signed` (a difference) takes a
/// diverging scale, white at zero.
pub fn map_svg(
    map: &HeightMap,
    title: &str,
    range: (f64, f64),
    label: &str,
    signed: bool,
) -> Result<String, PlotError> {
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
    };
    let bytes = render_bytes(Format::Svg, size, &fig)?;
    String::from_utf8(bytes).map_err(|e| PlotError::Draw(e.to_string()))
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
