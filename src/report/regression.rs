//! The regression report as Markdown and HTML (with the SVG plots inline): tables of measured
//! against simulated roughness per case, the method and the findings. Rendering only: the
//! numbers come from [`crate::study::regression`], the plots from [`crate::plot::regression`].

use crate::math::trim_decimals;
use crate::study::compare::{CaseResult, Regression};
use crate::study::measured::{Param, Stat};
use crate::study::regression::{CrestPrediction, PROFILE_STEP_MM};
use crate::surface::ModelKind;
use std::fmt::Write as _;

/// A number without trailing zeros (up to 4 decimals).
fn fmt_g(v: f64) -> String {
    crate::math::trim_decimals(v, 4)
}

/// Format a statistic as `mean ± σ` (σ omitted for one sample: `mean (n = 1)`).
pub fn fmt_stat(s: &Stat, decimals: usize) -> String {
    match s.sd {
        Some(sd) => format!("{:.d$} ± {:.d$}", s.mean, sd, d = decimals),
        None => format!("{:.d$} (n = 1)", s.mean, d = decimals),
    }
}

fn teeth_list(p: &CrestPrediction) -> String {
    let t: Vec<String> = p.teeth.iter().map(|t| t.to_string()).collect();
    format!("[{}]", t.join(", "))
}

/// The row cells of the main table, shared by Markdown and HTML.
fn table_rows(r: &Regression) -> Vec<[String; 10]> {
    let mut rows = Vec::new();
    for c in &r.cases {
        for cmp in &c.comparisons {
            rows.push([
                fmt_g(c.lead_deg),
                c.side.name().to_string(),
                if cmp.parameter == "Sdq" {
                    "Sdq (a ratio, not µm)".to_string()
                } else {
                    cmp.parameter.clone()
                },
                fmt_stat(&cmp.measured, 4),
                format!("{:.4}", cmp.simulated_um),
                format!("{:.3}", cmp.ratio),
                format!("{:.3}", 1.0 / cmp.ratio),
                format!("{:+.1}", cmp.deviation_pct),
                if cmp.within_sigma { "yes" } else { "no" }.to_string(),
                if cmp.pass { "pass" } else { "FAIL" }.to_string(),
            ]);
        }
    }
    rows
}

const TABLE_HEAD: [&str; 10] = [
    "lead (°)",
    "side",
    "param",
    "measured mean ± σ (µm)",
    "simulated (µm)",
    "ratio sim/meas",
    "meas/sim",
    "deviation (%)",
    "within ±σ",
    "result",
];

fn model_rows(r: &Regression) -> Vec<[String; 11]> {
    r.cases
        .iter()
        .map(|c| {
            let p = &c.prediction;
            let radii: Vec<String> = p
                .tooth_radius_mm
                .iter()
                .map(|x| format!("{x:.4}"))
                .collect();
            [
                fmt_g(c.lead_deg),
                c.side.name().to_string(),
                match &c.zmap {
                    Some(z) => format!(
                        "simulate ({}, grid {} µm{}; teeth by the {} rule)",
                        match z.surface_model {
                            ModelKind::Ice => "ICE",
                            ModelKind::Dome => "dome",
                            ModelKind::Swept => "swept ball",
                        },
                        fmt_g(z.grid_um),
                        match z.surface_model {
                            ModelKind::Ice => format!(", Δθ {}°", fmt_g(z.dtheta_deg)),
                            ModelKind::Dome | ModelKind::Swept => String::new(),
                        },
                        p.rule
                    ),
                    None => format!("{} ({} rule)", c.model.name(), p.rule),
                },
                format!("{:.4}", p.generating_height_mm),
                radii.join(" / "),
                format!("{} (zc = {})", teeth_list(p), p.zc),
                format!("{} → {}", fmt_g(c.fz_mm), fmt_g(p.fz_eff_mm)),
                format!("{:.4}", p.crest_um),
                format!("{:.3} / {:.3}", p.contact_radius_mm, p.effective_radius_mm),
                format!("{:.1}", 100.0 * p.cutting_speed_ratio),
                match &c.zmap {
                    Some(z) => format!("{:.4} / {:.4}", z.rz_um, z.ra_um),
                    None => "—".to_string(),
                },
            ]
        })
        .collect()
}

