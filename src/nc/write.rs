//! Writing postures as 5-axis G-code through the machine's inverse kinematics, posture by
//! posture: joints (TCP off, inverse-time feed G93) or the tip in the part frame with the
//! rotary joints (TCP on, `G43.4`, feed per minute), arcs as G2/G3 where the machine can
//! run them as arcs, contact data and tool data as `(CONTACT/…)` and `(TLDATA/…)`
//! comments. Numbers carry up to nine decimals (mm, degrees), so the program reads back
//! through the forward kinematics to the same postures within 1e-9 mm.

use super::joint_letters;
use crate::kinematics::{IkFailure, IkTracker, Joints, Machine};
use crate::math::{Point3, Vec3, nlerp};
use crate::toolpath::write::push_fixed;
use crate::toolpath::{ArcMove, MotionKind, Posture, Toolpath};
use std::io::{self, Write};

/// Decimals of lengths and angles: at least, at most.
const DECIMALS: (u32, u32) = (3, 9);
/// Largest angle of one line of an arc written as lines, rad.
const ARC_STEP_RAD: f64 = 0.0872664626; // 5°

/// Streams G-code (see the module docs).
pub struct GcodeWriter<'m> {
    machine: &'m Machine,
    tcp: bool,
    letters: [u8; 5],
    ik: IkTracker<'m>,
    line: Vec<u8>,
    started: bool,
    inverse_time: bool,
    feed: Option<f64>,
    spindle: Option<f64>,
    /// Tip, axis and joints of the last posture written.
    prev: Option<(Point3, Vec3, Joints)>,
    paths: usize,
}

