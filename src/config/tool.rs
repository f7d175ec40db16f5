//! `tool.toml`: the cutter configuration file, read into a [`Cutter`].
//!
//! ```toml
//! shape = "ball"              # "ball" | "torus" | "flat"
//! radius_mm = 5.0
//! corner_radius_mm = 1.5      # torus only (ignored by ball and flat, but checked)
//! teeth = 4
//! helix_deg = 30.0            # 0 = straight edges
//! tooth_pitch_deg = [0, 85, 180, 265]   # optional: uneven pitch, tooth 1 first and 0
//! edge_radius_um = 8.0        # optional: cutting-edge radius rβ (process effects)
//! min_chip_ratio = 0.3        # optional: h_min / rβ (default 0.3; docs/process-effects.md)
//! [runout]                    # optional; every key inside defaults to 0
//! offset_um = 10.0
//! offset_phase_deg = 0.0
//! axis_tilt_deg = 0.0
//! axis_tilt_phase_deg = 0.0
//! tooth_radius_deviation_um = [0.0, 0.0, 0.0, 0.0]
//! ```
//!
//! Unknown keys, missing required keys (`shape`, `radius_mm`, `teeth`, `helix_deg`, and
//! `corner_radius_mm` for a torus) and impossible values are rejected with the key's name
//! and the 1-based line and column of the offending text. Only these config types derive
//! serde; the `tool` stage itself stays free of it.

use crate::parse::line_column;
use crate::tool::{Cutter, Runout, Shape};
use serde::Deserialize;
use std::f64::consts::TAU;
use std::ops::Range;
use toml::Spanned;

/// Largest accepted number of teeth (a guard against absurd inputs).
pub const MAX_TEETH: i64 = 64;

/// Why a `tool.toml` was rejected. Every variant carries the 1-based line and column.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ToolConfigError {
    /// TOML syntax errors, unknown keys, missing keys and wrong value types (the message
    /// from the TOML reader names the key).
    #[error("line {line}, column {column}: {message}")]
    Toml {
        /// 1-based line.
        line: usize,
        /// 1-based column (characters).
        column: usize,
        /// Byte range of the offending text, when known.
        span: Option<Range<usize>>,
        /// What is wrong.
        message: String,
    },
    /// A value that parses but cannot describe a cutter.
    #[error("line {line}, column {column}: `{key}` {message}")]
    Invalid {
        /// The key, e.g. `radius_mm` or `runout.tooth_radius_deviation_um`.
        key: String,
        /// 1-based line.
        line: usize,
        /// 1-based column (characters).
        column: usize,
        /// Byte range of the value.
        span: Range<usize>,
        /// What is wrong with it.
        message: String,
    },
}

impl ToolConfigError {
    /// The 1-based line of the problem.
    pub fn line(&self) -> usize {
        match self {
            ToolConfigError::Toml { line, .. } | ToolConfigError::Invalid { line, .. } => *line,
        }
    }

    /// The 1-based column of the problem.
    pub fn column(&self) -> usize {
        match self {
            ToolConfigError::Toml { column, .. } | ToolConfigError::Invalid { column, .. } => {
                *column
            }
        }
    }

    /// Byte range of the offending text, when known.
    pub fn span(&self) -> Option<Range<usize>> {
        match self {
            ToolConfigError::Toml { span, .. } => span.clone(),
            ToolConfigError::Invalid { span, .. } => Some(span.clone()),
        }
    }

    /// The message without the position.
    pub fn message(&self) -> String {
        match self {
            ToolConfigError::Toml { message, .. } => message.clone(),
            ToolConfigError::Invalid { key, message, .. } => format!("`{key}` {message}"),
        }
    }
}

/// The `shape` key.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShapeName {
    /// `"ball"`.
    Ball,
    /// `"torus"` (filleted, bull-nose).
    Torus,
    /// `"flat"`.
    Flat,
}

