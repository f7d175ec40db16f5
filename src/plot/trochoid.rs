//! Trochoidal paths of the infinitesimal cutting-edge (ICE) elements (002 Fig 14a/b):
//! isometric views of several passes for each lead angle, a top view grouped by tool
//! height, and the crest heights between consecutive marks for two feeds per tooth.
//!
//! The geometry (the ICE paths and the crest between consecutive marks) is
//! [`crate::tool::trochoid`]'s; this module draws it.

use super::chart::{caption_font, color, draw_legend, style_mesh, tick_font, title_font};
use super::{Draw, DrawResult, PlotError, render};
use crate::math::Point3;
use crate::tool::Cutter;
use crate::tool::trochoid::{crest_between_marks_mm, trochoid};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// What a trochoid figure shows.
#[derive(Debug, Clone, PartialEq)]
pub struct TrochoidOptions {
    /// Tool heights z above the tip at which ICE elements are traced, mm.
    pub heights_mm: Vec<f64>,
    /// Lead angles, rad (one isometric panel each; the first is also shown from the top).
    pub leads_rad: Vec<f64>,
    /// Number of parallel passes.
    pub passes: usize,
    /// Lateral distance between passes, mm.
    pub stepover_mm: f64,
    /// Feed per tooth of the drawn trochoids, mm.
    pub fz_mm: f64,
    /// Feeds per tooth for the crest-height panel (e.g. 0.05 and 0.2), mm.
    pub crest_fz_mm: Vec<f64>,
    /// Spindle revolutions traced per pass.
    pub revolutions: f64,
    /// Samples per revolution.
    pub points_per_rev: usize,
    /// Figure title.
    pub title: String,
}

impl Default for TrochoidOptions {
    /// Six heights, leads 5/15/25°, 3 passes 0.5 mm apart, fz 0.2 mm, crest panel for
    /// fz 0.05 and 0.2 mm (the 002 case study), 3 revolutions.
    fn default() -> Self {
        TrochoidOptions {
            heights_mm: vec![0.1, 0.25, 0.5, 1.0, 2.0, 3.0],
            leads_rad: [5.0f64, 15.0, 25.0]
                .iter()
                .map(|d| d.to_radians())
                .collect(),
            passes: 3,
            stepover_mm: 0.5,
            fz_mm: 0.2,
            crest_fz_mm: vec![0.05, 0.2],
            revolutions: 3.0,
            points_per_rev: 180,
            title: "Trochoidal paths of ICE elements".to_string(),
        }
    }
}

struct Figure<'a> {
    cutter: &'a Cutter,
    o: &'a TrochoidOptions,
}

