//! Synthetic tool paths with contact data for known surfaces (plane, extruded parabola,
//! hyperbolic paraboloid, blade-like patch), with the stepover from a scallop height by the
//! exact swept-envelope method (model.md §7, R6).
//!
//! Every test of crest and every user without an NX seat needs paths whose CC points and
//! normals are known exactly. This stage makes them as [`Program`]s, the same type the
//! CLSF reader produces, so they go through the writers and the rest of the pipeline
//! unchanged.
//!
//! **Passes.** Parallel drive planes ("parallel plane" mode of CAM): pass k runs in the
//! vertical plane v = v_k of a frame (u, v) turned by the pass angle from the WCS x axis,
//! over a rectangle `size_mm = (length along u, width along v)` centred on the origin. The
//! CC points lie on the surface in that plane, every `point_step_mm` along u. Passes are
//! one-way (all in +u, the assumption of model.md §8) or zigzag (alternating).
//!
//! **Posture.** At each CC point C with normal n: f = the pass tangent (in the tangent
//! plane), g = n × f, and the tool axis by convention A of model.md §7 from tilt λ and yaw
//! ψ, `a = sin λ cos ψ f + sin λ sin ψ g + cos λ n`; a lead β is tilt β with yaw 0. The CL
//! point is the tool tip touching C exactly: the corner-circle centre is C + rc n, it lies
//! Rd from the axis in the direction w = −(n − (n·a) a)/|…|, so
//! `tip = C + rc n − rc a − Rd w` (ball: `C + R n − R a`; flat end: its rim touches).
//!
//! **Stepover.** Given directly (the drive-plane spacing), or from a scallop height: the
//! exact step s of the swept envelope on a plane ([`envelope`]), corrected for the normal
//! curvature κ across the pass by `s·(1 − R_eff κ)^(−1/2)` (model.md §7, κ > 0 concave)
//! and converted to a drive-plane spacing; the smallest spacing over the field is used,
//! so the scallop nowhere exceeds the target (to the accuracy of the curvature correction).
//!
//! **Links.** Each pass starts with a RAPID to a clearance point along the tool axis above
//! its first CL point, engages at feed along the axis to that point, cuts through its CC
//! points and ends with a RAPID back up along the axis. Every move that reaches a CC point
//! is a cutting move with contact data, and each pass is one cutting run (starting at its
//! clearance point), so CLSF and contact12 (with its blank non-cutting rows) read back the
//! same.

pub mod envelope;
pub mod mesh;
pub mod pass;
mod surface;

pub use envelope::{
    CrossSection, approx_step_mm, axis_convention_a, effective_radius_mm, exact_step_mm,
};
pub use surface::Surface;

use crate::math::{Point3, Vec3};
use crate::tool::{Cutter, Shape};
use crate::toolpath::{Contact, MotionKind, Posture, Program, ToolData, Toolpath};

/// Errors of the synthetic-path stage.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SynthError {
    /// A parameter out of range.
    #[error("{0}")]
    Invalid(String),
    /// A parameter beyond a plausibility limit.
    #[error(transparent)]
    Limit(#[from] crate::math::limits::LimitError),
    /// The cutter cannot follow the surface at the target scallop: a concave radius is
    /// smaller than the effective cutting radius.
    #[error(
        "the surface is concave with radius {radius_mm:.2} mm at x = {x_mm:.2}, y = {y_mm:.2} mm, \
         below the effective cutter radius {r_eff_mm:.2} mm: the tool would gouge; \
         tilt it more or use a smaller tool"
    )]
    Gouge {
        /// Concave radius across the pass, mm.
        radius_mm: f64,
        /// Effective radius of the cutter across the feed, mm.
        r_eff_mm: f64,
        /// Where, mm.
        x_mm: f64,
        /// Where, mm.
        y_mm: f64,
    },
}

/// Tool orientation in the local frame (f, g, n).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Orientation {
    /// Convention A of model.md §7: tilt λ and yaw ψ, rad.
    TiltYaw {
        /// λ, rad.
        tilt_rad: f64,
        /// ψ, rad.
        yaw_rad: f64,
    },
    /// Lead β in the feed direction (002's ball ends): the same as tilt β, yaw 0.
    Lead {
        /// β, rad.
        lead_rad: f64,
    },
    /// One tool axis for the whole path in the WCS (a 3-axis path: the axis is z).
    Fixed {
        /// Unit axis, WCS.
        axis: Vec3,
    },
}

