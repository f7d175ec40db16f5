//! Line charts: profiles (simulated against measured), and the shared machinery of the
//! charts in this folder (rendering to SVG or PNG through [`crate::io::write_atomic`],
//! the error type, axis ranges that ignore NaN).
//!
//! Every chart has a title, axis labels with units, and a legend when it has more than
//! one series. Text uses the embedded font ([`super::init_fonts`], [`super::FONT`]).

use super::{FONT, Format, init_fonts};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

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
        Format::Png => super::svg_to_png(&svg).map_err(|e| PlotError::Draw(e.to_string())),
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
    let margin = if span > 0.0 {
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

/// A title font.
pub(crate) fn title_font() -> TextStyle<'static> {
    (FONT, 24).into_font().into()
}

/// The font of axis labels.
pub(crate) fn label_font() -> TextStyle<'static> {
    (FONT, 18).into_font().into()
}

/// The font of tick labels and legends.
pub(crate) fn tick_font() -> TextStyle<'static> {
    (FONT, 15).into_font().into()
}

/// A colour-blind-safe palette (Okabe-Ito), for series in order.
pub(crate) fn series_color(i: usize) -> RGBColor {
    const P: [RGBColor; 8] = [
        RGBColor(0, 114, 178),
        RGBColor(213, 94, 0),
        RGBColor(0, 158, 115),
        RGBColor(204, 121, 167),
        RGBColor(230, 159, 0),
        RGBColor(86, 180, 233),
        RGBColor(0, 0, 0),
        RGBColor(240, 228, 66),
    ];
    P[i % P.len()]
}

/// One line of a chart: points (x[i], y[i]); non-finite points break the line.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
}

impl Series {
    /// A series from a label and two slices (the shorter length is used).
    pub fn new(label: impl Into<String>, x: &[f64], y: &[f64]) -> Series {
        let n = x.len().min(y.len());
        Series {
            label: label.into(),
            x: x[..n].to_vec(),
            y: y[..n].to_vec(),
        }
    }

    /// Maximal runs of finite points.
    fn segments(&self) -> Vec<Vec<(f64, f64)>> {
        let mut out = Vec::new();
        let mut cur = Vec::new();
        for (&x, &y) in self.x.iter().zip(&self.y) {
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
}

/// A line chart.
#[derive(Debug, Clone, PartialEq)]
pub struct LineChart {
    /// Title.
    pub title: String,
    /// x-axis label with unit, e.g. `x [mm]`.
    pub x_label: String,
    /// y-axis label with unit.
    pub y_label: String,
    /// The lines.
    pub series: Vec<Series>,
}

impl Draw for LineChart {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let (x0, x1) =
            finite_range(self.series.iter().flat_map(|s| &s.x), 0.0).unwrap_or((0.0, 1.0));
        let (y0, y1) = finite_range(
            self.series
                .iter()
                .flat_map(|s| s.x.iter().zip(&s.y).filter(|(x, _)| x.is_finite()))
                .map(|(_, y)| y),
            0.08,
        )
        .unwrap_or((0.0, 1.0));
        // Head room for the legend (about 20 px a line of a 430 px plot) above the data.
        let y1 = if self.series.len() > 1 {
            y1 + (y1 - y0) * (0.05 * self.series.len() as f64).min(1.5)
        } else {
            y1
        };
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, title_font())
            .margin(18)
            .x_label_area_size(55)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        let (dx, dy) = (tick_decimals(x1 - x0), tick_decimals(y1 - y0));
        let fx = move |v: &f64| tick_label(*v, dx);
        let fy = move |v: &f64| tick_label(*v, dy);
        chart
            .configure_mesh()
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .axis_desc_style(label_font())
            .label_style(tick_font())
            .max_light_lines(4)
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(210, 210, 210))
            .draw()?;
        for (i, s) in self.series.iter().enumerate() {
            let color = series_color(i);
            let style = ShapeStyle::from(&color).stroke_width(2);
            // Past the eight colours, the lines are dashed: no two series look alike.
            let dashed = (i / 8) % 2 == 1;
            let mut first = true;
            for seg in s.segments() {
                let drawn = if dashed {
                    chart.draw_series(DashedLineSeries::new(seg, 7, 4, style))?
                } else {
                    chart.draw_series(LineSeries::new(seg, style))?
                };
                if first {
                    drawn.label(&s.label).legend(move |(x, y)| {
                        if dashed {
                            EmptyElement::at((x, y))
                                + PathElement::new(vec![(0, 0), (9, 0)], style)
                                + PathElement::new(vec![(14, 0), (24, 0)], style)
                        } else {
                            EmptyElement::at((x, y))
                                + PathElement::new(vec![(0, 0), (24, 0)], style)
                                + PathElement::new(vec![(0, 0), (0, 0)], style)
                        }
                    });
                    first = false;
                }
            }
        }
        if self.series.len() > 1 {
            chart
                .configure_series_labels()
                .label_font(tick_font())
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(160, 160, 160))
                .position(SeriesLabelPosition::UpperRight)
                .draw()?;
        }
        Ok(())
    }
}

