//! Lowering: parse records → [`Posture`]s, one record at a time.
//!
//! [`Lowerer`] is an incremental state machine. It keeps the modal state of CLSF (feed,
//! spindle, tool, units, tool axis, one-shot RAPID, pending CIRCLE, open NURBS block,
//! cycle, cutter data) and hands every finished posture to a callback, so a file of any
//! size lowers in constant memory. A posture is finished when the next record arrives,
//! because a `CONTACT` record attaches to the GOTO before it.
//!
//! Coordinates stay in the frame they are written in (the operation's MCS) unless
//! [`LowerOptions::apply_msys`] maps them to the absolute frame with the path's `MSYS`.
//! Lengths become mm (`UNITS/INCH` and `IPM`/`IPR` feeds are converted), angles radians.

mod apt;
mod contour;
mod goto;
mod kinds;

pub use kinds::{FEED_HOLD_LIMIT, HOLD_LIMIT};

use super::geom::Spline;
use super::{
    ArcMove, Contact, MotionKind, Posture, Program, RawRecord, ToolData, Toolpath, Warning,
};
use crate::math::{Point3, Vec3, normalize_or_none};
use crate::parse::{
    Arg, Contact12Row, FeedUnit, LengthUnit, Located, Numbers, Problem, Record, RecordKind, Span,
};
use std::collections::HashMap;

/// mm per inch.
pub const MM_PER_INCH: f64 = 25.4;

/// The start of the warning of a file whose feeds are in inches (`FEDRAT/IPM`, `IPR`) and
/// whose lengths are millimetres for want of a `UNITS` record: `simulate` fails on it.
pub const CONTRADICTORY_UNITS: &str = "contradictory units";
/// At most this many warnings of one kind are kept; the rest are counted.
const WARNINGS_PER_KIND: usize = 5;
/// At most this many distinct feeds/spindle speeds are listed per path.
const SEEN_LIMIT: usize = 64;
/// At most this many raw (unknown) records are kept per path.
const RAW_LIMIT: usize = 1000;

/// How to lower.
#[derive(Debug, Clone, PartialEq)]
pub struct LowerOptions {
    /// Map coordinates with the path's MSYS to the absolute frame (`--absolute`).
    pub apply_msys: bool,
    /// Keep the postures in [`Toolpath::postures`] (off for streaming conversion).
    pub keep_postures: bool,
    /// Chord tolerance for sampling NURBS blocks, mm.
    pub nurbs_tolerance_mm: f64,
}

impl Default for LowerOptions {
    fn default() -> Self {
        LowerOptions {
            apply_msys: false,
            keep_postures: true,
            nurbs_tolerance_mm: 0.001,
        }
    }
}

/// Why lowering failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LowerError {
    /// A record that parses but cannot mean anything geometric (zero axis, radius ≤ 0, …).
    #[error("line {}, column {}: {}", .0.span.line, .0.span.column, .0.problem)]
    Invalid(Box<Located>),
    /// The posture callback failed (e.g. writing the output).
    #[error("writing failed: {0}")]
    Output(#[from] std::io::Error),
}

fn invalid(line: u32, column: u32, expected: &str, found: String) -> LowerError {
    LowerError::invalid(Span::line_column(line, column), expected, found)
}

impl LowerError {
    /// A record at `at` that means nothing geometric: what was `expected`, what was `found`.
    pub fn invalid(at: Span, expected: &str, found: String) -> LowerError {
        LowerError::Invalid(Box::new(Located::new(
            at,
            Problem::Expected {
                expected: expected.to_string(),
                found,
            },
        )))
    }
}

/// Refuse a point beyond the plausibility limit ([`crate::math::limits::MAX_COORD_MM`]):
/// a typo in a file must not cost unbounded time or output later.
fn check_coords(p: &Point3, line: u32, column: u32) -> Result<(), LowerError> {
    let lim = crate::math::limits::MAX_COORD_MM;
    match p.coords.iter().find(|c| c.is_nan() || c.abs() > lim) {
        Some(c) => Err(invalid(
            line,
            column,
            "a coordinate within ±100000 mm (100 m)",
            crate::math::limits::shown(*c),
        )),
        None => Ok(()),
    }
}