/// The `tool.toml` document as written (units in the key names).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolConfig {
    /// End shape.
    pub shape: Spanned<ShapeName>,
    /// Nominal radius R, mm.
    pub radius_mm: Spanned<f64>,
    /// Corner radius rc, mm (required for a torus).
    #[serde(default)]
    pub corner_radius_mm: Option<Spanned<f64>>,
    /// Number of teeth Z.
    pub teeth: Spanned<i64>,
    /// Helix angle α, degrees.
    pub helix_deg: Spanned<f64>,
    /// Optional uneven pitch: angular position of each tooth at the tip, degrees, in
    /// cutting order (tooth j trails tooth 1 by this angle); must start at 0 and increase.
    #[serde(default)]
    pub tooth_pitch_deg: Option<Spanned<Vec<f64>>>,
    /// Optional cutting-edge radius rβ, µm: h_min = `min_chip_ratio`·rβ unless the process
    /// gives `min_chip_um`.
    #[serde(default)]
    pub edge_radius_um: Option<Spanned<f64>>,
    /// h_min / rβ (typically 0.2-0.4; default [`DEFAULT_MIN_CHIP_RATIO`]).
    #[serde(default)]
    pub min_chip_ratio: Option<Spanned<f64>>,
    /// Optional run-out.
    #[serde(default)]
    pub runout: Option<RunoutConfig>,
}

/// h_min / rβ when a tool file gives `edge_radius_um` without `min_chip_ratio`.
pub const DEFAULT_MIN_CHIP_RATIO: f64 = 0.3;

impl ToolConfig {
    /// The minimum uncut chip thickness of the edge, mm: `edge_radius_um × min_chip_ratio`
    /// (None without an edge radius).
    pub fn min_chip_mm(&self, text: &str) -> Result<Option<f64>, ToolConfigError> {
        if let Some(r) = &self.min_chip_ratio {
            let v = finite(text, "min_chip_ratio", r)?;
            if !(v > 0.0 && v <= 1.0) {
                return Err(invalid(
                    text,
                    "min_chip_ratio",
                    r.span(),
                    format!("must lie in (0, 1], found {v}"),
                ));
            }
            if self.edge_radius_um.is_none() {
                return Err(invalid(
                    text,
                    "min_chip_ratio",
                    r.span(),
                    "needs edge_radius_um".to_string(),
                ));
            }
        }
        let Some(e) = &self.edge_radius_um else {
            return Ok(None);
        };
        let edge = finite(text, "edge_radius_um", e)?;
        if edge < 0.0 {
            return Err(invalid(
                text,
                "edge_radius_um",
                e.span(),
                format!("must not be negative, found {edge}"),
            ));
        }
        let ratio = self
            .min_chip_ratio
            .as_ref()
            .map_or(DEFAULT_MIN_CHIP_RATIO, |r| *r.get_ref());
        Ok(Some(edge * ratio * 1e-3))
    }
}

/// The minimum chip thickness a `tool.toml` document gives through its edge radius, mm.
pub fn load_tool_min_chip(text: &str) -> Result<Option<f64>, ToolConfigError> {
    let c = parse_tool_config(text)?;
    c.min_chip_mm(text)
}

/// The `[runout]` table (model.md §3.1); every key defaults to 0.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunoutConfig {
    /// e0, µm.
    #[serde(default)]
    pub offset_um: Option<Spanned<f64>>,
    /// φ_e, degrees.
    #[serde(default)]
    pub offset_phase_deg: Option<Spanned<f64>>,
    /// τ, degrees.
    #[serde(default)]
    pub axis_tilt_deg: Option<Spanned<f64>>,
    /// φ_τ, degrees.
    #[serde(default)]
    pub axis_tilt_phase_deg: Option<Spanned<f64>>,
    /// δ_j, µm, one per tooth.
    #[serde(default)]
    pub tooth_radius_deviation_um: Option<Spanned<Vec<f64>>>,
}

fn invalid(text: &str, key: &str, span: Range<usize>, message: String) -> ToolConfigError {
    let (line, column) = line_column(text, span.start);
    ToolConfigError::Invalid {
        key: key.to_string(),
        line,
        column,
        span,
        message,
    }
}

fn finite(text: &str, key: &str, v: &Spanned<f64>) -> Result<f64, ToolConfigError> {
    let x = *v.get_ref();
    if x.is_finite() {
        Ok(x)
    } else {
        Err(invalid(
            text,
            key,
            v.span(),
            format!("must be finite, found {x}"),
        ))
    }
}

fn opt_finite(text: &str, key: &str, v: &Option<Spanned<f64>>) -> Result<f64, ToolConfigError> {
    v.as_ref().map_or(Ok(0.0), |v| finite(text, key, v))
}

