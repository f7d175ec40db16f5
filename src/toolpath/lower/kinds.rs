//! Move kinds while lowering: each finished posture gets its kind (rapid, approach,
//! engage, cut, retract, departure; From, Cycle and GoHome stay as they are) before it
//! leaves the lowering.
//!
//! The sources, in order:
//!
//! 1. **NX's `PAINT/COLOR,n`**, written before each group of moves. NX's default display
//!    colours, as the twelve public NX exports use them (`clsf.md` §4): 186 rapid (and
//!    FROM/GOHOME), 211 approach and departure, 42 engage, 31 cut, 36 stepover (a
//!    cut-class move between passes: `nx_fixed_contour_nurbs.cls`,
//!    `nx_zlevel_core_spindl.cls`, `nx_face_side_tool_axis_y.cls`), 37 retract. Counts in
//!    `nx_5axis_varcontour_ijk_large.cls`: 186 once, 211 429 times, 42, 31 and 37 428
//!    times each. A 211 group is an **approach** when the group after it is an engage or a
//!    cut (it leads into the material), else a **departure**: so the group is held back
//!    until the next colour (or the end of the path) says which. A feed move under 211 or
//!    186 becomes an engage (before the cut) or a retract (after it) by the same rule. A
//!    `RAPID` under 42 is an approach, under 37 a departure; under 31 or 36 a rapid. A
//!    colour NX does not use by default leaves the moves as `RAPID` says (feed moves cut).
//! 2. **`RAPID`**: the lowering marks the next GOTO rapid.
//! 3. **Feed changes**, in a path without any colour: in a stretch of feed moves between
//!    rapids, the first moves are an engage when their feed is lower than the feed that
//!    follows them, and the last moves a retract when their feed is lower than the feed
//!    before them, provided they also turn away from the cut: the chord of the slower
//!    segment and the cut move next to it are more than [`TURN_DEG`] apart. A slower
//!    segment that goes straight on is the cut at a falling (or rising) feed. Everything
//!    else fed is a cut, as without this rule.
//!
//! Held-back postures are bounded ([`HOLD_LIMIT`] of a colour group, [`FEED_HOLD_LIMIT`]
//! of a feed segment): a group longer than that is decided as it stands (a colour group as
//! a departure, a feed segment as a cut), so lowering stays in constant memory and a
//! stream (`crest convert`) goes on.

use super::{LowerError, Lowerer};
use crate::math::{Point3, Vec3};
use crate::toolpath::{MotionKind, Posture, PostureSink, Toolpath};
use std::collections::VecDeque;

/// At most this many postures of a colour group are held back while their kind is
/// undecided.
pub const HOLD_LIMIT: usize = 4096;
/// At most this many postures of a feed segment are held back (no colours): an engage or
/// a retract is a short lead-in or lead-out, a longer segment is decided a cut at once.
pub const FEED_HOLD_LIMIT: usize = 64;

/// A slower first or last feed segment is an engage or a retract only when it turns by more
/// than this from the cut next to it (degrees).
pub const TURN_DEG: f64 = 10.0;

/// Whether the directions `a` and `b` differ by more than [`TURN_DEG`] (or one is not known).
fn turns(a: Option<Vec3>, b: Option<Vec3>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => {
            let (na, nb) = (a.norm(), b.norm());
            !(na > 1e-12 && nb > 1e-12) || a.dot(&b) < na * nb * TURN_DEG.to_radians().cos()
        }
        _ => true,
    }
}

/// NX's colours (`PAINT/COLOR,n`).
const RAPID: u32 = 186;
const APPROACH_DEPARTURE: u32 = 211;
const ENGAGE: u32 = 42;
const CUT: u32 = 31;
const STEPOVER: u32 = 36;
const RETRACT: u32 = 37;

/// Why postures are held back.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Hold {
    /// Nothing held.
    None,
    /// A 211 (or 186 feed) group: approach/engage or departure/retract by what follows.
    Group,
    /// The first feed segment of a stretch (no colours): engage when a higher feed follows.
    Lead(f64),
    /// A slower feed segment after the cut (no colours): retract when the stretch ends.
    Tail(f64),
}