/// Refuse a programmed feed or spindle speed beyond its limits ([`crate::math::limits`]),
/// at the record that sets it: every `FEDRAT` and `SPINDL`, not only the first. 0 (no feed,
/// spindle stopped) is kept.
fn check_rate(
    what: &str,
    unit: &str,
    v: f64,
    range: (f64, f64),
    line: u32,
    column: u32,
) -> Result<(), LowerError> {
    if v == 0.0 || crate::math::limits::within(what, unit, v, range).is_ok() {
        return Ok(());
    }
    Err(invalid(
        line,
        column,
        &format!("a {what} between {} and {} {unit} (or 0)", range.0, range.1),
        format!("{} {unit}", crate::math::limits::shown(v)),
    ))
}

/// Callback receiving each finished posture with the header of its path.
pub type PostureSink<'a> = dyn FnMut(&Toolpath, &Posture) -> std::io::Result<()> + 'a;

#[derive(Debug, Clone)]
struct PendingCircle {
    arc: ArcMove,
    line: u32,
}

#[derive(Debug, Clone)]
struct OpenNurbs {
    knots: Vec<f64>,
    cntrl: Vec<Point3>,
    line: u32,
}

/// The incremental lowering state machine (see the module docs).
pub struct Lowerer {
    opts: LowerOptions,
    path: Option<Toolpath>,
    finished: Vec<Toolpath>,
    warnings: Vec<Warning>,
    warning_counts: HashMap<&'static str, usize>,
    inch: bool,
    feed_mm_min: Option<f64>,
    feed_mm_rev: Option<f64>,
    spindle_rpm: Option<f64>,
    axis: Vec3,
    rapid_next: bool,
    circle: Option<PendingCircle>,
    cycle: bool,
    nurbs: Option<OpenNurbs>,
    /// Last posture, not yet emitted (a CONTACT record may follow), in the file frame.
    pending: Option<Posture>,
    /// Current tool position in the file frame (start of the next move).
    current: Option<Point3>,
    /// Last emitted position in the output frame (for lengths).
    last_out: Option<Point3>,
    frame: Option<MsysFrame>,
    /// The open path was started by a `TOOL PATH` record (and so needs `END-OF-PATH`).
    opened_by_record: bool,
    /// A `UNITS` record was read.
    units_seen: bool,
    /// Where the first inch feed (`FEDRAT/IPM`, `IPR`) was read: line, column.
    inch_feed_at: Option<(u32, u32)>,
    /// Records of the wider APT family were seen (`PARTNO`, `CUTTER`, `LOADTL`, …): such
    /// files have no `TOOL PATH` records, so motion outside one is no finding.
    apt: bool,
    /// `PARTNO` text: the name of paths started without a `TOOL PATH` record.
    partno: Option<String>,
    /// The last `CUTTER` tool: the tool of paths started without a `TOOL PATH` record.
    cutter: Option<ToolData>,
    /// `SET/MODE,INCR`: GOTO coordinates are increments from the current position.
    incremental: bool,
    /// `$$ contact contour data`: GOTO positions are contact points, not tool tips.
    contact_contour: bool,
    /// The pending posture's position is a contact point (contact contour data).
    pending_cc: bool,
    /// `PPRINT`/`TPRINT` records before the first path (they go into it).
    notes: Vec<RawRecord>,
    /// `TPRINT` text or `T<n>` of the last tool change: the tool name of APT paths.
    tool_label: Option<String>,
    /// The move kinds of the open path (postures held back until their kind is known).
    kinds: kinds::Kinds,
}

/// An orthonormal MSYS frame.
#[derive(Debug, Clone, Copy)]
struct MsysFrame {
    origin: Vec3,
    x: Vec3,
    y: Vec3,
    z: Vec3,
}

impl MsysFrame {
    fn new(m: &[f64; 9], scale: f64) -> Option<MsysFrame> {
        let x = normalize_or_none(&Vec3::new(m[3], m[4], m[5]), 1e-12)?;
        let y0 = Vec3::new(m[6], m[7], m[8]);
        let y = normalize_or_none(&(y0 - x * x.dot(&y0)), 1e-12)?;
        Some(MsysFrame {
            origin: Vec3::new(m[0], m[1], m[2]) * scale,
            x,
            y,
            z: x.cross(&y),
        })
    }
    fn dir(&self, v: &Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }
    fn point(&self, p: &Point3) -> Point3 {
        Point3::from(self.origin + self.dir(&p.coords))
    }
}

