//! `tool.toml`: the cutter configuration file, read into a [`Cutter`].
//!
//! ```toml
//! shape = "ball"              # "ball" | "torus" | "flat" | "round_insert" | "apt" | "profile"
//!                             # | "barrel" | "lens" | "oval" | "taper_barrel"
//! radius_mm = 5.0             # the largest radius (optional for apt and profile)
//! corner_radius_mm = 1.5      # torus; the insert radius of a round insert; barrel and lens
//!                             # (ignored by ball and flat, but checked)
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
//! tooth_axial_deviation_um = [0.0, 9.0, 0.0, 0.0]   # positive lifts the tooth
//! ```
//!
//! The other shapes take their own keys (lengths mm, angles degrees):
//!
//! * `round_insert`: `radius_mm` (outer radius) and `corner_radius_mm` (the insert radius ri);
//!   the insert circle's centre lies `radius_mm − corner_radius_mm` from the axis and its
//!   whole lower half cuts, inner flank included;
//! * `apt`: `apt = [d, r, e, f, a, b, h]`, APT's `CUTTER/` (see [`crate::tool::meridian::apt`]);
//! * `profile`: `profile_mm = [[r, z], [r, z, ρ], …]` from the tip upward, a third number
//!   making the piece from the previous point an arc of radius |ρ| (ρ > 0 convex, < 0
//!   concave);
//! * `barrel`: `radius_mm`, `segment_radius_mm`, `segment_height_mm` (height of the widest
//!   point), `corner_radius_mm`;
//! * `lens`: `radius_mm`, `segment_radius_mm` (centred on the axis), `corner_radius_mm`;
//! * `oval`: `radius_mm`, `segment_radius_mm` (vertical at R), `tip_radius_mm`;
//! * `taper_barrel`: `radius_mm`, `segment_radius_mm`, `tip_radius_mm`, `taper_deg` (the
//!   angle between the axis and the profile where the segment leaves the tip radius).
//!
//! Unknown keys, keys the shape does not use, missing required keys (`shape`, `teeth`,
//! `helix_deg` and those of the shape) and impossible values are rejected with the key's
//! name and the 1-based line and column of the offending text. Only these config types
//! derive serde; the `tool` stage itself stays free of it.

use crate::parse::Span;
use crate::tool::{Cutter, Meridian, Runout, Shape, meridian};
use serde::Deserialize;
use std::f64::consts::TAU;
use std::ops::Range;
use toml::Spanned;

/// Largest accepted number of teeth (a guard against absurd inputs).
pub const MAX_TEETH: i64 = 64;
/// Most points of a `profile_mm` meridian: a ground profile needs tens, a measured one
/// a few thousand; more only costs time in every sampling of the meridian.
pub const MAX_PROFILE_POINTS: usize = 10_000;

/// Why a `tool.toml` was rejected. Every variant carries the [`Span`] of the problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ToolConfigError {
    /// TOML syntax errors, unknown keys, missing keys and wrong value types (the message
    /// from the TOML reader names the key).
    #[error("line {}, column {}: {message}", at.line, at.column)]
    Toml {
        /// Where (line 1, column 1 when the TOML reader gives no place).
        at: Span,
        /// What is wrong.
        message: String,
    },
    /// A value that parses but cannot describe a cutter.
    #[error("line {}, column {}: `{key}` {message}", at.line, at.column)]
    Invalid {
        /// The key, e.g. `radius_mm` or `runout.tooth_radius_deviation_um`.
        key: String,
        /// The value.
        at: Span,
        /// What is wrong with it.
        message: String,
    },
}