impl Orientation {
    /// The unit tool axis in (f, g, n).
    pub fn axis_fgn(&self) -> Vec3 {
        match *self {
            Orientation::TiltYaw { tilt_rad, yaw_rad } => axis_convention_a(tilt_rad, yaw_rad),
            Orientation::Lead { lead_rad } => axis_convention_a(lead_rad, 0.0),
            // At a point whose normal is the axis (the field centre of a level surface).
            Orientation::Fixed { .. } => Vec3::z(),
        }
    }
}

/// How the pass interval is set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Step {
    /// From a target scallop height, mm.
    Scallop {
        /// Target scallop height h, mm.
        height_mm: f64,
    },
    /// The drive-plane spacing, mm.
    Stepover {
        /// Spacing, mm.
        spacing_mm: f64,
    },
    /// The distance between passes measured along the surface, across the passes through
    /// the field's centre, mm (the contact points of neighbouring passes are this far apart
    /// along the cross-section there).
    SurfaceArc {
        /// Spacing along the surface, mm.
        spacing_mm: f64,
    },
}

/// Pass direction pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Pattern {
    /// Every pass in +u (model.md §8).
    #[default]
    OneWay,
    /// Alternating +u, −u.
    Zigzag,
}

/// Everything that defines a synthetic path.
#[derive(Debug, Clone, PartialEq)]
pub struct PathSpec {
    /// The surface.
    pub surface: Surface,
    /// The cutter.
    pub cutter: Cutter,
    /// Tool orientation in (f, g, n).
    pub orientation: Orientation,
    /// Pass interval.
    pub step: Step,
    /// Field: length along the passes and width across, mm, centred on the origin.
    pub size_mm: (f64, f64),
    /// Direction of the passes in the XY plane, from +x towards +y, rad.
    pub pass_angle_rad: f64,
    /// Spacing of CC points along a pass (in u), mm.
    pub point_step_mm: f64,
    /// One-way or zigzag.
    pub pattern: Pattern,
    /// Programmed feed, mm/min (at the start of each pass when `feed_end_mm_min` is set).
    pub feed_mm_min: f64,
    /// Feed at the end of each pass, mm/min: the feed then changes linearly with the
    /// distance along the pass, one FEDRAT per move (001 Fig 6); `None` = constant.
    pub feed_end_mm_min: Option<f64>,
    /// Spindle speed, rpm.
    pub spindle_rpm: f64,
    /// Retract distance along the tool axis between passes, mm.
    pub clearance_mm: f64,
    /// Operation name (`TOOL PATH/<name>`).
    pub name: String,
    /// Tool name.
    pub tool_name: String,
}

impl PathSpec {
    /// A spec with the usual defaults: passes along +x, 0.5 mm point step, one-way,
    /// 5 mm clearance, names from the surface.
    pub fn new(
        surface: Surface,
        cutter: Cutter,
        orientation: Orientation,
        step: Step,
        size_mm: (f64, f64),
    ) -> PathSpec {
        PathSpec {
            name: format!("SYNTH_{}", surface.name().to_uppercase().replace('-', "_")),
            tool_name: tool_name(&cutter),
            surface,
            cutter,
            orientation,
            step,
            size_mm,
            pass_angle_rad: 0.0,
            point_step_mm: 0.5,
            pattern: Pattern::OneWay,
            feed_mm_min: 1000.0,
            feed_end_mm_min: None,
            spindle_rpm: 10000.0,
            clearance_mm: 5.0,
        }
    }
}

/// A synthetic path and how it was laid out.
#[derive(Debug, Clone)]
pub struct Synthetic {
    /// One tool path.
    pub program: Program,
    /// Drive-plane spacing used, mm.
    pub stepover_mm: f64,
    /// Number of passes.
    pub passes: usize,
    /// CC points per pass.
    pub points_per_pass: usize,
    /// Effective cutter radius across the feed (closed form, model.md §7), mm.
    pub r_eff_mm: f64,
    /// Exact step on a plane for the target scallop (scallop mode only), mm.
    pub plane_step_mm: Option<f64>,
}