fn vec3(t: [f64; 3]) -> Vec3 {
    Vec3::new(t[0], t[1], t[2])
}

/// Normalise a direction read from a file: vectors within 10⁻⁶ of unit length are kept
/// exactly as written (so printed digits survive round trips), others are normalised.
#[inline]
fn unit_as_written(v: Vec3) -> Option<Vec3> {
    let n = v.norm();
    if !(n > 1e-12 && n.is_finite()) {
        return None;
    }
    if (n - 1.0).abs() <= 1e-6 {
        Some(v)
    } else {
        Some(v / n)
    }
}

/// The surface normal at `cc` for a cutter with tip at `tip`, axis `axis`: from the CC
/// point towards the centre of the cutter's rounding (the ball centre for a ball end, the
/// nearest point of the corner-radius circle for a torus). Flat ends give the axis.
pub fn derive_normal(tool: &ToolData, tip: &Point3, axis: &Vec3, cc: &Point3) -> Option<Vec3> {
    let big_r = 0.5 * tool.diameter_mm;
    let r = tool.corner_radius_mm.clamp(0.0, big_r.max(0.0));
    if r <= 1e-9 {
        return Some(*axis);
    }
    let mut centre = tip + axis * r;
    if big_r - r > 1e-9 {
        let w = cc - centre;
        if let Some(radial) = normalize_or_none(&(w - axis * axis.dot(&w)), 1e-12) {
            centre += radial * (big_r - r);
        }
    }
    normalize_or_none(&(centre - cc), 1e-12)
}

impl Lowerer {
    /// A new lowering with the given options.
    pub fn new(opts: LowerOptions) -> Lowerer {
        Lowerer {
            opts,
            path: None,
            finished: Vec::new(),
            warnings: Vec::new(),
            warning_counts: HashMap::new(),
            inch: false,
            feed_mm_min: None,
            feed_mm_rev: None,
            spindle_rpm: None,
            axis: Vec3::z(),
            rapid_next: false,
            circle: None,
            cycle: false,
            nurbs: None,
            pending: None,
            current: None,
            last_out: None,
            frame: None,
            opened_by_record: false,
            units_seen: false,
            inch_feed_at: None,
            apt: false,
            partno: None,
            cutter: None,
            incremental: false,
            contact_contour: false,
            pending_cc: false,
            notes: Vec::new(),
            tool_label: None,
            kinds: kinds::Kinds::default(),
        }
    }

    fn scale(&self) -> f64 {
        if self.inch { MM_PER_INCH } else { 1.0 }
    }

    fn warn(&mut self, kind: &'static str, line: u32, column: u32, message: String) {
        let count = self.warning_counts.entry(kind).or_insert(0);
        *count += 1;
        if *count <= WARNINGS_PER_KIND {
            self.warnings.push(Warning {
                at: Span::line_column(line, column),
                message,
            });
        }
    }

    /// Record a finding of a front end that lowers its own input through this lowering
    /// (G-code): at most five of one `kind` are kept, the rest counted.
    pub fn note(&mut self, kind: &'static str, line: u32, column: u32, message: String) {
        self.warn(kind, line, column, message);
    }

    /// Start a tool path explicitly (contact12 input, or motion before any `TOOL PATH`).
    pub fn begin_path(
        &mut self,
        name: &str,
        tool_name: &str,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        self.end_path(sink)?;
        self.path = Some(Toolpath {
            name: name.to_string(),
            tool_name: tool_name.to_string(),
            prints: std::mem::take(&mut self.notes),
            ..Default::default()
        });
        Ok(())
    }

    fn ensure_path(
        &mut self,
        line: u32,
        column: u32,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        if self.path.is_none() {
            if self.apt {
                // An APT file: one path per tool, named by PARTNO, tool from CUTTER.
                self.path_mut();
            } else {
                self.warn(
                    "outside",
                    line,
                    column,
                    "motion before any TOOL PATH record; an unnamed tool path was started".into(),
                );
                self.begin_path("", "", sink)?;
            }
        }
        Ok(())
    }