/// The move-kind state of one tool path.
#[derive(Debug)]
pub(super) struct Kinds {
    colour: Option<u32>,
    coloured: bool,
    held: VecDeque<(Posture, f64)>,
    hold: Hold,
    /// Inside a stretch of feed moves (no colours).
    in_stretch: bool,
    /// Feed of the current segment of the stretch (no colours).
    seg_feed: Option<f64>,
    /// Where the last posture that arrived lies.
    last_pos: Option<Point3>,
    /// Where the tool was before the first held posture.
    hold_from: Option<Point3>,
    /// The direction of the last move into a posture emitted as a cut.
    cut_dir: Option<Vec3>,
}

impl Default for Kinds {
    fn default() -> Self {
        Kinds {
            colour: None,
            coloured: false,
            held: VecDeque::new(),
            hold: Hold::None,
            in_stretch: false,
            seg_feed: None,
            last_pos: None,
            hold_from: None,
            cut_dir: None,
        }
    }
}

/// Where a posture goes.
enum Step {
    Emit(MotionKind),
    Hold(Hold),
}

/// The side of a held group: `true` = before the cut (approach, engage).
fn side(kind: MotionKind, before: bool) -> MotionKind {
    match (kind != MotionKind::Cut, before) {
        (true, true) => MotionKind::Approach,
        (true, false) => MotionKind::Departure,
        (false, true) => MotionKind::Engage,
        (false, false) => MotionKind::Retract,
    }
}

impl Kinds {
    /// Whether postures are held back (the path has postures not yet emitted).
    pub(super) fn holding(&self) -> bool {
        !self.held.is_empty()
    }

    /// The kind of a posture lowered as `raw` (Rapid, Cut, From, Cycle or GoHome) at
    /// `feed`, when nothing is held back and it need not be: its kind now (the state moves
    /// on). `None`: nothing changed; give the posture to [`Self::push`].
    pub(super) fn quick(
        &mut self,
        raw: MotionKind,
        feed: Option<f64>,
        at: Point3,
    ) -> Option<MotionKind> {
        if self.hold != Hold::None {
            return None;
        }
        match self.step(raw, feed) {
            Step::Emit(k) => {
                self.advance(raw, feed);
                self.arrived(k, at);
                Some(k)
            }
            Step::Hold(_) => None,
        }
    }

    /// A posture of kind `kind` at `at` has left (in arrival order).
    fn arrived(&mut self, kind: MotionKind, at: Point3) {
        if kind == MotionKind::Cut {
            self.cut_dir = self.last_pos.map(|p| at - p);
        }
        self.last_pos = Some(at);
    }

    /// The chord of the held postures: from where the tool was before them to the last.
    fn held_chord(&self) -> Option<Vec3> {
        Some(self.held.back()?.0.position - self.hold_from?)
    }

    /// What the state says of a posture when nothing is held.
    fn step(&self, raw: MotionKind, feed: Option<f64>) -> Step {
        if matches!(
            raw,
            MotionKind::From | MotionKind::GoHome | MotionKind::Cycle
        ) {
            return Step::Emit(raw);
        }
        let rapid = raw != MotionKind::Cut;
        if self.coloured {
            return match (self.colour, rapid) {
                (Some(APPROACH_DEPARTURE), _) | (Some(RAPID), false) => Step::Hold(Hold::Group),
                (Some(ENGAGE), true) => Step::Emit(MotionKind::Approach),
                (Some(ENGAGE), false) => Step::Emit(MotionKind::Engage),
                (Some(RETRACT), true) => Step::Emit(MotionKind::Departure),
                (Some(RETRACT), false) => Step::Emit(MotionKind::Retract),
                (_, true) => Step::Emit(MotionKind::Rapid),
                (_, false) => Step::Emit(MotionKind::Cut),
            };
        }
        if rapid {
            return Step::Emit(MotionKind::Rapid);
        }
        match (self.in_stretch, feed, self.seg_feed) {
            (false, Some(f), _) => Step::Hold(Hold::Lead(f)),
            (true, Some(f), Some(g)) if f < g => Step::Hold(Hold::Tail(f)),
            _ => Step::Emit(MotionKind::Cut),
        }
    }