impl Figure<'_> {
    fn curves(&self, lead: f64, passes: std::ops::Range<usize>) -> Vec<(usize, Vec<Point3>)> {
        let o = self.o;
        let n = ((o.points_per_rev as f64) * o.revolutions).ceil().max(8.0) as usize;
        let mut out = Vec::new();
        for p in passes {
            let y = p as f64 * o.stepover_mm;
            for (hi, &z) in o.heights_mm.iter().enumerate() {
                for j in 0..self.cutter.teeth() {
                    out.push((
                        hi,
                        trochoid(self.cutter, j, z, lead, o.fz_mm, y, o.revolutions, n),
                    ));
                }
            }
        }
        out
    }

    fn iso<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, lead: f64) -> DrawResult<DB> {
        let curves = self.curves(lead, 0..self.o.passes);
        let pts = curves.iter().flat_map(|(_, c)| c.iter());
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in pts {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        // Equal scales on the three axes: a cube around the data.
        let half = (0..3).map(|k| 0.5 * (hi[k] - lo[k])).fold(0.1f64, f64::max) * 1.02;
        let mid: Vec<f64> = (0..3).map(|k| 0.5 * (hi[k] + lo[k])).collect();
        let r = |k: usize| (mid[k] - half)..(mid[k] + half);
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!(
                    "isometric view, lead {:.0}°, {} passes",
                    lead.to_degrees(),
                    self.o.passes
                ),
                caption_font(),
            )
            .margin(10)
            .margin_left(40)
            .margin_right(70)
            // plotters' 3-D axes: x, y (up), z. We map (feed, normal, lateral).
            .build_cartesian_3d(r(0), r(2), r(1))?;
        chart.with_projection(|mut pb| {
            pb.yaw = 0.7;
            pb.pitch = 0.45;
            pb.scale = 0.85;
            pb.into_matrix()
        });
        chart
            .configure_axes()
            .x_labels(5)
            .y_labels(5)
            .z_labels(5)
            .label_style(tick_font())
            .light_grid_style(RGBColor(238, 238, 238))
            .bold_grid_style(RGBColor(215, 215, 215))
            .max_light_lines(2)
            .draw()?;
        for (hi_idx, c) in &curves {
            let color = color(*hi_idx);
            chart.draw_series(LineSeries::new(
                c.iter().map(|p| (p.x, p.z, p.y)),
                color.stroke_width(1),
            ))?;
        }
        let at = |x: f64, y: f64, z: f64| (x, y, z);
        let style = tick_font();
        chart.draw_series([
            Text::new(
                "x feed [mm]",
                at(mid[0] + half, mid[2] - half, mid[1] - half),
                style.clone(),
            ),
            Text::new(
                "y lateral [mm]",
                at(mid[0] - half, mid[2] - half, mid[1] + half),
                style.clone(),
            ),
            Text::new(
                "z normal [mm]",
                at(mid[0] - half, mid[2] + half, mid[1] - half),
                style,
            ),
        ])?;
        Ok(())
    }

    fn top<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, lead: f64) -> DrawResult<DB> {
        // One pass: the loops of several passes overlap into a blur.
        let curves = self.curves(lead, 0..1);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in curves.iter().flat_map(|(_, c)| c.iter()) {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        // Equal scales: widen the shorter range to the panel's aspect ratio.
        let (w, h) = area.dim_in_pixel();
        let (pw, ph) = ((w as f64 - 100.0).max(50.0), (h as f64 - 110.0).max(50.0));
        let (mut sx, mut sy) = ((hi[0] - lo[0]) * 1.04, (hi[1] - lo[1]) * 1.04);
        if sx / pw > sy / ph {
            sy = sx * ph / pw;
        } else {
            sx = sy * pw / ph;
        }
        let (cx, cy) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]));
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!(
                    "top view of one pass, lead {:.0}°, fz {} mm",
                    lead.to_degrees(),
                    self.o.fz_mm
                ),
                caption_font(),
            )
            .margin(10)
            .x_label_area_size(50)
            .y_label_area_size(60)
            .build_cartesian_2d(cx - 0.5 * sx..cx + 0.5 * sx, cy - 0.5 * sy..cy + 0.5 * sy)?;
        style_mesh(
            chart
                .configure_mesh()
                .x_desc("x feed [mm]")
                .y_desc("y lateral [mm]"),
        )
        .draw()?;
        let mut labelled = vec![false; self.o.heights_mm.len()];
        for (hi_idx, c) in &curves {
            let color = color(*hi_idx);
            let drawn = chart.draw_series(LineSeries::new(
                c.iter().map(|p| (p.x, p.y)),
                color.stroke_width(1),
            ))?;
            if !labelled[*hi_idx] {
                labelled[*hi_idx] = true;
                let z = self.o.heights_mm[*hi_idx];
                drawn
                    .label(format!(
                        "z = {z} mm (r = {:.2} mm)",
                        self.cutter.profile_radius(z)
                    ))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
                    });
            }
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    }

    fn crest<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let o = self.o;
        let zmax = o.heights_mm.iter().cloned().fold(0.0, f64::max);
        let zmin = o.heights_mm.iter().cloned().fold(f64::INFINITY, f64::min);
        let n = 80;
        let zs: Vec<f64> = (0..=n)
            .map(|i| zmin + (zmax - zmin) * i as f64 / n as f64)
            .collect();
        let mut lines = Vec::new();
        for (fi, &fz) in o.crest_fz_mm.iter().enumerate() {
            for (li, &lead) in o.leads_rad.iter().enumerate() {
                let ys: Vec<f64> = zs
                    .iter()
                    .map(|&z| crest_between_marks_mm(self.cutter, z, fz, lead) * 1e3)
                    .collect();
                let marks: Vec<(f64, f64)> = o
                    .heights_mm
                    .iter()
                    .map(|&z| (z, crest_between_marks_mm(self.cutter, z, fz, lead) * 1e3))
                    .collect();
                lines.push((fi, li, fz, lead, ys, marks));
            }
        }
        let positive = lines
            .iter()
            .flat_map(|l| l.4.iter())
            .filter(|v| **v > 0.0 && v.is_finite());
        let lo = positive.clone().cloned().fold(f64::INFINITY, f64::min);
        let hi = positive.cloned().fold(0.0, f64::max);
        let (lo, hi) = if lo.is_finite() && hi > 0.0 {
            (lo / 1.5, hi * 1.5)
        } else {
            (1e-3, 1.0)
        };
        let mut chart = ChartBuilder::on(area)
            .caption(
                "crest between consecutive marks of the edges at tool height z",
                caption_font(),
            )
            .margin(10)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(zmin..zmax, (lo..hi).log_scale())?;
        style_mesh(
            chart
                .configure_mesh()
                .x_desc("tool height z [mm]")
                .y_desc("crest height [µm]")
                .y_label_formatter(&|v| format!("{v:.3}")),
        )
        .draw()?;
        for (fi, li, fz, lead, ys, marks) in &lines {
            let color = color(*li);
            let style = if *fi == 0 {
                color.stroke_width(2)
            } else {
                color.stroke_width(1)
            };
            let pts: Vec<(f64, f64)> = zs.iter().cloned().zip(ys.iter().cloned()).collect();
            let label = format!("fz {fz} mm, lead {:.0}°", lead.to_degrees());
            if *fi == 0 {
                chart
                    .draw_series(LineSeries::new(pts, style))?
                    .label(label)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
            } else {
                chart
                    .draw_series(DashedLineSeries::new(pts, 6, 4, style))?
                    .label(label)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 8, y)], style));
            }
            chart.draw_series(
                marks
                    .iter()
                    .map(|&(x, y)| Circle::new((x, y), 3, color.filled())),
            )?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    }
}