/// Parse a `tool.toml` document into its config form (syntax, unknown and missing keys).
pub fn parse_tool_config(text: &str) -> Result<ToolConfig, ToolConfigError> {
    toml::from_str::<ToolConfig>(text).map_err(|e| {
        let span = e.span();
        let (line, column) = span.as_ref().map_or((1, 1), |s| line_column(text, s.start));
        ToolConfigError::Toml {
            line,
            column,
            span,
            message: e.message().trim().to_string(),
        }
    })
}

impl ToolConfig {
    /// Check the values and build the cutter. `text` is the document the config was parsed
    /// from (for line numbers).
    pub fn to_cutter(&self, text: &str) -> Result<Cutter, ToolConfigError> {
        self.min_chip_mm(text)?;
        let radius = finite(text, "radius_mm", &self.radius_mm)?;
        let max_r = crate::math::limits::MAX_TOOL_RADIUS_MM;
        if radius <= 0.0 || radius > max_r {
            return Err(invalid(
                text,
                "radius_mm",
                self.radius_mm.span(),
                format!("must lie in (0, {max_r}] mm, found {radius}"),
            ));
        }
        let corner = match &self.corner_radius_mm {
            Some(c) => {
                let rc = finite(text, "corner_radius_mm", c)?;
                if rc < 0.0 {
                    return Err(invalid(
                        text,
                        "corner_radius_mm",
                        c.span(),
                        format!("must not be negative, found {rc}"),
                    ));
                }
                if rc > radius {
                    return Err(invalid(
                        text,
                        "corner_radius_mm",
                        c.span(),
                        format!("({rc} mm) must not exceed radius_mm ({radius} mm)"),
                    ));
                }
                Some(rc)
            }
            None => None,
        };
        let shape = match self.shape.get_ref() {
            ShapeName::Ball => Shape::Ball,
            ShapeName::Flat => Shape::Flat,
            ShapeName::Torus => match corner {
                Some(rc) => Shape::Torus {
                    corner_radius_mm: rc,
                },
                None => {
                    return Err(invalid(
                        text,
                        "corner_radius_mm",
                        self.shape.span(),
                        "is required when shape = \"torus\"".to_string(),
                    ));
                }
            },
        };
        let teeth = *self.teeth.get_ref();
        if !(1..=MAX_TEETH).contains(&teeth) {
            return Err(invalid(
                text,
                "teeth",
                self.teeth.span(),
                format!("must be between 1 and {MAX_TEETH}, found {teeth}"),
            ));
        }
        let teeth = teeth as usize;
        let helix = finite(text, "helix_deg", &self.helix_deg)?;
        if helix.abs() >= 89.0 {
            return Err(invalid(
                text,
                "helix_deg",
                self.helix_deg.span(),
                format!("must lie strictly between -89 and 89 degrees, found {helix}"),
            ));
        }
        let mut cutter = Cutter::new(shape, radius, teeth, helix.to_radians());
        if let Some(p) = &self.tooth_pitch_deg {
            let key = "tooth_pitch_deg";
            let list = p.get_ref();
            if list.len() != teeth {
                return Err(invalid(
                    text,
                    key,
                    p.span(),
                    format!("has {} values but teeth = {teeth}", list.len()),
                ));
            }
            let ok_start = list.first().is_some_and(|&a| a == 0.0);
            let ok_order = list.windows(2).all(|w| w[1] > w[0]);
            let ok_range = list.iter().all(|a| a.is_finite() && *a < 360.0);
            if !(ok_start && ok_order && ok_range) {
                return Err(invalid(
                    text,
                    key,
                    p.span(),
                    "must start at 0 and increase strictly below 360 degrees".to_string(),
                ));
            }
            cutter.pitch_rad = list.iter().map(|a| a.to_radians()).collect();
        }
        if let Some(r) = &self.runout {
            let offset_um = opt_finite(text, "runout.offset_um", &r.offset_um)?;
            if offset_um.abs() > 1e3 * radius {
                if let Some(o) = &r.offset_um {
                    return Err(invalid(
                        text,
                        "runout.offset_um",
                        o.span(),
                        format!(
                            "must not exceed the tool radius ({radius} mm), found {offset_um} µm"
                        ),
                    ));
                }
            }
            let tilt_deg = opt_finite(text, "runout.axis_tilt_deg", &r.axis_tilt_deg)?;
            if tilt_deg.abs() >= 45.0 {
                if let Some(s) = &r.axis_tilt_deg {
                    return Err(invalid(
                        text,
                        "runout.axis_tilt_deg",
                        s.span(),
                        format!("must lie strictly between -45 and 45 degrees, found {tilt_deg}"),
                    ));
                }
            }
            let devs = match &r.tooth_radius_deviation_um {
                Some(d) => {
                    let key = "runout.tooth_radius_deviation_um";
                    if d.get_ref().len() != teeth {
                        return Err(invalid(
                            text,
                            key,
                            d.span(),
                            format!("has {} values but teeth = {teeth}", d.get_ref().len()),
                        ));
                    }
                    if let Some(bad) = d.get_ref().iter().find(|v| !v.is_finite()) {
                        return Err(invalid(
                            text,
                            key,
                            d.span(),
                            format!("must be finite, found {bad}"),
                        ));
                    }
                    // A deviation may shorten a tooth, not turn it inside out.
                    if let Some(bad) = d.get_ref().iter().find(|v| radius + **v * 1e-3 <= 0.0) {
                        return Err(invalid(
                            text,
                            key,
                            d.span(),
                            format!(
                                "value {bad} µm makes a tooth radius negative (radius_mm = {radius})"
                            ),
                        ));
                    }
                    d.get_ref().iter().map(|v| v * 1e-3).collect()
                }
                None => Vec::new(),
            };
            cutter.runout = Runout {
                offset_mm: offset_um * 1e-3,
                offset_phase_rad: opt_finite(text, "runout.offset_phase_deg", &r.offset_phase_deg)?
                    .to_radians()
                    .rem_euclid(TAU),
                tilt_rad: tilt_deg.to_radians(),
                tilt_phase_rad: opt_finite(
                    text,
                    "runout.axis_tilt_phase_deg",
                    &r.axis_tilt_phase_deg,
                )?
                .to_radians()
                .rem_euclid(TAU),
                tooth_radius_dev_mm: devs,
            };
        }
        Ok(cutter)
    }
}

