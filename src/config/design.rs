//! The designed-experiment file of `crest study` (001 §4 and appendix): its schema and
//! checks, read into a [`Design`].
//!
//! ```toml
//! title = "001 appendix, 16 runs"
//! surface = "plane"
//! tool = "../synth/torus-r5-rc1.5.toml"   # relative to the design file
//! rpm = 15000.0
//! grid_um = 4.0
//! pattern = "one-way"                      # or "zigzag"
//! model = "ice"                            # or "dome"
//! step_rule = "exact"                      # or "convention-b"
//! responses = ["Sa", "Sq", "Sz"]
//! [factors]
//! yaw_deg = [0, 20]
//! tilt_deg = [1, 10]
//! scallop_um = [5, 10]                     # or stepover_mm
//! feed_mm_min = [2000, 4000]
//! [uncertainty]                            # optional: inputs of --monte-carlo
//! runout_offset_um = 1.0                   # as the regression study's (config::uncertainty)
//! tooth_deviation_um = 1.0
//! spindle_phase = true
//! ```

use super::ConfigError;
use crate::parse::Span;
use crate::study::design::{Design, FactorLevels, StepRule};
use crate::surface::ModelKind;
use crate::synth::Pattern;
use serde::Deserialize;
use toml::Spanned;

/// Largest number of runs a design may expand to.
pub const MAX_RUNS: usize = 10_000;
/// Smallest scallop height of a design, µm (1 nm, the smallest feed per tooth).
pub const MIN_SCALLOP_UM: f64 = 1e-3;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FactorsFile {
    yaw_deg: Option<Spanned<Vec<f64>>>,
    tilt_deg: Option<Spanned<Vec<f64>>>,
    lead_deg: Option<Spanned<Vec<f64>>>,
    scallop_um: Option<Spanned<Vec<f64>>>,
    stepover_mm: Option<Spanned<Vec<f64>>>,
    feed_mm_min: Option<Spanned<Vec<f64>>>,
}