impl ToolConfigError {
    /// Where the problem is.
    pub fn span(&self) -> Span {
        match self {
            ToolConfigError::Toml { at, .. } | ToolConfigError::Invalid { at, .. } => *at,
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
#[serde(rename_all = "snake_case")]
pub enum ShapeName {
    /// `"ball"`.
    Ball,
    /// `"torus"` (filleted, bull-nose).
    Torus,
    /// `"flat"`.
    Flat,
    /// `"round_insert"`: round-insert face mill.
    RoundInsert,
    /// `"apt"`: APT's seven-parameter cutter.
    Apt,
    /// `"profile"`: any meridian polyline or arc list.
    Profile,
    /// `"barrel"`: circle segment on the periphery.
    Barrel,
    /// `"lens"`: circle segment across the end.
    Lens,
    /// `"oval"`: tip radius and a segment up to the vertical at R.
    Oval,
    /// `"taper_barrel"`: tip radius and a segment along a taper.
    TaperBarrel,
}

impl ShapeName {
    /// The name as written.
    pub fn as_str(self) -> &'static str {
        match self {
            ShapeName::Ball => "ball",
            ShapeName::Torus => "torus",
            ShapeName::Flat => "flat",
            ShapeName::RoundInsert => "round_insert",
            ShapeName::Apt => "apt",
            ShapeName::Profile => "profile",
            ShapeName::Barrel => "barrel",
            ShapeName::Lens => "lens",
            ShapeName::Oval => "oval",
            ShapeName::TaperBarrel => "taper_barrel",
        }
    }
}

/// The `tool.toml` document as written (units in the key names).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolConfig {
    /// End shape.
    pub shape: Spanned<ShapeName>,
    /// Nominal (largest) radius R, mm (optional for `apt` and `profile`).
    #[serde(default)]
    pub radius_mm: Option<Spanned<f64>>,
    /// Corner radius rc, mm (torus, barrel, lens); the insert radius of a round insert.
    #[serde(default)]
    pub corner_radius_mm: Option<Spanned<f64>>,
    /// APT `CUTTER/d,r,e,f,a,b,h` (mm, degrees), for `shape = "apt"`.
    #[serde(default)]
    pub apt: Option<Spanned<Vec<f64>>>,
    /// The meridian `[[r, z], [r, z, arc radius], …]` from the tip upward, mm.
    #[serde(default)]
    pub profile_mm: Option<Spanned<Vec<Vec<f64>>>>,
    /// Segment radius Rs of a circle-segment tool, mm.
    #[serde(default)]
    pub segment_radius_mm: Option<Spanned<f64>>,
    /// Height of a barrel's widest point above the tip, mm.
    #[serde(default)]
    pub segment_height_mm: Option<Spanned<f64>>,
    /// Tip radius of an oval or taper barrel, mm.
    #[serde(default)]
    pub tip_radius_mm: Option<Spanned<f64>>,
    /// Taper angle of a taper barrel, degrees.
    #[serde(default)]
    pub taper_deg: Option<Spanned<f64>>,
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
    /// ε_j, µm, one per tooth; positive lifts the tooth toward the shank.
    #[serde(default)]
    pub tooth_axial_deviation_um: Option<Spanned<Vec<f64>>>,
}

fn invalid(text: &str, key: &str, span: Range<usize>, message: String) -> ToolConfigError {
    ToolConfigError::Invalid {
        key: key.to_string(),
        at: Span::of(text, span),
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
    toml::from_str::<ToolConfig>(text).map_err(|e| ToolConfigError::Toml {
        at: super::toml_span(text, &e),
        message: e.message().trim().to_string(),
    })
}

impl ToolConfig {
    /// Check the values and build the cutter. `text` is the document the config was parsed
    /// from (for line numbers).
    pub fn to_cutter(&self, text: &str) -> Result<Cutter, ToolConfigError> {
        self.min_chip_mm(text)?;
        let (shape, radius) = self.shape_and_radius(text)?;
        if let Err(m) = crate::math::limits::tool_radius(radius) {
            let span = match &self.radius_mm {
                Some(v) => v.span(),
                None => self.shape.span(),
            };
            return Err(invalid(
                text,
                "radius_mm",
                span,
                format!("{m}, found {radius}"),
            ));
        }
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
            if offset_um.abs() > 1e3 * radius
                && let Some(o) = &r.offset_um
            {
                return Err(invalid(
                    text,
                    "runout.offset_um",
                    o.span(),
                    format!("must not exceed the tool radius ({radius} mm), found {offset_um} µm"),
                ));
            }
            let tilt_deg = opt_finite(text, "runout.axis_tilt_deg", &r.axis_tilt_deg)?;
            if tilt_deg.abs() >= 45.0
                && let Some(s) = &r.axis_tilt_deg
            {
                return Err(invalid(
                    text,
                    "runout.axis_tilt_deg",
                    s.span(),
                    format!("must lie strictly between -45 and 45 degrees, found {tilt_deg}"),
                ));
            }
            let devs = per_tooth(
                text,
                "runout.tooth_radius_deviation_um",
                &r.tooth_radius_deviation_um,
                teeth,
            )?;
            // A deviation may shorten a tooth, not turn it inside out.
            if let (Some(d), Some(bad)) = (
                &r.tooth_radius_deviation_um,
                devs.iter().find(|v| radius + **v <= 0.0),
            ) {
                return Err(invalid(
                    text,
                    "runout.tooth_radius_deviation_um",
                    d.span(),
                    format!(
                        "value {} µm makes a tooth radius negative (radius_mm = {radius})",
                        bad * 1e3
                    ),
                ));
            }
            let axial = per_tooth(
                text,
                "runout.tooth_axial_deviation_um",
                &r.tooth_axial_deviation_um,
                teeth,
            )?;
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
                tooth_axial_dev_mm: axial,
            };
        }
        Ok(cutter)
    }
}