/// The `tool.toml` document `text` with its `[runout]` table replaced by one holding only
/// `tooth_radius_deviation_um = devs_um` (an identified run-out, ready to re-simulate).
pub fn with_tooth_deviations(text: &str, devs_um: &[f64]) -> String {
    let mut out = String::new();
    let mut skip = false;
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with('[') {
            skip = t.starts_with("[runout]");
        }
        if !skip {
            out.push_str(line);
            out.push('\n');
        }
    }
    let list: Vec<String> = devs_um
        .iter()
        .map(|d| crate::math::trim_decimals(*d, 4))
        .collect();
    out.push_str(&format!(
        "\n[runout]\ntooth_radius_deviation_um = [{}]\n",
        list.join(", ")
    ));
    out
}

/// Read a `tool.toml` document into a [`Cutter`] (lengths mm, angles rad).
///
/// ```
/// let cutter = crest::config::load_tool_toml(
///     "shape = \"ball\"\nradius_mm = 5.0\nteeth = 4\nhelix_deg = 30.0\n",
/// ).unwrap();
/// assert_eq!(cutter.teeth(), 4);
/// let err = crest::config::load_tool_toml("shape = \"ball\"\nradius_mm = -5.0\nteeth = 4\nhelix_deg = 0\n")
///     .unwrap_err();
/// assert_eq!(err.line(), 2);
/// ```
pub fn load_tool_toml(text: &str) -> Result<Cutter, ToolConfigError> {
    parse_tool_config(text)?.to_cutter(text)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    const ISSUE_EXAMPLE: &str = r#"shape = "ball"              # "ball" | "torus" | "flat"
radius_mm = 5.0
corner_radius_mm = 1.5      # torus only
teeth = 4
helix_deg = 30.0
[runout]                    # optional
offset_um = 10.0
offset_phase_deg = 0.0
axis_tilt_deg = 0.0
axis_tilt_phase_deg = 0.0
tooth_radius_deviation_um = [0.0, 0.0, 0.0, 0.0]
"#;

    #[test]
    fn edge_radius_gives_the_minimum_chip() {
        let base = "shape = \"ball\"\nradius_mm = 5\nteeth = 2\nhelix_deg = 0\n";
        assert_eq!(load_tool_min_chip(base).unwrap(), None);
        let t = format!("{base}edge_radius_um = 8\nmin_chip_ratio = 0.25\n");
        assert_relative_eq!(load_tool_min_chip(&t).unwrap().unwrap(), 0.002);
        let t = format!("{base}edge_radius_um = 10\n");
        assert_relative_eq!(load_tool_min_chip(&t).unwrap().unwrap(), 0.003);
        let t = format!("{base}min_chip_ratio = 0.3\n");
        let e = load_tool_toml(&t).unwrap_err();
        assert_eq!((e.line(), e.column()), (5, 18));
    }

    #[test]
    fn issue_example_loads() {
        let c = load_tool_toml(ISSUE_EXAMPLE).unwrap();
        assert_eq!(c.shape, Shape::Ball);
        assert_eq!(c.teeth(), 4);
        assert_relative_eq!(c.radius_mm, 5.0);
        assert_relative_eq!(c.helix_rad, 30f64.to_radians());
        assert_relative_eq!(c.runout.offset_mm, 0.010);
        assert_relative_eq!(c.pitch_rad[2], std::f64::consts::PI);
    }

    #[test]
    fn runout_keys_default_to_zero() {
        let c = load_tool_toml(
            "shape = \"torus\"\nradius_mm = 5\ncorner_radius_mm = 1.5\nteeth = 1\nhelix_deg = 0\n[runout]\noffset_um = 3\n",
        )
        .unwrap();
        assert_eq!(
            c.shape,
            Shape::Torus {
                corner_radius_mm: 1.5
            }
        );
        assert_relative_eq!(c.runout.offset_mm, 0.003);
        assert_eq!(c.runout.tilt_rad, 0.0);
        assert!(c.runout.tooth_radius_dev_mm.is_empty());
    }

    fn err(text: &str) -> ToolConfigError {
        load_tool_toml(text).unwrap_err()
    }

    #[test]
    fn rejections_name_key_and_line() {
        let base = "shape = \"ball\"\nradius_mm = 5.0\nteeth = 4\nhelix_deg = 30.0\n";
        let e = err(&format!("{base}colour = 3\n"));
        assert_eq!(e.line(), 5);
        assert!(e.to_string().contains("colour"), "{e}");

        let e = err("shape = \"ball\"\nteeth = 4\nhelix_deg = 30.0\n");
        assert!(e.to_string().contains("radius_mm"), "{e}");

        let e = err("shape = \"ball\"\nradius_mm = -1\nteeth = 4\nhelix_deg = 30.0\n");
        assert_eq!((e.line(), e.column()), (2, 13));
        assert!(e.to_string().contains("radius_mm"), "{e}");

        let e = err(
            "shape = \"torus\"\nradius_mm = 5\nteeth = 4\nhelix_deg = 0\ncorner_radius_mm = 6\n",
        );
        assert_eq!(e.line(), 5);
        assert!(e.to_string().contains("corner_radius_mm"), "{e}");

        let e = err("shape = \"ball\"\nradius_mm = 5.0\nteeth = 0\nhelix_deg = 30.0\n");
        assert_eq!(e.line(), 3);
        assert!(e.to_string().contains("teeth"), "{e}");

        let e = err(&format!(
            "{base}[runout]\noffset_um = 1\ntooth_radius_deviation_um = [1.0, 2.0]\n"
        ));
        assert_eq!(e.line(), 7);
        assert!(e.to_string().contains("tooth_radius_deviation_um"), "{e}");

        let e = err(&format!("{base}[runout]\nofset_um = 1\n"));
        assert_eq!(e.line(), 6);
        assert!(e.to_string().contains("ofset_um"), "{e}");

        let e = err("shape = \"cone\"\nradius_mm = 5.0\nteeth = 4\nhelix_deg = 30.0\n");
        assert_eq!(e.line(), 1);

        let e = err("shape = \"torus\"\nradius_mm = 5\nteeth = 4\nhelix_deg = 0\n");
        assert!(e.to_string().contains("corner_radius_mm"), "{e}");
    }

    #[test]
    fn uneven_pitch() {
        let c = load_tool_toml(
            "shape = \"ball\"\nradius_mm = 5\nteeth = 3\nhelix_deg = 0\ntooth_pitch_deg = [0, 100, 230]\n",
        )
        .unwrap();
        assert_relative_eq!(c.pitch_rad[1], 100f64.to_radians());
        let e = err(
            "shape = \"ball\"\nradius_mm = 5\nteeth = 3\nhelix_deg = 0\ntooth_pitch_deg = [0, 230, 100]\n",
        );
        assert_eq!(e.line(), 5);
    }
}
