//! The chart model and the one style of crest's figures. A [`Chart`] is one or more stacked
//! panels sharing an x axis, each with several series (solid or dashed lines, with or without
//! markers; a non-finite point breaks a line), a title, axis labels with units and a legend
//! when a panel has more than one series. The other kinds of figure (bars, maps, trochoids,
//! cutters) draw with the same palette, fonts, frame, grid and legend from this file.
//!
//! The chart is plain data ([`Chart`]); the modules that draw a study's figures (e.g.
//! [`super::runout`], [`super::feed`]) decide what goes in it. Styling follows a journal
//! figure: white background, black frame and ticks, a faint grid, a small fixed palette.

use super::{Draw, DrawResult, FONT, Format, PlotError, render, render_bytes};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::io;
use std::path::Path;

/// One line of a panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Points (x, y), drawn in order.
    pub points: Vec<(f64, f64)>,
    /// Colour index into the palette (series with the same index share a colour).
    pub color: usize,
    /// Dashed line (e.g. a second quantity of the same group).
    pub dashed: bool,
    /// Draw a marker at every point.
    pub markers: bool,
    /// Join the points with a line.
    pub line: bool,
}

/// One panel of a chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Caption above the panel (e.g. the value of a grouping parameter), or empty.
    pub caption: String,
    /// Y-axis label with unit.
    pub y_label: String,
    /// Fixed y range, or `None` to fit the data.
    pub y_range: Option<(f64, f64)>,
    /// Integer y ticks (counts).
    pub y_integer: bool,
    /// The lines.
    pub series: Vec<Series>,
}

/// A chart: a title, a shared x axis and stacked panels.
#[derive(Debug, Clone, PartialEq)]
pub struct Chart {
    /// Title.
    pub title: String,
    /// X-axis label with unit.
    pub x_label: String,
    /// Panels from top to bottom.
    pub panels: Vec<Panel>,
    /// Size in pixels (width, height).
    pub size: (u32, u32),
    /// Panels per row (panels fill the grid row by row); 0 or 1 = one column.
    pub columns: usize,
    /// Lines of explanation under the panels (what the series mean), or none.
    pub notes: Vec<String>,
    /// Integer x ticks (run numbers, counts).
    pub x_integer: bool,
}

/// Legend labels of a panel's series, where a series that lies exactly on an earlier one
/// says so (`… (= lead 5°)`): coincident curves would otherwise show as one.
fn legend_labels(panel: &Panel) -> Vec<String> {
    let same = |a: &[(f64, f64)], b: &[(f64, f64)]| {
        a.len() == b.len()
            && a.iter().zip(b).all(|(p, q)| {
                let close = |u: f64, v: f64| {
                    (u.is_nan() && v.is_nan())
                        || (u - v).abs() <= 1e-9 * u.abs().max(v.abs()).max(1e-12)
                };
                close(p.0, q.0) && close(p.1, q.1)
            })
    };
    panel
        .series
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let earlier = panel.series[..k].iter().find(|e| {
                e.line
                    && s.line
                    && !e.label.is_empty()
                    && !s.points.is_empty()
                    && same(&e.points, &s.points)
            });
            match earlier {
                Some(e) if !s.label.is_empty() => format!("{} (= {})", s.label, e.label),
                _ => s.label.clone(),
            }
        })
        .collect()
}

impl Series {
    /// Line `i` of a set of lines through (x[k], y[k]) (the shorter length is used): colour
    /// `i`, dashed past the eight colours so that no two lines look alike.
    pub fn line(label: impl Into<String>, x: &[f64], y: &[f64], i: usize) -> Series {
        Series {
            label: label.into(),
            points: x.iter().zip(y).map(|(&x, &y)| (x, y)).collect(),
            color: i,
            dashed: (i / PALETTE.len()) % 2 == 1,
            markers: false,
            line: true,
        }
    }
}

impl Chart {
    /// A chart of one panel of lines, 1000 × 560 pixels.
    pub fn lines(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
        series: Vec<Series>,
    ) -> Chart {
        Chart {
            title: title.into(),
            x_label: x_label.into(),
            panels: vec![Panel {
                caption: String::new(),
                y_label: y_label.into(),
                y_range: None,
                y_integer: false,
                series,
            }],
            size: (1000, 560),
            columns: 1,
            notes: Vec::new(),
            x_integer: false,
        }
    }

