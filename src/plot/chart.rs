//! The chart model: one or more stacked panels sharing an x axis, each with
//! several series (solid or dashed lines with markers), a title, axis labels with units and a
//! legend when a panel has more than one series. Rendered as SVG or PNG with the embedded
//! font (see [`super::init_fonts`]).
//!
//! The chart is plain data ([`Chart`]); the modules that draw a study's figures (e.g.
//! [`super::runout`]) decide what goes in it. Styling follows a journal figure: white background, black frame and ticks, a faint
//! grid, a small fixed palette.

use super::{FONT, init_fonts};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::io;

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

/// The palette: black, vermilion, blue, bluish green, orange, reddish purple, sky blue, grey.
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

fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// Marker shape of a colour index (circle, square, triangle, diamond), so overlapping
/// series stay distinguishable.
fn shape_of(index: usize) -> usize {
    index % 4
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

fn span(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    (lo <= hi).then_some((lo, hi))
}

fn padded((lo, hi): (f64, f64), share: f64) -> (f64, f64) {
    let w = hi - lo;
    if w <= 1e-12 * hi.abs().max(1.0) {
        let d = if hi.abs() > 0.0 { 0.1 * hi.abs() } else { 1.0 };
        return (lo - d, hi + d);
    }
    (lo - share * w, hi + share * w)
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, chart: &Chart) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let body = root
        .titled(&chart.title, (FONT, 24).into_font().color(&BLACK))
        .map_err(|e| e.to_string())?;
    let body = if chart.notes.is_empty() {
        body
    } else {
        let h = body.dim_in_pixel().1 as i32;
        let foot_h = 21 * chart.notes.len() as i32 + 12;
        let (top, foot) = body.split_vertically(h - foot_h);
        for (k, line) in chart.notes.iter().enumerate() {
            foot.draw_text(
                line,
                &(FONT, 15).into_font().color(&RGBColor(40, 40, 40)),
                (16, 6 + 21 * k as i32),
            )
            .map_err(|e| e.to_string())?;
        }
        top
    };
    let cols = chart.columns.max(1);
    let rows = chart.panels.len().max(1).div_ceil(cols);
    let areas = body.split_evenly((rows, cols));
    let x_all = span(
        chart
            .panels
            .iter()
            .flat_map(|p| p.series.iter())
            .flat_map(|s| s.points.iter().map(|p| p.0)),
    )
    .unwrap_or((0.0, 1.0));
    let (x0, x1) = padded(x_all, 0.03);
    let last_row_start = (rows - 1) * cols;
    for (k, (panel, area)) in chart.panels.iter().zip(areas.iter()).enumerate() {
        let y_data = span(
            panel
                .series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.1)),
        )
        .unwrap_or((0.0, 1.0));
        let entries = panel
            .series
            .iter()
            .filter(|s| (s.line || s.markers) && !s.label.is_empty())
            .count();
        let legend = entries > 1;
        // Legend box as shares of the plot area (about 19 px a line, 330 px wide).
        let plot_h = (chart.size.1 as f64 / rows as f64 - 110.0).max(100.0);
        let plot_w = (chart.size.0 as f64 / cols as f64 - 110.0).max(100.0);
        let legend_box = (
            (330.0 / plot_w).min(0.9),
            ((entries as f64 * 19.0 + 20.0) / plot_h).min(0.9),
        );
        let (y0, y1) = panel.y_range.unwrap_or_else(|| {
            let (lo, hi) = padded(y_data, 0.08);
            // Head room for the legend above the data.
            let hi = if legend {
                hi + (hi - lo) * legend_box.1 / (1.0 - legend_box.1)
            } else {
                hi
            };
            // Counts and heights read best from zero when the data are all positive.
            if y_data.0 >= 0.0 && lo < 0.0 {
                (0.0, hi)
            } else {
                (lo, hi)
            }
        });
        let mut builder = ChartBuilder::on(area);
        if !panel.caption.is_empty() {
            builder.caption(&panel.caption, (FONT, 18).into_font().color(&BLACK));
        }
        let mut cc = builder
            .margin_left(12)
            .margin_right(24)
            .margin_top(10)
            .margin_bottom(if k >= last_row_start { 6 } else { 2 })
            .x_label_area_size(52)
            .y_label_area_size(78)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| e.to_string())?;
        let y_integer = panel.y_integer;
        let y_fmt = move |v: &f64| {
            if y_integer {
                format!("{v:.0}")
            } else {
                let a = v.abs();
                if a != 0.0 && !(1e-3..1e4).contains(&a) {
                    format!("{v:.1e}")
                } else if a >= 100.0 {
                    format!("{v:.0}")
                } else {
                    format!("{v:.3}")
                        .trim_end_matches('0')
                        .trim_end_matches('.')
                        .to_string()
                }
            }
        };
        let x_fmt = |v: &f64| {
            format!("{v:.3}")
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_string()
        };
        let y_ticks = if y_integer {
            ((y1 - y0).round() as usize + 1).clamp(2, 12)
        } else {
            8
        };
        cc.configure_mesh()
            .x_desc(chart.x_label.as_str())
            .y_desc(panel.y_label.as_str())
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .y_labels(y_ticks)
            .x_labels(10)
            .label_style((FONT, 15).into_font().color(&BLACK))
            .axis_desc_style((FONT, 17).into_font().color(&BLACK))
            .axis_style(BLACK.stroke_width(1))
            .bold_line_style(RGBColor(225, 225, 225).stroke_width(1))
            .light_line_style(TRANSPARENT)
            .draw()
            .map_err(|e| e.to_string())?;
        let labels = legend_labels(panel);
        for (s, label) in panel.series.iter().zip(&labels) {
            let c = color(s.color);
            let style = c.stroke_width(2);
            let pts = s.points.clone();
            let dashed = s.dashed;
            let markers = s.markers;
            let color_index = s.color;
            if s.line {
                let anno = if s.dashed {
                    cc.draw_series(DashedLineSeries::new(pts.clone(), 8, 5, style))
                        .map_err(|e| e.to_string())?
                } else {
                    cc.draw_series(LineSeries::new(pts.clone(), style))
                        .map_err(|e| e.to_string())?
                };
                if !label.is_empty() {
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
                let finite = pts.iter().filter(|p| p.0.is_finite() && p.1.is_finite());
                let style = c.filled();
                let shape = shape_of(s.color);
                let anno =
                    match shape {
                        0 => cc.draw_series(finite.map(|&p| Circle::new(p, 4, style))),
                        1 => cc.draw_series(finite.map(|&p| {
                            EmptyElement::at(p) + Rectangle::new([(-4, -4), (4, 4)], style)
                        })),
                        2 => cc.draw_series(finite.map(|&p| TriangleMarker::new(p, 5, style))),
                        _ => cc.draw_series(finite.map(|&p| {
                            EmptyElement::at(p)
                                + Polygon::new(vec![(0, -5), (5, 0), (0, 5), (-5, 0)], style)
                        })),
                    }
                    .map_err(|e| e.to_string())?;
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
            cc.configure_series_labels()
                .position(legend_corner(panel, (x0, x1), (y0, y1), legend_box))
                .background_style(WHITE.mix(0.92))
                .border_style(BLACK.stroke_width(1))
                .label_font((FONT, 14).into_font().color(&BLACK))
                .margin(8)
                .draw()
                .map_err(|e| e.to_string())?;
        }
    }
    root.present().map_err(|e| e.to_string())
}

/// Render `chart` as an SVG document.
pub fn render_svg(chart: &Chart) -> io::Result<String> {
    init_fonts();
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, chart.size).into_drawing_area();
        draw(&root, chart).map_err(io::Error::other)?;
    }
    Ok(out)
}

/// Render `chart` as PNG bytes, in memory.
pub fn render_png(chart: &Chart) -> io::Result<Vec<u8>> {
    super::svg_to_png(&render_svg(chart)?)
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
}
