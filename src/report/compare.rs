//! The record of `crest compare` (a prediction against a measurement) and its rendering as
//! Markdown and HTML with the figures of [`crate::plot::compare`] inline. The numbers come
//! from `crate::pipeline::compare`; nothing here computes them.

use std::fmt::Write as _;

use crate::metrics::{LaySpectra, Level};
use crate::surface::HeightMap;

/// The parameters compared, in the table's order.
pub const COMPARED: [&str; 12] = [
    "Sa", "Sq", "Sp", "Sv", "Sz", "Ssk", "Sku", "Sdq", "Sdr", "Sal", "Str", "Std",
];

/// The parameters the verdict holds to the tolerance (with the feed-mark period and the
/// stepover): Ssk changes sign around 0, Str is undefined on a 1-D lay and Std is an angle,
/// so a percentage of them means nothing; they are reported, not judged.
pub const JUDGED: [&str; 9] = ["Sa", "Sq", "Sp", "Sv", "Sz", "Sku", "Sdq", "Sdr", "Sal"];

/// Default tolerance of the verdict, %.
pub const DEFAULT_TOLERANCE_PCT: f64 = 20.0;

/// Options of a comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompareOptions {
    /// F-operator (form removal).
    pub level: Level,
    /// S-filter nesting index, µm.
    pub lambda_s_um: Option<f64>,
    /// L-filter nesting index, µm.
    pub lambda_c_um: Option<f64>,
    /// Register the prediction onto the measurement (feed direction, then shift).
    pub register: bool,
    /// A judged value passes within this percentage of the measured one.
    pub tolerance_pct: f64,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            level: Level::Plane,
            lambda_s_um: None,
            lambda_c_um: None,
            register: true,
            tolerance_pct: DEFAULT_TOLERANCE_PCT,
        }
    }
}

/// A predicted and a measured value and their difference, % of the measured one.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Pair {
    /// Predicted value.
    pub predicted: f64,
    /// Measured value.
    pub measured: f64,
    /// `(predicted − measured) / |measured| · 100` (`NaN` when undefined).
    pub diff_pct: f64,
}

impl Pair {
    /// The pair and its difference.
    pub fn new(predicted: f64, measured: f64) -> Pair {
        let d = (predicted - measured) / measured.abs() * 100.0;
        Pair {
            predicted,
            measured,
            diff_pct: if d.is_finite() { d } else { f64::NAN },
        }
    }
}

/// The outcome of a comparison.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// The predicted file, as given.
    pub predicted_name: String,
    /// The measured file, as given.
    pub measured_name: String,
    /// The options.
    pub options: CompareOptions,
    /// The parameters of [`COMPARED`], in that order.
    pub params: Vec<(&'static str, Pair)>,
    /// Feed direction of the prediction in its own frame and of the measurement, degrees.
    pub feed_direction_deg: [f64; 2],
    /// Rotation applied to the prediction, degrees counter-clockwise.
    pub rotation_deg: f64,
    /// Shift applied to the rotated prediction, µm.
    pub shift_um: [f64; 2],
    /// Pearson correlation of the two processed maps over the evaluation area.
    pub correlation: f64,
    /// Sq of the difference map (predicted − measured), µm.
    pub residual_sq_um: f64,
    /// Feed-mark period along the feed (from the 1-D spectra), µm.
    pub feed_period: Pair,
    /// Stepover across the feed (from the 1-D spectra), µm.
    pub stepover: Pair,
    /// The processed prediction on the evaluation area (measured grid).
    pub predicted: HeightMap,
    /// The processed measurement on the evaluation area.
    pub measured: HeightMap,
    /// `predicted − measured`, µm.
    pub difference: HeightMap,
    /// Profiles and spectra of the prediction along and across the measured feed direction.
    pub lay_predicted: Option<LaySpectra>,
    /// Profiles and spectra of the measurement along and across its feed direction.
    pub lay_measured: Option<LaySpectra>,
    /// The judged values beyond the tolerance (empty: pass).
    pub failing: Vec<String>,
}

impl Comparison {
    /// Whether every judged value is within the tolerance.
    pub fn pass(&self) -> bool {
        self.failing.is_empty()
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A number to four significant decimals, `–` when undefined.
fn num(v: f64) -> String {
    if v.is_finite() {
        crate::math::trim_decimals(v, 4)
    } else {
        "–".to_string()
    }
}

fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{v:+.1}")
    } else {
        "–".to_string()
    }
}