/// A per-tooth list in µm as mm: one finite value per tooth (empty when absent).
fn per_tooth(
    text: &str,
    key: &str,
    v: &Option<Spanned<Vec<f64>>>,
    teeth: usize,
) -> Result<Vec<f64>, ToolConfigError> {
    let Some(d) = v else {
        return Ok(Vec::new());
    };
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
    Ok(d.get_ref().iter().map(|v| v * 1e-3).collect())
}

impl ToolConfig {
    /// A positive, finite length or angle the shape requires.
    fn required(
        &self,
        text: &str,
        key: &str,
        v: &Option<Spanned<f64>>,
    ) -> Result<(f64, Range<usize>), ToolConfigError> {
        let shape = self.shape.get_ref().as_str();
        let Some(v) = v else {
            return Err(invalid(
                text,
                key,
                self.shape.span(),
                format!("is required when shape = \"{shape}\""),
            ));
        };
        let x = finite(text, key, v)?;
        if x <= 0.0 {
            return Err(invalid(
                text,
                key,
                v.span(),
                format!("must be positive, found {x}"),
            ));
        }
        Ok((x, v.span()))
    }

    /// Keys given that the shape does not use are rejected.
    fn unused(&self, text: &str, used: &[&str]) -> Result<(), ToolConfigError> {
        let spans: [(&str, Option<Range<usize>>); 7] = [
            (
                "corner_radius_mm",
                self.corner_radius_mm.as_ref().map(|v| v.span()),
            ),
            ("apt", self.apt.as_ref().map(|v| v.span())),
            ("profile_mm", self.profile_mm.as_ref().map(|v| v.span())),
            (
                "segment_radius_mm",
                self.segment_radius_mm.as_ref().map(|v| v.span()),
            ),
            (
                "segment_height_mm",
                self.segment_height_mm.as_ref().map(|v| v.span()),
            ),
            (
                "tip_radius_mm",
                self.tip_radius_mm.as_ref().map(|v| v.span()),
            ),
            ("taper_deg", self.taper_deg.as_ref().map(|v| v.span())),
        ];
        let shape = self.shape.get_ref();
        for (key, span) in spans {
            let Some(span) = span else { continue };
            // Ball and flat ends ignore (but check) a corner radius, as they always did.
            let tolerated =
                key == "corner_radius_mm" && matches!(shape, ShapeName::Ball | ShapeName::Flat);
            if !used.contains(&key) && !tolerated {
                return Err(invalid(
                    text,
                    key,
                    span,
                    format!("is not used by shape = \"{}\"", shape.as_str()),
                ));
            }
        }
        Ok(())
    }