    /// Move the fallback state on past an emitted posture.
    fn advance(&mut self, raw: MotionKind, feed: Option<f64>) {
        if raw == MotionKind::Cut {
            if !self.in_stretch || feed.is_some_and(|f| self.seg_feed.is_none_or(|g| f > g)) {
                self.seg_feed = feed;
            }
            self.in_stretch = true;
        } else {
            self.in_stretch = false;
            self.seg_feed = None;
        }
    }

    /// Give every held posture its kind (`before`: the group leads into the cut; for the
    /// fallback, `lead_engage`/`tail_retract` say whether the segment was one) and emit
    /// them in order.
    fn release(
        &mut self,
        decide: impl Fn(Hold, MotionKind) -> MotionKind,
        out: &mut dyn FnMut(Posture, f64) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        let hold = std::mem::replace(&mut self.hold, Hold::None);
        if let Hold::Lead(f) | Hold::Tail(f) = hold {
            // The segment is over: the stretch goes on at its feed.
            self.in_stretch = true;
            if matches!(hold, Hold::Lead(_)) || self.seg_feed.is_none() {
                self.seg_feed = Some(f);
            }
        }
        self.last_pos = self.hold_from;
        while let Some((mut p, seg)) = self.held.pop_front() {
            p.motion = decide(hold, p.motion);
            self.arrived(p.motion, p.position);
            out(p, seg)?;
        }
        self.hold_from = None;
        Ok(())
    }

    /// Decide what is held as the end of its stretch or group says: a colour group is a
    /// departure (retract), a first feed segment a cut, a slower last one a retract.
    fn release_at_end(
        &mut self,
        out: &mut dyn FnMut(Posture, f64) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        // A slower tail that goes straight on from the cut is the cut at a lower feed.
        let retract = turns(self.cut_dir, self.held_chord());
        self.release(
            |h, raw| match h {
                Hold::Group => side(raw, false),
                Hold::Lead(_) | Hold::None => raw,
                Hold::Tail(_) if retract => MotionKind::Retract,
                Hold::Tail(_) => MotionKind::Cut,
            },
            out,
        )
    }

    /// A finished posture (its motion as lowered: Rapid, Cut, From, Cycle or GoHome) and
    /// the length of the move into it: postures whose kind is known go to `out`, in order.
    pub(super) fn push(
        &mut self,
        p: Posture,
        seg: f64,
        out: &mut dyn FnMut(Posture, f64) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        let (raw, feed) = (p.motion, p.feed_mm_min);
        match self.hold {
            Hold::None => {}
            Hold::Group => {
                if raw == MotionKind::Cut || raw == MotionKind::Rapid {
                    // Still the same colour (no PAINT between): the group goes on.
                    self.held.push_back((p, seg));
                    if self.held.len() >= HOLD_LIMIT {
                        self.release_at_end(out)?;
                    }
                    return Ok(());
                }
                self.release_at_end(out)?;
            }
            Hold::Lead(g) | Hold::Tail(g) => {
                if raw == MotionKind::Cut && feed == Some(g) {
                    self.held.push_back((p, seg));
                    if self.held.len() >= FEED_HOLD_LIMIT {
                        self.release(|_, _| MotionKind::Cut, out)?;
                    }
                    return Ok(());
                }
                if raw == MotionKind::Cut {
                    // The feed changes inside the stretch: a first segment slower than
                    // what follows is an engage; a slower segment followed by more
                    // feed moves was a slower cut.
                    let lead = matches!(self.hold, Hold::Lead(_));
                    let next = self.held.back().map(|(q, _)| p.position - q.position);
                    let engage =
                        lead && feed.is_some_and(|f| f > g) && turns(self.held_chord(), next);
                    self.release(
                        |_, _| {
                            if engage {
                                MotionKind::Engage
                            } else {
                                MotionKind::Cut
                            }
                        },
                        out,
                    )?;
                } else {
                    self.release_at_end(out)?;
                }
            }
        }
        match self.step(raw, feed) {
            Step::Emit(k) => {
                self.advance(raw, feed);
                let mut p = p;
                p.motion = k;
                self.arrived(k, p.position);
                out(p, seg)
            }
            Step::Hold(h) => {
                self.hold = h;
                self.hold_from = self.last_pos;
                self.last_pos = Some(p.position);
                self.held.push_back((p, seg));
                Ok(())
            }
        }
    }