    /// The open path, or a new one: in an APT file (no `TOOL PATH` records) named by
    /// `PARTNO`, with the tool of the last `CUTTER` and `TPRINT`/`LOADTL`.
    fn path_mut(&mut self) -> &mut Toolpath {
        if self.path.is_none() {
            let mut p = Toolpath {
                prints: std::mem::take(&mut self.notes),
                ..Default::default()
            };
            if self.apt {
                p.name = self.partno.clone().unwrap_or_default();
                p.tool_name = self.tool_label.clone().unwrap_or_default();
                p.tool = self.cutter.clone();
            }
            self.path = Some(p);
        }
        self.path.get_or_insert_with(Toolpath::default)
    }

    /// Emit the pending posture (and close an open NURBS block).
    fn flush(&mut self, sink: &mut PostureSink<'_>) -> Result<(), LowerError> {
        if self.nurbs.is_some() {
            self.close_nurbs(sink)?;
        }
        self.flush_pending(sink)
    }

    fn flush_pending(&mut self, sink: &mut PostureSink<'_>) -> Result<(), LowerError> {
        let Some(mut p) = self.pending.take() else {
            return Ok(());
        };
        if std::mem::take(&mut self.pending_cc) {
            self.contact_contour_tip(&mut p);
        }
        let start_file = self.current;
        self.current = Some(p.position);
        // Length of the move into p, in the file frame (MSYS is a rigid motion).
        let seg = match (p.motion, start_file) {
            (MotionKind::From, _) | (_, None) => 0.0,
            (_, Some(s)) => match &p.arc {
                Some(arc) => arc.length_mm(&s, &p.position),
                None => (p.position - s).norm(),
            },
        };
        if self.opts.apply_msys
            && let Some(f) = self.frame
        {
            p.position = f.point(&p.position);
            p.axis = f.dir(&p.axis);
            if let Some(a) = &mut p.arc {
                a.centre = f.point(&a.centre);
                a.axis = f.dir(&a.axis);
            }
            if let Some(c) = &mut p.contact {
                c.point = f.point(&c.point);
                c.normal = f.dir(&c.normal);
            }
        }
        self.last_out = Some(p.position);
        self.emit(p, seg, sink)
    }

    fn close_nurbs(&mut self, sink: &mut PostureSink<'_>) -> Result<(), LowerError> {
        let Some(nb) = self.nurbs.take() else {
            return Ok(());
        };
        // The spline starts at the current position: emit the pending posture first.
        self.flush_pending(sink)?;
        let Some(start) = self.current else {
            self.warn(
                "nurbs-start",
                nb.line,
                1,
                "NURBS block without a start position; its control points are used as moves".into(),
            );
            return self.nurbs_polyline(nb, sink);
        };
        match Spline::from_clsf(start, &nb.knots, &nb.cntrl) {
            Some(sp) => {
                for q in sp.sample(self.opts.nurbs_tolerance_mm) {
                    self.pending = Some(self.posture_here(q, nb.line));
                    self.flush_pending(sink)?;
                }
                Ok(())
            }
            None => {
                self.warn(
                    "nurbs-knots",
                    nb.line,
                    1,
                    format!(
                        "NURBS block with {} knots and {} control points is not a clamped cubic; its control points are used as moves",
                        nb.knots.len(),
                        nb.cntrl.len()
                    ),
                );
                self.nurbs_polyline(nb, sink)
            }
        }
    }

    fn nurbs_polyline(
        &mut self,
        nb: OpenNurbs,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        for q in nb.cntrl {
            self.pending = Some(self.posture_here(q, nb.line));
            self.flush_pending(sink)?;
        }
        Ok(())
    }

    fn motion_now(&mut self) -> MotionKind {
        let m = if self.cycle {
            MotionKind::Cycle
        } else if self.rapid_next {
            MotionKind::Rapid
        } else {
            MotionKind::Cut
        };
        self.rapid_next = false;
        m
    }

    fn posture_here(&mut self, position: Point3, line: u32) -> Posture {
        let motion = self.motion_now();
        Posture {
            position,
            axis: self.axis,
            motion,
            arc: None,
            contact: None,
            feed_mm_min: self.feed_mm_min,
            spindle_rpm: self.spindle_rpm,
            line,
        }
    }

    fn read_axis(&self, n: &Numbers, k: usize, line: u32, column: u32) -> Result<Vec3, LowerError> {
        let t = n.triple(k);
        unit_as_written(vec3(t)).ok_or_else(|| {
            invalid(
                line,
                column,
                "a unit vector",
                format!("({}, {}, {})", t[0], t[1], t[2]),
            )
        })
    }

