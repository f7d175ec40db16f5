//! Height maps as colour maps: viridis colours, a colour scale bar in µm, axes in mm, and
//! blank (white) cells where the height is NaN (not reached, or not measured).
//!
//! Large maps are block-averaged (NaN-aware) to at most a few hundred cells per side
//! before drawing, so the SVG stays small; the colour range is that of the full map.

use super::chart::{finite_range, label_font, tick_decimals, tick_font, tick_label, title_font};
use super::{Draw, DrawResult, PlotError, render};
use crate::surface::HeightMap;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Viridis, 9 stops (matplotlib).
const VIRIDIS: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (71, 44, 122),
    (59, 81, 139),
    (44, 113, 142),
    (33, 144, 141),
    (39, 173, 129),
    (92, 200, 99),
    (170, 220, 50),
    (253, 231, 37),
];

/// Viridis colour of `t` in [0, 1] (clamped; NaN gives the lowest colour).
pub fn viridis(t: f64) -> RGBColor {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let r = x - i as f64;
    let lerp = |a: u8, b: u8| (a as f64 + (b as f64 - a as f64) * r).round() as u8;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// A map reduced to at most `max_cells` per side by NaN-aware block means.
#[derive(Debug, Clone, PartialEq)]
struct Cells {
    nx: usize,
    ny: usize,
    /// Cell size, mm.
    dx_mm: f64,
    dy_mm: f64,
    z: Vec<f64>,
}

fn reduce(map: &HeightMap, max_cells: usize) -> Cells {
    let bx = map.nx.div_ceil(max_cells).max(1);
    let by = map.ny.div_ceil(max_cells).max(1);
    let nx = map.nx.div_ceil(bx);
    let ny = map.ny.div_ceil(by);
    let mut z = vec![f64::NAN; nx * ny];
    for cy in 0..ny {
        for cx in 0..nx {
            let (mut sum, mut n) = (0.0, 0usize);
            for row in cy * by..((cy + 1) * by).min(map.ny) {
                for col in cx * bx..((cx + 1) * bx).min(map.nx) {
                    let v = map.z_um[row * map.nx + col];
                    if v.is_finite() {
                        sum += v;
                        n += 1;
                    }
                }
            }
            if n > 0 {
                z[cy * nx + cx] = sum / n as f64;
            }
        }
    }
    Cells {
        nx,
        ny,
        dx_mm: map.dx_um * 1e-3 * bx as f64,
        dy_mm: map.dy_um * 1e-3 * by as f64,
        z,
    }
}

struct MapChart<'a> {
    title: &'a str,
    map: &'a HeightMap,
    cells: Cells,
    range: (f64, f64),
}

impl Draw for MapChart<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let root = root.titled(self.title, title_font())?;
        let (w, _) = root.dim_in_pixel();
        let (main, bar) = root.split_horizontally(w.saturating_sub(150));
        let m = self.map;
        let x0 = m.x0_mm - 0.5 * m.dx_um * 1e-3;
        let y0 = m.y0_mm - 0.5 * m.dy_um * 1e-3;
        let x1 = x0 + m.nx as f64 * m.dx_um * 1e-3;
        let y1 = y0 + m.ny as f64 * m.dy_um * 1e-3;
        let mut chart = ChartBuilder::on(&main)
            .margin(14)
            .x_label_area_size(55)
            .y_label_area_size(75)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        let (dx, dy) = (tick_decimals(x1 - x0), tick_decimals(y1 - y0));
        let fx = move |v: &f64| tick_label(*v, dx);
        let fy = move |v: &f64| tick_label(*v, dy);
        chart
            .configure_mesh()
            .disable_mesh()
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .x_desc("x [mm]")
            .y_desc("y [mm]")
            .axis_desc_style(label_font())
            .label_style(tick_font())
            .draw()?;
        let (lo, hi) = self.range;
        let c = &self.cells;
        chart.draw_series((0..c.ny).flat_map(|cy| {
            (0..c.nx).filter_map(move |cx| {
                let z = c.z[cy * c.nx + cx];
                if !z.is_finite() {
                    return None;
                }
                let xa = x0 + cx as f64 * c.dx_mm;
                let ya = y0 + cy as f64 * c.dy_mm;
                let xb = (xa + c.dx_mm).min(x1);
                let yb = (ya + c.dy_mm).min(y1);
                let color = viridis((z - lo) / (hi - lo));
                Some(Rectangle::new([(xa, ya), (xb, yb)], color.filled()))
            })
        }))?;

        colour_bar(&bar, lo, hi, "height [µm], 0 = reference surface")?;
        Ok(())
    }
}

/// The viridis scale bar of a colour map, from `lo` to `hi`, labelled `label`, drawn in
/// `bar` (the strip beside the map).
pub(super) fn colour_bar<DB: DrawingBackend>(
    bar: &DrawingArea<DB, Shift>,
    lo: f64,
    hi: f64,
    label: &str,
) -> DrawResult<DB> {
    colour_bar_with(bar, lo, hi, label, &viridis)
}