    /// A `PAINT/COLOR,n` record.
    pub(super) fn paint(
        &mut self,
        colour: u32,
        out: &mut dyn FnMut(Posture, f64) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        match self.hold {
            Hold::Group => {
                let before = matches!(colour, ENGAGE | CUT | STEPOVER);
                self.release(|_, raw| side(raw, before), out)?;
            }
            Hold::Lead(_) | Hold::Tail(_) => self.release_at_end(out)?,
            Hold::None => {}
        }
        self.colour = Some(colour);
        self.coloured = true;
        Ok(())
    }

    /// The end of the path: decide and emit everything held; the next path starts afresh.
    pub(super) fn end(
        &mut self,
        out: &mut dyn FnMut(Posture, f64) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        self.release_at_end(out)?;
        *self = Kinds::default();
        Ok(())
    }
}

/// Count an emitted posture (with the length of the move into it) in its path's stats
/// and hand it to the sink.
#[inline(always)]
pub(super) fn record(
    path: &mut Toolpath,
    p: &Posture,
    seg: f64,
    sink: &mut PostureSink<'_>,
) -> std::io::Result<()> {
    let st = &mut path.stats;
    st.postures += 1;
    st.length_mm += seg;
    if p.motion == MotionKind::Cut {
        st.cutting_length_mm += seg;
    }
    if p.motion.is_feed() {
        st.feed_length_mm += seg;
    }
    st.moves.add(p.motion);
    sink(path, p)
}

/// What the move kinds do next: take a posture, a colour, or the end of the path. (Built
/// and taken apart at once, never stored: the size of a posture is no cost.)
#[allow(clippy::large_enum_variant)]
enum Event {
    Posture(Posture, f64),
    Colour(u32),
    End,
}

impl Lowerer {
    /// Whether the open path has postures (emitted, or held back for their kind).
    pub(super) fn moved(&self) -> bool {
        self.path.as_ref().is_some_and(|p| p.stats.postures > 0) || self.kinds.holding()
    }

    /// Hand an event to the move kinds; the postures they pass on (with their kinds) are
    /// counted, given to the sink and kept when the options say so.
    fn kinds_event(&mut self, ev: Event, sink: &mut PostureSink<'_>) -> Result<(), LowerError> {
        let keep = self.opts.keep_postures;
        let path = self.path.get_or_insert_with(Toolpath::default);
        let mut out = |p: Posture, seg: f64| -> std::io::Result<()> {
            record(path, &p, seg, sink)?;
            if keep {
                path.postures.push(p);
            }
            Ok(())
        };
        match ev {
            Event::Posture(p, seg) => self.kinds.push(p, seg, &mut out)?,
            Event::Colour(c) => self.kinds.paint(c, &mut out)?,
            Event::End => self.kinds.end(&mut out)?,
        }
        Ok(())
    }

    /// Hand a finished posture (its motion as lowered) to the move kinds, which pass it on
    /// with its kind, now or once the records after it tell.
    pub(super) fn emit(
        &mut self,
        p: Posture,
        seg: f64,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        self.kinds_event(Event::Posture(p, seg), sink)
    }

    /// A `PAINT/COLOR,n` record: NX's colour of the moves that follow.
    pub(super) fn paint(
        &mut self,
        colour: u32,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        self.kinds_event(Event::Colour(colour), sink)
    }

    /// Decide and emit the postures held back for their kind (end of a path).
    pub(super) fn end_kinds(&mut self, sink: &mut PostureSink<'_>) -> Result<(), LowerError> {
        if self.path.is_none() {
            self.kinds = Kinds::default();
            return Ok(());
        }
        self.kinds_event(Event::End, sink)
    }

    /// Emit the postures held back for their kind, decided as the end of the path would
    /// decide them (for a reading that stops at an error part way).
    pub fn release_held(&mut self, sink: &mut PostureSink<'_>) -> Result<(), LowerError> {
        self.end_kinds(sink)
    }
}

