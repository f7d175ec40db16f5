//! `machine.toml` (kinematics.md §3.2): the schema of the machine file and its checks, read
//! into a [`Machine`].
//!
//! Values in the file carry the units written in the key comments: mm, mm/s, mm/s², mm/s³
//! for linear axes and deg, deg/s, deg/s², deg/s³ for rotary axes. A value may also be
//! written as a string with its unit (`vmax = "50 m/min"`, `amax = "3 rev/s2"`); the loader
//! converts those and rejects a unit of the wrong kind. Catalogue values typed as plain
//! numbers in m/min, m/s² or rev/min are a common error, so implausibly small limits are
//! rejected with the key, the line and the likely mistake.

use crate::kinematics::Machine;
use crate::kinematics::machine::{BranchPreference, Limits, LinearAxis, RotaryAxis, Side};
use crate::math::{Point3, Vec3};
use crate::parse::Span;
use serde::Deserialize;
use toml::Spanned;

/// Why a machine description was rejected. Every message names the key and the 1-based line.
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum MachineError {
    /// The text is not valid TOML or has unknown keys / wrong value types.
    #[error("machine description: {0}")]
    Syntax(String),
    /// TOML that does not parse into a machine (a value of the wrong type or out of its
    /// type's range, an unknown key), where the TOML reader knows the place.
    #[error("line {}, column {}: {message}", at.line, at.column)]
    Toml {
        /// Where.
        at: Span,
        /// The TOML reader's message.
        message: String,
    },
    /// A required key is missing.
    #[error("line {}: missing `{key}` in {table}", at.line)]
    Missing {
        /// Key name.
        key: String,
        /// The table it belongs in, e.g. `[[linear]] X`.
        table: String,
        /// Where that table starts (line 1 for the top level).
        at: Span,
    },
    /// A value is out of range, has the wrong unit, or is inconsistent.
    #[error("line {}: `{key}` {message}", at.line)]
    Invalid {
        /// Key name.
        key: String,
        /// The value.
        at: Span,
        /// What is wrong and what was expected.
        message: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileMachine {
    name: Option<String>,
    cycle_time: Option<Spanned<Quantity>>,
    min_block_cycles: Option<Spanned<f64>>,
    lookahead_blocks: Option<Spanned<i64>>,
    junction_spacing_rule: Option<bool>,
    branch: Option<Spanned<String>>,
    tool: Option<Spanned<FileTool>>,
    #[serde(default)]
    linear: Vec<Spanned<FileAxis>>,
    #[serde(default)]
    rotary: Vec<Spanned<FileAxis>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileTool {
    dir_home: Option<Spanned<super::Fixed<3>>>,
    tip_home: Option<Spanned<super::Fixed<3>>>,
    part_origin: Option<Spanned<super::Fixed<3>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileAxis {
    name: Option<String>,
    side: Option<Spanned<String>>,
    direction: Option<Spanned<super::Fixed<3>>>,
    axis: Option<Spanned<super::Fixed<3>>>,
    point: Option<Spanned<super::Fixed<3>>>,
    sign: Option<Spanned<f64>>,
    limits: Option<Spanned<Vec<f64>>>,
    vmax: Option<Spanned<Quantity>>,
    amax: Option<Spanned<Quantity>>,
    jmax: Option<Spanned<Quantity>>,
    tol: Option<Spanned<Quantity>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Quantity {
    Number(f64),
    Text(String),
}

/// The physical kind of a limit, which fixes its unit in the file.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Kind {
    Vel,
    Acc,
    Jerk,
    Len,
    Time,
}

impl Kind {
    fn unit(self, rotary: bool) -> &'static str {
        match (self, rotary) {
            (Kind::Vel, false) => "mm/s",
            (Kind::Acc, false) => "mm/s2",
            (Kind::Jerk, false) => "mm/s3",
            (Kind::Len, false) => "mm",
            (Kind::Vel, true) => "deg/s",
            (Kind::Acc, true) => "deg/s2",
            (Kind::Jerk, true) => "deg/s3",
            (Kind::Len, true) => "deg",
            (Kind::Time, _) => "s",
        }
    }

    /// Smallest plausible value in the file unit; below it the value was almost surely
    /// typed in a catalogue unit (m/min, m/s², rev/s², µm…).
    fn plausible_min(self, rotary: bool) -> f64 {
        match (self, rotary) {
            (Kind::Vel, false) => 10.0,
            (Kind::Acc, false) => 50.0,
            (Kind::Jerk, false) => 100.0,
            (Kind::Vel, true) => 1.0,
            (Kind::Acc, true) => 10.0,
            (Kind::Jerk, true) => 100.0,
            (Kind::Len, _) => 0.0,
            // An interpolator faster than 10 µs per cycle does not exist; 1e-9 s would plan
            // for ever.
            (Kind::Time, _) => 1e-5,
        }
    }

    /// Largest plausible value in the file unit.
    fn plausible_max(self, rotary: bool) -> f64 {
        match (self, rotary) {
            (Kind::Len, false) => 1.0,
            (Kind::Len, true) => 5.0,
            (Kind::Time, _) => 0.1,
            _ => f64::INFINITY,
        }
    }
}

/// Conversion factor of a unit string to the file unit of `kind`, or `None` if the unit is
/// of another kind.
fn unit_factor(unit: &str, kind: Kind, rotary: bool) -> Option<f64> {
    let u: String = unit
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect::<String>()
        .replace('²', "2")
        .replace('³', "3")
        .replace("^", "")
        .replace("sec", "s")
        .to_ascii_lowercase();
    let lin = |u: &str| -> Option<f64> {
        Some(match u {
            "mm" => 1.0,
            "m" => 1000.0,
            "um" | "µm" => 1e-3,
            _ => return None,
        })
    };
    let ang = |u: &str| -> Option<f64> {
        Some(match u {
            "deg" | "°" => 1.0,
            "rev" => 360.0,
            "rad" => 180.0 / std::f64::consts::PI,
            _ => return None,
        })
    };
    let base = |u: &str| if rotary { ang(u) } else { lin(u) };
    if kind == Kind::Time {
        return match u.as_str() {
            "s" => Some(1.0),
            "ms" => Some(1e-3),
            _ => None,
        };
    }
    if kind == Kind::Len {
        return base(&u);
    }
    let (num, den) = u.split_once('/')?;
    let per = match (kind, den) {
        (Kind::Vel, "s") => 1.0,
        (Kind::Vel, "min") => 1.0 / 60.0,
        (Kind::Acc, "s2") => 1.0,
        (Kind::Jerk, "s3") => 1.0,
        _ => return None,
    };
    Some(base(num)? * per)
}

struct Ctx<'a> {
    text: &'a str,
}

impl Ctx<'_> {
    fn span<T>(&self, s: &Spanned<T>) -> Span {
        Span::of(self.text, s.span())
    }

    fn invalid<T>(&self, key: &str, s: &Spanned<T>, message: impl Into<String>) -> MachineError {
        MachineError::Invalid {
            key: key.to_string(),
            at: self.span(s),
            message: message.into(),
        }
    }

    /// A limit in its file unit, checked for kind, sign and plausibility.
    fn quantity(
        &self,
        key: &str,
        value: &Spanned<Quantity>,
        kind: Kind,
        rotary: bool,
    ) -> Result<f64, MachineError> {
        let unit = kind.unit(rotary);
        let v = match value.get_ref() {
            Quantity::Number(x) => *x,
            Quantity::Text(t) => {
                let t = t.trim();
                let split = t
                    .find(|c: char| !(c.is_ascii_digit() || "+-.eE".contains(c)))
                    .unwrap_or(t.len());
                let (num, u) = t.split_at(split);
                let x: f64 = num.trim().parse().map_err(|_| {
                    self.invalid(key, value, format!("\"{t}\" is not a number with a unit"))
                })?;
                let f = unit_factor(u, kind, rotary).ok_or_else(|| {
                    self.invalid(
                        key,
                        value,
                        format!(
                            "has unit \"{}\", expected {unit} or a convertible unit",
                            u.trim()
                        ),
                    )
                })?;
                x * f
            }
        };
        if !v.is_finite() || v <= 0.0 {
            return Err(self.invalid(
                key,
                value,
                format!("must be > 0 {unit}, got {}", crate::math::limits::shown(v)),
            ));
        }
        if v < kind.plausible_min(rotary) {
            let hint = match (kind, rotary) {
                (Kind::Vel, false) => "m/min? 50 m/min = 833.333 mm/s",
                (Kind::Acc, false) => "m/s2? 5 m/s2 = 5000 mm/s2",
                (Kind::Jerk, false) => "m/s3? 40 m/s3 = 40000 mm/s3",
                (Kind::Vel, true) => "rev/s? 5 rev/s = 1800 deg/s",
                (Kind::Acc, true) => "rev/s2? 3 rev/s2 = 1080 deg/s2",
                (Kind::Jerk, true) => "rev/s3? 100 rev/s3 = 36000 deg/s3",
                (Kind::Time, _) => "µs? the cycle time is in s (0.003 for 3 ms)",
                _ => "",
            };
            return Err(self.invalid(
                key,
                value,
                format!(
                    "= {} {unit} is implausibly small: was it given in {hint}",
                    crate::math::limits::shown(v)
                ),
            ));
        }
        if v > kind.plausible_max(rotary) {
            let hint = match kind {
                Kind::Time => "ms? write 0.003 for 3 ms",
                _ => "µm? the tolerance is in mm (deg for rotary axes)",
            };
            return Err(self.invalid(
                key,
                value,
                format!(
                    "= {} {unit} is implausibly large: was it given in {hint}",
                    crate::math::limits::shown(v)
                ),
            ));
        }
        Ok(v)
    }
}

fn unit_vec(ctx: &Ctx, key: &str, v: &Spanned<super::Fixed<3>>) -> Result<Vec3, MachineError> {
    let [x, y, z] = v.get_ref().0;
    let w = Vec3::new(x, y, z);
    let n = w.norm();
    if !n.is_finite() || n < 1e-9 {
        return Err(ctx.invalid(key, v, "must be a non-zero direction"));
    }
    if (n - 1.0).abs() > 1e-3 {
        return Err(ctx.invalid(key, v, format!("must be a unit vector, has length {n:.6}")));
    }
    Ok(w / n)
}

fn finite3(ctx: &Ctx, key: &str, v: &Spanned<super::Fixed<3>>) -> Result<Vec3, MachineError> {
    let [x, y, z] = v.get_ref().0;
    if !(x.is_finite() && y.is_finite() && z.is_finite()) {
        return Err(ctx.invalid(key, v, "must be finite"));
    }
    Ok(Vec3::new(x, y, z))
}

fn need<'b, T>(v: &'b Option<T>, key: &str, table: &str, at: Span) -> Result<&'b T, MachineError> {
    v.as_ref().ok_or_else(|| MachineError::Missing {
        key: key.to_string(),
        table: table.to_string(),
        at,
    })
}

