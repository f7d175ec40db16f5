//! `x,y,z` point lists on a regular grid (all µm): one point per line in any order, optional
//! header line (`x,y,z`, `x_um,y_um,z_um`, …), separators like the grid CSV. The grid steps
//! are the smallest spacing between distinct coordinates; every coordinate must sit on that
//! grid (within 1e-3 of a step). Nodes without a line stay `NaN`.

use std::io::Write;

use super::csv_grid::{detect_sep, split};
use super::{FormatError, fmt_value, parse_value};
use crate::surface::HeightMap;

/// True when the first non-comment line is a three-field `x, y, z` header.
pub(crate) fn has_xyz_header(text: &str) -> bool {
    let Some(line) = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
    else {
        return false;
    };
    let f = split(line, detect_sep(line));
    f.len() == 3
        && ["x", "y", "z"].iter().zip(&f).all(|(k, s)| {
            s.trim()
                .trim_matches('"')
                .to_ascii_lowercase()
                .starts_with(k)
        })
}

struct Axis {
    origin: f64,
    step: f64,
    n: usize,
}

/// Grid of the coordinates `v` (with their lines for errors).
/// Nodes a point list may imply beyond 64 per point.
const SMALL_LIST_NODES: usize = 256 * 256;

fn axis(v: &[(f64, usize)], name: &str) -> Result<Option<Axis>, FormatError> {
    let mut u: Vec<f64> = v.iter().map(|p| p.0).collect();
    u.sort_by(f64::total_cmp);
    let lo = u[0];
    let hi = u[u.len() - 1];
    let scale = lo.abs().max(hi.abs()).max(1e-12);
    u.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * scale);
    if u.len() == 1 {
        return Ok(None);
    }
    let step = u
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    let kmax = ((hi - lo) / step).round();
    if kmax > 1e8 {
        return Err(FormatError::file(format!(
            "{name} coordinates span {} steps of {step}: not a regular grid",
            kmax
        )));
    }
    for &(x, line) in v {
        let k = (x - lo) / step;
        if (k - k.round()).abs() > 1e-3 {
            return Err(FormatError::line(
                line,
                if name == "x" { 1 } else { 2 },
                format!("{name} = {x} is not on the grid (origin {lo}, step {step} µm)"),
            ));
        }
    }
    // Refine the step over the whole span (less rounding than one difference).
    let step = (hi - lo) / kmax;
    Ok(Some(Axis {
        origin: lo,
        step,
        n: kmax as usize + 1,
    }))
}

pub(crate) fn parse(text: &str) -> Result<HeightMap, FormatError> {
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    let mut zs = Vec::new();
    let mut sep = None;
    let mut header_done = false;
    for (idx, raw) in text.lines().enumerate() {
        let line_no = idx + 1;
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let s = *sep.get_or_insert_with(|| detect_sep(line));
        let f = split(line, s);
        if !header_done && xs.is_empty() && f.iter().all(|v| parse_value(v).is_none()) {
            header_done = true;
            continue;
        }
        if f.len() != 3 {
            return Err(FormatError::line(
                line_no,
                0,
                format!("expected 3 fields x,y,z, found {}", f.len()),
            ));
        }
        let mut vals = [0.0; 3];
        for k in 0..3 {
            let v = parse_value(f[k]).ok_or_else(|| {
                FormatError::line(
                    line_no,
                    k + 1,
                    format!("expected a number, found {:?}", f[k].trim()),
                )
            })?;
            if k < 2 && !v.is_finite() {
                return Err(FormatError::line(
                    line_no,
                    k + 1,
                    "a coordinate is missing (only z may be NaN)",
                ));
            }
            vals[k] = v;
        }
        xs.push((vals[0], line_no));
        ys.push((vals[1], line_no));
        zs.push(vals[2]);
    }
    if xs.is_empty() {
        return Err(FormatError::file("no points found"));
    }
    let ax = axis(&xs, "x")?;
    let ay = axis(&ys, "y")?;
    let (ax, ay) = match (ax, ay) {
        (None, None) => {
            return Err(FormatError::file(
                "all points share one x and one y: no grid spacing",
            ));
        }
        (Some(a), None) => {
            let s = a.step;
            (
                a,
                Axis {
                    origin: ys[0].0,
                    step: s,
                    n: 1,
                },
            )
        }
        (None, Some(b)) => {
            let s = b.step;
            (
                Axis {
                    origin: xs[0].0,
                    step: s,
                    n: 1,
                },
                b,
            )
        }
        (Some(a), Some(b)) => (a, b),
    };
    // A measured point list fills most of its grid; one that leaves more than 63 of every 64
    // nodes empty (beyond a 256 × 256 allowance for small lists) is not a grid. The bound also
    // keeps a few bytes from implying a million-node map: such inputs of 22-55 bytes took 1-3 s
    // of areal parameters each in the fuzz corpus (reports/fuzzing.md).
    let nodes = ax.n.saturating_mul(ay.n);
    if nodes > 64 * xs.len() + SMALL_LIST_NODES {
        return Err(FormatError::file(format!(
            "{} points would fill a {}×{} grid: too sparse to be a grid",
            xs.len(),
            ax.n,
            ay.n
        )));
    }
    let mut z = vec![f64::NAN; nodes];
    let mut seen = vec![0usize; nodes];
    for (i, &zv) in zs.iter().enumerate() {
        let col = ((xs[i].0 - ax.origin) / ax.step).round() as usize;
        let row = ((ys[i].0 - ay.origin) / ay.step).round() as usize;
        let k = row * ax.n + col;
        if seen[k] != 0 {
            return Err(FormatError::line(
                xs[i].1,
                0,
                format!(
                    "point ({}, {}) repeats the node of line {}",
                    xs[i].0, ys[i].0, seen[k]
                ),
            ));
        }
        seen[k] = xs[i].1;
        z[k] = zv;
    }
    let mut map = HeightMap::from_rows(ax.n, ay.n, ax.step, ay.step, z)
        .ok_or_else(|| FormatError::file("internal: node count mismatch"))?;
    map.x0_mm = ax.origin / 1000.0;
    map.y0_mm = ay.origin / 1000.0;
    Ok(map)
}