    /// An error naming the chart when no series has a finite point.
    pub fn check_finite(&self) -> Result<(), PlotError> {
        let finite = self
            .panels
            .iter()
            .flat_map(|p| &p.series)
            .flat_map(|s| &s.points)
            .any(|(x, y)| x.is_finite() && y.is_finite());
        if finite {
            Ok(())
        } else {
            Err(PlotError::Empty(format!(
                "no finite point in '{}'",
                self.title
            )))
        }
    }
}

/// The palette (Okabe-Ito, with grey for yellow, which reads badly on white): black,
/// vermilion, blue, bluish green, orange, reddish purple, sky blue, grey.
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 0, 0),
    RGBColor(213, 94, 0),
    RGBColor(0, 114, 178),
    RGBColor(0, 158, 115),
    RGBColor(230, 159, 0),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(120, 120, 120),
];

/// Colour `i` of the palette (wrapping).
pub(crate) fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// Grey of the grid lines.
const GRID: RGBColor = RGBColor(225, 225, 225);

/// The font of a figure's title.
pub(crate) fn title_font() -> TextStyle<'static> {
    (FONT, 24).into_font().color(&BLACK)
}

/// The font of a panel's caption.
pub(crate) fn caption_font() -> TextStyle<'static> {
    (FONT, 18).into_font().color(&BLACK)
}

/// The font of axis labels.
pub(crate) fn label_font() -> TextStyle<'static> {
    (FONT, 18).into_font().color(&BLACK)
}

/// The font of tick labels, legends and notes.
pub(crate) fn tick_font() -> TextStyle<'static> {
    (FONT, 15).into_font().color(&BLACK)
}

/// The frame of every plot: tick and axis-label fonts, a black axis, a faint grid at the
/// labelled ticks and none between them.
pub(crate) fn style_mesh<
    'm,
    'a,
    'b,
    X: plotters::coord::ranged1d::Ranged,
    Y: plotters::coord::ranged1d::Ranged,
    DB: DrawingBackend,
>(
    mesh: &'m mut plotters::chart::MeshStyle<'a, 'b, X, Y, DB>,
) -> &'m mut plotters::chart::MeshStyle<'a, 'b, X, Y, DB> {
    mesh.label_style(tick_font())
        .axis_desc_style(label_font())
        .axis_style(BLACK.stroke_width(1))
        .bold_line_style(GRID.stroke_width(1))
        .light_line_style(TRANSPARENT)
}

/// Draw the legend of `cc`'s labelled series at `position`: a white box with a thin black
/// border.
pub(crate) fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    cc: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> DrawResult<DB> {
    cc.configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.92))
        .border_style(BLACK.stroke_width(1))
        .label_font(tick_font())
        .margin(8)
        .draw()
}

/// The legend box of the entries `labels` as shares (width, height) of a plot area of
/// `plot_px` (width, height) pixels: about 20 px a line, the sample and 7.5 px a character
/// wide.
pub(crate) fn legend_box<'a>(
    labels: impl IntoIterator<Item = &'a str>,
    (plot_w, plot_h): (f64, f64),
) -> (f64, f64) {
    let (mut entries, mut chars) = (0usize, 0usize);
    for l in labels {
        entries += 1;
        chars = chars.max(l.chars().count());
    }
    (
        ((64.0 + 7.5 * chars as f64) / plot_w.max(100.0)).min(0.9),
        ((entries as f64 * 20.0 + 20.0) / plot_h.max(100.0)).min(0.9),
    )
}

/// The range `(lo, hi)` raised so that a legend box `share` of the plot (its height, or its
/// width when the legend stands right of the data; see [`legend_box`]) fits beyond the
/// data: the one head-room rule of every figure.
pub(crate) fn legend_headroom((lo, hi): (f64, f64), share: f64) -> (f64, f64) {
    (lo, hi + (hi - lo) * share / (1.0 - share))
}

/// The range of the finite values of `values`, widened by `pad` (a fraction) and made
/// non-empty; `None` when there is no finite value.
pub(crate) fn finite_range<'a>(
    values: impl IntoIterator<Item = &'a f64>,
    pad: f64,
) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &v in values {
        if v.is_finite() {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if lo > hi {
        return None;
    }
    let span = hi - lo;
    let margin = if span > 1e-12 * hi.abs().max(1.0) {
        span * pad
    } else {
        lo.abs().max(1.0) * 0.05
    };
    Some((lo - margin, hi + margin))
}

/// Decimals for tick labels on an axis spanning `span`: about three significant digits
/// of the tick step.
pub(crate) fn tick_decimals(span: f64) -> usize {
    if !(span.is_finite() && span > 0.0) {
        return 1;
    }
    (1.0 - span.log10().floor()).clamp(0.0, 6.0) as usize
}

/// A tick label with `decimals` decimals; a value that rounds to zero prints as `0`
/// without a sign (never `-0.0`).
pub(crate) fn tick_label(v: f64, decimals: usize) -> String {
    let text = format!("{v:.decimals$}");
    match text.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
        _ => text,
    }
}

