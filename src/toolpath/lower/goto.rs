//! The fast path of the bulk of a CLSF file: a plain `GOTO` lowered in place, without a
//! `Record` or a copy of the posture; anything else goes to [`Lowerer::push`].

use super::{Lowerer, unit_as_written, vec3};
use crate::math::Point3;
use crate::parse::{Numbers, Record, RecordKind};
use crate::toolpath::{Contact, LowerError, MotionKind, Posture, PostureSink};

impl Lowerer {
    /// The bulk of a CLSF file: a `GOTO` with the tool axis (6 numbers) or with the
    /// contact point and normal too (12), in an open path with no CIRCLE, NURBS block,
    /// incremental or contact-contour mode pending, no MSYS to apply and postures not
    /// kept, all its numbers valid. Does what [`Self::push`] does for it, but emits the
    /// pending posture where it lies and overwrites it field by field (no copies of the
    /// posture, no `Result`s of the checks); returns `false`, having done nothing, for
    /// anything else, which [`Self::push`] then lowers (errors and warnings included).
    /// The only failure is the sink's, an `io::Error` (a word, where a [`LowerError`] is
    /// returned through memory).
    #[inline(always)]
    pub(super) fn push_goto_fast(
        &mut self,
        n: &Numbers,
        line: u32,
        sink: &mut PostureSink<'_>,
    ) -> std::io::Result<bool> {
        let len = n.len();
        let plain = (len == 6 || len == 12)
            && self.path.is_some()
            && self.nurbs.is_none()
            && self.circle.is_none()
            && !self.incremental
            && !self.contact_contour
            && !self.pending_cc
            && !self.opts.keep_postures
            && !(self.opts.apply_msys && self.frame.is_some());
        if !plain {
            return Ok(false);
        }
        let s = self.scale();
        let position = Point3::from(vec3(n.triple(0)) * s);
        // As `check_coords` (NaN fails every comparison).
        let lim = crate::math::limits::MAX_COORD_MM;
        let c = &position.coords;
        if !((c.x.abs() <= lim) & (c.y.abs() <= lim) & (c.z.abs() <= lim)) {
            return Ok(false);
        }
        let Some(axis) = unit_as_written(vec3(n.triple(3))) else {
            return Ok(false);
        };
        let contact = if len == 12 {
            let Some(normal) = unit_as_written(vec3(n.triple(9))) else {
                return Ok(false);
            };
            Some(Contact {
                point: Point3::from(vec3(n.triple(6)) * s),
                normal,
                normal_derived: false,
            })
        } else {
            None
        };
        // Every check has passed (`plain` saw the path): from here the GOTO is lowered. The
        // motion is taken now, as the `Goto` arm of `push` does after the flush (the flush
        // reads neither the cycle nor the rapid flag).
        let motion = self.motion_now();
        let Some(path) = self.path.as_mut() else {
            return Ok(false);
        };
        // As `flush_pending` (nothing of the posture changes on the way out but its kind).
        if let Some(p) = &mut self.pending {
            let seg = match (p.motion, self.current) {
                (MotionKind::From, _) | (_, None) => 0.0,
                (_, Some(s)) => match &p.arc {
                    Some(arc) => arc.length_mm(&s, &p.position),
                    None => (p.position - s).norm(),
                },
            };
            self.current = Some(p.position);
            self.last_out = Some(p.position);
            match self.kinds.quick(p.motion, p.feed_mm_min, p.position) {
                Some(kind) => {
                    p.motion = kind;
                    super::kinds::record(path, p, seg, sink)?;
                }
                None => {
                    // Held back until its kind is known: the posture moves into the queue.
                    if let Some(p) = self.pending.take() {
                        let mut out =
                            |p: Posture, seg: f64| super::kinds::record(path, &p, seg, sink);
                        self.kinds.push(p, seg, &mut out)?;
                    }
                }
            }
        }
        // As the `Goto` arm of `push`.
        path.stats.gotos += 1;
        self.axis = axis;
        let new = Posture {
            position,
            axis,
            motion,
            arc: None,
            contact,
            feed_mm_min: self.feed_mm_min,
            spindle_rpm: self.spindle_rpm,
            line,
        };
        match &mut self.pending {
            Some(p) => *p = new,
            None => self.pending = Some(new),
        }
        Ok(true)
    }

    /// Lower a `GOTO` of numbers only that starts in column 1 (what
    /// [`crate::parse::ClsfReader::next_goto`] reads), as [`Self::push`] of its record.
    pub fn push_goto(
        &mut self,
        n: &Numbers,
        line: u32,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        if self
            .push_goto_fast(n, line, sink)
            .map_err(LowerError::Output)?
        {
            return Ok(());
        }
        self.push(
            &Record {
                kind: RecordKind::Goto(*n),
                line,
                column: 1,
            },
            sink,
        )
    }
}
