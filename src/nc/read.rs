//! Reading G-code through the machine: the NC's modal state, every block that moves turned
//! into CL records (`TOOL PATH`, `SPINDL`, `FEDRAT`, `RAPID`, `CIRCLE`, `GOTO`, `CONTACT`)
//! for [`Lowerer`] through the forward kinematics (see the module docs of [`crate::nc`]).

use super::{Rtcp, joint_letters};
use crate::kinematics::{Joints, Machine};
use crate::math::{Point3, Vec3, normalize_or_none};
use crate::parse::gcode::{Block, Word};
use crate::parse::{Arg, FeedUnit, Numbers, Record, RecordKind, Span};
use crate::toolpath::{ArcMove, LowerError, Lowerer, PostureSink};

/// mm per inch.
const MM_PER_INCH: f64 = 25.4;
/// Arc ends farther than this from the circle through the start are reported, mm.
const ARC_END_TOL_MM: f64 = 0.005;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Motion {
    Rapid,
    Line,
    Cw,
    Ccw,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FeedMode {
    PerMinute,
    InverseTime,
    PerRevolution,
}

fn invalid(line: u32, column: u32, expected: &str, found: String) -> LowerError {
    LowerError::invalid(Span::line_column(line, column), expected, found)
}

/// The modal state of the NC and the bookkeeping of the paths it opens (see the module
/// docs of [`crate::nc`]).
pub struct NcReader<'m> {
    machine: &'m Machine,
    rtcp: Rtcp,
    letters: [u8; 5],
    name: String,
    motion: Option<Motion>,
    /// Index (0 = X, 1 = Y, 2 = Z) of the axis normal to the arc plane.
    plane: usize,
    absolute: bool,
    inch: bool,
    feed_mode: FeedMode,
    f: Option<f64>,
    s: Option<f64>,
    spindle_on: bool,
    tcp: bool,
    joints: Joints,
    tip: Point3,
    /// Which of X, Y, Z, rotary 1, rotary 2 have been programmed.
    known: [bool; 5],
    tool_label: String,
    path_open: bool,
    path_moved: bool,
    /// Records waiting for the path to open (`TLDATA` comments).
    queue: Vec<Record>,
    feed_out: Option<f64>,
    spindle_out: Option<f64>,
    warned_letters: Vec<u8>,
}

