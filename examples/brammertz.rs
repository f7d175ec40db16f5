//! The figure of docs/process-effects.md: the engine's Rt with a minimum chip thickness against
//! Brammertz's closed form, for a 1 mm ball end and h_min = 2 µm. Run from the repository root:
//! `cargo run --release --example brammertz` (writes reports/process-brammertz/).

use crest::plot::chart::{Chart, Panel, Series, render_svg};
use crest::study::brammertz::{closed_form_mm, optimum_feed_mm, sweep};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (r, h) = (1.0, 0.002);
    let factors: Vec<f64> = (0..=16).map(|i| 1.0 + 0.125 * i as f64).collect();
    let pts = sweep(r, h, &factors, 0.0005)?;
    let s0 = optimum_feed_mm(r, h);
    let closed: Vec<(f64, f64)> = (0..=120)
        .map(|i| {
            let s = s0 * (0.6 + 2.5 * i as f64 / 120.0);
            (s * 1e3, closed_form_mm(r, s, h) * 1e3)
        })
        .collect();
    let geometric: Vec<(f64, f64)> = closed
        .iter()
        .map(|&(s, _)| (s, (s * 1e-3).powi(2) / (8.0 * r) * 1e3))
        .collect();
    let engine: Vec<(f64, f64)> = pts
        .iter()
        .map(|p| (p.s_mm * 1e3, p.engine_mm * 1e3))
        .collect();
    let chart = Chart {
        title: format!(
            "Ploughing: engine vs Brammertz (R = {r} mm, h_min = {} µm)",
            h * 1e3
        ),
        x_label: "feed s (µm)".into(),
        panels: vec![Panel {
            caption: format!(
                "minimum at s = √(2R h_min) = {:.1} µm; closed form valid to its right",
                s0 * 1e3
            ),
            y_label: "Rt (µm)".into(),
            y_range: Some((0.0, 8.0)),
            y_integer: false,
            series: vec![
                Series {
                    label: "Brammertz closed form".into(),
                    points: closed,
                    color: 0,
                    dashed: false,
                    markers: false,
                    line: true,
                },
                Series {
                    label: "geometric s²/(8R)".into(),
                    points: geometric,
                    color: 7,
                    dashed: true,
                    markers: false,
                    line: true,
                },
                Series {
                    label: "crest engine (dome, 0.5 µm grid)".into(),
                    points: engine,
                    color: 1,
                    dashed: false,
                    markers: true,
                    line: false,
                },
            ],
        }],
        size: (900, 560),
        columns: 1,
        notes: Vec::new(),
        x_integer: false,
    };
    let svg = render_svg(&chart)?;
    let dir = std::path::Path::new("reports/process-brammertz");
    let mut csv = String::from("s_mm,engine_rt_um,brammertz_rt_um,deviation_pct\n");
    for p in &pts {
        csv.push_str(&format!(
            "{:.6},{:.5},{:.5},{:.3}\n",
            p.s_mm,
            p.engine_mm * 1e3,
            p.closed_form_mm * 1e3,
            100.0 * (p.engine_mm / p.closed_form_mm - 1.0)
        ));
    }
    crest::io::write_files(
        dir,
        &[
            ("brammertz.svg".to_string(), svg.into_bytes()),
            ("brammertz.csv".to_string(), csv.into_bytes()),
        ],
    )?;
    println!("wrote {}", dir.display());
    Ok(())
}