fn sign_of(ctx: &Ctx, s: &Option<Spanned<f64>>) -> Result<f64, MachineError> {
    match s {
        None => Ok(1.0),
        Some(v) if *v.get_ref() == 1.0 || *v.get_ref() == -1.0 => Ok(*v.get_ref()),
        Some(v) => Err(ctx.invalid("sign", v, "must be 1 or -1")),
    }
}

fn limits_of(
    ctx: &Ctx,
    a: &FileAxis,
    table: &str,
    at: Span,
    rotary: bool,
) -> Result<Limits, MachineError> {
    let q = |key: &str, v: &Option<Spanned<Quantity>>, kind: Kind| -> Result<f64, MachineError> {
        ctx.quantity(key, need(v, key, table, at)?, kind, rotary)
    };
    let scale = if rotary { 1f64.to_radians() } else { 1.0 };
    Ok(Limits {
        vmax: q("vmax", &a.vmax, Kind::Vel)? * scale,
        amax: q("amax", &a.amax, Kind::Acc)? * scale,
        jmax: q("jmax", &a.jmax, Kind::Jerk)? * scale,
        tol: q("tol", &a.tol, Kind::Len)? * scale,
    })
}

impl Machine {
    /// Read a machine description (kinematics.md §3.2). Errors name the key and the line.
    pub fn from_toml_str(text: &str) -> Result<Machine, MachineError> {
        let file: FileMachine = toml::from_str(text).map_err(|e| {
            let msg = e.message().trim().to_string();
            match e.span() {
                Some(_) => MachineError::Toml {
                    at: super::toml_span(text, &e),
                    message: msg,
                },
                None => MachineError::Syntax(msg),
            }
        })?;
        let ctx = Ctx { text };
        let top = "the top level";
        let cycle = need(&file.cycle_time, "cycle_time", top, Span::at(text, 0))?;
        let cycle_time = ctx.quantity("cycle_time", cycle, Kind::Time, false)?;
        let min_block_cycles = match &file.min_block_cycles {
            None => 1.0,
            Some(v) if v.get_ref().is_finite() && (0.0..=1000.0).contains(v.get_ref()) => {
                *v.get_ref()
            }
            Some(v) => return Err(ctx.invalid("min_block_cycles", v, "must lie in [0, 1000]")),
        };
        let lookahead_blocks = match &file.lookahead_blocks {
            None => 0,
            Some(v) if *v.get_ref() >= 0 => *v.get_ref() as usize,
            Some(v) => return Err(ctx.invalid("lookahead_blocks", v, "must be >= 0")),
        };
        let branch = match &file.branch {
            None => BranchPreference::default(),
            Some(v) => match v.get_ref().as_str() {
                "first_positive" => BranchPreference::FirstPositive,
                "first_negative" => BranchPreference::FirstNegative,
                other => {
                    return Err(ctx.invalid(
                        "branch",
                        v,
                        format!(
                            "is \"{other}\", expected \"first_positive\" or \"first_negative\""
                        ),
                    ));
                }
            },
        };
        let tool = need(&file.tool, "[tool]", top, Span::at(text, 0))?;
        let tool_at = ctx.span(tool);
        let t = tool.get_ref();
        let dir_home = unit_vec(
            &ctx,
            "dir_home",
            need(&t.dir_home, "dir_home", "[tool]", tool_at)?,
        )?;
        let tip_home = finite3(
            &ctx,
            "tip_home",
            need(&t.tip_home, "tip_home", "[tool]", tool_at)?,
        )?;
        let part_origin = match &t.part_origin {
            Some(v) => finite3(&ctx, "part_origin", v)?,
            None => Vec3::zeros(),
        };

        if file.linear.len() != 3 {
            return Err(MachineError::Invalid {
                key: "[[linear]]".into(),
                at: file
                    .linear
                    .first()
                    .map_or(Span::at(text, 0), |l| ctx.span(l)),
                message: format!("needs exactly 3 linear axes, found {}", file.linear.len()),
            });
        }
        let mut linear = Vec::with_capacity(3);
        for (i, l) in file.linear.iter().enumerate() {
            let at = ctx.span(l);
            let a = l.get_ref();
            let name = a
                .name
                .clone()
                .unwrap_or_else(|| ["X", "Y", "Z"][i].to_string());
            let table = format!("[[linear]] {name}");
            if let Some(s) = &a.side {
                return Err(ctx.invalid("side", s, "is only for rotary axes"));
            }
            let direction = unit_vec(
                &ctx,
                "direction",
                need(&a.direction, "direction", &table, at)?,
            )?;
            linear.push(LinearAxis {
                sign: sign_of(&ctx, &a.sign)?,
                limits: limits_of(&ctx, a, &table, at, false)?,
                name,
                direction,
            });
        }
        let m = nalgebra::Matrix3::from_columns(&[
            linear[0].direction,
            linear[1].direction,
            linear[2].direction,
        ]);
        if m.determinant().abs() < 1e-6 {
            return Err(MachineError::Invalid {
                key: "direction".into(),
                at: ctx.span(&file.linear[0]),
                message: "the three linear directions do not span space".into(),
            });
        }

        if file.rotary.len() != 2 {
            return Err(MachineError::Invalid {
                key: "[[rotary]]".into(),
                at: file
                    .rotary
                    .first()
                    .map_or(Span::at(text, 0), |l| ctx.span(l)),
                message: format!("needs exactly 2 rotary axes, found {}", file.rotary.len()),
            });
        }
        let mut rotary = Vec::with_capacity(2);
        for (i, r) in file.rotary.iter().enumerate() {
            let at = ctx.span(r);
            let a = r.get_ref();
            let name = a.name.clone().unwrap_or_else(|| ["A", "C"][i].to_string());
            let table = format!("[[rotary]] {name}");
            let side_v = need(&a.side, "side", &table, at)?;
            let side = match side_v.get_ref().as_str() {
                "table" => Side::Table,
                "head" => Side::Head,
                other => {
                    return Err(ctx.invalid(
                        "side",
                        side_v,
                        format!("is \"{other}\", expected \"table\" or \"head\""),
                    ));
                }
            };
            let axis = unit_vec(&ctx, "axis", need(&a.axis, "axis", &table, at)?)?;
            let point = match &a.point {
                Some(p) => Point3::from(finite3(&ctx, "point", p)?),
                None => Point3::origin(),
            };
            let lim_v = need(&a.limits, "limits", &table, at)?;
            let travel = match lim_v.get_ref().as_slice() {
                [] => None,
                [lo, hi] if lo.is_finite() && hi.is_finite() && lo < hi => {
                    Some((lo.to_radians(), hi.to_radians()))
                }
                _ => {
                    return Err(ctx.invalid(
                        "limits",
                        lim_v,
                        "must be [] (endless) or [min_deg, max_deg] with min < max",
                    ));
                }
            };
            rotary.push(RotaryAxis {
                sign: sign_of(&ctx, &a.sign)?,
                limits: limits_of(&ctx, a, &table, at, true)?,
                name,
                side,
                axis,
                point,
                travel,
            });
        }
        if rotary[0].side == Side::Head && rotary[1].side == Side::Table {
            return Err(MachineError::Invalid {
                key: "side".into(),
                at: ctx.span(&file.rotary[0]),
                message: "list table axes (base -> part) before head axes (base -> spindle)".into(),
            });
        }
        let [l0, l1, l2]: [LinearAxis; 3] = linear
            .try_into()
            .map_err(|_| MachineError::Syntax("linear axes".into()))?;
        let [r0, r1]: [RotaryAxis; 2] = rotary
            .try_into()
            .map_err(|_| MachineError::Syntax("rotary axes".into()))?;
        Ok(Machine {
            name: file.name.unwrap_or_default(),
            cycle_time,
            min_block_cycles,
            lookahead_blocks,
            junction_spacing_rule: file.junction_spacing_rule.unwrap_or(true),
            branch,
            dir_home,
            tip_home: Point3::from(tip_home),
            part_origin,
            linear: [l0, l1, l2],
            rotary: [r0, r1],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::machine::TABLE_I_AC_TOML;
    use approx::assert_relative_eq;

    #[test]
    fn table_i_loads_in_internal_units() {
        let m = Machine::from_toml_str(TABLE_I_AC_TOML).unwrap();
        assert_relative_eq!(m.cycle_time, 0.003);
        assert_relative_eq!(m.linear[0].limits.vmax, 833.333, epsilon = 1e-9);
        assert_relative_eq!(m.linear[1].limits.jmax, 80000.0);
        assert_relative_eq!(
            m.rotary[0].limits.vmax,
            300f64.to_radians(),
            epsilon = 1e-12
        );
        assert_relative_eq!(
            m.rotary[1].limits.amax,
            1080f64.to_radians(),
            epsilon = 1e-12
        );
        assert_eq!(m.rotary[1].travel, None);
        let (lo, hi) = m.rotary[0].travel.unwrap();
        assert_relative_eq!(hi, 120f64.to_radians());
        assert_relative_eq!(lo, -120f64.to_radians());
        assert!(m.junction_spacing_rule);
        assert_eq!(m.joint_names(), ["X", "Y", "Z", "A", "C"]);
    }

    #[test]
    fn unit_strings_are_converted() {
        let t = TABLE_I_AC_TOML
            .replacen("vmax = 833.333", "vmax = \"50 m/min\"", 1)
            .replacen("amax = 1080.0", "amax = \"3 rev/s2\"", 1);
        let m = Machine::from_toml_str(&t).unwrap();
        assert_relative_eq!(m.linear[0].limits.vmax, 50_000.0 / 60.0, epsilon = 1e-9);
        assert_relative_eq!(
            m.rotary[0].limits.amax,
            1080f64.to_radians(),
            epsilon = 1e-12
        );
    }

    fn line_of_str(text: &str, needle: &str) -> u32 {
        Span::at(text, text.find(needle).unwrap()).line
    }

    #[test]
    fn wrong_units_are_rejected_with_key_and_line() {
        // 5 m/s² typed as 5 in mm/s².
        let t = TABLE_I_AC_TOML.replacen("amax = 5000.0", "amax = 5.0", 1);
        let line = line_of_str(&t, "amax = 5.0");
        match Machine::from_toml_str(&t).unwrap_err() {
            MachineError::Invalid { key, at, message } => {
                assert_eq!(key, "amax");
                assert_eq!(at.line, line);
                assert!(message.contains("m/s2"), "{message}");
            }
            e => panic!("unexpected {e}"),
        }
        // A unit of the wrong kind.
        let t = TABLE_I_AC_TOML.replacen("vmax = 300.0", "vmax = \"3 rev/s2\"", 1);
        let line = line_of_str(&t, "vmax = \"3 rev/s2\"");
        let e = Machine::from_toml_str(&t).unwrap_err();
        let at = Span::of(
            &t,
            t.find("\"3 rev/s2\"").unwrap()..t.find("\"3 rev/s2\"").unwrap() + 10,
        );
        assert_eq!(at.line, line);
        assert_eq!(
            e,
            MachineError::Invalid {
                key: "vmax".into(),
                at,
                message: "has unit \"rev/s2\", expected deg/s or a convertible unit".into()
            }
        );
        // 3 ms typed as 3.
        let t = TABLE_I_AC_TOML.replacen("cycle_time = 0.003", "cycle_time = 3", 1);
        let e = Machine::from_toml_str(&t).unwrap_err();
        assert!(e.to_string().contains("`cycle_time`"), "{e}");
        assert!(e.to_string().starts_with("line 2:"), "{e}");
    }

    #[test]
    fn missing_limits_name_the_key_and_table_line() {
        let t = TABLE_I_AC_TOML.replacen("jmax = 80000.0\n", "", 1);
        let line = line_of_str(&t, "name = \"Y\"") - 1;
        match Machine::from_toml_str(&t).unwrap_err() {
            MachineError::Missing { key, table, at } => {
                assert_eq!(
                    (key.as_str(), table.as_str(), at.line),
                    ("jmax", "[[linear]] Y", line)
                );
            }
            e => panic!("unexpected {e}"),
        }
        let t = TABLE_I_AC_TOML.replacen("limits = []", "", 1);
        let e = Machine::from_toml_str(&t).unwrap_err();
        assert!(
            matches!(&e, MachineError::Missing { key, table, .. } if key == "limits" && table == "[[rotary]] C"),
            "{e}"
        );
    }

    #[test]
    fn unknown_keys_and_bad_toml_are_errors() {
        let t = TABLE_I_AC_TOML.replacen("tol = 0.01", "tol = 0.01\nvmx = 3.0", 1);
        let e = Machine::from_toml_str(&t).unwrap_err();
        assert!(e.to_string().contains("vmx"), "{e}");
        assert!(Machine::from_toml_str("cycle_time = [").is_err());
        assert!(Machine::from_toml_str("").is_err());
    }
}