impl Draw for Figure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let root = root.titled(&self.o.title, title_font())?;
        let (top_row, bottom_row) = root.split_vertically(root.dim_in_pixel().1 / 2);
        let panels = top_row.split_evenly((1, self.o.leads_rad.len()));
        for (area, &lead) in panels.iter().zip(&self.o.leads_rad) {
            self.iso(area, lead)?;
        }
        let (left, right) = bottom_row.split_horizontally(bottom_row.dim_in_pixel().0 / 2);
        self.top(&left, self.o.leads_rad[0])?;
        self.crest(&right)?;
        Ok(())
    }
}

/// Draw the trochoid figure of `cutter` to `path` (SVG or PNG).
pub fn plot_trochoids(
    cutter: &Cutter,
    options: &TrochoidOptions,
    path: &Path,
) -> Result<(), PlotError> {
    let o = options;
    let bad = |m: &str| Err(PlotError::Invalid(m.to_string()));
    if cutter.teeth() == 0 {
        return bad("the cutter has no teeth");
    }
    if o.heights_mm.is_empty() || o.heights_mm.iter().any(|z| !(*z >= 0.0 && z.is_finite())) {
        return bad("tool heights must be given and not negative");
    }
    if o.leads_rad.is_empty()
        || o.leads_rad.len() > 4
        || o.leads_rad.iter().any(|b| b.is_nan() || b.abs() >= 1.5)
    {
        return bad("give one to four lead angles below 85°");
    }
    if o.passes == 0 || o.passes > 20 || o.stepover_mm.is_nan() || o.stepover_mm < 0.0 {
        return bad("passes must be 1 to 20 and the stepover not negative");
    }
    let positive = |v: f64| v > 0.0 && v.is_finite();
    if !positive(o.fz_mm) || o.crest_fz_mm.iter().any(|f| !positive(*f)) || o.crest_fz_mm.is_empty()
    {
        return bad("feeds per tooth must be positive");
    }
    if !(o.revolutions > 0.0 && o.revolutions <= 50.0) || o.points_per_rev < 8 {
        return bad("revolutions must lie in (0, 50] and points per revolution be at least 8");
    }
    let width = 560 * o.leads_rad.len().max(2) as u32;
    render(path, (width, 1120), &Figure { cutter, o })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::Shape;

    #[test]
    fn figure_svg_has_title_and_labels() {
        let c = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        let o = TrochoidOptions {
            points_per_rev: 36,
            revolutions: 1.0,
            ..TrochoidOptions::default()
        };
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("t.svg");
        plot_trochoids(&c, &o, &out).unwrap();
        let svg = std::fs::read_to_string(&out).unwrap();
        for t in [
            "Trochoidal paths of ICE elements",
            "x feed [mm]",
            "y lateral [mm]",
            "crest height [µm]",
            "tool height z [mm]",
            "fz 0.05 mm, lead 15°",
        ] {
            assert!(svg.contains(t), "missing {t}");
        }
        let bad = TrochoidOptions {
            heights_mm: vec![],
            ..o
        };
        assert!(plot_trochoids(&c, &bad, &out).is_err());
    }
}