#[cfg(test)]
mod tests {
    use crate::parse::clsf::parse_str;
    use crate::toolpath::{LowerOptions, MotionKind, lower_records};

    fn kinds(text: &str) -> Vec<MotionKind> {
        let recs = parse_str(text).unwrap_or_else(|e| panic!("{e}"));
        let p = lower_records(&recs, LowerOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        p.paths[0].postures.iter().map(|q| q.motion).collect()
    }

    #[test]
    fn colours_give_the_kinds_and_211_is_decided_by_what_follows() {
        use MotionKind::*;
        let k = kinds(
            "TOOL PATH/A,TOOL,T\nPAINT/COLOR,186\nRAPID\nGOTO/0,0,50\nPAINT/COLOR,211\nRAPID\nGOTO/0,0,5\n\
             PAINT/COLOR,42\nFEDRAT/MMPM,100\nGOTO/0,0,0\nPAINT/COLOR,31\nGOTO/5,0,0\nPAINT/COLOR,36\nGOTO/5,1,0\n\
             PAINT/COLOR,37\nGOTO/5,1,5\nRAPID\nGOTO/5,1,9\nPAINT/COLOR,211\nRAPID\nGOTO/5,1,50\n\
             PAINT/COLOR,186\nRAPID\nGOTO/0,0,50\nEND-OF-PATH\n",
        );
        assert_eq!(
            k,
            [
                Rapid, Approach, Engage, Cut, Cut, Retract, Departure, Departure, Rapid
            ]
        );
    }

    #[test]
    fn without_colours_slower_ends_of_a_stretch_are_engage_and_retract() {
        use MotionKind::*;
        let k = kinds(
            "TOOL PATH/A,TOOL,T\nRAPID\nGOTO/0,0,5\nFEDRAT/MMPM,100\nGOTO/0,0,1\nGOTO/0,0,0\nFEDRAT/MMPM,900\n\
             GOTO/5,0,0\nFEDRAT/MMPM,400\nGOTO/6,0,0\nFEDRAT/MMPM,900\nGOTO/9,0,0\nFEDRAT/MMPM,100\nGOTO/9,0,3\n\
             RAPID\nGOTO/9,0,9\nGOTO/20,0,0\nEND-OF-PATH\n",
        );
        // 400 between two 900 stretches is a slower cut; the lone feed after the last
        // rapid has nothing to compare with: a cut.
        assert_eq!(
            k,
            [Rapid, Engage, Engage, Cut, Cut, Cut, Retract, Rapid, Cut]
        );
    }

    #[test]
    fn a_slower_end_that_goes_straight_on_is_the_cut() {
        use MotionKind::*;
        // The feed ramps down along the pass (as 001 Fig 6's path does) and up into the
        // next: the slower last and first segments go straight on, so they cut. A slower
        // segment that turns (down into the part, up out of it) is still an engage or a
        // retract.
        let k = kinds(
            "TOOL PATH/A,TOOL,T\nRAPID\nGOTO/0,0,0\nFEDRAT/MMPM,900\nGOTO/5,0,0\nFEDRAT/MMPM,800\nGOTO/6,0,0\n\
             FEDRAT/MMPM,500\nGOTO/7,0,0\nRAPID\nGOTO/7,0,5\nRAPID\nGOTO/0,1,0\nFEDRAT/MMPM,500\nGOTO/1,1,0\n\
             FEDRAT/MMPM,900\nGOTO/6,1,0\nFEDRAT/MMPM,300\nGOTO/6.5,1,0.5\nRAPID\nGOTO/6.5,1,5\nEND-OF-PATH\n",
        );
        assert_eq!(
            k,
            [Rapid, Cut, Cut, Cut, Rapid, Rapid, Cut, Cut, Retract, Rapid]
        );
        assert!(super::turns(
            Some(crate::math::Vec3::x()),
            Some(crate::math::Vec3::new(1.0, 0.2, 0.0))
        ));
        assert!(!super::turns(
            Some(crate::math::Vec3::x()),
            Some(crate::math::Vec3::new(1.0, 0.1, 0.0))
        ));
    }
}