    fn contact_from(
        &mut self,
        n: &Numbers,
        k: usize,
        tip: &Point3,
        axis: &Vec3,
        line: u32,
        column: u32,
    ) -> Result<Contact, LowerError> {
        let s = self.scale();
        let point = Point3::from(vec3(n.triple(k)) * s);
        if n.len() >= k + 6 {
            let normal = self.read_axis(n, k + 3, line, column)?;
            return Ok(Contact {
                point,
                normal,
                normal_derived: false,
            });
        }
        if self.contact_contour {
            // The position is the contact point, not the tip: nothing to derive from.
            return Ok(Contact {
                point,
                normal: *axis,
                normal_derived: true,
            });
        }
        let derived = self
            .path
            .as_ref()
            .and_then(|p| p.tool.as_ref())
            .and_then(|t| derive_normal(t, tip, axis, &point));
        let normal = match derived {
            Some(nv) => nv,
            None => {
                self.warn(
                    "normal-axis",
                    line,
                    column,
                    "contact point without normal and no usable TLDATA: the tool axis is used as the normal".into(),
                );
                *axis
            }
        };
        Ok(Contact {
            point,
            normal,
            normal_derived: true,
        })
    }

    /// Lower one CLSF record.
    pub fn push(&mut self, rec: &Record, sink: &mut PostureSink<'_>) -> Result<(), LowerError> {
        if let RecordKind::Goto(n) = &rec.kind
            && self
                .push_goto_fast(n, rec.line, sink)
                .map_err(LowerError::Output)?
        {
            return Ok(());
        }
        let (line, column) = (rec.line, rec.column);
        // Anything but KNOT/CNTRL closes an open NURBS block; anything but CONTACT
        // finishes the pending posture.
        match &rec.kind {
            RecordKind::Knot(_) | RecordKind::Cntrl(_) | RecordKind::Comment(_) => {}
            RecordKind::Contact(_) => {
                if self.nurbs.is_some() {
                    self.close_nurbs(sink)?;
                }
            }
            _ => self.flush(sink)?,
        }
        match &rec.kind {
            RecordKind::ToolPath { name, tool } => {
                if self.path.is_some() {
                    self.warn(
                        "no-end",
                        line,
                        column,
                        "TOOL PATH before END-OF-PATH of the previous path".into(),
                    );
                }
                self.begin_path(name, tool, sink)?;
                self.opened_by_record = true;
            }
            RecordKind::EndOfPath => {
                if self.path.is_none() {
                    self.warn(
                        "stray-end",
                        line,
                        column,
                        "END-OF-PATH without TOOL PATH".into(),
                    );
                }
                self.end_path(sink)?;
            }
            RecordKind::Tldata {
                kind,
                subtype: _,
                args,
            } => {
                let tool = self.tldata(kind, args, line, column)?;
                self.path_mut().tool = Some(tool);
            }
            RecordKind::Msys(m) => {
                let frame = MsysFrame::new(m, self.scale());
                if let Some(f) = &frame
                    && let Err(e) = crate::math::limits::coordinates(f.origin.as_slice())
                {
                    return Err(invalid(
                        line,
                        column,
                        "an MSYS origin within ±100000 mm (100 m)",
                        e.to_string(),
                    ));
                }
                if frame.is_none() {
                    return Err(invalid(
                        line,
                        column,
                        "MSYS with two independent axis vectors",
                        "a zero or parallel axis".into(),
                    ));
                }
                self.frame = frame;
                let s = self.scale();
                let mut mm = *m;
                for v in mm.iter_mut().take(3) {
                    *v *= s;
                }
                let applied = self.opts.apply_msys;
                let p = self.path_mut();
                p.msys = Some(mm);
                p.msys_applied = applied;
            }
            RecordKind::Comment(text) => {
                let t = text.to_ascii_lowercase();
                if t.contains("contact contour") {
                    self.contact_contour = true;
                } else if t.contains("centerline data") || t.contains("centreline data") {
                    self.contact_contour = false;
                }
            }
            RecordKind::Paint(args) => {
                if let [a, Arg::Num(n)] = args.as_slice()
                    && a.is_word("COLOR")
                    && *n >= 0.0
                    && n.fract() == 0.0
                    && *n <= f64::from(u32::MAX)
                {
                    self.paint(*n as u32, sink)?;
                }
            }
            RecordKind::Cutcom(_) => {}
            RecordKind::Units(u) => {
                self.inch = *u == LengthUnit::Inch;
                self.units_seen = true;
            }
            RecordKind::LoadTool { number, .. } => self.load_tool(*number, sink)?,
            RecordKind::SelectTool { .. } => {}
            RecordKind::Print { .. }
            | RecordKind::Partno(_)
            | RecordKind::Multax(_)
            | RecordKind::Cutter(_)
            | RecordKind::Tlaxis(_)
            | RecordKind::Indirv(_)
            | RecordKind::SetMode { .. }
            | RecordKind::Fini
            | RecordKind::End => self.push_apt(&rec.kind, line, column, sink)?,
            RecordKind::Fedrat { unit, value } => {
                let per_rev = matches!(
                    unit,
                    Some(FeedUnit::Mmpr | FeedUnit::Ipr | FeedUnit::Perrev)
                );
                if matches!(unit, Some(FeedUnit::Ipm | FeedUnit::Ipr))
                    && self.inch_feed_at.is_none()
                {
                    self.inch_feed_at = Some((line, column));
                }
                let factor = match unit {
                    Some(FeedUnit::Mmpm | FeedUnit::Mmpr) => 1.0,
                    Some(FeedUnit::Ipm | FeedUnit::Ipr) => MM_PER_INCH,
                    Some(FeedUnit::Permin | FeedUnit::Perrev) | None => self.scale(),
                };
                if value.is_nan() || *value < 0.0 {
                    return Err(invalid(line, column, "a feed ≥ 0", format!("{value}")));
                }
                let v = value * factor;
                let feed = crate::math::limits::FEED_MM_MIN;
                if per_rev {
                    self.feed_mm_rev = Some(v);
                    self.feed_mm_min = self.spindle_rpm.map(|rpm| v * rpm);
                    if self.spindle_rpm.is_none() {
                        self.warn(
                            "feed-per-rev",
                            line,
                            column,
                            "feed per revolution before any spindle speed: feed unknown until SPINDL".into(),
                        );
                    }
                } else {
                    self.feed_mm_rev = None;
                    self.feed_mm_min = Some(v);
                }
                if let Some(f) = self.feed_mm_min {
                    check_rate("feed", "mm/min", f, feed, line, column)?;
                    self.note_feed(f);
                } else if !v.is_finite() {
                    return Err(invalid(line, column, "a finite feed", format!("{value}")));
                }
            }
            RecordKind::Spindl(args) => self.spindl(args, line, column)?,
            RecordKind::Rapid => {
                self.rapid_next = true;
                self.path_mut().stats.rapids += 1;
            }
            RecordKind::Cycle(args) => {
                self.cycle = !args.first().is_some_and(|a| a.is_word("OFF"));
            }
            RecordKind::Circle { numbers, times } => {
                self.ensure_path(line, column, sink)?;
                let s = self.scale();
                let axis = self.read_axis(numbers, 3, line, column)?;
                let radius = numbers.as_slice()[6] * s;
                if radius <= 0.0 {
                    return Err(invalid(
                        line,
                        column,
                        "a CIRCLE radius > 0",
                        format!("{}", numbers.as_slice()[6]),
                    ));
                }
                if let Some(c) = &self.circle {
                    let l = c.line;
                    self.warn(
                        "circle-unused",
                        line,
                        column,
                        format!("CIRCLE on line {l} was not followed by a GOTO"),
                    );
                }
                self.circle = Some(PendingCircle {
                    arc: ArcMove {
                        centre: Point3::from(vec3(numbers.triple(0)) * s),
                        axis,
                        radius_mm: radius,
                        extra_turns: times.map(|t| t.saturating_sub(1)).unwrap_or(0),
                    },
                    line,
                });
                self.path_mut().stats.circles += 1;
            }
            RecordKind::Goto(n) => {
                self.ensure_path(line, column, sink)?;
                self.path_mut().stats.gotos += 1;
                let s = self.scale();
                let mut position = Point3::from(vec3(n.triple(0)) * s);
                if self.incremental {
                    position += self.current.map_or_else(Vec3::zeros, |c| c.coords);
                }
                check_coords(&position, line, column)?;
                if n.len() >= 6 {
                    self.axis = self.read_axis(n, 3, line, column)?;
                }
                self.pending_cc = self.contact_contour;
                let mut p = self.posture_here(position, line);
                if let Some(c) = self.circle.take() {
                    p.arc = Some(c.arc);
                }
                if n.len() >= 9 {
                    let axis = self.axis;
                    p.contact = Some(self.contact_from(n, 6, &position, &axis, line, column)?);
                }
                self.pending = Some(p);
            }
            RecordKind::From(n) | RecordKind::GoHome(n) => {
                self.ensure_path(line, column, sink)?;
                let s = self.scale();
                let position = Point3::from(vec3(n.triple(0)) * s);
                check_coords(&position, line, column)?;
                if n.len() >= 6 {
                    self.axis = self.read_axis(n, 3, line, column)?;
                }
                let mut p = self.posture_here(position, line);
                p.motion = if matches!(rec.kind, RecordKind::From(_)) {
                    MotionKind::From
                } else {
                    MotionKind::GoHome
                };
                self.pending = Some(p);
            }
            RecordKind::Contact(n) => {
                let Some(p) = self.pending.take() else {
                    self.warn(
                        "contact-orphan",
                        line,
                        column,
                        "CONTACT record without a GOTO before it; ignored".into(),
                    );
                    return Ok(());
                };
                let mut p = p;
                if p.contact.is_some() {
                    self.warn(
                        "contact-twice",
                        line,
                        column,
                        format!(
                            "CONTACT record replaces the contact data of the GOTO on line {}",
                            p.line
                        ),
                    );
                }
                let (tip, axis) = (p.position, p.axis);
                p.contact = Some(self.contact_from(n, 0, &tip, &axis, line, column)?);
                self.pending = Some(p);
            }
            RecordKind::Nurbs => {
                self.ensure_path(line, column, sink)?;
                self.path_mut().stats.nurbs += 1;
                self.nurbs = Some(OpenNurbs {
                    knots: Vec::new(),
                    cntrl: Vec::new(),
                    line,
                });
            }
            RecordKind::Knot(k) => match &mut self.nurbs {
                Some(nb) => nb.knots.extend_from_slice(k),
                None => self.warn(
                    "knot-orphan",
                    line,
                    column,
                    "KNOT outside a NURBS block; ignored".into(),
                ),
            },
            RecordKind::Cntrl(c) => {
                let s = self.scale();
                let p = Point3::from(vec3(*c) * s);
                check_coords(&p, line, column)?;
                match &mut self.nurbs {
                    Some(nb) => nb.cntrl.push(p),
                    None => self.warn(
                        "cntrl-orphan",
                        line,
                        column,
                        "CNTRL outside a NURBS block; ignored".into(),
                    ),
                }
            }
            RecordKind::Unknown { word, text } => {
                self.warn(
                    "unknown",
                    line,
                    column,
                    format!("unknown record {word} kept raw"),
                );
                let p = self.path_mut();
                if p.raw_records.len() < RAW_LIMIT {
                    p.raw_records.push(RawRecord {
                        line,
                        text: text.clone(),
                    });
                }
            }
        }
        Ok(())
    }