/// The unit of a compared parameter.
fn unit(symbol: &str) -> &'static str {
    match symbol {
        "Sa" | "Sq" | "Sp" | "Sv" | "Sz" | "Sal" => "µm",
        "Sdr" => "%",
        "Std" => "°",
        "Sdq" => "µm/µm",
        _ => "1",
    }
}

/// The rows of the table: name, unit, predicted, measured, difference %, judged.
fn rows(c: &Comparison) -> Vec<[String; 6]> {
    let mut out: Vec<[String; 6]> = c
        .params
        .iter()
        .map(|(s, p)| {
            [
                s.to_string(),
                unit(s).to_string(),
                num(p.predicted),
                num(p.measured),
                pct(p.diff_pct),
                if JUDGED.contains(s) { "yes" } else { "no" }.to_string(),
            ]
        })
        .collect();
    for (name, p) in [
        ("feed-mark period", c.feed_period),
        ("stepover", c.stepover),
    ] {
        out.push([
            name.to_string(),
            "µm".to_string(),
            num(p.predicted),
            num(p.measured),
            pct(p.diff_pct),
            "yes".to_string(),
        ]);
    }
    out
}

const HEAD: [&str; 6] = [
    "parameter",
    "unit",
    "predicted",
    "measured",
    "difference (%)",
    "judged",
];

fn verdict(c: &Comparison) -> String {
    if c.pass() {
        format!(
            "PASS: every judged value is within ±{} % of the measured one.",
            num(c.options.tolerance_pct)
        )
    } else {
        format!(
            "FAIL: beyond ±{} %: {}.",
            num(c.options.tolerance_pct),
            c.failing.join(", ")
        )
    }
}

/// The registration and chain, one line each.
fn facts(c: &Comparison) -> Vec<String> {
    let opt = |v: Option<f64>| v.map_or("none".to_string(), |v| format!("{} µm", num(v)));
    vec![
        format!("Predicted map: `{}`", c.predicted_name),
        format!("Measured map: `{}`", c.measured_name),
        format!(
            "Chain (both maps, on the measured grid {} × {} µm, over their overlap of {} × {} nodes): F-operator {}, S-filter λs {}, L-filter λc {}",
            num(c.measured.dx_um),
            num(c.measured.dy_um),
            c.measured.nx,
            c.measured.ny,
            c.options.level.label(),
            opt(c.options.lambda_s_um),
            opt(c.options.lambda_c_um)
        ),
        format!(
            "Feed direction (CCW from +x): predicted {}°, measured {}°",
            num(c.feed_direction_deg[0]),
            num(c.feed_direction_deg[1])
        ),
        if c.options.register {
            format!(
                "Registration: prediction rotated by {}°, shifted by ({}, {}) µm",
                num(c.rotation_deg),
                num(c.shift_um[0]),
                num(c.shift_um[1])
            )
        } else {
            "Registration: none (--no-register), the maps laid centre on centre".to_string()
        },
        format!(
            "Correlation of the processed maps: {}; Sq of the difference map: {} µm",
            num(c.correlation),
            num(c.residual_sq_um)
        ),
    ]
}

/// A figure's content: a height map as PNG (a map's thousands of cells would make a large
/// SVG), a line chart as SVG.
enum Body {
    Png(Vec<u8>),
    Svg(String),
}

/// The figures: (file, caption, content).
fn figures(c: &Comparison) -> Result<Vec<(String, String, Body)>, crate::plot::PlotError> {
    use crate::plot::compare as pc;
    let (both, diff) = pc::ranges(&c.predicted, &c.measured, &c.difference);
    let label = "height [µm]";
    let mut out = vec![
        (
            "predicted.png".to_string(),
            "Predicted height map (processed, on the measured grid)".to_string(),
            Body::Png(pc::map_png(
                &c.predicted,
                "Predicted (processed, placed on the measured grid)",
                both,
                label,
                false,
            )?),
        ),
        (
            "measured.png".to_string(),
            "Measured height map (processed), same colour scale (dark grey = missing)".to_string(),
            Body::Png(pc::map_png(
                &c.measured,
                "Measured (processed)",
                both,
                label,
                false,
            )?),
        ),
        (
            "difference.png".to_string(),
            "Difference predicted − measured (white = equal, red = prediction higher, dark grey = missing)".to_string(),
            Body::Png(pc::map_png(
                &c.difference,
                "Difference: predicted − measured",
                diff,
                "difference [µm]",
                true,
            )?),
        ),
    ];
    if let (Some(p), Some(m)) = (&c.lay_predicted, &c.lay_measured) {
        for (along, what) in [(true, "along"), (false, "across")] {
            out.push((
                format!("profiles-{what}.svg"),
                format!("Profiles through the centre {what} the feed"),
                Body::Svg(pc::profiles_svg(p, m, along)?),
            ));
            out.push((
                format!("spectrum-{what}.svg"),
                format!("1-D spectra {what} the feed"),
                Body::Svg(pc::spectra_svg(p, m, along)?),
            ));
        }
    }
    Ok(out)
}