/// A diverging colour scale for signed values (a difference): blue below the middle, white
/// at it, red above (ColorBrewer RdBu, reversed); `t` in [0, 1], 0.5 = zero.
pub fn diverging(t: f64) -> RGBColor {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [33.0, 102.0, 172.0]),
        (0.25, [146.0, 197.0, 222.0]),
        (0.5, [247.0, 247.0, 247.0]),
        (0.75, [244.0, 165.0, 130.0]),
        (1.0, [178.0, 24.0, 43.0]),
    ];
    let t = if t.is_nan() { 0.5 } else { t.clamp(0.0, 1.0) };
    let k = STOPS
        .windows(2)
        .position(|w| t <= w[1].0)
        .unwrap_or(STOPS.len() - 2);
    let ((t0, a), (t1, b)) = (STOPS[k], STOPS[k + 1]);
    let u = (t - t0) / (t1 - t0);
    let c = |i: usize| (a[i] + u * (b[i] - a[i])).round() as u8;
    RGBColor(c(0), c(1), c(2))
}

/// [`colour_bar`] in the colours of `colour` (t in [0, 1] from `lo` to `hi`).
pub(super) fn colour_bar_with<DB: DrawingBackend>(
    bar: &DrawingArea<DB, Shift>,
    lo: f64,
    hi: f64,
    label: &str,
    colour: &dyn Fn(f64) -> RGBColor,
) -> DrawResult<DB> {
    let mut scale = ChartBuilder::on(bar)
        .margin_top(14)
        .margin_bottom(69)
        .margin_right(10)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    let dz = tick_decimals(hi - lo);
    let fz = move |v: &f64| tick_label(*v, dz);
    scale
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_label_formatter(&fz)
        .y_desc(label)
        .axis_desc_style(label_font())
        .label_style(tick_font())
        .draw()?;
    let n = 128;
    scale.draw_series((0..n).map(|i| {
        let a = lo + (hi - lo) * i as f64 / n as f64;
        let b = lo + (hi - lo) * (i + 1) as f64 / n as f64;
        let color = colour((i as f64 + 0.5) / n as f64);
        Rectangle::new([(0.0, a), (1.0, b)], color.filled())
    }))?;
    Ok(())
}

/// Draw `map` as a colour map to `path` (SVG or PNG). The picture keeps the map's aspect
/// ratio within about 900 × 900 pixels.
pub fn plot_heightmap(map: &HeightMap, title: &str, path: &Path) -> Result<(), PlotError> {
    if map.nx == 0 || map.ny == 0 || map.z_um.len() != map.nx * map.ny {
        return Err(PlotError::Invalid(format!(
            "a {} × {} height map with {} values",
            map.nx,
            map.ny,
            map.z_um.len()
        )));
    }
    if !(map.dx_um > 0.0 && map.dy_um > 0.0) {
        return Err(PlotError::Invalid(
            "the grid spacing must be positive".to_string(),
        ));
    }
    let Some((lo, hi)) = finite_range(&map.z_um, 0.0) else {
        return Err(PlotError::Empty(format!(
            "every height of '{title}' is missing"
        )));
    };
    let max_cells = match super::Format::from_path(path) {
        Some(super::Format::Png) => 450,
        _ => 220,
    };
    // Plot area about 700 px on its longer side, plus axes, title and scale bar.
    let wx = map.nx as f64 * map.dx_um;
    let wy = map.ny as f64 * map.dy_um;
    let (pw, ph) = if wx >= wy {
        (700.0, (700.0 * wy / wx).max(220.0))
    } else {
        ((700.0 * wx / wy).max(220.0), 700.0)
    };
    let size = ((pw + 89.0 + 150.0) as u32, (ph + 69.0 + 14.0 + 40.0) as u32);
    render(
        path,
        size,
        &MapChart {
            title,
            map,
            cells: reduce(map, max_cells),
            range: (lo, hi),
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_ends() {
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        assert_eq!(viridis(f64::NAN), RGBColor(68, 1, 84));
        assert_eq!(viridis(2.0), RGBColor(253, 231, 37));
    }

    #[test]
    fn reduce_averages_blocks_and_keeps_nan() {
        let mut z: Vec<f64> = (0..16).map(|i| i as f64).collect();
        for v in &mut z[8..] {
            *v = f64::NAN;
        }
        let map = HeightMap::from_rows(4, 4, 1.0, 1.0, z).unwrap();
        let c = reduce(&map, 2);
        assert_eq!((c.nx, c.ny), (2, 2));
        assert_eq!(c.z[0], (0.0 + 1.0 + 4.0 + 5.0) / 4.0);
        assert!(c.z[2].is_nan() && c.z[3].is_nan());
    }

    #[test]
    fn heightmap_svg_has_axes_and_scale() {
        let (nx, ny) = (60, 30);
        let z = (0..nx * ny)
            .map(|i| {
                if i % 7 == 0 {
                    f64::NAN
                } else {
                    ((i % nx) as f64 * 0.3).sin()
                }
            })
            .collect();
        let mut map = HeightMap::from_rows(nx, ny, 2.0, 2.0, z).unwrap();
        map.x0_mm = 1.0;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("m.svg");
        plot_heightmap(&map, "Simulated surface", &out).unwrap();
        let svg = std::fs::read_to_string(&out).unwrap();
        for t in ["Simulated surface", "x [mm]", "y [mm]", "height [µm]"] {
            assert!(svg.contains(t), "missing {t}");
        }
        let all_nan = HeightMap::new_nan(3, 3, 1.0, 1.0);
        assert!(matches!(
            plot_heightmap(&all_nan, "t", &out),
            Err(PlotError::Empty(_))
        ));
    }
}