/// A tool name such as `BALL_D10` or `TORUS_D10_R1.5`.
pub fn tool_name(cutter: &Cutter) -> String {
    let d = fmt_num(2.0 * cutter.radius_mm);
    match &cutter.shape {
        Shape::Ball => format!("BALL_D{d}"),
        Shape::Torus { corner_radius_mm } => {
            format!("TORUS_D{d}_R{}", fmt_num(*corner_radius_mm))
        }
        Shape::Flat => format!("FLAT_D{d}"),
        Shape::RoundInsert { insert_radius_mm } => {
            format!("ROUND_D{d}_R{}", fmt_num(*insert_radius_mm))
        }
        Shape::Profile(m) => format!("{}_D{d}", m.family().name().to_ascii_uppercase()),
    }
}

fn fmt_num(x: f64) -> String {
    let s = format!("{x:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The CL point (tool tip) of `cutter` with unit axis `axis` touching the CC point `cc`
/// whose unit surface normal is `normal` (see the module docs).
pub fn tool_tip(cutter: &Cutter, cc: &Point3, normal: &Vec3, axis: &Vec3) -> Point3 {
    if let Shape::Profile(m) = &cutter.shape {
        // The meridian's point whose outward normal is −n touches the CC point.
        let m_a = -normal.dot(axis);
        let radial = -normal - axis * m_a;
        let w = crate::math::normalize_or_none(&radial, 1e-12).unwrap_or_else(Vec3::zeros);
        let p = m.support(radial.norm(), m_a);
        return cc - axis * p[1] - w * p[0];
    }
    let rc = cutter.corner_radius_mm();
    let rd = cutter.radius_mm - rc;
    let radial = normal - axis * normal.dot(axis);
    let w = crate::math::normalize_or_none(&radial, 1e-12)
        .map(|r| -r)
        .unwrap_or_else(Vec3::zeros);
    cc + normal * rc - axis * rc - w * rd
}

/// The TLDATA of a synthetic path: diameter and corner radius of a ball, torus or flat end,
/// all seven parameters of an APT cutter (written as NX's seven-value TLDATA/MILL); `None`
/// for the shapes TLDATA cannot describe (round inserts, other profiles: give `--tool`).
pub fn tool_data(cutter: &Cutter) -> Option<ToolData> {
    let apt = match &cutter.shape {
        Shape::Profile(m) => match m.family() {
            crate::tool::Family::Apt(p) => Some([
                p[0],
                p[1],
                p[2],
                p[3],
                p[4].to_radians(),
                p[5].to_radians(),
                p[6],
            ]),
            _ => return None,
        },
        Shape::RoundInsert { .. } => return None,
        _ => None,
    };
    Some(ToolData {
        kind: "MILL".to_string(),
        diameter_mm: apt.map_or(2.0 * cutter.radius_mm, |p| p[0]),
        corner_radius_mm: cutter.corner_radius_mm(),
        length_mm: apt.map_or(75.0, |p| p[6]),
        taper_rad: apt.map_or(0.0, |p| p[5]),
        tip_rad: apt.map_or(0.0, |p| p[4]),
        apt,
    })
}

/// One point of a pass: CC point, normal, feed direction.
struct Station {
    cc: Point3,
    normal: Vec3,
    feed: Vec3,
}

fn station(surface: &Surface, u: f64, v: f64, du: &Vec3, dv: &Vec3, sign: f64) -> Station {
    let x = u * du.x + v * dv.x;
    let y = u * du.y + v * dv.y;
    let cc = Point3::new(x, y, surface.height(x, y));
    let normal = surface.normal(x, y);
    let (fx, fy) = surface.gradient(x, y);
    // Tangent of the drive-plane section: d/du (x, y, F) = (du, ∇F·du).
    let t = Vec3::new(du.x, du.y, fx * du.x + fy * du.y) * sign;
    let feed = (t - normal * t.dot(&normal)).normalize();
    Station { cc, normal, feed }
}

fn check_positive(name: &str, v: f64) -> Result<(), SynthError> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(SynthError::Invalid(format!(
            "{name} must be positive, got {}",
            crate::math::limits::shown(v)
        )))
    }
}