/// Marker shape of a colour index (circle, square, triangle, diamond), so overlapping
/// series stay distinguishable.
fn shape_of(index: usize) -> usize {
    index % 4
}

/// Maximal runs of finite points: a non-finite point breaks a line.
fn segments(points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut cur = Vec::new();
    for &(x, y) in points {
        if x.is_finite() && y.is_finite() {
            cur.push((x, y));
        } else if !cur.is_empty() {
            out.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// The legend corner whose box (`w` × `h`, as shares of the plot) covers the fewest points.
fn legend_corner(
    panel: &Panel,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    (w, h): (f64, f64),
) -> SeriesLabelPosition {
    let corners = [
        (SeriesLabelPosition::UpperRight, true, true),
        (SeriesLabelPosition::UpperLeft, false, true),
        (SeriesLabelPosition::LowerRight, true, false),
        (SeriesLabelPosition::LowerLeft, false, false),
    ];
    let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
    for (pos, right, upper) in corners {
        let n = panel
            .series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|(x, y)| {
                let u = (x - x0) / (x1 - x0);
                let v = (y - y0) / (y1 - y0);
                let in_x = if right { u > 1.0 - w } else { u < w };
                let in_y = if upper { v > 1.0 - h } else { v < h };
                in_x && in_y
            })
            .count();
        if n < best.0 {
            best = (n, pos);
        }
    }
    best.1
}

impl Draw for Chart {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let chart = self;
        let body = root.titled(&chart.title, title_font())?;
        let body = if chart.notes.is_empty() {
            body
        } else {
            let h = body.dim_in_pixel().1 as i32;
            let foot_h = 21 * chart.notes.len() as i32 + 12;
            let (top, foot) = body.split_vertically(h - foot_h);
            for (k, line) in chart.notes.iter().enumerate() {
                foot.draw_text(
                    line,
                    &tick_font().color(&RGBColor(40, 40, 40)),
                    (16, 6 + 21 * k as i32),
                )?;
            }
            top
        };
        let cols = chart.columns.max(1);
        let rows = chart.panels.len().max(1).div_ceil(cols);
        let areas = body.split_evenly((rows, cols));
        let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
        let (x0, x1) = finite_range(
            chart
                .panels
                .iter()
                .flat_map(|p| p.series.iter())
                .flat_map(|s| s.points.iter().filter(finite).map(|p| &p.0)),
            0.03,
        )
        .unwrap_or((0.0, 1.0));
        let last_row_start = (rows - 1) * cols;
        for (k, (panel, area)) in chart.panels.iter().zip(areas.iter()).enumerate() {
            let ys = || {
                panel
                    .series
                    .iter()
                    .flat_map(|s| s.points.iter().filter(finite).map(|p| &p.1))
            };
            let labels = legend_labels(panel);
            let entries: Vec<&str> = panel
                .series
                .iter()
                .zip(&labels)
                .filter(|(s, l)| (s.line || s.markers) && !l.is_empty())
                .map(|(_, l)| l.as_str())
                .collect();
            let legend = entries.len() > 1;
            let plot_px = (
                chart.size.0 as f64 / cols as f64 - 110.0,
                chart.size.1 as f64 / rows as f64 - 110.0,
            );
            let legend_box = legend_box(entries.iter().copied(), plot_px);
            // The head room goes where it costs less: above the data or, in a chart of one
            // panel (its x axis is its own), right of them.
            let right = legend && chart.panels.len() == 1 && legend_box.0 < legend_box.1;
            let (x0, x1) = if right {
                legend_headroom((x0, x1), legend_box.0)
            } else {
                (x0, x1)
            };
            let (y0, y1) = panel.y_range.unwrap_or_else(|| {
                let (lo, hi) = finite_range(ys(), 0.08).unwrap_or((0.0, 1.0));
                // Counts and heights read best from zero when the data are all positive.
                let all_positive = ys().all(|&y| y >= 0.0);
                let lo = if all_positive && lo < 0.0 { 0.0 } else { lo };
                if legend && !right {
                    legend_headroom((lo, hi), legend_box.1)
                } else {
                    (lo, hi)
                }
            });
            let mut builder = ChartBuilder::on(area);
            if !panel.caption.is_empty() {
                builder.caption(&panel.caption, caption_font());
            }
            let mut cc = builder
                .margin_left(12)
                .margin_right(24)
                .margin_top(10)
                .margin_bottom(if k >= last_row_start { 6 } else { 2 })
                .x_label_area_size(52)
                .y_label_area_size(78)
                .build_cartesian_2d(x0..x1, y0..y1)?;
            let y_integer = panel.y_integer;
            let (dx, dy) = (tick_decimals(x1 - x0), tick_decimals(y1 - y0));
            let y_fmt = move |v: &f64| {
                if y_integer {
                    format!("{v:.0}")
                } else {
                    tick_label(*v, dy)
                }
            };
            let x_integer = chart.x_integer;
            let x_fmt = move |v: &f64| {
                if x_integer {
                    format!("{v:.0}")
                } else {
                    tick_label(*v, dx)
                }
            };
            let x_ticks = if x_integer {
                ((x1 - x0).round() as usize + 1).clamp(2, 12)
            } else {
                10
            };
            let y_ticks = if y_integer {
                ((y1 - y0).round() as usize + 1).clamp(2, 12)
            } else {
                8
            };
            style_mesh(
                cc.configure_mesh()
                    .x_desc(chart.x_label.as_str())
                    .y_desc(panel.y_label.as_str())
                    .x_label_formatter(&x_fmt)
                    .y_label_formatter(&y_fmt)
                    .y_labels(y_ticks)
                    .x_labels(x_ticks),
            )
            .draw()?;
            for (s, label) in panel.series.iter().zip(&labels) {
                let c = color(s.color);
                let style = c.stroke_width(2);
                let dashed = s.dashed;
                let markers = s.markers;
                let color_index = s.color;
                if s.line {
                    for (j, seg) in segments(&s.points).into_iter().enumerate() {
                        let anno = if s.dashed {
                            cc.draw_series(DashedLineSeries::new(seg, 8, 5, style))?
                        } else {
                            cc.draw_series(LineSeries::new(seg, style))?
                        };
                        if j > 0 || label.is_empty() {
                            continue;
                        }
                        anno.label(label.as_str()).legend(move |(x, y)| {
                            let (gap0, gap1) = if dashed { (9, 15) } else { (12, 12) };
                            let shape = if markers {
                                Some(shape_of(color_index))
                            } else {
                                None
                            };
                            let fill = |k: usize| {
                                if shape == Some(k) {
                                    c.filled()
                                } else {
                                    TRANSPARENT.filled()
                                }
                            };
                            EmptyElement::at((x, y))
                                + PathElement::new(vec![(0, 0), (gap0, 0)], c.stroke_width(2))
                                + PathElement::new(vec![(gap1, 0), (24, 0)], c.stroke_width(2))
                                + Circle::new((12, 0), 4, fill(0))
                                + Rectangle::new([(8, -4), (16, 4)], fill(1))
                                + TriangleMarker::new((12, 0), 5, fill(2))
                                + Polygon::new(vec![(12, -5), (17, 0), (12, 5), (7, 0)], fill(3))
                        });
                    }
                }
                if s.markers {
                    let finite = s
                        .points
                        .iter()
                        .filter(|p| p.0.is_finite() && p.1.is_finite());
                    let style = c.filled();
                    let shape = shape_of(s.color);
                    let anno = match shape {
                        0 => cc.draw_series(finite.map(|&p| Circle::new(p, 4, style))),
                        1 => cc.draw_series(finite.map(|&p| {
                            EmptyElement::at(p) + Rectangle::new([(-4, -4), (4, 4)], style)
                        })),
                        2 => cc.draw_series(finite.map(|&p| TriangleMarker::new(p, 5, style))),
                        _ => cc.draw_series(finite.map(|&p| {
                            EmptyElement::at(p)
                                + Polygon::new(vec![(0, -5), (5, 0), (0, 5), (-5, 0)], style)
                        })),
                    }?;
                    // A series of markers alone gets its marker in the legend.
                    if !s.line && !s.label.is_empty() {
                        anno.label(s.label.as_str()).legend(move |(x, y)| {
                            let fill = |k: usize| {
                                if shape == k {
                                    c.filled()
                                } else {
                                    TRANSPARENT.filled()
                                }
                            };
                            EmptyElement::at((x, y))
                                + Circle::new((12, 0), 4, fill(0))
                                + Rectangle::new([(8, -4), (16, 4)], fill(1))
                                + TriangleMarker::new((12, 0), 5, fill(2))
                                + Polygon::new(vec![(12, -5), (17, 0), (12, 5), (7, 0)], fill(3))
                        });
                    }
                }
            }
            if legend {
                let corner = legend_corner(panel, (x0, x1), (y0, y1), legend_box);
                draw_legend(&mut cc, corner)?;
            }
        }
        Ok(())
    }
}

fn io_err(e: PlotError) -> io::Error {
    io::Error::other(e.to_string())
}

/// Render `chart` as an SVG document.
pub fn render_svg(chart: &Chart) -> io::Result<String> {
    let bytes = render_bytes(Format::Svg, chart.size, chart).map_err(io_err)?;
    String::from_utf8(bytes).map_err(io::Error::other)
}

/// Render `chart` as PNG bytes, in memory.
pub fn render_png(chart: &Chart) -> io::Result<Vec<u8>> {
    render_bytes(Format::Png, chart.size, chart).map_err(io_err)
}

/// Draw `chart` to `path` (SVG or PNG by extension), atomically; an error when it has no
/// finite point.
pub fn write(chart: &Chart, path: &Path) -> Result<(), PlotError> {
    chart.check_finite()?;
    render(path, chart.size, chart)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chart() -> Chart {
        Chart {
            title: "Test".into(),
            x_label: "x (mm)".into(),
            columns: 1,
            notes: Vec::new(),
            x_integer: false,
            panels: vec![Panel {
                caption: String::new(),
                y_label: "y (µm)".into(),
                y_range: None,
                y_integer: false,
                series: vec![
                    Series {
                        label: "alpha series".into(),
                        points: vec![(0.0, 1.0), (1.0, 2.0)],
                        color: 0,
                        dashed: false,
                        markers: true,
                        line: true,
                    },
                    Series {
                        label: "beta series".into(),
                        points: vec![(0.0, 2.0), (1.0, 0.5)],
                        color: 1,
                        dashed: true,
                        markers: false,
                        line: true,
                    },
                ],
            }],
            size: (640, 480),
        }
    }

    #[test]
    fn svg_has_title_labels_and_legend() {
        let svg = render_svg(&chart()).unwrap();
        assert!(svg.starts_with("<svg"));
        for text in ["Test", "x (mm)", "y (µm)", "alpha series", "beta series"] {
            assert!(svg.contains(text), "missing {text}");
        }
    }

    #[test]
    fn png_is_a_png() {
        let png = render_png(&chart()).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    }

    #[test]
    fn ranges_skip_nan_and_widen_flat_data() {
        assert_eq!(finite_range(&[f64::NAN, 1.0, 3.0], 0.0), Some((1.0, 3.0)));
        assert_eq!(finite_range(&[f64::NAN], 0.0), None);
        let (lo, hi) = finite_range(&[2.0, 2.0], 0.1).unwrap();
        assert!(lo < 2.0 && hi > 2.0);
    }

    #[test]
    fn tick_decimals_follow_the_span() {
        assert_eq!(tick_decimals(500.0), 0);
        assert_eq!(tick_decimals(5.0), 1);
        assert_eq!(tick_decimals(0.05), 3);
        assert_eq!(tick_decimals(f64::NAN), 1);
    }

    #[test]
    fn tick_labels_never_show_minus_zero() {
        assert_eq!(tick_label(-1e-17, 1), "0.0");
        assert_eq!(tick_label(-0.04, 1), "0.0");
        assert_eq!(tick_label(-0.06, 1), "-0.1");
        assert_eq!(tick_label(0.25, 2), "0.25");
        assert_eq!(tick_label(-3.0, 0), "-3");
    }

    #[test]
    fn segments_break_at_nan() {
        let s = Series::line("a", &[0.0, 1.0, 2.0, 3.0], &[1.0, f64::NAN, 2.0, 3.0], 0);
        assert_eq!(segments(&s.points).len(), 2);
    }

    #[test]
    fn headroom_leaves_the_legend_box_free() {
        let (lo, hi) = legend_headroom((0.0, 1.0), 0.25);
        assert_eq!(lo, 0.0);
        // The data end at 1.0, three quarters of the way up: the top quarter is free.
        assert!(((1.0 - lo) / (hi - lo) - 0.75).abs() < 1e-12);
    }
}