const MODEL_HEAD: [&str; 11] = [
    "lead (°)",
    "side",
    "model",
    "generating height z (mm)",
    "tooth radii r_j(z) (mm)",
    "participating teeth",
    "fz → fz_eff (mm)",
    "crest hc (µm)",
    "R at contact / R_ef,max (mm)",
    "Vc,ef,max (% of Vc)",
    "z-map Rz / Ra (µm)",
];

/// Ranges of measured/simulated over all comparisons of one parameter.
fn ratio_range(r: &Regression, parameter: &str) -> Option<(f64, f64)> {
    let v: Vec<f64> = r
        .cases
        .iter()
        .flat_map(|c| c.comparisons.iter())
        .filter(|c| c.parameter == parameter)
        .map(|c| c.measured.mean / c.simulated_um)
        .filter(|x| x.is_finite())
        .collect();
    if v.is_empty() {
        return None;
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Some((lo, hi))
}

/// The plain-language findings: which cases fail and by how much.
fn findings(r: &Regression) -> Vec<String> {
    let mut out = Vec::new();
    let failing: Vec<&CaseResult> = r.cases.iter().filter(|c| !c.pass).collect();
    if failing.is_empty() {
        out.push(format!(
            "Every case is within ±{}% of the measured mean: the model explains the measurements to this tolerance.",
            fmt_g(r.tolerance_pct)
        ));
    } else {
        out.push(format!(
            "{} of {} cases are outside ±{}% of the measured mean: there the model does not explain the measurement.",
            failing.len(),
            r.cases.len(),
            fmt_g(r.tolerance_pct)
        ));
    }
    for p in Param::ALL.map(Param::label) {
        if let Some((lo, hi)) = ratio_range(r, p) {
            let under = r
                .cases
                .iter()
                .flat_map(|c| c.comparisons.iter())
                .filter(|c| c.parameter == p)
                .all(|c| c.simulated_um < c.measured.mean);
            let dir = if under {
                "every simulated value lies below the measurement"
            } else {
                "the simulated values straddle the measurements"
            };
            out.push(format!(
                "Measured {p} is {lo:.2}× to {hi:.2}× the simulated {p}; {dir}."
            ));
        }
    }
    if let Some(cal) = &r.calibration {
        out.push(format!(
            "With process effects calibrated ({}), a case counts as explained only by its leave-one-out prediction (refitted without it), never by the in-sample fit: leave-one-out RMS {:.1} % (see Calibration).",
            cal.parameters
                .iter()
                .map(|(n, v, s)| format!("{n} = {v:.3} ± {s:.3}"))
                .collect::<Vec<_>>()
                .join(", "),
            cal.loo_rms_pct
        ));
        return out;
    }
    if !r.process.is_off() {
        out.push(format!(
            "The simulated values include the study's process effects (minimum chip {} µm, recovery {}, texture Sq {} µm).",
            trim_decimals(r.process.min_chip_mm * 1e3, 4),
            trim_decimals(r.process.recovery, 4),
            trim_decimals(r.process.texture.map_or(0.0, |t| t.sq_mm * 1e3), 4)
        ));
        return out;
    }
    out.push(
        "The models are purely geometric: a rigid tool with the given run-out sweeping its \
         circular arcs (crest) or its edges (z-map). They have no plowing, elastic recovery or \
         side flow of the material, no tool wear or edge radius, no vibration, and no \
         measurement noise or filtering; any excess of the measured roughness over the \
         simulated one is outside what they can explain."
            .to_string(),
    );
    out
}

fn method_text(r: &Regression) -> Vec<String> {
    let mut v = vec![
        "Measured: mean and sample standard deviation σ (n − 1 convention) of the samples of \
         each case, as Marin et al. 2023, Table 2 prints them."
            .to_string(),
        "Crest model (Marin et al. 2023, §3.3, computed by `crest::tool::analyse`): the generating point of a \
         ball end at lead β lies at height z = R(1 − cos β). Paper rule: the teeth whose local \
         radius r_j(z) (run-out included) exceeds max r_j − hc(fz) cut (Marin et al. 2023, Eq 8; hc is Eq 14 \
         at the programmed fz), the marks are fz_eff = fz·Z/zc apart (Eq 7) and the crest is \
         Eq 14 with fz_eff. Exact rule: the profile is the lower envelope of every tooth's arc \
         (radius R + Δ_j, Δ_j its run-out along the normal) at its own mark, period Z·fz, and \
         the crest is its peak-to-valley height (model.md §3.2)."
            .to_string(),
        format!(
            "Simulated Rz and Ra: computed on that feed-direction profile (paper rule: circular \
             arcs of the tool radius spaced fz_eff), sampled every {} µm (or finer, so that every crest and \
             valley is a sample) over 5 sampling lengths λc chosen by ISO 4288 from RSm = fz_eff \
             (λc = 0.8 mm for 0.13 < RSm ≤ 0.4 mm). The periodic profile has no form, so no \
             filter is applied: Ra = mean |z − z̄| over the evaluation length, Rz = mean of the \
             5 peak-to-valley heights (Marin et al. 2023, Eq 15), which equals the crest hc for evenly spaced marks.",
            fmt_g(PROFILE_STEP_MM * 1e3)
        ),
        "Curvature: without a local surface radius a case is computed as on a plane, so the \
         concave and convex sides get the same prediction. With `surface_radius_mm` = Rs the \
         marks stay fz_eff apart on the surface (feed at the contact point) and the profile \
         arcs take the relative radius R·Rs/(Rs ± R) (+ convex, − concave), i.e. \
         hc ≈ fz_eff²/8·(1/R ± 1/Rs) (model.md §7)."
            .to_string(),
        format!(
            "Pass/fail: a parameter passes when |simulated − measured mean| ≤ {}% of the measured \
             mean; a case passes when all its parameters pass. 'within ±σ' is informative.",
            fmt_g(r.tolerance_pct)
        ),
    ];
    let extra = r
        .cases
        .iter()
        .flat_map(|c| c.comparisons.iter())
        .any(|k| Param::from_label(&k.parameter).is_some_and(Param::is_extra));
    if extra {
        v.push(format!(
            "Stepover direction and areal parameters (columns Sz_um, Sa_um, Rz_stepover_um, \
             Ra_stepover_um of the table): across the passes a ball end leaves arcs of radius R \
             spaced the stepover ae = {} mm (on a plane), whose Rz and Ra are computed as above \
             with λc chosen from RSm = ae. The areal surface is z(x, y) = f(x) + g(y), f the \
             case model's feed-direction profile and g that scallop profile (the lower envelope \
             of the tool's marks to second order); Sz and Sa are computed on it \
             (`crest::metrics::height_stats`: mean plane removed, no filter) over the 5λc of f \
             and one period of g.",
            r.stepover_mm.map_or("?".to_string(), fmt_g)
        ));
    }
    if let Some(z) = r.cases.iter().find_map(|c| c.zmap.as_ref()) {
        v.push(format!(
            "Simulate model: one straight pass along +x over the plane z = 0, tool axis tilted by \
             the lead in the feed plane, spindle phase 0 at the start, simulated by \
             `crest::surface::simulate` ({} model) on a window 5λc long and 5 nodes wide at {} µm; \
             Rz and Ra on its centre row as above (no filter). The crest-model columns stay for \
             reference.",
            match z.surface_model {
                ModelKind::Ice => "ICE",
                ModelKind::Dome => "dome",
                ModelKind::Swept => "swept ball",
            },
            fmt_g(z.grid_um)
        ));
    }
    v.push(format!(
        "Effective radius (Marin et al. 2023, Table 3; model.md §6): R_ef,max = R sin(β + acos((R − ap)/R)) at \
         ap = {} mm; Vc,ef/Vc = R_ef,max/R{}. It does not enter the crest; it shows how close \
         the slow tool centre is to the cut (plowing).",
        fmt_g(r.ap_mm),
        match r.cutting_speed_m_min {
            Some(vc) => format!(" (nominal Vc = {} m/min)", fmt_g(vc)),
            None => String::new(),
        }
    ));
    v
}

/// Render `report.md`. `plots` are the file names of the SVG plots written beside it.
pub fn render_markdown(r: &Regression, plots: &[(String, String)]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# {}\n", r.title);
    let _ = writeln!(
        s,
        "Made by crest {}. Regenerate, from the directory it was made in, with\n\n```sh\n{}\n```\n",
        r.version, r.command
    );
    let _ = writeln!(
        s,
        "The command exits with status {} ({}).\n",
        if r.pass { 0 } else { 1 },
        if r.pass {
            "every case within tolerance"
        } else {
            "at least one case beyond tolerance"
        }
    );
    let _ = writeln!(s, "- Measured table: `{}`", r.measured_file);
    let _ = writeln!(s, "- Study: `{}`", r.study_file);
    if let Some(src) = &r.source {
        let _ = writeln!(s, "- Source: {src}");
    }
    let _ = writeln!(
        s,
        "- Tool: `{}` (relative to the study): {}",
        r.tool_file, r.tool
    );
    let _ = writeln!(s, "- Run-out: {}", r.runout);
    let _ = writeln!(
        s,
        "- Tolerance: ±{}% of the measured mean\n",
        fmt_g(r.tolerance_pct)
    );

    let _ = writeln!(s, "## Verdict\n");
    for f in findings(r) {
        let _ = writeln!(s, "- {f}");
    }
    let _ = writeln!(s);

    let _ = writeln!(s, "## Measured against simulated\n");
    if r.calibration.is_some() {
        let _ = writeln!(s, "{LOO_NOTE}\n");
    }
    let _ = writeln!(s, "| {} |", TABLE_HEAD.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(TABLE_HEAD.len()));
    for row in table_rows(r) {
        let row: Vec<String> = row.iter().map(|c| super::md_cell(c)).collect();
        let _ = writeln!(s, "| {} |", row.join(" | "));
    }
    let _ = writeln!(s);

    s.push_str(&super::calibration::markdown(r));

    let _ = writeln!(s, "## Model\n");
    let _ = writeln!(s, "| {} |", MODEL_HEAD.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(MODEL_HEAD.len()));
    for row in model_rows(r) {
        let row: Vec<String> = row.iter().map(|c| super::md_cell(c)).collect();
        let _ = writeln!(s, "| {} |", row.join(" | "));
    }
    let _ = writeln!(s);

    let _ = writeln!(s, "## Measured samples\n");
    // The measured files' column only when a row names one.
    let with_files = r
        .cases
        .iter()
        .any(|c| c.measured.files.iter().any(|f| !f.is_empty()));
    let (file_head, file_rule) = if with_files {
        (" measured file |", "---|")
    } else {
        ("", "")
    };
    let _ = writeln!(
        s,
        "| lead (°) | side | sample | Ra (µm) | Rz (µm) |{file_head}"
    );
    let _ = writeln!(s, "|---|---|---|---|---|{file_rule}");
    for c in &r.cases {
        let m = &c.measured;
        for (i, name) in m.samples.iter().enumerate() {
            let file = if with_files {
                format!(
                    " {} |",
                    super::md_cell(m.files.get(i).map_or("", String::as_str))
                )
            } else {
                String::new()
            };
            let ra = m
                .ra_values_um
                .get(i)
                .map_or("".to_string(), |v| format!("{v:.3}"));
            let rz = m
                .rz_values_um
                .get(i)
                .map_or("".to_string(), |v| format!("{v:.3}"));
            let _ = writeln!(
                s,
                "| {} | {} | {} | {ra} | {rz} |{file}",
                fmt_g(c.lead_deg),
                super::md_cell(c.side.name()),
                super::md_cell(name)
            );
        }
    }
    let _ = writeln!(s);

    if !plots.is_empty() {
        let _ = writeln!(s, "## Plots\n");
        for (file, caption) in plots {
            let _ = writeln!(s, "![{caption}]({file})\n");
        }
    }

    if let Some(notes) = &r.notes {
        let _ = writeln!(s, "## Discussion\n\n{}\n", notes.trim());
    }

    let _ = writeln!(s, "## Method\n");
    for m in method_text(r) {
        let _ = writeln!(s, "- {m}");
    }
    s
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Inline Markdown code spans (`x`) to `<code>`, on escaped text.
fn inline_code(s: &str) -> String {
    let e = esc(s);
    let mut out = String::new();
    for (i, part) in e.split('`').enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<code>{part}</code>");
        } else {
            out.push_str(part);
        }
    }
    out
}