/// Make a synthetic tool path.
pub fn generate(spec: &PathSpec) -> Result<Synthetic, SynthError> {
    check_positive("the field length", spec.size_mm.0)?;
    check_positive("the field width", spec.size_mm.1)?;
    check_positive("the point step", spec.point_step_mm)?;
    check_positive("the feed", spec.feed_mm_min)?;
    if let Some(f) = spec.feed_end_mm_min {
        check_positive("the feed at the end of a pass", f)?;
    }
    check_positive("the spindle speed", spec.spindle_rpm)?;
    check_positive("the tool radius", spec.cutter.radius_mm)?;
    if !(spec.clearance_mm >= 0.0 && spec.clearance_mm.is_finite()) {
        return Err(SynthError::Invalid(format!(
            "the clearance must not be negative, got {}",
            spec.clearance_mm
        )));
    }
    let rc = spec.cutter.corner_radius_mm();
    let is_profile = matches!(spec.cutter.shape, Shape::Profile(_));
    if !is_profile && !(0.0..=spec.cutter.radius_mm).contains(&rc) {
        return Err(SynthError::Invalid(format!(
            "the corner radius {rc} mm must lie in [0, R = {} mm]",
            spec.cutter.radius_mm
        )));
    }
    if let Orientation::Fixed { axis } = spec.orientation
        && !(axis.iter().all(|c| c.is_finite()) && (axis.norm() - 1.0).abs() < 1e-6)
    {
        return Err(SynthError::Invalid(format!(
            "the fixed tool axis must be a unit vector, got {axis:?}"
        )));
    }
    let axis_fgn = spec.orientation.axis_fgn();
    if !axis_fgn.iter().all(|c| c.is_finite()) || axis_fgn.z <= 1e-9 {
        return Err(SynthError::Invalid(
            "the tilt must lie in [0°, 90°)".to_string(),
        ));
    }
    let (length, width) = spec.size_mm;
    if length > 1e4 || width > 1e4 {
        return Err(SynthError::Invalid(format!(
            "the field {length} × {width} mm is beyond 10 m"
        )));
    }
    if !spec.pass_angle_rad.is_finite() {
        return Err(SynthError::Invalid(format!(
            "the pass angle must be finite, got {}",
            spec.pass_angle_rad
        )));
    }
    for (what, unit, v, range) in [
        (
            "the feed",
            "mm/min",
            spec.feed_mm_min,
            crate::math::limits::FEED_MM_MIN,
        ),
        (
            "the spindle speed",
            "rpm",
            spec.spindle_rpm,
            crate::math::limits::RPM,
        ),
    ] {
        crate::math::limits::within(what, unit, v, range)?;
    }
    if length / spec.point_step_mm > 1e6 {
        return Err(SynthError::Invalid(format!(
            "{:.0} points of {} mm along a {length} mm pass are too many (at most 1e6)",
            length / spec.point_step_mm,
            spec.point_step_mm
        )));
    }
    let du = Vec3::new(spec.pass_angle_rad.cos(), spec.pass_angle_rad.sin(), 0.0);
    let dv = Vec3::new(-du.y, du.x, 0.0);
    let n_points = ((length / spec.point_step_mm).ceil() as usize).max(1) + 1;
    let us: Vec<f64> = (0..n_points)
        .map(|i| -0.5 * length + length * i as f64 / (n_points - 1) as f64)
        .collect();
    let r_eff = effective_radius_mm(&spec.cutter, &axis_fgn);

    let mut pass_v: Option<Vec<f64>> = None;
    let (stepover, plane_step) = match spec.step {
        Step::Stepover { spacing_mm } => {
            check_positive("the stepover", spacing_mm)?;
            (spacing_mm, None)
        }
        Step::SurfaceArc { spacing_mm } => {
            check_positive("the stepover along the surface", spacing_mm)?;
            if width / spacing_mm > 100_000.0 {
                return Err(SynthError::Invalid(format!(
                    "{:.0} passes of {spacing_mm} mm over {width} mm are too many",
                    width / spacing_mm
                )));
            }
            let n = (width / spacing_mm - 1e-9).ceil().max(0.0) as usize + 1;
            let vs: Vec<f64> = (0..n)
                .map(|k| {
                    let a = (k as f64 - 0.5 * (n - 1) as f64) * spacing_mm;
                    arc_to_v(&spec.surface, &du, &dv, a)
                })
                .collect();
            pass_v = Some(vs);
            (spacing_mm, None)
        }
        Step::Scallop { height_mm } => {
            let s = exact_step_mm(&spec.cutter, &axis_fgn, height_mm)?;
            let spacing = drive_plane_spacing(spec, s, r_eff, &us, &du, &dv)?;
            (spacing, Some(s))
        }
    };
    if width / stepover > 100_000.0 {
        return Err(SynthError::Invalid(format!(
            "{:.0} passes of {stepover} mm over {width} mm are too many",
            width / stepover
        )));
    }
    let passes = pass_v.as_ref().map_or_else(
        || (width / stepover - 1e-9).ceil().max(0.0) as usize + 1,
        Vec::len,
    );

    let mut postures = Vec::with_capacity(passes * (n_points + 2));
    let posture = |position: Point3, axis: Vec3, motion, contact, feed: f64| Posture {
        position,
        axis,
        motion,
        arc: None,
        contact,
        feed_mm_min: Some(feed),
        spindle_rpm: Some(spec.spindle_rpm),
        line: 0,
    };
    for k in 0..passes {
        let v = match &pass_v {
            Some(vs) => vs[k],
            None => (k as f64 - 0.5 * (passes - 1) as f64) * stepover,
        };
        let reverse = spec.pattern == Pattern::Zigzag && k % 2 == 1;
        let sign = if reverse { -1.0 } else { 1.0 };
        let order: Box<dyn Iterator<Item = &f64>> = if reverse {
            Box::new(us.iter().rev())
        } else {
            Box::new(us.iter())
        };
        let mut pass = Vec::with_capacity(n_points);
        for &u in order {
            let st = station(&spec.surface, u, v, &du, &dv, sign);
            if !spec.surface.covers(st.cc.x, st.cc.y) {
                return Err(SynthError::Invalid(format!(
                    "the field reaches ({:.3}, {:.3}), beyond the {} (radius {} mm): choose a smaller ‹size_mm›",
                    st.cc.x,
                    st.cc.y,
                    spec.surface.name(),
                    spec.surface.radius_mm().unwrap_or(f64::NAN)
                )));
            }
            let g = st.normal.cross(&st.feed);
            let axis = match spec.orientation {
                Orientation::Fixed { axis } => axis,
                _ => (st.feed * axis_fgn.x + g * axis_fgn.y + st.normal * axis_fgn.z).normalize(),
            };
            let tip = tool_tip(&spec.cutter, &st.cc, &st.normal, &axis);
            pass.push((tip, axis, st));
        }
        let (first, last) = match (pass.first(), pass.last()) {
            (Some(f), Some(l)) => (f, l),
            _ => continue,
        };
        let approach = first.0 + first.1 * spec.clearance_mm;
        let retract = last.0 + last.1 * spec.clearance_mm;
        let f0 = spec.feed_mm_min;
        postures.push(posture(approach, first.1, MotionKind::Rapid, None, f0));
        for (i, (tip, axis, st)) in pass.iter().enumerate() {
            let contact = Contact {
                point: st.cc,
                normal: st.normal,
                normal_derived: false,
            };
            // The move ending at point i runs at the feed of its end along the pass.
            let feed = match spec.feed_end_mm_min {
                Some(f1) if pass.len() > 1 => f0 + (f1 - f0) * i as f64 / (pass.len() - 1) as f64,
                _ => f0,
            };
            postures.push(posture(*tip, *axis, MotionKind::Cut, Some(contact), feed));
        }
        let f_last = spec.feed_end_mm_min.unwrap_or(f0);
        postures.push(posture(retract, last.1, MotionKind::Rapid, None, f_last));
    }

    let path = Toolpath {
        name: spec.name.clone(),
        tool_name: spec.tool_name.clone(),
        tool: tool_data(&spec.cutter),
        msys: None,
        postures,
        ..Default::default()
    };
    Ok(Synthetic {
        program: Program {
            paths: vec![path],
            warnings: Vec::new(),
        },
        stepover_mm: stepover,
        passes,
        points_per_pass: n_points,
        r_eff_mm: r_eff,
        plane_step_mm: plane_step,
    })
}