#[derive(Deserialize)]
#[serde(rename_all = "kebab-case")]
enum PatternName {
    OneWay,
    Zigzag,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DesignFile {
    #[serde(default)]
    title: String,
    #[serde(default)]
    source: String,
    surface: Spanned<String>,
    tool: std::path::PathBuf,
    rpm: Spanned<f64>,
    grid_um: Spanned<f64>,
    window_mm: Option<Spanned<super::Fixed<2>>>,
    pattern: Option<Spanned<PatternName>>,
    model: Option<Spanned<ModelKind>>,
    dtheta_deg: Option<Spanned<f64>>,
    step_rule: Option<Spanned<StepRule>>,
    responses: Spanned<Vec<String>>,
    factors: FactorsFile,
    uncertainty: Option<super::uncertainty::UncertaintyFile>,
}

/// The first line that starts with `key` (for rules about a whole table), at its first
/// character: the column counts the bytes of its indentation ([`Span::NONE`] when no line
/// does).
fn key_position(text: &str, key: &str) -> Span {
    let mut start = 0;
    for (i, whole) in text.split_inclusive('\n').enumerate() {
        let l = whole.strip_suffix('\n').unwrap_or(whole);
        let l = l.strip_suffix('\r').unwrap_or(l);
        let lead = l.len() - l.trim_start().len();
        if l.trim_start().starts_with(key) {
            return Span {
                offset: start + lead,
                len: 0,
                line: u32::try_from(i + 1).unwrap_or(u32::MAX),
                column: u32::try_from(lead + 1).unwrap_or(u32::MAX),
            };
        }
        start += whole.len();
    }
    Span::NONE
}

/// Parse a design file; `file` names it in errors (line and column of the key or value).
pub fn parse_design(text: &str, file: &str) -> Result<Design, ConfigError> {
    let d: DesignFile = super::from_toml(text, file)?;
    let at = |pos: usize, message: String| ConfigError::at(file, text, pos, message);
    let at_key =
        |key: &str, message: String| ConfigError::new(file, key_position(text, key), message);
    let positive = |key: &str, v: &Spanned<f64>| {
        let x = *v.get_ref();
        if x > 0.0 && x.is_finite() {
            Ok(x)
        } else {
            Err(at(
                v.span().start,
                format!("{key} must be positive, got {x}"),
            ))
        }
    };
    let rpm = positive("rpm", &d.rpm)?;
    let (rlo, rhi) = crate::math::limits::RPM;
    if !(rlo..=rhi).contains(&rpm) {
        return Err(at(
            d.rpm.span().start,
            format!("rpm must lie between {rlo} and {rhi}, got {rpm}"),
        ));
    }
    let grid_um = positive("grid_um", &d.grid_um)?;
    let window_mm = match &d.window_mm {
        Some(w) => {
            let [a, b] = w.get_ref().0;
            if !(a > 0.0 && a.is_finite() && b > 0.0 && b.is_finite()) {
                return Err(at(
                    w.span().start,
                    format!("window_mm must be positive, got [{a}, {b}]"),
                ));
            }
            Some([a, b])
        }
        None => None,
    };
    if d.surface.get_ref() != "plane" {
        return Err(at(
            d.surface.span().start,
            format!(
                "crest study simulates unit cells of a plane; surface '{}' is not supported",
                d.surface.get_ref()
            ),
        ));
    }
    let dtheta_deg = match &d.dtheta_deg {
        Some(v) => {
            let x = *v.get_ref();
            let lo = crate::math::limits::MIN_DTHETA_DEG;
            if !(x.is_finite() && x >= lo && x <= 90.0) {
                return Err(at(
                    v.span().start,
                    format!("dtheta_deg must lie in [{lo}, 90], got {x}"),
                ));
            }
            Some(x)
        }
        None => None,
    };
    for r in d.responses.get_ref() {
        match crate::metrics::Param::from_symbol(r) {
            Some(p) if !p.is_profile() => {}
            _ => {
                return Err(at(
                    d.responses.span().start,
                    format!("responses: '{r}' is not an areal (ISO 25178) parameter"),
                ));
            }
        }
    }
    if d.responses.get_ref().is_empty() {
        return Err(at(
            d.responses.span().start,
            "responses must name at least one parameter".into(),
        ));
    }
    let f = &d.factors;
    match (&f.scallop_um, &f.stepover_mm) {
        (Some(_), Some(s)) => {
            return Err(at(
                s.span().start,
                "give scallop_um or stepover_mm, not both".into(),
            ));
        }
        (None, None) => {
            return Err(at_key(
                "[factors]",
                "factors need scallop_um or stepover_mm".into(),
            ));
        }
        _ => {}
    }
    if f.feed_mm_min.is_none() {
        return Err(at_key("[factors]", "factors need feed_mm_min".into()));
    }
    if let (Some(l), true) = (&f.lead_deg, f.tilt_deg.is_some() || f.yaw_deg.is_some()) {
        return Err(at(
            l.span().start,
            "lead_deg excludes tilt_deg and yaw_deg (a lead is a tilt with yaw 0)".into(),
        ));
    }
    let mut runs = 1usize;
    let mut levels =
        |key: &str, v: &Option<Spanned<Vec<f64>>>| -> Result<Option<Vec<f64>>, ConfigError> {
            let Some(v) = v else { return Ok(None) };
            let list = v.get_ref();
            if list.is_empty() {
                return Err(at(
                    v.span().start,
                    format!("{key} needs at least one level"),
                ));
            }
            let ok = list.iter().all(|x| {
                x.is_finite()
                    && match key {
                        // A scallop under 1 nm is not machining (as a feed per tooth).
                        "scallop_um" => *x >= MIN_SCALLOP_UM && *x <= 1e4,
                        "stepover_mm" => *x > 0.0 && *x <= 1e4,
                        "feed_mm_min" => {
                            let (lo, hi) = crate::math::limits::FEED_MM_MIN;
                            (lo..=hi).contains(x)
                        }
                        "tilt_deg" | "lead_deg" => (0.0..90.0).contains(x),
                        _ => true,
                    }
            });
            if !ok {
                return Err(at(
                    v.span().start,
                    format!(
                        "{key} has a level out of range: {list:?} ({})",
                        match key {
                            "scallop_um" => format!("{MIN_SCALLOP_UM} to 1e4 µm"),
                            "stepover_mm" => "above 0, at most 1e4 mm".to_string(),
                            "feed_mm_min" => format!(
                                "{} to {} mm/min",
                                crate::math::limits::FEED_MM_MIN.0,
                                crate::math::limits::FEED_MM_MIN.1
                            ),
                            "tilt_deg" | "lead_deg" => "0 to under 90°".to_string(),
                            _ => "finite".to_string(),
                        }
                    ),
                ));
            }
            runs = runs.saturating_mul(list.len());
            if runs > MAX_RUNS {
                return Err(at(
                    v.span().start,
                    format!("the design expands to more than {MAX_RUNS} runs"),
                ));
            }
            Ok(Some(list.clone()))
        };
    let uncertainty = match &d.uncertainty {
        Some(u) => {
            if let Some(pos) = u.parameter_scale_at() {
                return Err(at(
                    pos,
                    "uncertainty.parameter_scale scales calibrated parameters (crest report \
                     ‹free›); a design has none"
                        .into(),
                ));
            }
            u.to_uncertainty(text, file)?
        }
        None => crate::study::uncertainty::Uncertainty::default(),
    };
    let factors = FactorLevels {
        yaw_deg: levels("yaw_deg", &f.yaw_deg)?,
        tilt_deg: levels("tilt_deg", &f.tilt_deg)?,
        lead_deg: levels("lead_deg", &f.lead_deg)?,
        scallop_um: levels("scallop_um", &f.scallop_um)?,
        stepover_mm: levels("stepover_mm", &f.stepover_mm)?,
        feed_mm_min: levels("feed_mm_min", &f.feed_mm_min)?,
    };
    Ok(Design {
        title: d.title,
        source: d.source,
        tool: d.tool,
        rpm,
        grid_um,
        window_mm,
        pattern: match d.pattern.map(|p| p.into_inner()) {
            Some(PatternName::Zigzag) => Pattern::Zigzag,
            _ => Pattern::OneWay,
        },
        model: d.model.map(|m| m.into_inner()).unwrap_or_default(),
        dtheta_deg,
        step_rule: d.step_rule.map(|s| s.into_inner()).unwrap_or_default(),
        responses: d.responses.into_inner(),
        factors,
        uncertainty,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOE16: &str = include_str!("../../samples/studies/lavernhe-doe16.toml");
    const YAW6: &str = include_str!("../../samples/studies/lavernhe-yaw6.toml");

    #[test]
    fn the_sample_designs_parse_into_the_001_runs() {
        use crate::study::design::{Factor, StepSpec};
        let d = parse_design(DOE16, "doe16").unwrap();
        let names: Vec<String> = d.factors().into_iter().map(|f| f.name).collect();
        assert_eq!(names, ["yaw_deg", "tilt_deg", "scallop_um", "feed_mm_min"]);
        let runs = d.runs();
        assert_eq!(runs.len(), 16);
        // Appendix run 6: yaw 0, tilt 10, scallop 5 µm, feed 4000.
        let r = &runs[5];
        assert_eq!(r.run, 6);
        assert_eq!((r.yaw_deg, r.tilt_deg, r.feed_mm_min), (0.0, 10.0, 4000.0));
        assert_eq!(r.step, StepSpec::ScallopUm(5.0));
        let f = |name: &str, levels: &[f64]| Factor {
            name: name.into(),
            levels: levels.to_vec(),
        };
        assert_eq!(
            d.factors(),
            vec![
                f("yaw_deg", &[0.0, 20.0]),
                f("tilt_deg", &[1.0, 10.0]),
                f("scallop_um", &[5.0, 10.0]),
                f("feed_mm_min", &[2000.0, 4000.0]),
            ]
        );
        let y6 = parse_design(YAW6, "yaw6").unwrap();
        assert_eq!(y6.runs().len(), 48);
        assert_eq!(
            y6.factors()[0].levels,
            vec![0.0, 2.0, 5.0, 10.0, 15.0, 20.0]
        );
    }

    fn design_err(text: &str) -> (u32, String) {
        match parse_design(text, "d.toml") {
            Err(e) => (e.0.span.line, e.message()),
            Ok(_) => panic!("accepted: {text}"),
        }
    }

    #[test]
    fn bad_designs_are_rejected_at_their_line() {
        let base = "surface = \"plane\"\ntool = \"t.toml\"\nrpm = 15000.0\ngrid_um = 4.0\n\
                    responses = [\"Sq\"]\n[factors]\nscallop_um = [5.0]\nfeed_mm_min = [2000.0]\n";
        assert!(parse_design(base, "d.toml").is_ok());
        let (line, msg) = design_err(&base.replace("grid_um", "grid"));
        assert_eq!(line, 4, "{msg}");
        let (line, msg) = design_err(&format!("{base}stepover_mm = [0.5]\n"));
        assert_eq!(line, 9, "{msg}");
        assert!(msg.contains("not both"), "{msg}");
        let (line, msg) = design_err(&base.replace("rpm = 15000.0", "rpm = -1.0"));
        assert_eq!(line, 3, "{msg}");
        let (_, msg) = design_err(&format!("{base}tilt_deg = [95.0]\n"));
        assert!(msg.contains("out of range"), "{msg}");
        let (_, msg) = design_err(&format!("{base}lead_deg = [5.0]\nyaw_deg = [0.0]\n"));
        assert!(msg.contains("excludes"), "{msg}");
        let (_, msg) = design_err(&base.replace("responses = [\"Sq\"]", "responses = []"));
        assert!(msg.contains("at least one"), "{msg}");
        let (line, msg) = design_err(&base.replace("[\"Sq\"]", "[\"Sq\", \"Ra\"]"));
        assert_eq!(line, 5, "{msg}");
        assert!(msg.contains("'Ra'"), "{msg}");
        let (line, msg) = design_err(&base.replace("\"plane\"", "\"sphere\""));
        assert_eq!(line, 1, "{msg}");
        let (line, msg) = design_err(&format!("model = \"exact\"\n{base}"));
        assert_eq!(line, 1, "{msg}");
        assert!(msg.contains("ice") && msg.contains("dome"), "{msg}");
        let (line, msg) = design_err(&format!("dtheta_deg = 0.0\n{base}"));
        assert_eq!(line, 1, "{msg}");
        let (line, msg) = design_err(&format!("step_rule = \"cam\"\n{base}"));
        assert_eq!(line, 1, "{msg}");
        assert!(msg.contains("convention-b"), "{msg}");
    }

    #[test]
    fn a_design_of_too_many_runs_is_refused_before_any_work() {
        let levels: Vec<String> = (0..1000).map(|i| format!("{}", 1 + i)).collect();
        let list = format!("[{}]", levels.join(", "));
        let text = format!(
            "surface = \"plane\"\ntool = \"t\"\nrpm = 1.0\ngrid_um = 1.0\nresponses = [\"Sq\"]\n\
             [factors]\nyaw_deg = {list}\ntilt_deg = [1]\nscallop_um = {list}\nfeed_mm_min = {list}\n"
        );
        let (line, msg) = design_err(&text);
        assert_eq!(line, 9, "{msg}");
        assert!(msg.contains("runs"), "{msg}");
    }
}