/// The size of a line chart, pixels.
const LINE_CHART_SIZE: (u32, u32) = (1000, 560);

/// A line chart as SVG bytes, 1000 × 560 pixels.
pub fn line_chart_svg(chart: &LineChart) -> Result<Vec<u8>, PlotError> {
    check_finite(chart)?;
    render_bytes(Format::Svg, LINE_CHART_SIZE, chart)
}

fn check_finite(chart: &LineChart) -> Result<(), PlotError> {
    let finite = chart.series.iter().any(|s| {
        s.x.iter()
            .zip(&s.y)
            .any(|(x, y)| x.is_finite() && y.is_finite())
    });
    if finite {
        Ok(())
    } else {
        Err(PlotError::Empty(format!(
            "no finite point in '{}'",
            chart.title
        )))
    }
}

/// Draw a line chart to `path` (SVG or PNG), 1000 × 560 pixels.
pub fn plot_lines(chart: &LineChart, path: &Path) -> Result<(), PlotError> {
    check_finite(chart)?;
    render(path, LINE_CHART_SIZE, chart)
}

/// Plot height profiles against position: a simulated profile and, optionally, a measured
/// one (x in mm, heights in µm).
pub fn plot_profiles(
    title: &str,
    simulated: (&[f64], &[f64]),
    measured: Option<(&[f64], &[f64])>,
    path: &Path,
) -> Result<(), PlotError> {
    let mut series = vec![Series::new("simulated", simulated.0, simulated.1)];
    if let Some((x, z)) = measured {
        series.push(Series::new("measured", x, z));
    }
    plot_lines(
        &LineChart {
            title: title.to_string(),
            x_label: "position along the profile [mm]".to_string(),
            y_label: "height [µm]".to_string(),
            series,
        },
        path,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let s = Series::new("a", &[0.0, 1.0, 2.0, 3.0], &[1.0, f64::NAN, 2.0, 3.0]);
        assert_eq!(s.segments().len(), 2);
    }

    #[test]
    fn profile_svg_has_title_labels_and_legend() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("p.svg");
        let x: Vec<f64> = (0..200).map(|i| i as f64 * 0.01).collect();
        let z: Vec<f64> = x.iter().map(|x| (x * 20.0).sin()).collect();
        let m: Vec<f64> = x.iter().map(|x| 1.1 * (x * 20.0).sin()).collect();
        plot_profiles("Profile test 3", (&x, &z), Some((&x, &m)), &out).unwrap();
        let svg = std::fs::read_to_string(&out).unwrap();
        for text in [
            "Profile test 3",
            "height [µm]",
            "[mm]",
            "simulated",
            "measured",
        ] {
            assert!(svg.contains(text), "missing {text}");
        }
        assert!(matches!(
            plot_profiles("x", (&x, &z), None, &dir.path().join("p.pdf")),
            Err(PlotError::Format(_))
        ));
        let nan = [f64::NAN];
        assert!(matches!(
            plot_profiles("x", (&nan, &nan), None, &out),
            Err(PlotError::Empty(_))
        ));
    }
}