/// Render `report.html`: the same content as the Markdown, with the SVG plots inline.
/// `plots` holds (caption, SVG text).
pub fn render_html(r: &Regression, plots: &[(String, String)]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>",
        esc(&r.title)
    );
    let _ = writeln!(
        s,
        "<style>body{{font-family:sans-serif;max-width:72em;margin:2em auto;padding:0 1em;line-height:1.4}}\
         table{{border-collapse:collapse;margin:1em 0}}th,td{{border:1px solid #bbb;padding:.25em .6em;text-align:right}}\
         th{{background:#eee}}td:nth-child(2),td:nth-child(3){{text-align:left}}.fail{{color:#b00;font-weight:bold}}\
         .pass{{color:#070}}pre,code{{background:#f4f4f4}}pre{{padding:.5em;overflow-x:auto}}</style>\n</head>\n<body>"
    );
    let _ = writeln!(s, "<h1>{}</h1>", esc(&r.title));
    let _ = writeln!(
        s,
        "<p>Made by crest {}. Regenerate, from the directory it was made in, with</p>\n<pre>{}</pre>",
        esc(&r.version),
        esc(&r.command)
    );
    let _ = writeln!(
        s,
        "<p>The command exits with status {}.</p>\n<ul>",
        if r.pass { 0 } else { 1 }
    );
    let _ = writeln!(
        s,
        "<li>Measured table: <code>{}</code></li>",
        esc(&r.measured_file)
    );
    let _ = writeln!(s, "<li>Study: <code>{}</code></li>", esc(&r.study_file));
    if let Some(src) = &r.source {
        let _ = writeln!(s, "<li>Source: {}</li>", esc(src));
    }
    let _ = writeln!(
        s,
        "<li>Tool: <code>{}</code> (relative to the study): {}</li>\n<li>Run-out: {}</li>\n<li>Tolerance: ±{}% of the measured mean</li>\n</ul>",
        esc(&r.tool_file),
        esc(&r.tool),
        esc(&r.runout),
        fmt_g(r.tolerance_pct)
    );
    let _ = writeln!(s, "<h2>Verdict</h2>\n<ul>");
    for f in findings(r) {
        let _ = writeln!(s, "<li>{}</li>", esc(&f));
    }
    let _ = writeln!(
        s,
        "</ul>\n<h2>Measured against simulated</h2>\n{}<table>\n<tr>",
        if r.calibration.is_some() {
            format!("<p>{}</p>\n", esc(LOO_NOTE))
        } else {
            String::new()
        }
    );
    for h in TABLE_HEAD {
        let _ = write!(s, "<th>{}</th>", esc(h));
    }
    let _ = writeln!(s, "</tr>");
    for row in table_rows(r) {
        let _ = write!(s, "<tr>");
        for (i, cell) in row.iter().enumerate() {
            if i == row.len() - 1 {
                let class = if cell == "pass" { "pass" } else { "fail" };
                let _ = write!(s, "<td class=\"{class}\">{}</td>", esc(cell));
            } else {
                let _ = write!(s, "<td>{}</td>", esc(cell));
            }
        }
        let _ = writeln!(s, "</tr>");
    }
    let _ = writeln!(s, "</table>");
    s.push_str(&super::calibration::html(r));
    let _ = writeln!(s, "<h2>Model</h2>\n<table>\n<tr>");
    for h in MODEL_HEAD {
        let _ = write!(s, "<th>{}</th>", esc(h));
    }
    let _ = writeln!(s, "</tr>");
    for row in model_rows(r) {
        let _ = write!(s, "<tr>");
        for cell in &row {
            let _ = write!(s, "<td>{}</td>", esc(cell));
        }
        let _ = writeln!(s, "</tr>");
    }
    let _ = writeln!(s, "</table>");
    if !plots.is_empty() {
        let _ = writeln!(s, "<h2>Plots</h2>");
        for (caption, svg) in plots {
            let body = svg
                .find("<svg")
                .map_or(svg.as_str(), |i| &svg[i..])
                .trim_end();
            let _ = writeln!(
                s,
                "<figure>\n{body}\n<figcaption>{}</figcaption>\n</figure>",
                esc(caption)
            );
        }
    }
    if let Some(notes) = &r.notes {
        let _ = writeln!(s, "<h2>Discussion</h2>");
        for para in notes.trim().split("\n\n") {
            let _ = writeln!(s, "<p>{}</p>", inline_code(para.trim()));
        }
    }
    let _ = writeln!(s, "<h2>Method</h2>\n<ul>");
    for m in method_text(r) {
        let _ = writeln!(s, "<li>{}</li>", inline_code(&m));
    }
    let _ = writeln!(s, "</ul>\n</body>\n</html>");
    s
}