pub(crate) fn write(w: &mut dyn Write, map: &HeightMap) -> std::io::Result<()> {
    let mut csv = csv::Writer::from_writer(w);
    csv.write_record(["x_um", "y_um", "z_um"])?;
    let x0 = map.x0_mm * 1000.0;
    let y0 = map.y0_mm * 1000.0;
    for row in 0..map.ny {
        let y = (y0 + row as f64 * map.dy_um).to_string();
        for (col, v) in map.row(row).iter().enumerate() {
            let x = x0 + col as f64 * map.dx_um;
            csv.write_record([x.to_string(), y.clone(), fmt_value(*v)])?;
        }
    }
    csv.flush()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::Location;

    #[test]
    fn any_order_with_gap() {
        let m = parse("x,y,z\n2,0,3\n0,0,1\n0,1.5,4\n2,1.5,6\n4,1.5,7\n").unwrap();
        assert_eq!((m.nx, m.ny), (3, 2));
        assert_eq!((m.dx_um, m.dy_um), (2.0, 1.5));
        assert_eq!(m.get(0, 0), 1.0);
        assert_eq!(m.get(1, 0), 3.0);
        assert!(m.get(2, 0).is_nan());
        assert_eq!(m.get(2, 1), 7.0);
    }

    #[test]
    fn off_grid_point_names_line() {
        let e = parse("0 0 1\n1 0 1\n2.5 0 1\n").unwrap_err();
        assert_eq!(e.at, Location::Line { line: 3, field: 1 });
    }

    #[test]
    fn a_few_points_spanning_a_huge_grid_are_refused() {
        // Three points implying 2 × 500 001 nodes (a fuzz corpus input).
        let e = parse("0,0,2\n0,1,2\n1,5E5,4\n").unwrap_err();
        assert!(e.message.contains("2×500001 grid: too sparse"), "{e}");
        // At the bound: 64 per point plus the small-list allowance is still a grid.
        let n = 64 * 3 + SMALL_LIST_NODES;
        let m = parse(&format!("0,0,1\n1,0,1\n{},0,2\n", n - 1)).unwrap();
        assert_eq!((m.nx, m.ny), (n, 1));
        assert!(parse(&format!("0,0,1\n1,0,1\n{},0,2\n", n)).is_err());
    }

    #[test]
    fn duplicate_node_is_an_error() {
        let e = parse("0,0,1\n1,0,1\n0,0,2\n").unwrap_err();
        assert!(e.message.contains("line 1"), "{e}");
        assert_eq!(e.at, Location::Line { line: 3, field: 0 });
    }

    #[test]
    fn header_detection() {
        assert!(has_xyz_header("x_um,y_um,z_um\n1,2,3\n"));
        assert!(!has_xyz_header("1,2,3\n"));
    }
}
