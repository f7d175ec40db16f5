//! The designed experiment's figures: relative first-level effects per roughness
//! parameter as grouped bars, one bar per factor (Lavernhe et al., Fig 11), the effect
//! of one factor at each of its levels as lines (their Fig 12), and with Monte Carlo the
//! P5-P95 band of every run's responses.

use super::chart::Panel;
use super::chart::{
    Chart, Series, color, draw_legend, finite_range, legend_box, legend_headroom, style_mesh,
    tick_decimals, tick_label, title_font,
};
use super::{Draw, DrawResult, Format, PlotError, render_bytes};
use crate::study::design::{Design, Effects, RunResult};
use plotters::coord::Shift;
use plotters::prelude::*;

/// The bars of one series (a factor), one per category.
#[derive(Debug, Clone, PartialEq)]
pub struct Bars {
    /// Legend label.
    pub label: String,
    /// The bar of each category, in order; a non-finite value draws no bar.
    pub y: Vec<f64>,
}

/// Grouped bars: one group per category (a roughness parameter), one bar per series (a
/// factor); `series[i].y[k]` is the bar of series i in category k.
#[derive(Debug, Clone, PartialEq)]
pub struct BarChart {
    /// Title.
    pub title: String,
    /// The categories along x, in order.
    pub categories: Vec<String>,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label with unit.
    pub y_label: String,
    /// The bars of each series.
    pub series: Vec<Bars>,
}

impl Draw for BarChart {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let n = self.categories.len().max(1);
        let ys = self
            .series
            .iter()
            .flat_map(|s| s.y.iter())
            .chain(std::iter::once(&0.0));
        let (y0, y1) = finite_range(ys, 0.08).unwrap_or((-1.0, 1.0));
        // Head room for the legend above the bars.
        let legend = self.series.len() > 1;
        let (w, h) = root.dim_in_pixel();
        let (y0, y1) = if legend {
            let plot_px = (w as f64 - 110.0, h as f64 - 110.0);
            legend_headroom(
                (y0, y1),
                legend_box(self.series.iter().map(|s| s.label.as_str()), plot_px).1,
            )
        } else {
            (y0, y1)
        };
        let names = self.categories.clone();
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, title_font())
            .margin(18)
            .x_label_area_size(55)
            .y_label_area_size(80)
            .build_cartesian_2d((0..n as i32 - 1).into_segmented(), y0..y1)?;
        let dy = tick_decimals(y1 - y0);
        let fy = move |v: &f64| tick_label(*v, dy);
        let fx = move |v: &SegmentValue<i32>| match v {
            SegmentValue::CenterOf(k) => names.get(*k as usize).cloned().unwrap_or_default(),
            _ => String::new(),
        };
        style_mesh(
            chart
                .configure_mesh()
                .disable_x_mesh()
                .x_labels(n + 1)
                .x_label_formatter(&fx)
                .y_label_formatter(&fy)
                .x_desc(&self.x_label)
                .y_desc(&self.y_label),
        )
        .draw()?;
        // Bar widths in pixels: 80 % of a category, shared by the series.
        let seg_px = chart.plotting_area().dim_in_pixel().0 as f64 / n as f64;
        let m = self.series.len().max(1) as f64;
        let bar = 0.8 * seg_px / m;
        for (i, s) in self.series.iter().enumerate() {
            let color = color(i);
            let left = 0.1 * seg_px + i as f64 * bar;
            let right = seg_px - left - bar;
            let bars =
                s.y.iter()
                    .enumerate()
                    .filter(|(_, y)| y.is_finite())
                    .map(|(k, &y)| {
                        let k = k as i32;
                        let mut r = Rectangle::new(
                            [
                                (SegmentValue::Exact(k), y),
                                (SegmentValue::Exact(k + 1), 0.0),
                            ],
                            color.filled(),
                        );
                        r.set_margin(0, 0, left.round() as u32, right.max(0.0).round() as u32);
                        r
                    });
            chart
                .draw_series(bars)?
                .label(&s.label)
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 18, y + 6)], color.filled())
                });
        }
        // The zero line.
        chart.draw_series(LineSeries::new(
            [
                (SegmentValue::Exact(0), 0.0),
                (SegmentValue::Exact(n as i32), 0.0),
            ],
            BLACK.stroke_width(1),
        ))?;
        if legend {
            draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        }
        Ok(())
    }
}

/// A bar chart as SVG bytes, 1000 × 560 pixels.
pub fn bar_chart_svg(chart: &BarChart) -> Result<Vec<u8>, PlotError> {
    if !chart
        .series
        .iter()
        .any(|s| s.y.iter().any(|y| y.is_finite()))
    {
        return Err(PlotError::Empty(format!(
            "no finite bar in '{}'",
            chart.title
        )));
    }
    render_bytes(Format::Svg, (1000, 560), chart)
}