    fn note_feed(&mut self, f: f64) {
        let st = &mut self.path_mut().stats;
        if !st.feeds_mm_min.contains(&f) && st.feeds_mm_min.len() < SEEN_LIMIT {
            st.feeds_mm_min.push(f);
        }
    }

    /// Lower one contact12 line: columns 7-12 given in full = a cutting move with contact
    /// data; all of them missing or zero, or a missing/zero normal = a non-cutting move
    /// (`MotionKind::Rapid`).
    pub fn push_contact12(
        &mut self,
        row: &Contact12Row,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        self.flush(sink)?;
        let line = row.line;
        self.ensure_path(line, 1, sink)?;
        self.path_mut().stats.gotos += 1;
        let c = &row.cl_axis;
        let position = Point3::new(c[0], c[1], c[2]);
        check_coords(&position, line, row.columns[0])?;
        let raw_axis = Vec3::new(c[3], c[4], c[5]);
        let axis = unit_as_written(raw_axis).ok_or_else(|| {
            invalid(
                line,
                row.columns[3],
                "a unit tool axis",
                format!("({}, {}, {})", c[3], c[4], c[5]),
            )
        })?;
        self.axis = axis;
        let t = &row.contact;
        let triple_state = |k: usize| -> Result<Option<[f64; 3]>, LowerError> {
            match (t[k], t[k + 1], t[k + 2]) {
                (Some(a), Some(b), Some(c)) => Ok(Some([a, b, c])),
                (None, None, None) => Ok(None),
                _ => {
                    let bad = (k..k + 3).find(|&j| t[j].is_none()).unwrap_or(k);
                    Err(invalid(
                        line,
                        row.columns[6 + bad],
                        "a number (a CC point or normal is given in full or marked missing in full)",
                        "a missing value".into(),
                    ))
                }
            }
        };
        let cc = triple_state(0)?;
        let normal = triple_state(3)?;
        let normal = normal.and_then(|n| unit_as_written(vec3(n)));
        let mut p = Posture {
            position,
            axis,
            motion: MotionKind::Cut,
            arc: None,
            contact: None,
            feed_mm_min: None,
            spindle_rpm: None,
            line,
        };
        match (cc, normal) {
            (Some(cc), Some(n)) => {
                p.contact = Some(Contact {
                    point: Point3::from(vec3(cc)),
                    normal: n,
                    normal_derived: false,
                });
            }
            (cc, _) => {
                if cc.is_some_and(|c| c.iter().any(|v| *v != 0.0)) {
                    self.warn(
                        "cc-without-normal",
                        line,
                        row.columns[9],
                        "CC point without a usable normal: line treated as non-cutting".into(),
                    );
                }
                p.motion = MotionKind::Rapid;
            }
        }
        self.pending = Some(p);
        Ok(())
    }