fn render_markdown(c: &Comparison, figs: &[(String, String, Body)], command: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Prediction against measurement\n");
    let _ = writeln!(s, "Regenerate with\n\n```\n{command}\n```\n");
    for f in facts(c) {
        let _ = writeln!(s, "- {f}");
    }
    let _ = writeln!(s, "\n**{}**\n", verdict(c));
    let _ = writeln!(s, "| {} |", HEAD.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(HEAD.len()));
    for r in rows(c) {
        let _ = writeln!(s, "| {} |", r.join(" | "));
    }
    let _ = writeln!(
        s,
        "\nDifference = (predicted − measured) / |measured| · 100. Ssk, Str and Std are reported, not judged (a sign-changing value, undefined on a 1-D lay, an angle). The feed-mark period and the stepover are the strongest peaks of the 1-D spectra along and across the feed.\n"
    );
    for (file, caption, _) in figs {
        let _ = writeln!(s, "![{caption}]({file})\n");
    }
    s
}

fn render_html(c: &Comparison, figs: &[(String, String, Body)], command: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>Prediction against measurement</title>\n<style>body{{font-family:sans-serif;max-width:72em;margin:2em auto;padding:0 1em;line-height:1.4}}table{{border-collapse:collapse;margin:1em 0}}th,td{{border:1px solid #bbb;padding:.25em .6em;text-align:right}}th{{background:#eee}}td:first-child{{text-align:left}}.fail{{color:#b00;font-weight:bold}}.pass{{color:#070;font-weight:bold}}pre,code{{background:#f4f4f4}}figure{{margin:1em 0}}</style>\n</head>\n<body>\n<h1>Prediction against measurement</h1>"
    );
    let _ = writeln!(
        s,
        "<p>Regenerate with</p>\n<pre>{}</pre>\n<ul>",
        esc(command)
    );
    for f in facts(c) {
        let _ = writeln!(s, "<li>{}</li>", esc(&f.replace('`', "")));
    }
    let _ = writeln!(
        s,
        "</ul>\n<p class=\"{}\">{}</p>\n<table>\n<tr>{}</tr>",
        if c.pass() { "pass" } else { "fail" },
        esc(&verdict(c)),
        HEAD.iter()
            .map(|h| format!("<th>{}</th>", esc(h)))
            .collect::<String>()
    );
    for r in rows(c) {
        let cells: String = r.iter().map(|v| format!("<td>{}</td>", esc(v))).collect();
        let _ = writeln!(s, "<tr>{cells}</tr>");
    }
    let _ = writeln!(s, "</table>");
    for (file, caption, body) in figs {
        let body = match body {
            Body::Png(bytes) => {
                use base64::Engine;
                format!(
                    "<img alt=\"{}\" src=\"data:image/png;base64,{}\">",
                    esc(file),
                    base64::engine::general_purpose::STANDARD.encode(bytes)
                )
            }
            Body::Svg(svg) => svg
                .find("<svg")
                .map_or(svg.as_str(), |k| &svg[k..])
                .to_string(),
        };
        let _ = writeln!(
            s,
            "<figure>{body}<figcaption>{}</figcaption></figure>",
            esc(caption)
        );
    }
    let _ = writeln!(s, "</body>\n</html>");
    s
}

/// Every output file of a comparison, rendered in memory: `compare.md`, `compare.html` (the
/// figures inline), the height maps as PNG (`predicted.png`, `measured.png`,
/// `difference.png`) and the profiles and spectra as SVG.
pub fn outputs(
    c: &Comparison,
    command: &str,
) -> Result<Vec<(String, Vec<u8>)>, crate::plot::PlotError> {
    let figs = figures(c)?;
    let md = render_markdown(c, &figs, command);
    let html = render_html(c, &figs, command);
    let mut out: Vec<(String, Vec<u8>)> = figs
        .into_iter()
        .map(|(f, _, body)| match body {
            Body::Png(bytes) => (f, bytes),
            Body::Svg(svg) => (f, svg.into_bytes()),
        })
        .collect();
    out.push(("compare.md".to_string(), md.into_bytes()));
    out.push(("compare.html".to_string(), html.into_bytes()));
    Ok(out)
}