/// The drive-plane coordinate v whose point on the cross-section through the field centre
/// (u = 0) lies arc length `a` along the surface from v = 0 (negative `a` towards −v):
/// Simpson's rule on √(1 + (dF/dv)²) and bisection.
fn arc_to_v(surface: &Surface, du: &Vec3, dv: &Vec3, a: f64) -> f64 {
    let _ = du;
    let slope = |v: f64| {
        let (fx, fy) = surface.gradient(dv.x * v, dv.y * v);
        let d = fx * dv.x + fy * dv.y;
        (1.0 + d * d).sqrt()
    };
    let arc = |v: f64| {
        let n = 200;
        let h = v / n as f64;
        let mut sum = slope(0.0) + slope(v);
        for i in 1..n {
            sum += slope(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        sum * h / 3.0
    };
    if a == 0.0 {
        return 0.0;
    }
    // The arc is at least |v|: search v in [0, a].
    let (mut lo, mut hi) = if a > 0.0 { (0.0, a) } else { (a, 0.0) };
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if arc(mid) < a {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The drive-plane spacing that keeps the scallop at or below the target everywhere:
/// the curvature-corrected surface step, projected on the drive-plane normal, minimised
/// over a grid of the field.
fn drive_plane_spacing(
    spec: &PathSpec,
    plane_step: f64,
    r_eff: f64,
    us: &[f64],
    du: &Vec3,
    dv: &Vec3,
) -> Result<f64, SynthError> {
    if spec.surface == Surface::Plane {
        return Ok(plane_step);
    }
    let (_, width) = spec.size_mm;
    let n_v = 41;
    let stride = (us.len() / 40).max(1);
    let mut best = f64::INFINITY;
    for j in 0..n_v {
        let v = -0.5 * width + width * j as f64 / (n_v - 1) as f64;
        for &u in us.iter().step_by(stride).chain(us.last()) {
            for sign in [1.0, -1.0] {
                if sign < 0.0 && spec.pattern == Pattern::OneWay {
                    continue;
                }
                let st = station(&spec.surface, u, v, du, dv, sign);
                let g = st.normal.cross(&st.feed);
                let (x, y) = (st.cc.x, st.cc.y);
                let kappa = spec.surface.normal_curvature(x, y, &g);
                let s = if r_eff.is_finite() {
                    let q = 1.0 - r_eff * kappa;
                    if q <= 0.0 {
                        return Err(SynthError::Gouge {
                            radius_mm: 1.0 / kappa,
                            r_eff_mm: r_eff,
                            x_mm: x,
                            y_mm: y,
                        });
                    }
                    plane_step / q.sqrt()
                } else {
                    plane_step
                };
                // Moving one unit in v moves the CC point by e = (dv, ∇F·dv); its lateral
                // part along g is what the step s measures.
                let (fx, fy) = spec.surface.gradient(x, y);
                let e = Vec3::new(dv.x, dv.y, fx * dv.x + fy * dv.y);
                let lateral = e.dot(&g).abs().max(1e-9);
                best = best.min(s / lateral);
            }
        }
    }
    Ok(best)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn torus() -> Cutter {
        Cutter::new(
            Shape::Torus {
                corner_radius_mm: 1.5,
            },
            5.0,
            1,
            0.0,
        )
    }

    fn cut_contacts(p: &Toolpath) -> impl Iterator<Item = (&Posture, &Contact)> {
        p.postures
            .iter()
            .filter_map(|q| q.contact.as_ref().map(|c| (q, c)))
    }

    #[test]
    fn plane_trial_3_pass_count_and_step() {
        // model.md R6 test 3: tilt 10°, yaw 0, h = 10 µm → s = 1.3115 mm.
        let spec = PathSpec::new(
            Surface::Plane,
            torus(),
            Orientation::TiltYaw {
                tilt_rad: 10f64.to_radians(),
                yaw_rad: 0.0,
            },
            Step::Scallop { height_mm: 0.010 },
            (20.0, 10.0),
        );
        let s = generate(&spec).unwrap();
        assert!((s.stepover_mm - 1.3115).abs() < 1e-3);
        // ceil(10 / 1.3115) + 1 = 9 passes of 41 points.
        assert_eq!(s.passes, 9);
        assert_eq!(s.points_per_pass, 41);
        let path = &s.program.paths[0];
        assert_eq!(path.cutting_runs().len(), 9);
        assert_eq!(path.postures.len(), 9 * 43);
        // Passes are centred and exactly one stepover apart.
        let ys: Vec<f64> = path
            .cutting_runs()
            .iter()
            .map(|r| path.postures[r.start + 1].contact.as_ref().unwrap().point.y)
            .collect();
        for w in ys.windows(2) {
            assert_relative_eq!(w[1] - w[0], s.stepover_mm, epsilon = 1e-12);
        }
        assert_relative_eq!(ys[0] + ys[8], 0.0, epsilon = 1e-12);
        // The axis is tilted 10° towards the feed (+x), and the tip is behind the contact.
        for (q, c) in cut_contacts(path) {
            assert_relative_eq!(
                q.axis,
                axis_convention_a(10f64.to_radians(), 0.0),
                epsilon = 1e-12
            );
            assert!(q.position.x < c.point.x);
        }
    }

    #[test]
    fn cl_is_cc_plus_cutter_offset_for_a_ball() {
        let ball = Cutter::new(Shape::Ball, 5.0, 2, 0.0);
        for surface in [
            Surface::paper_parabola(),
            Surface::paper_hyperbolic_paraboloid(),
            Surface::default_blade(),
        ] {
            let mut spec = PathSpec::new(
                surface,
                ball.clone(),
                Orientation::Lead {
                    lead_rad: 15f64.to_radians(),
                },
                Step::Stepover { spacing_mm: 2.0 },
                (20.0, 10.0),
            );
            spec.pass_angle_rad = 45f64.to_radians();
            spec.pattern = Pattern::Zigzag;
            let s = generate(&spec).unwrap();
            let path = &s.program.paths[0];
            for (q, c) in cut_contacts(path) {
                let expect = c.point + c.normal * 5.0 - q.axis * 5.0;
                assert_relative_eq!(q.position, expect, epsilon = 1e-12);
                // Lead 15°: the axis makes 15° with the normal.
                assert_relative_eq!(
                    q.axis.dot(&c.normal),
                    15f64.to_radians().cos(),
                    epsilon = 1e-12
                );
            }
        }
    }

    #[test]
    fn cc_points_lie_on_the_surface_with_unit_correct_normals() {
        for surface in [
            Surface::Plane,
            Surface::paper_parabola(),
            Surface::paper_hyperbolic_paraboloid(),
            Surface::default_blade(),
        ] {
            let mut spec = PathSpec::new(
                surface,
                torus(),
                Orientation::TiltYaw {
                    tilt_rad: 10f64.to_radians(),
                    yaw_rad: 20f64.to_radians(),
                },
                Step::Stepover { spacing_mm: 1.5 },
                (16.0, 8.0),
            );
            spec.pass_angle_rad = 0.3;
            let s = generate(&spec).unwrap();
            let e = 1e-6;
            for (q, c) in cut_contacts(&s.program.paths[0]) {
                let p = c.point;
                assert_relative_eq!(p.z, surface.height(p.x, p.y), epsilon = 1e-12);
                assert_relative_eq!(c.normal.norm(), 1.0, epsilon = 1e-12);
                // The normal is orthogonal to two surface tangents (finite differences).
                let tx = Vec3::new(
                    2.0 * e,
                    0.0,
                    surface.height(p.x + e, p.y) - surface.height(p.x - e, p.y),
                );
                let ty = Vec3::new(
                    0.0,
                    2.0 * e,
                    surface.height(p.x, p.y + e) - surface.height(p.x, p.y - e),
                );
                assert!(c.normal.dot(&tx.normalize()).abs() < 1e-8);
                assert!(c.normal.dot(&ty.normalize()).abs() < 1e-8);
                assert!(c.normal.z > 0.0);
                // Torus contact: the corner-circle centre is rc along n from C and Rd
                // from the axis, at height rc above the tip.
                let centre = p + c.normal * 1.5;
                let rel = centre - q.position;
                assert_relative_eq!(rel.dot(&q.axis), 1.5, epsilon = 1e-12);
                assert_relative_eq!(
                    (rel - q.axis * rel.dot(&q.axis)).norm(),
                    3.5,
                    epsilon = 1e-12
                );
                // Tilt 10° from the normal.
                assert_relative_eq!(
                    q.axis.dot(&c.normal).acos().to_degrees(),
                    10.0,
                    epsilon = 1e-9
                );
            }
        }
    }

    #[test]
    fn feed_falls_linearly_along_every_pass() {
        // 001 Fig 6: 4000 → 500 mm/min along a 10 mm pass, CC points every 1 mm.
        let mut spec = PathSpec::new(
            Surface::Plane,
            torus(),
            Orientation::TiltYaw {
                tilt_rad: 1f64.to_radians(),
                yaw_rad: 0.0,
            },
            Step::Stepover { spacing_mm: 2.0 },
            (10.0, 4.0),
        );
        spec.point_step_mm = 1.0;
        spec.pattern = Pattern::Zigzag;
        spec.feed_mm_min = 4000.0;
        spec.feed_end_mm_min = Some(500.0);
        let s = generate(&spec).unwrap();
        let path = &s.program.paths[0];
        assert_eq!(s.passes, 3);
        for r in path.cutting_runs() {
            let cuts: Vec<&Posture> = path.postures[r.start + 1..r.end]
                .iter()
                .filter(|p| p.contact.is_some())
                .collect();
            assert_eq!(cuts.len(), 11);
            for (i, p) in cuts.iter().enumerate() {
                let want = 4000.0 - 350.0 * i as f64;
                assert!((p.feed_mm_min.unwrap() - want).abs() < 1e-9, "{i}");
            }
        }
        spec.feed_end_mm_min = Some(-1.0);
        assert!(generate(&spec).is_err());
    }

    #[test]
    fn zigzag_alternates_the_feed_direction() {
        let mut spec = PathSpec::new(
            Surface::Plane,
            torus(),
            Orientation::TiltYaw {
                tilt_rad: 1f64.to_radians(),
                yaw_rad: 0.0,
            },
            Step::Scallop { height_mm: 0.005 },
            (10.0, 10.0),
        );
        spec.pattern = Pattern::Zigzag;
        let s = generate(&spec).unwrap();
        assert!((s.stepover_mm - 2.7850).abs() < 1e-3);
        assert_eq!(s.passes, 5);
        let path = &s.program.paths[0];
        for (k, r) in path.cutting_runs().iter().enumerate() {
            assert!(
                path.postures[r.start].contact.is_none(),
                "the run starts at clearance"
            );
            let a = &path.postures[r.start + 1];
            let b = &path.postures[r.end - 1];
            let dx = b.position.x - a.position.x;
            assert_eq!(dx > 0.0, k % 2 == 0);
            assert_eq!(a.axis.x > 0.0, k % 2 == 0, "the axis leans into the feed");
        }
    }

    #[test]
    fn curved_surfaces_adjust_the_step() {
        let ball = Cutter::new(Shape::Ball, 5.0, 2, 0.0);
        let plane_step = exact_step_mm(&ball, &Vec3::z(), 0.002).unwrap();
        // Passes along y on the parabola: across the pass the surface is convex with
        // radius ≥ 125 mm, so the spacing is below the plane step: at the apex
        // s/√(1 + 5/125), further out also reduced by the slope.
        let mut spec = PathSpec::new(
            Surface::paper_parabola(),
            ball.clone(),
            Orientation::TiltYaw {
                tilt_rad: 0.0,
                yaw_rad: 0.0,
            },
            Step::Scallop { height_mm: 0.002 },
            (10.0, 10.0),
        );
        spec.pass_angle_rad = 90f64.to_radians();
        let s = generate(&spec).unwrap();
        assert_eq!(s.plane_step_mm, Some(plane_step));
        assert!(s.stepover_mm < plane_step / (1.0f64 + 5.0 / 125.0).sqrt());
        // Concave regions tighter than R_eff are refused (torus at tilt 1°: R_eff = 202 mm).
        let spec = PathSpec::new(
            Surface::default_blade(),
            torus(),
            Orientation::TiltYaw {
                tilt_rad: 1f64.to_radians(),
                yaw_rad: 0.0,
            },
            Step::Scallop { height_mm: 0.005 },
            (40.0, 20.0),
        );
        assert!(matches!(generate(&spec), Err(SynthError::Gouge { .. })));
    }

    #[test]
    fn bad_specs_are_errors() {
        let mut spec = PathSpec::new(
            Surface::Plane,
            torus(),
            Orientation::TiltYaw {
                tilt_rad: 0.1,
                yaw_rad: 0.0,
            },
            Step::Stepover { spacing_mm: 0.0 },
            (10.0, 10.0),
        );
        assert!(generate(&spec).is_err());
        spec.step = Step::Stepover { spacing_mm: 1.0 };
        spec.size_mm = (f64::NAN, 1.0);
        assert!(generate(&spec).is_err());
        spec.size_mm = (10.0, 10.0);
        spec.orientation = Orientation::TiltYaw {
            tilt_rad: 2.0,
            yaw_rad: 0.0,
        };
        assert!(generate(&spec).is_err());
    }
}