    fn end_path(&mut self, sink: &mut PostureSink<'_>) -> Result<(), LowerError> {
        self.flush(sink)?;
        self.end_kinds(sink)?;
        if let Some(c) = self.circle.take() {
            self.warn(
                "circle-unused",
                c.line,
                1,
                "CIRCLE not followed by a GOTO".into(),
            );
        }
        if let Some(p) = self.path.take() {
            self.finished.push(p);
        }
        // State resets at the end of a path (units are file-wide).
        self.feed_mm_min = None;
        self.feed_mm_rev = None;
        self.spindle_rpm = None;
        self.axis = Vec3::z();
        self.rapid_next = false;
        self.cycle = false;
        self.current = None;
        self.last_out = None;
        self.frame = None;
        self.opened_by_record = false;
        self.contact_contour = false;
        self.pending_cc = false;
        self.tool_label = None;
        Ok(())
    }

    /// Finish: close an unterminated path and return the program (postures included only
    /// when [`LowerOptions::keep_postures`]).
    pub fn finish(mut self, sink: &mut PostureSink<'_>) -> Result<Program, LowerError> {
        if self.path.is_some() {
            self.flush(sink)?;
            if self.opened_by_record {
                self.warn("no-end", 0, 0, "file ends without END-OF-PATH".into());
            }
            self.end_path(sink)?;
        }
        if let (Some((line, column)), false) = (self.inch_feed_at, self.units_seen) {
            self.warn(
                "units",
                line,
                column,
                format!("{CONTRADICTORY_UNITS}: the feeds are in inches (FEDRAT/IPM or IPR) but the file has no UNITS record, so its coordinates and tool are read in millimetres; add UNITS/INCH or UNITS/MM"),
            );
        }
        let mut counts: Vec<(&'static str, usize)> = self
            .warning_counts
            .iter()
            .filter(|(_, c)| **c > WARNINGS_PER_KIND)
            .map(|(k, c)| (*k, *c))
            .collect();
        counts.sort();
        for (kind, c) in counts {
            self.warnings.push(Warning {
                at: Span::NONE,
                message: format!(
                    "{} more warnings of kind {kind} not shown",
                    c - WARNINGS_PER_KIND
                ),
            });
        }
        Ok(Program {
            paths: self.finished,
            warnings: self.warnings,
        })
    }
}

/// Lower records held in memory (tests, small inputs).
pub fn lower_records(records: &[Record], opts: LowerOptions) -> Result<Program, LowerError> {
    let mut low = Lowerer::new(opts);
    let mut sink = |_: &Toolpath, _: &Posture| Ok(());
    for r in records {
        low.push(r, &mut sink)?;
    }
    low.finish(&mut sink)
}

#[cfg(test)]
mod tests;