impl<'m> NcReader<'m> {
    /// A reader for `machine`; `name` names the tool paths (the file's stem). Fails when
    /// the machine's axis names are not G-code address letters.
    pub fn new(
        machine: &'m Machine,
        rtcp: Rtcp,
        name: &str,
    ) -> Result<NcReader<'m>, super::LetterError> {
        let letters = joint_letters(machine)?;
        let joints = [0.0; 5];
        Ok(NcReader {
            machine,
            rtcp,
            letters,
            name: name.to_string(),
            motion: None,
            plane: 2,
            absolute: true,
            inch: false,
            feed_mode: FeedMode::PerMinute,
            f: None,
            s: None,
            spindle_on: false,
            tcp: rtcp == Rtcp::On,
            joints,
            tip: machine.forward(&joints).tip,
            known: [false; 5],
            tool_label: String::new(),
            path_open: false,
            path_moved: false,
            queue: Vec::new(),
            feed_out: None,
            spindle_out: None,
            warned_letters: Vec::new(),
        })
    }

    fn scale(&self) -> f64 {
        if self.inch { MM_PER_INCH } else { 1.0 }
    }

    fn set_tcp(&mut self, on: bool) {
        if self.rtcp == Rtcp::Auto {
            self.tcp = on;
        }
    }

    fn emit(
        low: &mut Lowerer,
        sink: &mut PostureSink<'_>,
        kind: RecordKind,
        line: u32,
        column: u32,
    ) -> Result<(), LowerError> {
        low.push(&Record { kind, line, column }, sink)
    }

    /// Open a tool path (once per tool) and bring the spindle up to date.
    fn open(
        &mut self,
        low: &mut Lowerer,
        sink: &mut PostureSink<'_>,
        line: u32,
    ) -> Result<(), LowerError> {
        if !self.path_open {
            let kind = RecordKind::ToolPath {
                name: self.name.clone(),
                tool: self.tool_label.clone(),
            };
            Self::emit(low, sink, kind, line, 1)?;
            self.path_open = true;
            self.path_moved = false;
            self.feed_out = None;
            self.spindle_out = None;
            for r in std::mem::take(&mut self.queue) {
                low.push(&r, sink)?;
            }
        }
        let want = if self.spindle_on { self.s } else { None };
        if want != self.spindle_out {
            let args = match want {
                Some(v) => vec![
                    Arg::Word("RPM".into()),
                    Arg::Num(v),
                    Arg::Word("CLW".into()),
                ],
                None => vec![Arg::Word("OFF".into())],
            };
            Self::emit(low, sink, RecordKind::Spindl(args), line, 1)?;
            self.spindle_out = want;
        }
        Ok(())
    }

    fn close(
        &mut self,
        low: &mut Lowerer,
        sink: &mut PostureSink<'_>,
        line: u32,
    ) -> Result<(), LowerError> {
        if self.path_open {
            Self::emit(low, sink, RecordKind::EndOfPath, line, 1)?;
            self.path_open = false;
        }
        Ok(())
    }

    /// Read one block.
    pub fn push(
        &mut self,
        b: &Block,
        low: &mut Lowerer,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        let line = b.line;
        // G codes: modal groups and the blocks whose axis words are not a move.
        let mut not_a_move = false;
        let mut motion_word: Option<&Word> = None;
        for w in b.words.iter().filter(|w| w.letter == b'G') {
            let code = w
                .code()
                .ok_or_else(|| invalid(line, w.column, "a G code", format!("G{}", w.value)))?;
            match code {
                0 | 10 | 20 | 30 => {
                    self.motion = Some(match code {
                        0 => Motion::Rapid,
                        10 => Motion::Line,
                        20 => Motion::Cw,
                        _ => Motion::Ccw,
                    });
                    motion_word = Some(w);
                }
                170 => self.plane = 2,
                180 => self.plane = 1,
                190 => self.plane = 0,
                200 => self.inch = true,
                210 => self.inch = false,
                900 => self.absolute = true,
                910 => self.absolute = false,
                930 => self.feed_mode = FeedMode::InverseTime,
                940 => self.feed_mode = FeedMode::PerMinute,
                950 => self.feed_mode = FeedMode::PerRevolution,
                434 => self.set_tcp(true),
                490 => self.set_tcp(false),
                // Dwell, data setting, macro call: their words are no move.
                40 | 100 | 650 => not_a_move = true,
                280 | 300 | 530 | 920 => {
                    not_a_move = true;
                    low.note(
                        "gcode-ignored",
                        line,
                        w.column,
                        format!(
                            "G{} is not interpreted: the axis words of its block are no move",
                            fmt_code(code)
                        ),
                    );
                }
                410 | 420 => low.note(
                    "gcode-cutcom",
                    line,
                    w.column,
                    "cutter radius compensation (G41/G42) is not applied: the path is read as programmed".into(),
                ),
                // No effect on postures: compensation cancel and length offsets, work
                // offsets (the part frame is the machine's), path control, cycles off,
                // high-speed modes, coordinate rotation and scaling cancel.
                400 | 430 | 440 | 540..=590 | 610 | 611 | 640 | 800 | 980 | 990 | 150
                | 690 | 500 | 50 | 51 | 80 | 1870 => {}
                _ => low.note(
                    "gcode-unknown",
                    line,
                    w.column,
                    format!("G{} is not interpreted", fmt_code(code)),
                ),
            }
        }
        let mut tool_change = false;
        let mut program_end = false;
        for w in b.words.iter().filter(|w| w.letter == b'M') {
            match w.code() {
                Some(30 | 40) => self.spindle_on = true,
                Some(50) => self.spindle_on = false,
                Some(60) => tool_change = true,
                Some(20 | 300) => program_end = true,
                Some(1280) => self.set_tcp(true),
                Some(1290) => self.set_tcp(false),
                _ => {}
            }
        }
        for k in &b.keywords {
            match k.name.as_str() {
                "TRAORI" => self.set_tcp(true),
                "TRAFOOF" => self.set_tcp(false),
                _ => low.note(
                    "gcode-keyword",
                    line,
                    k.column,
                    format!("{} is not interpreted", k.text),
                ),
            }
        }
        self.check_letters(b, low);
        if let Some(w) = b.word(b'F') {
            if w.value < 0.0 {
                return Err(invalid(
                    line,
                    w.column,
                    "a feed ≥ 0",
                    format!("{}", w.value),
                ));
            }
            self.f = Some(w.value);
        }
        if let Some(w) = b.word(b'S') {
            if w.value < 0.0 {
                return Err(invalid(
                    line,
                    w.column,
                    "a spindle speed ≥ 0",
                    format!("{}", w.value),
                ));
            }
            self.s = Some(w.value);
        }
        if let Some(w) = b.word(b'T') {
            self.tool_label = if w.value.fract() == 0.0 && w.value.abs() < 1e9 {
                format!("T{}", w.value as i64)
            } else {
                format!("T{}", w.value)
            };
        }
        if tool_change && self.path_moved {
            self.close(low, sink, line)?;
        }
        for r in &b.records {
            let rec = Record {
                kind: r.kind.clone(),
                line,
                column: r.column,
            };
            if matches!(r.kind, RecordKind::Tldata { .. }) {
                if self.path_open {
                    low.push(&rec, sink)?;
                } else {
                    self.queue.push(rec);
                }
            }
        }
        if !not_a_move {
            self.motion_block(b, motion_word, low, sink)?;
        }
        if program_end {
            self.close(low, sink, line)?;
        }
        Ok(())
    }

    /// Warn once per address letter that means nothing here.
    fn check_letters(&mut self, b: &Block, low: &mut Lowerer) {
        for w in &b.words {
            let known = b"NOGMFSTHDPQLXYZIJKR".contains(&w.letter)
                || w.letter == self.letters[3]
                || w.letter == self.letters[4];
            if !known && !self.warned_letters.contains(&w.letter) {
                self.warned_letters.push(w.letter);
                low.note(
                    "gcode-letter",
                    b.line,
                    w.column,
                    format!(
                        "{} words are no axis of the machine and are ignored",
                        w.letter as char
                    ),
                );
            }
        }
    }

    /// The move of a block, if it has one.
    fn motion_block(
        &mut self,
        b: &Block,
        motion_word: Option<&Word>,
        low: &mut Lowerer,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        let line = b.line;
        let axis_letters = [b'X', b'Y', b'Z', self.letters[3], self.letters[4]];
        let has_axis = axis_letters.iter().any(|l| b.word(*l).is_some());
        let arc = matches!(self.motion, Some(Motion::Cw | Motion::Ccw));
        let has_centre = [b'I', b'J', b'K', b'R']
            .iter()
            .any(|l| b.word(*l).is_some());
        if !(has_axis || (arc && has_centre && motion_word.is_some())) {
            return Ok(());
        }
        let motion = match self.motion {
            Some(m) => m,
            None => {
                low.note(
                    "gcode-no-motion",
                    line,
                    1,
                    "axis words before any G0, G1, G2 or G3: read as a rapid move (G0)".into(),
                );
                self.motion = Some(Motion::Rapid);
                Motion::Rapid
            }
        };
        let scale = self.scale();
        // Program coordinates of the start: the tip (TCP on) or the linear joints.
        let start_prog = if self.tcp {
            self.tip.coords
        } else {
            let mut v = Vec3::zeros();
            for j in 0..3 {
                v[(self.letters[j] - b'X') as usize] = self.joints[j];
            }
            v
        };
        let mut end_prog = start_prog;
        let mut joints = self.joints;
        let mut missing = Vec::new();
        for (k, letter) in axis_letters.iter().enumerate() {
            match b.word(*letter) {
                Some(w) => {
                    let v = if k < 3 {
                        w.value * scale
                    } else {
                        w.value.to_radians()
                    };
                    let (target, base) = if k < 3 {
                        (&mut end_prog[k], start_prog[k])
                    } else {
                        (&mut joints[k], self.joints[k])
                    };
                    *target = if self.absolute { v } else { base + v };
                    self.known[k] = true;
                }
                None if !self.known[k] => {
                    self.known[k] = true;
                    missing.push(*letter as char);
                }
                None => {}
            }
        }
        if !missing.is_empty() {
            let list: Vec<String> = missing.iter().map(|c| c.to_string()).collect();
            low.note(
                "gcode-unprogrammed",
                line,
                1,
                format!(
                    "axis {} not programmed before this move: taken as 0",
                    list.join(", ")
                ),
            );
        }
        for j in 0..3 {
            joints[j] = end_prog[(self.letters[j] - b'X') as usize];
        }
        // The pose at the end of the block.
        let (tip, axis) = if self.tcp {
            let tip = Point3::from(end_prog);
            let axis = self
                .machine
                .forward(&[0.0, 0.0, 0.0, joints[3], joints[4]])
                .axis;
            self.machine.linear_joints(&mut joints, &tip);
            (tip, axis)
        } else {
            let pose = self.machine.forward(&joints);
            (pose.tip, pose.axis)
        };
        let arc_move = match motion {
            Motion::Cw | Motion::Ccw => {
                Some(self.arc(b, motion, &start_prog, &end_prog, &joints, low)?)
            }
            _ => None,
        };
        let length = match &arc_move {
            Some(a) => a.length_mm(&self.tip, &tip),
            None => (tip - self.tip).norm(),
        };
        let feed = if motion == Motion::Rapid {
            None
        } else {
            self.tip_feed(b, length, &start_prog, &end_prog, &joints, low)
        };
        self.open(low, sink, line)?;
        if let Some(f) = feed
            && Some(f) != self.feed_out
        {
            let kind = RecordKind::Fedrat {
                unit: Some(FeedUnit::Mmpm),
                value: f,
            };
            Self::emit(low, sink, kind, line, 1)?;
            self.feed_out = Some(f);
        }
        if motion == Motion::Rapid {
            Self::emit(low, sink, RecordKind::Rapid, line, 1)?;
        }
        if let Some(a) = &arc_move {
            let v = [
                a.centre.x,
                a.centre.y,
                a.centre.z,
                a.axis.x,
                a.axis.y,
                a.axis.z,
                a.radius_mm,
            ];
            let numbers = Numbers::from_slice(&v).unwrap_or_else(|| unreachable!("7 numbers"));
            Self::emit(
                low,
                sink,
                RecordKind::Circle {
                    numbers,
                    times: None,
                },
                line,
                1,
            )?;
        }
        let v = [tip.x, tip.y, tip.z, axis.x, axis.y, axis.z];
        let numbers = Numbers::from_slice(&v).unwrap_or_else(|| unreachable!("6 numbers"));
        Self::emit(low, sink, RecordKind::Goto(numbers), line, 1)?;
        for r in &b.records {
            if matches!(r.kind, RecordKind::Contact(_)) {
                Self::emit(low, sink, r.kind.clone(), line, r.column)?;
            }
        }
        self.path_moved = true;
        self.tip = tip;
        self.joints = joints;
        Ok(())
    }

    /// The feed at the tool tip of a feed move of tip length `length`, mm/min; `None`
    /// keeps the feed before (no F yet, or no tip motion to spread it over).
    fn tip_feed(
        &mut self,
        b: &Block,
        length: f64,
        start_prog: &Vec3,
        end_prog: &Vec3,
        joints: &Joints,
        low: &mut Lowerer,
    ) -> Option<f64> {
        let Some(f) = self.f else {
            low.note(
                "gcode-no-feed",
                b.line,
                1,
                "a feed move before any F word: its feed is unknown".into(),
            );
            return None;
        };
        if self.feed_mode == FeedMode::InverseTime && b.word(b'F').is_none() {
            low.note(
                "gcode-inverse-time",
                b.line,
                1,
                "inverse-time feed (G93) without F in the block: the F before is used".into(),
            );
        }
        let scale = self.scale();
        let per_minute = match self.feed_mode {
            FeedMode::PerMinute => f,
            FeedMode::PerRevolution => match self.s {
                Some(s) if self.spindle_on => f * s,
                _ => {
                    low.note(
                        "gcode-per-rev",
                        b.line,
                        1,
                        "feed per revolution (G95) with the spindle off: feed unknown".into(),
                    );
                    return None;
                }
            },
            FeedMode::InverseTime => {
                return (length > 1e-12).then_some(fedrat_digits(length * f));
            }
        };
        if self.tcp {
            return Some(per_minute * scale);
        }
        // TCP off: the NC spreads F over the joint motion (linear in program units,
        // rotary in degrees).
        let lin = (end_prog - start_prog).norm() / scale;
        let lin = if matches!(self.motion, Some(Motion::Cw | Motion::Ccw)) {
            length / scale
        } else {
            lin
        };
        let rot = ((joints[3] - self.joints[3]).to_degrees().powi(2)
            + (joints[4] - self.joints[4]).to_degrees().powi(2))
        .sqrt();
        let d = (lin * lin + rot * rot).sqrt();
        if d <= 1e-12 || length <= 1e-12 || per_minute <= 0.0 {
            return None;
        }
        Some(fedrat_digits(length * per_minute / d))
    }

    /// The arc of a G2/G3 block in the part frame.
    fn arc(
        &self,
        b: &Block,
        motion: Motion,
        start: &Vec3,
        end: &Vec3,
        joints: &Joints,
        low: &mut Lowerer,
    ) -> Result<ArcMove, LowerError> {
        let line = b.line;
        let n = self.plane;
        let normal = Vec3::ith(n, 1.0);
        let flat = |v: Vec3| v - normal * v[n];
        let scale = self.scale();
        let cw = motion == Motion::Cw;
        let centre = if let Some(r) = b.word(b'R') {
            let chord = flat(end - start);
            let d = chord.norm();
            let rr = r.value.abs() * scale;
            if d < 1e-12 {
                return Err(invalid(
                    line,
                    r.column,
                    "I, J, K for a full circle (R gives no centre when start and end meet)",
                    "R".into(),
                ));
            }
            let h2 = rr * rr - 0.25 * d * d;
            if h2 < -1e-6 * rr.max(1.0) {
                return Err(invalid(
                    line,
                    r.column,
                    "a radius at least half the chord",
                    format!("R{} for a chord of {:.6} mm", r.value, d / scale),
                ));
            }
            let h = h2.max(0.0).sqrt();
            let left = normal.cross(&(chord / d));
            let side = if cw { -1.0 } else { 1.0 } * if r.value < 0.0 { -1.0 } else { 1.0 };
            start + 0.5 * (end - start) - normal * (0.5 * (end - start)[n]) + left * (side * h)
        } else {
            let mut c = *start;
            let mut any = false;
            for (k, l) in [b'I', b'J', b'K'].iter().enumerate() {
                if let Some(w) = b.word(*l) {
                    any = true;
                    if k != n {
                        c[k] += w.value * scale;
                    }
                }
            }
            if !any {
                return Err(invalid(
                    line,
                    1,
                    "the centre of the arc (I, J, K or R)",
                    "none".into(),
                ));
            }
            c
        };
        let radius = flat(start - centre).norm();
        let off = (flat(end - centre).norm() - radius).abs();
        if off > ARC_END_TOL_MM {
            low.note(
                "gcode-arc-end",
                line,
                1,
                format!("the arc ends {off:.4} mm off the circle through its start"),
            );
        }
        let sense = if cw { 1.0 } else { -1.0 };
        if self.tcp {
            return Ok(ArcMove {
                centre: Point3::from(centre),
                axis: normal * sense,
                radius_mm: radius,
                extra_turns: 0,
            });
        }
        // TCP off: the arc of the linear joints, carried into the part frame by the
        // (fixed) rotary axes.
        if (joints[3] - self.joints[3]).abs() > 1e-12 || (joints[4] - self.joints[4]).abs() > 1e-12
        {
            return Err(invalid(
                line,
                1,
                "an arc (G2, G3) with the rotary axes at rest (or tool-centre-point control on)",
                "rotary motion in the arc's block".into(),
            ));
        }
        let at = |p: &Vec3| {
            let mut q = *joints;
            for j in 0..3 {
                q[j] = p[(self.letters[j] - b'X') as usize];
            }
            self.machine.forward(&q).tip
        };
        let c = at(&centre);
        let dir = at(&(centre + normal)) - c;
        let mirror = self.linear_mirror();
        let axis = normalize_or_none(&dir, 1e-12).unwrap_or(normal) * (sense * mirror);
        Ok(ArcMove {
            centre: c,
            axis,
            radius_mm: radius,
            extra_turns: 0,
        })
    }

    /// −1 when the machine's linear axes (with their signs) form a left-handed frame.
    fn linear_mirror(&self) -> f64 {
        let col = |k: usize| self.machine.linear[k].direction * self.machine.linear[k].sign;
        let mut cols = [col(0), col(1), col(2)];
        // Columns in X, Y, Z order of the program.
        let mut ordered = cols;
        for j in 0..3 {
            ordered[(self.letters[j] - b'X') as usize] = cols[j];
        }
        cols = ordered;
        if cols[0].cross(&cols[1]).dot(&cols[2]) < 0.0 {
            -1.0
        } else {
            1.0
        }
    }

    /// Close the last tool path.
    pub fn finish(
        &mut self,
        low: &mut Lowerer,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        self.close(low, sink, 0)
    }
}

