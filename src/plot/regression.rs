//! The regression figure: measured roughness (mean ± σ and single samples) against the
//! simulated value per lead angle and side (the leave-one-out value in a calibrated report,
//! with the Monte Carlo P5-P95 band when there is one), as SVG in the one style of
//! [`super::chart`].

use super::chart::{
    color, draw_legend, legend_box, legend_headroom, style_mesh, tick_decimals, tick_label,
    title_font,
};
use super::{Draw, DrawResult, Format, PlotError, render_bytes};
use crate::study::compare::{CaseResult, Comparison, Regression};
use crate::study::measured::{Param, Side};
use crate::study::uncertainty::Band;
use plotters::coord::Shift;
use plotters::prelude::*;

/// The Monte Carlo band of `c`'s `parameter`, when the report has bands.
fn band_of(r: &Regression, c: &CaseResult, parameter: &str) -> Option<Band> {
    let b = r
        .monte_carlo
        .as_ref()?
        .iter()
        .find(|b| b.lead_deg == c.lead_deg && b.side == c.side)?;
    match parameter {
        "Rz" => Some(b.rz),
        "Ra" => Some(b.ra),
        _ => None,
    }
}

/// Draw the figure of one parameter (a [`crate::study::measured::Param`] label: `Rz`, `Ra`,
/// `Sz`, `Sa`, `Rz stepover`, `Ra stepover`) as an SVG string.
pub fn render_plot(r: &Regression, parameter: &str) -> Result<String, PlotError> {
    let param = Param::from_label(parameter)
        .ok_or_else(|| PlotError::Invalid(format!("no parameter {parameter}")))?;
    let pts: Vec<(&CaseResult, &Comparison)> = r
        .cases
        .iter()
        .flat_map(|c| {
            c.comparisons
                .iter()
                .filter(|k| k.parameter == parameter)
                .map(move |k| (c, k))
        })
        .collect();
    if pts.is_empty() {
        return Err(PlotError::Invalid(format!("no {parameter} values to plot")));
    }
    let figure = Figure {
        r,
        parameter,
        param,
        pts,
    };
    let bytes = render_bytes(Format::Svg, PLOT_SIZE, &figure)?;
    String::from_utf8(bytes).map_err(|e| PlotError::Draw(e.to_string()))
}

const PLOT_SIZE: (u32, u32) = (1000, 560);

/// What one figure draws: the comparisons of one parameter, case by case.
struct Figure<'a> {
    r: &'a Regression,
    parameter: &'a str,
    param: Param,
    pts: Vec<(&'a CaseResult, &'a Comparison)>,
}

impl Figure<'_> {
    fn samples(&self, c: &CaseResult) -> Vec<f64> {
        c.measured.values(self.param).to_vec()
    }

    fn model_word(&self) -> &'static str {
        if self.r.calibration.is_some() {
            "leave-one-out"
        } else {
            "simulated"
        }
    }

    /// The legend entries in the order they are drawn (for the legend's head room).
    fn legend_labels(&self, sides: &[Side]) -> Vec<String> {
        let mut labels = Vec::new();
        for (si, side) in sides.iter().enumerate() {
            labels.push(format!("measured {} (mean ± σ)", side.name()));
            if si + 1 == sides.len() {
                labels.push("single samples".to_string());
            }
            labels.push(self.model_label(side));
            let banded = self
                .pts
                .iter()
                .any(|(c, _)| c.side == *side && band_of(self.r, c, self.parameter).is_some());
            if banded {
                labels.push(format!("model P5-P95 {} (Monte Carlo)", side.name()));
            }
        }
        labels
    }

    fn model_label(&self, side: &Side) -> String {
        format!(
            "{} {} ({})",
            self.model_word(),
            side.name(),
            self.r.cases[0].model.name()
        )
    }
}