impl<'m> GcodeWriter<'m> {
    /// A writer for `machine`; `tcp` writes the tip in the part frame under `G43.4`
    /// instead of joint positions. Fails when the machine's axis names are not G-code
    /// address letters.
    pub fn new(machine: &'m Machine, tcp: bool) -> Result<GcodeWriter<'m>, super::LetterError> {
        Ok(GcodeWriter {
            machine,
            tcp,
            letters: joint_letters(machine)?,
            ik: IkTracker::new(machine),
            line: Vec::with_capacity(200),
            started: false,
            inverse_time: false,
            feed: None,
            spindle: None,
            prev: None,
            paths: 0,
        })
    }

    /// Write the header of a path: the program start (first path), a tool change, the
    /// tool data, tool-centre-point control.
    pub fn begin_path(&mut self, path: &Toolpath, out: &mut dyn Write) -> io::Result<()> {
        if !self.started {
            self.started = true;
            writeln!(out, "%")?;
            writeln!(
                out,
                "(crest: {} through the inverse kinematics of {})",
                clean(&path.name),
                clean(&self.machine.name)
            )?;
            writeln!(out, "G90 G17 G21 G40 G94")?;
        }
        self.paths += 1;
        writeln!(
            out,
            "(TOOL PATH {}, TOOL {})",
            clean(&path.name),
            clean(&path.tool_name)
        )?;
        let number = path
            .tool_name
            .strip_prefix('T')
            .and_then(|n| n.parse::<u32>().ok())
            .unwrap_or(self.paths as u32);
        writeln!(out, "T{number} M6")?;
        if let Some(t) = &path.tool {
            let l = &mut self.line;
            l.clear();
            l.extend_from_slice(b"(TLDATA/MILL");
            for v in [
                t.diameter_mm,
                t.corner_radius_mm,
                t.length_mm,
                t.taper_rad.to_degrees(),
                t.tip_rad.to_degrees(),
            ] {
                l.push(b',');
                push_fixed(l, v, DECIMALS);
            }
            l.extend_from_slice(b")\n");
            out.write_all(l)?;
        }
        if self.tcp {
            writeln!(out, "G43.4 H{number}")?;
        }
        Ok(())
    }

    fn solve(&mut self, p: &Point3, u: &Vec3, line: u32) -> io::Result<Joints> {
        let u = &u.normalize();
        self.ik.solve(p, u).map(|s| s.joints).map_err(|e| {
            io::Error::other(match e {
                IkFailure::Unreachable => format!(
                    "line {line}: the tool axis ({:.6}, {:.6}, {:.6}) is out of reach of the rotary axes of \"{}\"",
                    u.x, u.y, u.z, self.machine.name
                ),
                IkFailure::Travel => format!(
                    "line {line}: every joint solution is outside the rotary travel limits of \"{}\"",
                    self.machine.name
                ),
            })
        })
    }

    /// Write one posture.
    pub fn posture(&mut self, p: &Posture, out: &mut dyn Write) -> io::Result<()> {
        if p.spindle_rpm != self.spindle {
            self.line.clear();
            match p.spindle_rpm {
                Some(s) => {
                    self.line.push(b'S');
                    push_fixed(&mut self.line, s, (0, 6));
                    self.line.extend_from_slice(b" M3\n");
                }
                None => self.line.extend_from_slice(b"M5\n"),
            }
            out.write_all(&self.line)?;
            self.spindle = p.spindle_rpm;
        }
        let rapid = matches!(
            p.motion,
            MotionKind::Rapid
                | MotionKind::Approach
                | MotionKind::Departure
                | MotionKind::From
                | MotionKind::GoHome
        );
        if let (Some(arc), Some((tip0, axis0, q0)), false) = (&p.arc, self.prev, rapid) {
            if let Some((plane, cw, centre_prog)) = self.arc_in_plane(arc, &tip0, &axis0, &q0, p) {
                let q = self.solve(&p.position, &p.axis, p.line)?;
                let start_prog = self.program_point(&tip0, &q0);
                let length = arc.length_mm(&tip0, &p.position);
                return self.block(
                    p,
                    q,
                    Some((plane, cw, centre_prog - start_prog)),
                    length,
                    out,
                );
            }
            // Not an arc of the machine's planes: lines every 5° at most.
            let sweep = arc.sweep_rad(&tip0, &p.position);
            let n = ((sweep / ARC_STEP_RAD).ceil() as usize).max(2);
            writeln!(
                out,
                "(crest: the arc of line {} written as {n} lines)",
                p.line
            )?;
            for k in 1..n {
                let t = k as f64 / n as f64;
                let q_pos = arc.point_at(&tip0, &p.position, t);
                let q_axis = nlerp(&axis0, &p.axis, t);
                let (prev_tip, _, _) = self.prev.unwrap_or((tip0, axis0, q0));
                let mid = Posture {
                    position: q_pos,
                    axis: q_axis,
                    arc: None,
                    contact: None,
                    ..p.clone()
                };
                let q = self.solve(&q_pos, &q_axis, p.line)?;
                let length = (q_pos - prev_tip).norm();
                self.block(&mid, q, None, length, out)?;
            }
            let (prev_tip, _, _) = self.prev.unwrap_or((tip0, axis0, q0));
            let q = self.solve(&p.position, &p.axis, p.line)?;
            let length = (p.position - prev_tip).norm();
            let mut last = p.clone();
            last.arc = None;
            return self.block(&last, q, None, length, out);
        }
        let q = self.solve(&p.position, &p.axis, p.line)?;
        let length = self.prev.map_or(0.0, |(t, _, _)| (p.position - t).norm());
        self.block(p, q, None, length, out)
    }

    /// Program coordinates (X, Y, Z words) of tip `tip` at joints `q`.
    fn program_point(&self, tip: &Point3, q: &Joints) -> Vec3 {
        if self.tcp {
            tip.coords
        } else {
            let mut v = Vec3::zeros();
            for j in 0..3 {
                v[(self.letters[j] - b'X') as usize] = q[j];
            }
            v
        }
    }

    /// The plane (normal index), sense (clockwise) and centre in program coordinates of an
    /// arc the NC can run as G2/G3 from the last posture, or `None`.
    fn arc_in_plane(
        &self,
        arc: &ArcMove,
        tip0: &Point3,
        axis0: &Vec3,
        q0: &Joints,
        p: &Posture,
    ) -> Option<(usize, bool, Vec3)> {
        if arc.extra_turns > 0 {
            return None;
        }
        let (axis_prog, centre_prog) = if self.tcp {
            (arc.axis, arc.centre.coords)
        } else {
            // The joints run the arc only with the rotary axes at rest.
            if (p.axis - axis0).norm() > 1e-15 {
                return None;
            }
            let joint = |x: &Point3| {
                let mut q = *q0;
                self.machine.linear_joints(&mut q, x);
                self.program_point(tip0, &q)
            };
            let c = joint(&arc.centre);
            let d = joint(&(arc.centre + arc.axis)) - c;
            (d * self.mirror(), c)
        };
        let k = (0..3).find(|&k| axis_prog[k].abs() > 1.0 - 1e-12)?;
        if (0..3).any(|j| j != k && axis_prog[j].abs() > 1e-9) {
            return None;
        }
        Some((k, axis_prog[k] > 0.0, centre_prog))
    }

    /// −1 when the machine's linear axes (with their signs, in X, Y, Z order) are
    /// left-handed.
    fn mirror(&self) -> f64 {
        let mut cols = [Vec3::zeros(); 3];
        for j in 0..3 {
            let a = &self.machine.linear[j];
            cols[(self.letters[j] - b'X') as usize] = a.direction * a.sign;
        }
        if cols[0].cross(&cols[1]).dot(&cols[2]) < 0.0 {
            -1.0
        } else {
            1.0
        }
    }

    /// Write one block: motion word, axis words, feed, contact comment.
    fn block(
        &mut self,
        p: &Posture,
        q: Joints,
        arc: Option<(usize, bool, Vec3)>,
        length: f64,
        out: &mut dyn Write,
    ) -> io::Result<()> {
        let rapid = matches!(
            p.motion,
            MotionKind::Rapid
                | MotionKind::Approach
                | MotionKind::Departure
                | MotionKind::From
                | MotionKind::GoHome
        ) || self.prev.is_none();
        let l = &mut self.line;
        l.clear();
        if !rapid && !self.tcp && !self.inverse_time {
            l.extend_from_slice(b"G93 ");
            self.inverse_time = true;
        }
        match arc {
            None => l.extend_from_slice(if rapid { b"G0" } else { b"G1" }),
            Some((plane, cw, _)) => {
                l.extend_from_slice(match plane {
                    2 => b"G17 ",
                    1 => b"G18 ",
                    _ => b"G19 ",
                });
                l.extend_from_slice(if cw { b"G2" } else { b"G3" });
            }
        }
        let prog = if self.tcp {
            p.position.coords
        } else {
            let mut v = Vec3::zeros();
            for j in 0..3 {
                v[(self.letters[j] - b'X') as usize] = q[j];
            }
            v
        };
        for (k, c) in [b'X', b'Y', b'Z'].iter().enumerate() {
            l.push(b' ');
            l.push(*c);
            push_fixed(l, prog[k], DECIMALS);
        }
        for r in 0..2 {
            l.push(b' ');
            l.push(self.letters[3 + r]);
            push_fixed(l, q[3 + r].to_degrees(), DECIMALS);
        }
        if let Some((plane, _, offset)) = arc {
            for (k, c) in [b'I', b'J', b'K'].iter().enumerate() {
                if k != plane {
                    l.push(b' ');
                    l.push(*c);
                    push_fixed(l, offset[k], DECIMALS);
                }
            }
        }
        if !rapid && let Some(f) = p.feed_mm_min {
            if self.tcp {
                if Some(f) != self.feed {
                    l.extend_from_slice(b" F");
                    push_fixed(l, f, (0, 6));
                    self.feed = Some(f);
                }
            } else {
                // Inverse time: the block lasts length / feed minutes.
                let inv = if length > 1e-12 { f / length } else { 1.0e6 };
                l.extend_from_slice(b" F");
                push_fixed(l, inv, (0, 9));
            }
        }
        if let Some(c) = &p.contact {
            l.extend_from_slice(b" (CONTACT/");
            let mut v = vec![c.point.x, c.point.y, c.point.z];
            if !c.normal_derived {
                v.extend([c.normal.x, c.normal.y, c.normal.z]);
            }
            for (k, x) in v.iter().enumerate() {
                if k > 0 {
                    l.push(b',');
                }
                push_fixed(l, *x, DECIMALS);
            }
            l.push(b')');
        }
        l.push(b'\n');
        out.write_all(l)?;
        self.prev = Some((p.position, p.axis, q));
        Ok(())
    }

    /// Close a path (nothing to write: the next path starts with its tool change).
    pub fn end_path(&mut self, _out: &mut dyn Write) -> io::Result<()> {
        Ok(())
    }

    /// End the program: spindle off, `M30`, `%`.
    pub fn finish(&mut self, out: &mut dyn Write) -> io::Result<()> {
        if !self.started {
            writeln!(out, "%")?;
        }
        if self.spindle.is_some() {
            writeln!(out, "M5")?;
        }
        if self.tcp {
            writeln!(out, "G49")?;
        }
        writeln!(out, "M30")?;
        writeln!(out, "%")
    }
}

/// Text safe inside a G-code comment.
fn clean(s: &str) -> String {
    let t: String = s
        .chars()
        .map(|c| {
            if c == '(' || c == ')' || c.is_control() {
                '_'
            } else {
                c
            }
        })
        .collect();
    if t.trim().is_empty() { "-".into() } else { t }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::machine::TABLE_I_AC_TOML;
    use crate::nc::{NcReader, Rtcp};
    use crate::parse::GcodeReader;
    use crate::parse::clsf::parse_str;
    use crate::toolpath::{LowerOptions, Lowerer, Program, lower_records};
    use approx::assert_relative_eq;

    fn ac() -> Machine {
        Machine::from_toml_str(TABLE_I_AC_TOML).unwrap_or_else(|e| panic!("{e}"))
    }

    fn write(program: &Program, m: &Machine, tcp: bool) -> io::Result<String> {
        let mut w = GcodeWriter::new(m, tcp).unwrap_or_else(|e| panic!("{e}"));
        let mut out = Vec::new();
        for path in &program.paths {
            w.begin_path(path, &mut out)?;
            for p in &path.postures {
                w.posture(p, &mut out)?;
            }
            w.end_path(&mut out)?;
        }
        w.finish(&mut out)?;
        Ok(String::from_utf8(out).unwrap_or_default())
    }

    fn read(text: &str, m: &Machine) -> Program {
        let mut nc = NcReader::new(m, Rtcp::Auto, "p").unwrap_or_else(|e| panic!("{e}"));
        let mut low = Lowerer::new(LowerOptions::default());
        let mut sink = |_: &Toolpath, _: &Posture| Ok(());
        for b in GcodeReader::new(text.as_bytes()) {
            let b = b.unwrap_or_else(|e| panic!("{e}"));
            nc.push(&b, &mut low, &mut sink)
                .unwrap_or_else(|e| panic!("{e}"));
        }
        nc.finish(&mut low, &mut sink)
            .unwrap_or_else(|e| panic!("{e}"));
        low.finish(&mut sink).unwrap_or_else(|e| panic!("{e}"))
    }

    fn clsf(text: &str) -> Program {
        let recs = parse_str(text).unwrap_or_else(|e| panic!("{e}"));
        lower_records(&recs, LowerOptions::default()).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn arcs_and_tilted_moves_round_trip() {
        let p = clsf(
            "TOOL PATH/A,TOOL,T1\nTLDATA/MILL,10,5,75,0,0\nSPINDL/RPM,12000,CLW\nRAPID\nGOTO/10,0,5,0,0,1\nFEDRAT/MMPM,800\nGOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10,0.06,0.5,10,5\nGOTO/0,-10,0\nCIRCLE/0,0,-1,0,0,-1,10,0.06,0.5,10,5\nGOTO/10,0,-1\nGOTO/12,1,-1,0.3,0.4,0.866025404\nCIRCLE/12,5,-1,0.6,0,0.8,4,0.06,0.5,10,5\nGOTO/12,9,-1\nEND-OF-PATH\n",
        );
        let m = ac();
        for tcp in [false, true] {
            let text = write(&p, &m, tcp).unwrap_or_else(|e| panic!("{e}"));
            // The XY arcs are G2/G3 (joints at rest in the TCP-off case); the tilted one
            // becomes lines.
            assert_eq!(text.matches("G17 G2 X").count(), 1, "{text}");
            assert_eq!(text.matches("G17 G3 X").count(), 1, "{text}");
            assert!(text.contains("written as"), "{text}");
            let back = read(&text, &m);
            let (a, b) = (&p.paths[0], &back.paths[0]);
            assert_eq!(b.tool.as_ref().map(|t| t.diameter_mm), Some(10.0));
            let sampled = b.postures.len() - a.postures.len();
            assert!(sampled >= 1);
            // Every posture of the CLSF is there (the sampled arc adds lines before its end).
            let mut k = 0;
            for q in &a.postures {
                while (b.postures[k].position - q.position).norm() > 1e-6 {
                    k += 1;
                }
                assert_relative_eq!(b.postures[k].axis, q.axis, epsilon = 1e-9);
                assert_eq!(b.postures[k].arc.is_some(), q.arc.is_some() && k < 4, "{k}");
                assert_relative_eq!(
                    b.postures[k].feed_mm_min.unwrap_or(0.0),
                    q.feed_mm_min.unwrap_or(0.0),
                    epsilon = 1e-4
                );
                assert_eq!(b.postures[k].spindle_rpm, q.spindle_rpm);
            }
            assert_relative_eq!(b.stats.length_mm, a.stats.length_mm, epsilon = 0.05);
        }
    }

    #[test]
    fn unreachable_axes_name_the_line() {
        // A travels ±120°: a tool axis 150° from +Z is out of reach.
        let p = clsf("TOOL PATH/A,TOOL,T\nGOTO/0,0,0,0.5,0,-0.866025404\nEND-OF-PATH\n");
        let e = write(&p, &ac(), false)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.starts_with("line 2: every joint solution is outside"),
            "{e}"
        );
    }
}