/// Relative first-level effect EF_i1 (%) per roughness parameter (x = the parameters in
/// [`Design::responses`] order), one bar per factor with more than one level: the change
/// of the parameter when the factor is at its first level, relative to the mean of all
/// runs.
pub fn effects_chart(design: &Design, effects: &[Effects]) -> BarChart {
    let factors = design.factors();
    let series = factors
        .iter()
        .enumerate()
        .filter(|(_, f)| f.levels.len() > 1)
        .map(|(i, f)| {
            let y: Vec<f64> = effects
                .iter()
                .map(|e| 100.0 * e.relative_first[i])
                .collect();
            Bars {
                label: format!("{} = {}", f.name, f.levels[0]),
                y,
            }
        })
        .collect();
    let series: Vec<Bars> = series;
    let mut title = if design.title.is_empty() {
        "Effect of each factor at its first level".to_string()
    } else {
        format!("{}: effect of each factor at its first level", design.title)
    };
    // A single series gets no legend: name it in the title.
    if let [only] = series.as_slice() {
        title = format!("{title}, {}", only.label);
    }
    BarChart {
        title,
        categories: design.responses.clone(),
        x_label: "roughness parameter".into(),
        y_label: "change from the mean of all runs [%]".into(),
        series,
    }
}

/// The chart of 001 Fig 12: the relative effect `EF_ij/M` (%) of one factor at each of its
/// levels (x = the level), one series per response.
pub fn level_chart(design: &Design, effects: &[Effects], factor: usize) -> Option<Chart> {
    let f = design.factors().into_iter().nth(factor)?;
    let series = design
        .responses
        .iter()
        .zip(effects)
        .enumerate()
        .map(|(i, (name, e))| {
            let y: Vec<f64> = e
                .effects
                .get(factor)
                .map(|row| {
                    row.iter()
                        .map(|v| {
                            if e.mean != 0.0 {
                                100.0 * v / e.mean
                            } else {
                                f64::NAN
                            }
                        })
                        .collect()
                })
                .unwrap_or_default();
            Series::line(name.clone(), &f.levels, &y, i)
        })
        .collect();
    Some(Chart::lines(
        if design.title.is_empty() {
            format!("Effect of {} at each of its levels", f.name)
        } else {
            format!(
                "{}: effect of {} at each of its levels",
                design.title, f.name
            )
        },
        f.name.clone(),
        "change from the mean of all runs [%]",
        series,
    ))
}

/// With Monte Carlo bands (`crest study --monte-carlo N`): one panel per response, x = the
/// run, the P5 and P95 of each run as a dashed band, its P50 as a line and the
/// deterministic run (nominal inputs) as markers. `None` when no run has bands.
pub fn bands_chart(design: &Design, results: &[RunResult], samples: usize) -> Option<Chart> {
    if !results.iter().any(|r| r.bands.is_some()) {
        return None;
    }
    let x: Vec<f64> = results.iter().map(|r| r.point.run as f64).collect();
    let panels: Vec<Panel> = design
        .responses
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let band = |f: fn(&crate::study::uncertainty::Band) -> f64| -> Vec<f64> {
                results
                    .iter()
                    .map(|r| r.bands.as_ref().and_then(|b| b.get(k)).map_or(f64::NAN, f))
                    .collect()
            };
            let det: Vec<f64> = results
                .iter()
                .map(|r| r.responses.get(k).copied().unwrap_or(f64::NAN))
                .collect();
            let mut p5 = Series::line("P5 / P95", &x, &band(|b| b.p5), 2);
            p5.dashed = true;
            let mut p95 = Series::line("", &x, &band(|b| b.p95), 2);
            p95.dashed = true;
            let p50 = Series::line("P50", &x, &band(|b| b.p50), 2);
            let mut nominal = Series::line("deterministic run", &x, &det, 0);
            nominal.line = false;
            nominal.markers = true;
            let unit = crate::metrics::Param::from_symbol(name).map_or("", |p| p.unit());
            Panel {
                caption: name.clone(),
                y_label: if unit.is_empty() || unit == "1" {
                    name.clone()
                } else {
                    format!("{name} [{unit}]")
                },
                y_range: None,
                y_integer: false,
                series: vec![p5, p95, p50, nominal],
            }
        })
        .collect();
    let columns = if panels.len() > 3 { 2 } else { 1 };
    let rows = panels.len().div_ceil(columns);
    let title = if design.title.is_empty() {
        "Monte Carlo bands of every run".to_string()
    } else {
        format!("{}: Monte Carlo bands of every run", design.title)
    };
    let mut chart = Chart::lines(title, "run", "", Vec::new());
    chart.panels = panels;
    chart.columns = columns;
    chart.x_integer = true;
    chart.notes = vec![
        format!(
            "{samples} Monte Carlo samples per run (the inputs drawn within their [uncertainty]): \
             dashed, their P5 and P95; line, their median."
        ),
        "Markers: the deterministic run (nominal inputs, every pass starting at spindle phase 0)."
            .to_string(),
        "With the spindle phase drawn per pass the feed marks of neighbouring passes no longer \
         line up, so it can lie outside the band."
            .to_string(),
    ];
    chart.size = (
        if columns > 1 { 1400 } else { 1000 },
        120 + 260 * rows as u32 + 21 * chart.notes.len() as u32,
    );
    Some(chart)
}