    /// The nominal radius: required, positive.
    fn radius(&self, text: &str) -> Result<f64, ToolConfigError> {
        self.required(text, "radius_mm", &self.radius_mm)
            .map(|(r, _)| r)
    }

    /// A profile's meridian, or the builder's complaint at the shape key.
    fn profile(
        &self,
        text: &str,
        built: Result<Meridian, meridian::ProfileError>,
        span: Range<usize>,
    ) -> Result<Meridian, ToolConfigError> {
        built.map_err(|e| {
            invalid(
                text,
                self.shape.get_ref().as_str(),
                span,
                format!("describes no cutter: {e}"),
            )
        })
    }

    /// The shape and the nominal radius R.
    fn shape_and_radius(&self, text: &str) -> Result<(Shape, f64), ToolConfigError> {
        let corner = match &self.corner_radius_mm {
            Some(c) => {
                let rc = *c.get_ref();
                crate::math::limits::corner_radius(rc, f64::INFINITY).map_err(|m| {
                    invalid(
                        text,
                        "corner_radius_mm",
                        c.span(),
                        format!("{m}, found {rc}"),
                    )
                })?;
                Some((rc, c.span()))
            }
            None => None,
        };
        let corner_within = |radius: f64| -> Result<(), ToolConfigError> {
            if let Some((rc, span)) = &corner {
                crate::math::limits::corner_radius(*rc, radius).map_err(|m| {
                    invalid(
                        text,
                        "corner_radius_mm",
                        span.clone(),
                        format!("{m}, found {rc}"),
                    )
                })?;
            }
            Ok(())
        };
        let name = *self.shape.get_ref();
        let shape_span = self.shape.span();
        let classic = |s: Shape| -> Result<(Shape, f64), ToolConfigError> {
            let r = self.radius(text)?;
            corner_within(r)?;
            Ok((s, r))
        };
        match name {
            ShapeName::Ball => {
                self.unused(text, &[])?;
                classic(Shape::Ball)
            }
            ShapeName::Flat => {
                self.unused(text, &[])?;
                classic(Shape::Flat)
            }
            ShapeName::Torus => {
                self.unused(text, &["corner_radius_mm"])?;
                let r = self.radius(text)?;
                corner_within(r)?;
                match corner {
                    Some((rc, _)) => Ok((
                        Shape::Torus {
                            corner_radius_mm: rc,
                        },
                        r,
                    )),
                    None => Err(invalid(
                        text,
                        "corner_radius_mm",
                        shape_span,
                        "is required when shape = \"torus\"".to_string(),
                    )),
                }
            }
            ShapeName::RoundInsert => {
                self.unused(text, &["corner_radius_mm"])?;
                let r = self.radius(text)?;
                corner_within(r)?;
                let (ri, _) = self.required(text, "corner_radius_mm", &self.corner_radius_mm)?;
                Ok((
                    Shape::RoundInsert {
                        insert_radius_mm: ri,
                    },
                    r,
                ))
            }
            ShapeName::Apt => {
                self.unused(text, &["apt"])?;
                let Some(p) = &self.apt else {
                    return Err(invalid(
                        text,
                        "apt",
                        shape_span,
                        "is required when shape = \"apt\" (apt = [d, r, e, f, a, b, h])"
                            .to_string(),
                    ));
                };
                let v = p.get_ref();
                if v.len() != 7 {
                    return Err(invalid(
                        text,
                        "apt",
                        p.span(),
                        format!(
                            "needs the seven numbers d, r, e, f, a, b, h, found {}",
                            v.len()
                        ),
                    ));
                }
                let arr = [v[0], v[1], v[2], v[3], v[4], v[5], v[6]];
                let m = self.profile(text, meridian::apt(arr).map(|(m, _)| m), p.span())?;
                self.matching_radius(text, Shape::Profile(m))
            }
            ShapeName::Profile => {
                self.unused(text, &["profile_mm"])?;
                let Some(p) = &self.profile_mm else {
                    return Err(invalid(
                        text,
                        "profile_mm",
                        shape_span,
                        "is required when shape = \"profile\"".to_string(),
                    ));
                };
                if p.get_ref().len() > MAX_PROFILE_POINTS {
                    return Err(invalid(
                        text,
                        "profile_mm",
                        p.span(),
                        format!(
                            "has {} points, more than {MAX_PROFILE_POINTS}",
                            p.get_ref().len()
                        ),
                    ));
                }
                let mut pts = Vec::with_capacity(p.get_ref().len());
                for (i, q) in p.get_ref().iter().enumerate() {
                    let ok = (q.len() == 2 || q.len() == 3) && q.iter().all(|v| v.is_finite());
                    if !ok {
                        return Err(invalid(
                            text,
                            "profile_mm",
                            p.span(),
                            format!(
                                "point {} must be [r, z] or [r, z, arc radius] of finite numbers",
                                i + 1
                            ),
                        ));
                    }
                    pts.push([q[0], q[1], q.get(2).copied().unwrap_or(0.0)]);
                }
                let m = self.profile(text, meridian::polyline(&pts), p.span())?;
                self.matching_radius(text, Shape::Profile(m))
            }
            ShapeName::Barrel => {
                self.unused(
                    text,
                    &["segment_radius_mm", "segment_height_mm", "corner_radius_mm"],
                )?;
                let r = self.radius(text)?;
                let (rs, span) =
                    self.required(text, "segment_radius_mm", &self.segment_radius_mm)?;
                let (zb, _) = self.required(text, "segment_height_mm", &self.segment_height_mm)?;
                let (rc, _) = self.required(text, "corner_radius_mm", &self.corner_radius_mm)?;
                let m = self.profile(text, meridian::barrel(r, rs, zb, rc), span)?;
                Ok((Shape::Profile(m), r))
            }
            ShapeName::Lens => {
                self.unused(text, &["segment_radius_mm", "corner_radius_mm"])?;
                let r = self.radius(text)?;
                let (rs, span) =
                    self.required(text, "segment_radius_mm", &self.segment_radius_mm)?;
                let (rc, _) = self.required(text, "corner_radius_mm", &self.corner_radius_mm)?;
                let m = self.profile(text, meridian::lens(r, rs, rc), span)?;
                Ok((Shape::Profile(m), r))
            }
            ShapeName::Oval => {
                self.unused(text, &["segment_radius_mm", "tip_radius_mm"])?;
                let r = self.radius(text)?;
                let (rs, span) =
                    self.required(text, "segment_radius_mm", &self.segment_radius_mm)?;
                let (rt, _) = self.required(text, "tip_radius_mm", &self.tip_radius_mm)?;
                let m = self.profile(text, meridian::oval(r, rs, rt), span)?;
                Ok((Shape::Profile(m), r))
            }
            ShapeName::TaperBarrel => {
                self.unused(text, &["segment_radius_mm", "tip_radius_mm", "taper_deg"])?;
                let r = self.radius(text)?;
                let (rs, span) =
                    self.required(text, "segment_radius_mm", &self.segment_radius_mm)?;
                let (rt, _) = self.required(text, "tip_radius_mm", &self.tip_radius_mm)?;
                let (taper, _) = self.required(text, "taper_deg", &self.taper_deg)?;
                let m = self.profile(text, meridian::taper_barrel(r, rs, rt, taper), span)?;
                Ok((Shape::Profile(m), r))
            }
        }
    }

