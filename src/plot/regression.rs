//! The regression figure: measured roughness (mean ± σ and single samples) against the
//! simulated value per lead angle and side (the leave-one-out value in a calibrated report,
//! with the Monte Carlo P5-P95 band when there is one), as SVG.

use crate::study::measured::Side;
use crate::study::montecarlo::Band;
use crate::study::regression::{CaseResult, Comparison, Regression};

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
pub fn render_plot(r: &Regression, parameter: &str) -> Result<String, String> {
    let mut svg = String::new();
    {
        let root = plotters::prelude::SVGBackend::with_string(&mut svg, PLOT_SIZE);
        draw_plot(r, parameter, root)?;
    }
    Ok(svg)
}

const PLOT_SIZE: (u32, u32) = (760, 480);

fn draw_plot<DB: plotters::prelude::DrawingBackend>(
    r: &Regression,
    parameter: &str,
    backend: DB,
) -> Result<(), String> {
    use plotters::prelude::*;
    super::init_fonts();
    let font = super::FONT;
    let mut sides: Vec<Side> = r.cases.iter().map(|c| c.side.clone()).collect();
    sides.sort();
    sides.dedup();
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
        return Err(format!("no {parameter} values to plot"));
    }
    let param = crate::study::measured::Param::from_label(parameter)
        .ok_or_else(|| format!("no parameter {parameter}"))?;
    let samples = |c: &CaseResult| -> Vec<f64> { c.measured.values(param).to_vec() };
    let mut ymax: f64 = 0.0;
    for (c, k) in &pts {
        ymax = ymax
            .max(k.measured.mean + k.measured.sd.unwrap_or(0.0))
            .max(k.simulated_um);
        if let Some(b) = band_of(r, c, parameter) {
            ymax = ymax.max(b.p95);
        }
        for v in samples(c) {
            ymax = ymax.max(v);
        }
    }
    let ymax = if ymax > 0.0 { ymax * 1.15 } else { 1.0 };
    let lmin = pts
        .iter()
        .map(|(c, _)| c.lead_deg)
        .fold(f64::INFINITY, f64::min);
    let lmax = pts
        .iter()
        .map(|(c, _)| c.lead_deg)
        .fold(f64::NEG_INFINITY, f64::max);
    let pad = ((lmax - lmin) * 0.15).max(2.0);
    let (x0, x1) = (lmin - pad, lmax + pad);
    let offset = (x1 - x0) * 0.012;

    {
        let root = backend.into_drawing_area();
        let e = |x: DrawingAreaErrorKind<_>| x.to_string();
        root.fill(&WHITE).map_err(e)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "{parameter}: measured (mean ± σ, samples) against {}",
                    if r.calibration.is_some() {
                        "leave-one-out prediction"
                    } else {
                        "simulated"
                    }
                ),
                (font, 20),
            )
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, 0.0..ymax)
            .map_err(|x| x.to_string())?;
        chart
            .configure_mesh()
            .x_desc("lead angle (°)")
            .x_label_formatter(&|x| crate::math::trim_decimals(*x, 4))
            .y_desc(format!("{parameter} (µm)"))
            .label_style((font, 14))
            .axis_desc_style((font, 15))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(|x| x.to_string())?;
        let palette = [
            RGBColor(31, 119, 180),
            RGBColor(214, 39, 40),
            RGBColor(44, 160, 44),
        ];
        for (si, side) in sides.iter().enumerate() {
            let colour = palette[si % palette.len()];
            let dx = if sides.len() > 1 {
                offset * (2.0 * si as f64 - (sides.len() - 1) as f64)
            } else {
                0.0
            };
            let mine: Vec<&(&CaseResult, &Comparison)> =
                pts.iter().filter(|(c, _)| c.side == *side).collect();
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
                }))
                .map_err(|x| x.to_string())?
                .label(format!("measured {} (mean ± σ)", side.name()))
                .legend(move |(x, y)| Circle::new((x + 10, y), 4, colour.filled()));
            // Individual samples, hollow.
            let samples_series = chart
                .draw_series(mine.iter().flat_map(|(c, _)| {
                    samples(c)
                        .into_iter()
                        .map(move |v| Circle::new((c.lead_deg + dx, v), 4, colour.stroke_width(1)))
                }))
                .map_err(|x| x.to_string())?;
            if si + 1 == sides.len() {
                samples_series
                    .label("single samples")
                    .legend(|(x, y)| Circle::new((x + 10, y), 4, BLACK.stroke_width(1)));
            }
            // Simulated, dashed-look line with crosses.
            let mut sim: Vec<(f64, f64)> = mine
                .iter()
                .map(|(c, k)| (c.lead_deg + dx, k.simulated_um))
                .collect();
            sim.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(
                    sim.clone(),
                    colour.mix(0.6).stroke_width(2),
                ))
                .map_err(|x| x.to_string())?
                .label(format!(
                    "{} {} ({})",
                    if r.calibration.is_some() {
                        "leave-one-out"
                    } else {
                        "simulated"
                    },
                    side.name(),
                    r.cases[0].model.name()
                ))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.mix(0.6).stroke_width(2))
                });
            chart
                .draw_series(
                    sim.iter()
                        .map(|p| Cross::new(*p, 6, colour.stroke_width(2))),
                )
                .map_err(|x| x.to_string())?;
            // Monte Carlo P5-P95 band of the model, a translucent bar beside the marks.
            let bars: Vec<(f64, Band)> = mine
                .iter()
                .filter_map(|(c, _)| band_of(r, c, parameter).map(|b| (c.lead_deg + dx, b)))
                .collect();
            if !bars.is_empty() {
                let w = 0.6 * offset;
                chart
                    .draw_series(bars.iter().map(|(x, b)| {
                        Rectangle::new([(x - w, b.p5), (x + w, b.p95)], colour.mix(0.25).filled())
                    }))
                    .map_err(|x| x.to_string())?
                    .label(format!("model P5-P95 {} (Monte Carlo)", side.name()))
                    .legend(move |(x, y)| {
                        Rectangle::new([(x + 6, y - 6), (x + 14, y + 6)], colour.mix(0.25).filled())
                    });
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .label_font((font, 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()
            .map_err(|x| x.to_string())?;
        root.present().map_err(e)?;
    }
    Ok(())
}