impl Draw for Figure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let parameter = self.parameter;
        let mut sides: Vec<Side> = self.pts.iter().map(|(c, _)| c.side.clone()).collect();
        sides.sort();
        sides.dedup();
        let mut ymax: f64 = 0.0;
        for (c, k) in &self.pts {
            ymax = ymax
                .max(k.measured.mean + k.measured.sd.unwrap_or(0.0))
                .max(k.simulated_um);
            if let Some(b) = band_of(self.r, c, parameter) {
                ymax = ymax.max(b.p95);
            }
            for v in self.samples(c) {
                ymax = ymax.max(v);
            }
        }
        let ymax = if ymax > 0.0 { ymax * 1.08 } else { 1.0 };
        let (w, h) = root.dim_in_pixel();
        let labels = self.legend_labels(&sides);
        let plot_px = (w as f64 - 120.0, h as f64 - 120.0);
        let (_, ymax) = legend_headroom(
            (0.0, ymax),
            legend_box(labels.iter().map(String::as_str), plot_px).1,
        );
        let lmin = self
            .pts
            .iter()
            .map(|(c, _)| c.lead_deg)
            .fold(f64::INFINITY, f64::min);
        let lmax = self
            .pts
            .iter()
            .map(|(c, _)| c.lead_deg)
            .fold(f64::NEG_INFINITY, f64::max);
        let pad = ((lmax - lmin) * 0.15).max(2.0);
        let (x0, x1) = (lmin - pad, lmax + pad);
        let offset = (x1 - x0) * 0.012;

        let mut chart = ChartBuilder::on(root)
            .caption(
                format!(
                    "{parameter}: measured (mean ± σ, samples) against {}",
                    if self.r.calibration.is_some() {
                        "leave-one-out prediction"
                    } else {
                        "simulated"
                    }
                ),
                title_font(),
            )
            .margin(18)
            .x_label_area_size(55)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, 0.0..ymax)?;
        let (dx_ticks, dy_ticks) = (tick_decimals(x1 - x0), tick_decimals(ymax));
        let fx = move |v: &f64| tick_label(*v, dx_ticks);
        let fy = move |v: &f64| tick_label(*v, dy_ticks);
        let y_desc = if parameter == "Sdq" {
            "Sdq (µm/µm)".to_string()
        } else {
            format!("{parameter} (µm)")
        };
        style_mesh(
            chart
                .configure_mesh()
                .x_label_formatter(&fx)
                .y_label_formatter(&fy)
                .x_desc("lead angle (°)")
                .y_desc(&y_desc),
        )
        .draw()?;
        for (si, side) in sides.iter().enumerate() {
            // Palette colours from blue on (black is kept for frames and samples' legend).
            let colour = color(si + 2);
            let dx = if sides.len() > 1 {
                offset * (2.0 * si as f64 - (sides.len() - 1) as f64)
            } else {
                0.0
            };
            let mine: Vec<&(&CaseResult, &Comparison)> =
                self.pts.iter().filter(|(c, _)| c.side == *side).collect();
            // Error bars (mean ± σ) with the mean marker.
            chart
                .draw_series(mine.iter().map(|(c, k)| {
                    let sd = k.measured.sd.unwrap_or(0.0);
                    ErrorBar::new_vertical(
                        c.lead_deg + dx,
                        k.measured.mean - sd,
                        k.measured.mean,
                        k.measured.mean + sd,
                        colour.filled(),
                        8,
                    )
                }))?
                .label(format!("measured {} (mean ± σ)", side.name()))
                .legend(move |(x, y)| Circle::new((x + 9, y), 4, colour.filled()));
            // Individual samples, hollow.
            let samples_series = chart.draw_series(mine.iter().flat_map(|(c, _)| {
                self.samples(c)
                    .into_iter()
                    .map(move |v| Circle::new((c.lead_deg + dx, v), 4, colour.stroke_width(1)))
            }))?;
            if si + 1 == sides.len() {
                samples_series
                    .label("single samples")
                    .legend(|(x, y)| Circle::new((x + 9, y), 4, BLACK.stroke_width(1)));
            }
            // The model: a line through crosses.
            let mut sim: Vec<(f64, f64)> = mine
                .iter()
                .map(|(c, k)| (c.lead_deg + dx, k.simulated_um))
                .collect();
            sim.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(sim.clone(), colour.stroke_width(2)))?
                .label(self.model_label(side))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            chart.draw_series(
                sim.iter()
                    .map(|p| Cross::new(*p, 6, colour.stroke_width(2))),
            )?;
            // Monte Carlo P5-P95 band of the model, a translucent bar beside the marks.
            let bars: Vec<(f64, Band)> = mine
                .iter()
                .filter_map(|(c, _)| band_of(self.r, c, parameter).map(|b| (c.lead_deg + dx, b)))
                .collect();
            if !bars.is_empty() {
                let w = 0.6 * offset;
                chart
                    .draw_series(bars.iter().map(|(x, b)| {
                        Rectangle::new([(x - w, b.p5), (x + w, b.p95)], colour.mix(0.25).filled())
                    }))?
                    .label(format!("model P5-P95 {} (Monte Carlo)", side.name()))
                    .legend(move |(x, y)| {
                        Rectangle::new([(x + 5, y - 6), (x + 13, y + 6)], colour.mix(0.25).filled())
                    });
            }
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
    }
}