    /// For `apt` and `profile`: R is the profile's largest radius; a `radius_mm` given
    /// must agree.
    fn matching_radius(&self, text: &str, shape: Shape) -> Result<(Shape, f64), ToolConfigError> {
        let Shape::Profile(m) = &shape else {
            return Err(invalid(
                text,
                "shape",
                self.shape.span(),
                "is not a profile".to_string(),
            ));
        };
        let r = m.r_max();
        if let Some(v) = &self.radius_mm {
            let given = finite(text, "radius_mm", v)?;
            if (given - r).abs() > 1e-6 {
                return Err(invalid(
                    text,
                    "radius_mm",
                    v.span(),
                    format!(
                        "({given} mm) disagrees with the profile's largest radius ({r} mm); leave it out"
                    ),
                ));
            }
        }
        Ok((shape, r))
    }
}

/// The `tool.toml` document `text` with its `[runout]` table replaced by one holding only
/// `tooth_radius_deviation_um = devs_um` (an identified run-out, ready to re-simulate).
pub fn with_tooth_deviations(text: &str, devs_um: &[f64]) -> String {
    with_runout(text, None, devs_um)
}

/// The `tool.toml` document `text` with its `[runout]` table replaced by one holding
/// `offset_um` and `offset_phase_deg` (when `offset` = (µm, degrees) is given) and
/// `tooth_radius_deviation_um = devs_um`: an identified run-out, ready to re-simulate.
pub fn with_runout(text: &str, offset: Option<(f64, f64)>, devs_um: &[f64]) -> String {
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
    out.push_str("\n[runout]\n");
    if let Some((e, phase)) = offset {
        out.push_str(&format!(
            "offset_um = {}\noffset_phase_deg = {}\n",
            crate::math::trim_decimals(e, 5),
            crate::math::trim_decimals(phase, 4)
        ));
    }
    out.push_str(&format!(
        "tooth_radius_deviation_um = [{}]\n",
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
/// assert_eq!(err.span().line, 2);
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
        assert_eq!((e.span().line, e.span().column), (5, 18));
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
        assert_eq!(e.span().line, 5);
        assert!(e.to_string().contains("colour"), "{e}");

        let e = err("shape = \"ball\"\nteeth = 4\nhelix_deg = 30.0\n");
        assert!(e.to_string().contains("radius_mm"), "{e}");

        let e = err("shape = \"ball\"\nradius_mm = -1\nteeth = 4\nhelix_deg = 30.0\n");
        assert_eq!((e.span().line, e.span().column), (2, 13));
        assert!(e.to_string().contains("radius_mm"), "{e}");

        let e = err(
            "shape = \"torus\"\nradius_mm = 5\nteeth = 4\nhelix_deg = 0\ncorner_radius_mm = 6\n",
        );
        assert_eq!(e.span().line, 5);
        assert!(e.to_string().contains("corner_radius_mm"), "{e}");

        let e = err("shape = \"ball\"\nradius_mm = 5.0\nteeth = 0\nhelix_deg = 30.0\n");
        assert_eq!(e.span().line, 3);
        assert!(e.to_string().contains("teeth"), "{e}");

        let e = err(&format!(
            "{base}[runout]\noffset_um = 1\ntooth_radius_deviation_um = [1.0, 2.0]\n"
        ));
        assert_eq!(e.span().line, 7);
        assert!(e.to_string().contains("tooth_radius_deviation_um"), "{e}");

        let e = err(&format!("{base}[runout]\nofset_um = 1\n"));
        assert_eq!(e.span().line, 6);
        assert!(e.to_string().contains("ofset_um"), "{e}");

        let e = err("shape = \"cone\"\nradius_mm = 5.0\nteeth = 4\nhelix_deg = 30.0\n");
        assert_eq!(e.span().line, 1);

        let e = err("shape = \"torus\"\nradius_mm = 5\nteeth = 4\nhelix_deg = 0\n");
        assert!(e.to_string().contains("corner_radius_mm"), "{e}");
    }

    #[test]
    fn every_shape_loads() {
        let tail = "teeth = 2\nhelix_deg = 0\n";
        let ok = |head: &str| {
            load_tool_toml(&format!("{head}{tail}")).unwrap_or_else(|e| panic!("{head}: {e}"))
        };
        let c = ok("shape = \"round_insert\"\nradius_mm = 10\ncorner_radius_mm = 5\n");
        assert_eq!(
            c.shape,
            Shape::RoundInsert {
                insert_radius_mm: 5.0
            }
        );
        assert_relative_eq!(
            c.profile_height(2.5).unwrap(),
            5.0 - 18.75f64.sqrt(),
            epsilon = 1e-12
        );
        let c = ok("shape = \"apt\"\napt = [10, 1, 4, 1, 0, 0, 30]\n");
        assert_relative_eq!(c.radius_mm, 5.0, epsilon = 1e-12);
        assert_eq!(c.shape.name(), "apt");
        let c = ok("shape = \"profile\"\nprofile_mm = [[0, 0], [3, 0], [5, 2, 2], [5, 8]]\n");
        assert_relative_eq!(c.radius_mm, 5.0, epsilon = 1e-12);
        assert_relative_eq!(c.end_height_mm(), 2.0, epsilon = 1e-12);
        for (head, name) in [
            (
                "shape = \"barrel\"\nradius_mm = 8\nsegment_radius_mm = 250\nsegment_height_mm = 10\ncorner_radius_mm = 1\n",
                "barrel",
            ),
            (
                "shape = \"lens\"\nradius_mm = 5\nsegment_radius_mm = 50\ncorner_radius_mm = 1\n",
                "lens",
            ),
            (
                "shape = \"oval\"\nradius_mm = 5\nsegment_radius_mm = 20\ntip_radius_mm = 2\n",
                "oval",
            ),
            (
                "shape = \"taper_barrel\"\nradius_mm = 3\nsegment_radius_mm = 250\ntip_radius_mm = 1\ntaper_deg = 10\n",
                "taper_barrel",
            ),
        ] {
            let c = ok(head);
            assert_eq!(c.shape.name(), name);
        }
        // The run-out table comes last: the tail's keys belong to the top level.
        let c = load_tool_toml(&format!(
            "shape = \"ball\"\nradius_mm = 5\n{tail}[runout]\ntooth_axial_deviation_um = [0, 9]\n"
        ))
        .unwrap();
        assert_relative_eq!(c.tooth_axial_dev_mm(1), 0.009, epsilon = 1e-15);
    }

    #[test]
    fn shape_errors_point_at_the_key() {
        let tail = "teeth = 2\nhelix_deg = 0\n";
        let e = err(&format!(
            "shape = \"lens\"\nradius_mm = 5\nsegment_radius_mm = 4\ncorner_radius_mm = 1\n{tail}"
        ));
        assert_eq!(e.span().line, 3);
        assert!(e.to_string().contains("describes no cutter"), "{e}");
        let e = err(&format!(
            "shape = \"apt\"\napt = [10, 1, 4, 1, 0, 0, 30]\nradius_mm = 4\n{tail}"
        ));
        assert_eq!(e.span().line, 3);
        assert!(e.to_string().contains("largest radius"), "{e}");
        let e = err(&format!(
            "shape = \"oval\"\nradius_mm = 5\nsegment_radius_mm = 20\n{tail}"
        ));
        assert_eq!(e.span().line, 1);
        assert!(e.to_string().contains("tip_radius_mm"), "{e}");
        let e = err(&format!(
            "shape = \"flat\"\nradius_mm = 5\nprofile_mm = [[0, 0], [5, 0]]\n{tail}"
        ));
        assert_eq!(e.span().line, 3);
        assert!(e.to_string().contains("not used"), "{e}");
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
        assert_eq!(e.span().line, 5);
    }
}