/// A feed worked out from the joint motion or inverse time carries the rounding of the
/// printed joints: keep the four decimals of a FEDRAT.
fn fedrat_digits(f: f64) -> f64 {
    (f * 1e4).round() / 1e4
}

/// `43.4` for 434, `1` for 10.
fn fmt_code(tenths: i64) -> String {
    if tenths % 10 == 0 {
        format!("{}", tenths / 10)
    } else {
        format!("{}.{}", tenths / 10, (tenths % 10).abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::machine::TABLE_I_AC_TOML;
    use crate::parse::GcodeReader;
    use crate::toolpath::{LowerOptions, MotionKind, Program};
    use approx::assert_relative_eq;

    fn ac() -> Machine {
        Machine::from_toml_str(TABLE_I_AC_TOML).unwrap_or_else(|e| panic!("{e}"))
    }

    fn read(text: &str, rtcp: Rtcp) -> Result<Program, LowerError> {
        let m = ac();
        let mut nc = NcReader::new(&m, rtcp, "prog").unwrap_or_else(|e| panic!("{e}"));
        let mut low = Lowerer::new(LowerOptions::default());
        let mut sink = |_: &crate::toolpath::Toolpath, _: &crate::toolpath::Posture| Ok(());
        for b in GcodeReader::new(text.as_bytes()) {
            let b = b.unwrap_or_else(|e| panic!("{e}"));
            nc.push(&b, &mut low, &mut sink)?;
        }
        nc.finish(&mut low, &mut sink)?;
        low.finish(&mut sink)
    }

    fn ok(text: &str, rtcp: Rtcp) -> Program {
        read(text, rtcp).unwrap_or_else(|e| panic!("{e}"))
    }

    fn dir(tilt_deg: f64, az_deg: f64) -> Vec3 {
        let (t, a) = (tilt_deg.to_radians(), az_deg.to_radians());
        Vec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos())
    }

    #[test]
    fn joints_through_the_forward_kinematics() {
        // kinematics.md K6: (A, C) = (30°, −30°) puts the tool at tilt 30°, azimuth 120°.
        let p = ok(
            "G90 G94 G21\nS10000 M3\nG0 X0 Y0 Z50 A0 C0\nG1 X10 Y0 Z0 A30 C-30 F1000\n",
            Rtcp::Auto,
        );
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
        let ps = &p.paths[0].postures;
        assert_eq!(ps[0].motion, MotionKind::Rapid);
        assert_eq!(ps[1].spindle_rpm, Some(10000.0));
        assert_relative_eq!(ps[1].axis, dir(30.0, 120.0), epsilon = 1e-12);
        let m = ac();
        let pose = m.forward(&[10.0, 0.0, 0.0, 30f64.to_radians(), -30f64.to_radians()]);
        assert_relative_eq!(ps[1].position, pose.tip, epsilon = 1e-12);
        // TCP off: F spreads over √(ΔX² + ΔZ² + ΔA² + ΔC²) (mm and degrees).
        let d = (100.0f64 + 2500.0 + 900.0 + 900.0).sqrt();
        let len = (ps[1].position - ps[0].position).norm();
        assert_relative_eq!(
            ps[1].feed_mm_min.unwrap_or(0.0),
            (1000.0 * len / d * 1e4).round() / 1e4,
            epsilon = 1e-9
        );
    }

    #[test]
    fn tool_centre_point_control_and_its_switches() {
        let text = "G0 X1 Y2 Z3 A0 C0\nG43.4 H1\nG1 X1 Y2 Z3 A30 C-30 F500\nG91 X1 C10\nG49\nG90 G1 X0 Y0 Z0\n";
        let p = ok(text, Rtcp::Auto);
        let ps = &p.paths[0].postures;
        assert_eq!(ps[1].position, Point3::new(1.0, 2.0, 3.0));
        assert_relative_eq!(ps[1].axis, dir(30.0, 120.0), epsilon = 1e-12);
        assert_eq!(ps[1].feed_mm_min, Some(500.0));
        assert_relative_eq!(ps[2].position, Point3::new(2.0, 2.0, 3.0), epsilon = 1e-12);
        assert_relative_eq!(ps[2].axis, dir(30.0, 110.0), epsilon = 1e-12);
        // G49: X Y Z are joints again (A, C kept).
        let m = ac();
        let q = [0.0, 0.0, 0.0, 30f64.to_radians(), (-20f64).to_radians()];
        assert_relative_eq!(ps[3].position, m.forward(&q).tip, epsilon = 1e-12);
        // --rtcp on: the first block is a tip in the part frame too.
        let on = ok(text, Rtcp::On);
        assert_eq!(on.paths[0].postures[0].position, Point3::new(1.0, 2.0, 3.0));
        assert_eq!(on.paths[0].postures[3].position, Point3::origin());
        let t = ok("TRAORI\nG1 X1 Y2 Z3 A0 C0 F100\nTRAFOOF\n", Rtcp::Auto);
        assert_eq!(t.paths[0].postures[0].position, Point3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn arcs_in_the_three_planes() {
        let p = ok(
            "G43.4\nG0 X10 Y0 Z0 A0 C0\nG17 G2 X0 Y-10 I-10 J0 F100\nG3 X10 Y0 R-10\nG18 G2 X20 Z0 I5 K0\nG91 G19 G3 Y0 Z0 J0 K5\n",
            Rtcp::Auto,
        );
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
        let t = &p.paths[0];
        assert_eq!(t.stats.circles, 4);
        let a = t.postures[1].arc.as_ref().unwrap_or_else(|| panic!("arc"));
        assert_eq!(
            (a.centre, a.axis, a.radius_mm),
            (Point3::origin(), Vec3::z(), 10.0)
        );
        // R < 0: the long way round, counter-clockwise: three quarters of a turn.
        let b = t.postures[2].arc.as_ref().unwrap_or_else(|| panic!("arc"));
        assert_relative_eq!(b.centre, Point3::new(10.0, -10.0, 0.0), epsilon = 1e-12);
        assert_eq!(b.axis, -Vec3::z());
        let sweep = b.sweep_rad(&t.postures[1].position, &t.postures[2].position);
        assert_relative_eq!(sweep, 1.5 * std::f64::consts::PI, epsilon = 1e-12);
        let c = t.postures[3].arc.as_ref().unwrap_or_else(|| panic!("arc"));
        assert_eq!((c.centre, c.axis), (Point3::new(15.0, 0.0, 0.0), Vec3::y()));
        // G19 full circle about −X (incremental, end = start).
        let d = t.postures[4].arc.as_ref().unwrap_or_else(|| panic!("arc"));
        assert_eq!(d.axis, -Vec3::x());
        assert_relative_eq!(
            t.stats.length_mm,
            35.0 * std::f64::consts::PI,
            epsilon = 1e-9
        );
    }

    #[test]
    fn inches_inverse_time_spindle_and_tool_changes() {
        let p = ok(
            "G20 G43.4\nT1 M6\nS8000 M3\nG0 X0 Y0 Z1 A0 C0\nG93 G1 Z0 F60\nM5\nG94 G1 X1 F10\nT2 M6\nS9000 M4\nG1 X2\nM30\n",
            Rtcp::Auto,
        );
        assert_eq!(p.paths.len(), 2);
        let (a, b) = (&p.paths[0], &p.paths[1]);
        assert_eq!((a.name.as_str(), a.tool_name.as_str()), ("prog", "T1"));
        assert_eq!(b.tool_name, "T2");
        assert_eq!(a.postures[0].position, Point3::new(0.0, 0.0, 25.4));
        // Inverse time: 25.4 mm in 1/60 min.
        assert_relative_eq!(
            a.postures[1].feed_mm_min.unwrap_or(0.0),
            1524.0,
            epsilon = 1e-9
        );
        assert_eq!(a.postures[1].spindle_rpm, Some(8000.0));
        assert_eq!(a.postures[2].spindle_rpm, None);
        assert_relative_eq!(
            a.postures[2].feed_mm_min.unwrap_or(0.0),
            254.0,
            epsilon = 1e-9
        );
        assert_eq!(b.postures[0].spindle_rpm, Some(9000.0));
        assert_eq!(b.postures[0].position, Point3::new(50.8, 0.0, 0.0));
    }

    #[test]
    fn findings_and_errors_name_line_and_column() {
        let p = ok(
            "G1 X1 F100\nG68.2 X0\nCYCLE832(0.01)\nG1 X2 Y1 Z0 A0 C0 B5\n",
            Rtcp::Auto,
        );
        let msgs: Vec<(u32, String)> = p
            .warnings
            .iter()
            .map(|w| (w.at.line, w.message.clone()))
            .collect();
        assert!(
            msgs[0].1.contains("axis Y, Z, A, C not programmed"),
            "{msgs:?}"
        );
        assert_eq!(msgs[1], (2, "G68.2 is not interpreted".into()));
        assert_eq!(msgs[2], (3, "CYCLE832(0.01) is not interpreted".into()));
        assert!(msgs[3].1.starts_with("B words"), "{msgs:?}");
        for (text, at) in [
            ("G0 X0 Y0 Z0 A0 C0\nG2 X1 Y1\n", (2, 1)),
            ("G0 X0 Y0 Z0 A0 C0\nG2 X10 Y0 R2\n", (2, 11)),
            ("G0 X0 Y0 Z0 A0 C0\nG2 X10 Y0 A5 I5\n", (2, 1)),
            ("F-5\n", (1, 1)),
        ] {
            match read(text, Rtcp::Auto) {
                Err(LowerError::Invalid(e)) => {
                    assert_eq!((e.span.line, e.span.column), at, "{text}")
                }
                other => panic!("{text}: {other:?}"),
            }
        }
    }
}
