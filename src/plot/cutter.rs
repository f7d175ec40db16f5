//! The cutter's profile: its meridian (r, z) from the tip upward and its mirror image through
//! the axis, at equal scales, with the joins between its lines and arcs marked. One figure
//! documents a shape (round insert, APT cutter, profile, circle-segment family).

use super::chart::{color, draw_legend, style_mesh, title_font};
use super::{Draw, DrawResult, PlotError, render};
use crate::tool::Cutter;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

struct Figure {
    title: String,
    profile: Vec<[f64; 2]>,
    joins: Vec<[f64; 2]>,
}

impl Draw for Figure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let root = root.titled(&self.title, title_font())?;
        let (lo_z, hi_z) = self
            .profile
            .iter()
            .fold((0.0f64, 0.0f64), |(a, b), p| (a.min(p[1]), b.max(p[1])));
        let r = self.profile.iter().fold(0.0f64, |m, p| m.max(p[0]));
        // Equal scales: widen the shorter extent to the area's aspect ratio.
        let (pw, ph) = root.dim_in_pixel();
        let (pw, ph) = (
            pw.saturating_sub(110).max(1) as f64,
            ph.saturating_sub(90).max(1) as f64,
        );
        let mut sx = 2.0 * r * 1.1;
        let mut sy = (hi_z - lo_z) * 1.1 + 0.05 * r;
        if sx / sy > pw / ph {
            sy = sx * ph / pw;
        } else {
            sx = sy * pw / ph;
        }
        let cy = 0.5 * (lo_z + hi_z);
        let mut chart = ChartBuilder::on(&root)
            .margin(10)
            .x_label_area_size(50)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.5 * sx..0.5 * sx, cy - 0.5 * sy..cy + 0.5 * sy)?;
        style_mesh(
            chart
                .configure_mesh()
                .x_desc("r [mm]")
                .y_desc("z above the tip [mm]"),
        )
        .draw()?;
        let (blue, grey) = (color(2), color(7));
        chart
            .draw_series(LineSeries::new(
                self.profile.iter().map(|p| (p[0], p[1])),
                blue.stroke_width(3),
            ))?
            .label("meridian")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], blue.stroke_width(3))
            });
        chart
            .draw_series(LineSeries::new(
                self.profile.iter().map(|p| (-p[0], p[1])),
                grey.stroke_width(2),
            ))?
            .label("mirror image")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(2))
            });
        let top = cy + 0.5 * sy;
        chart.draw_series(DashedLineSeries::new(
            [(0.0, cy - 0.5 * sy), (0.0, top)],
            6,
            4,
            BLACK.stroke_width(1),
        ))?;
        chart
            .draw_series(
                self.joins
                    .iter()
                    .map(|p| Circle::new((p[0], p[1]), 4, BLACK.filled())),
            )?
            .label("joins of lines and arcs")
            .legend(|(x, y)| Circle::new((x + 10, y), 4, BLACK.filled()));
        draw_legend(&mut chart, SeriesLabelPosition::UpperMiddle)?;
        Ok(())
    }
}

/// Draw the profile of `cutter` to `path` (SVG or PNG), with its side drawn `side_mm` above
/// the end; `title` (default: the cutter's description).
pub fn plot_cutter(
    cutter: &Cutter,
    title: Option<&str>,
    side_mm: f64,
    path: &Path,
) -> Result<(), PlotError> {
    let m = cutter
        .meridian()
        .map_err(|e| PlotError::Invalid(e.to_string()))?;
    if !(side_mm.is_finite() && side_mm >= 0.0) {
        return Err(PlotError::Invalid(format!(
            "the side above the end must not be negative, got {side_mm} mm"
        )));
    }
    let profile = m.polyline(1e-3, side_mm);
    let mut joins: Vec<[f64; 2]> = m.segments().iter().map(|s| s.start()).collect();
    joins.extend(m.segments().last().map(|s| s.end()));
    // Only the joins on the drawn part (an APT cutter's top lies far above its end).
    let top = profile.iter().fold(f64::MIN, |t, p| t.max(p[1]));
    joins.retain(|p| p[1] <= top + 1e-9);
    let figure = Figure {
        title: title.map_or_else(|| cutter.describe(), str::to_string),
        profile,
        joins,
    };
    render(path, (900, 800), &figure)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::{Shape, meridian};

    #[test]
    fn a_barrel_draws_with_its_description() {
        let m = meridian::barrel(8.0, 250.0, 10.0, 1.0).unwrap();
        let c = Cutter::new(Shape::Profile(m), 8.0, 4, 0.0);
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("b.svg");
        plot_cutter(&c, None, 2.0, &out).unwrap();
        let svg = std::fs::read_to_string(&out).unwrap();
        assert!(svg.contains("barrel R 8 mm"), "title");
        assert!(svg.contains("z above the tip [mm]"));
        assert!(plot_cutter(&c, None, -1.0, &out).is_err());
    }
}