pub use super::calibration::{calibration_csv, calibration_json};

/// What the simulated column holds in a calibrated report.
const LOO_NOTE: &str = "With --free, the simulated column (and the plots) hold each case's leave-one-out prediction: the model refitted without that case. The model table below shows the model fitted on every case.";

/// A report's figure that could not be drawn.
#[derive(Debug, thiserror::Error)]
#[error("cannot draw the {param} plot: {error}")]
pub struct PlotFailed {
    /// The figure's parameter (`Rz`, `Sa`, …).
    pub param: String,
    /// Why.
    pub error: crate::plot::PlotError,
}

/// Every file of a report, rendered in memory: `rz.svg` and `ra.svg`, and `sz.svg`, `sa.svg`,
/// `rz-stepover.svg`, `ra-stepover.svg` (for the parameters the table has), `report.html` and
/// `report.md`, as `(file name, bytes)`.
pub fn outputs(reg: &Regression) -> Result<Vec<(String, Vec<u8>)>, PlotFailed> {
    let mut plots: Vec<(String, String, String)> = Vec::new(); // (file, caption, svg)
    for p in Param::ALL {
        let (param, file) = (p.label(), format!("{}.svg", p.file_stem()));
        if reg
            .cases
            .iter()
            .any(|c| c.comparisons.iter().any(|k| k.parameter == param))
        {
            let svg =
                crate::plot::regression::render_plot(reg, param).map_err(|error| PlotFailed {
                    param: param.to_string(),
                    error,
                })?;
            let caption = format!(
                "{param}: measured mean ± σ and samples against simulated, per lead angle and side"
            );
            plots.push((file, caption, svg));
        }
    }
    let md_plots: Vec<(String, String)> = plots
        .iter()
        .map(|(f, c, _)| (f.clone(), c.clone()))
        .collect();
    let html_plots: Vec<(String, String)> = plots
        .iter()
        .map(|(_, c, s)| (c.clone(), s.clone()))
        .collect();
    let markdown = render_markdown(reg, &md_plots);
    let html = render_html(reg, &html_plots);
    let mut out: Vec<(String, Vec<u8>)> = plots
        .into_iter()
        .map(|(f, _, svg)| (f, svg.into_bytes()))
        .collect();
    out.push(("report.html".to_string(), html.into_bytes()));
    out.push(("report.md".to_string(), markdown.into_bytes()));
    Ok(out)
}
