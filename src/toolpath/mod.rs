//! The tool-path model: what the machine is asked to do, in mm and radians.
//!
//! Lowering (from `parse` records) resolves the modal state of CLSF (feed, spindle, tool,
//! one-shot RAPID, tool axis carried over), converts inches to mm, keeps or applies MSYS,
//! and turns arcs and NURBS into postures. Everything after this stage sees only
//! [`Program`], [`Toolpath`] and [`Posture`].
//!
//! Lowering is incremental ([`Lowerer`]): each parse record goes in, finished postures
//! come out through a callback, so conversion streams; [`lower_records`] collects a whole
//! [`Program`]. The writers ([`write_clsf`], [`write_contact12`], and their streaming forms
//! [`ClsfWriter`], [`Contact12Writer`]) print fixed-point numbers that read back to the
//! same digits.
//!
//! ```
//! use crest::parse::clsf::parse_str;
//! use crest::toolpath::{lower_records, LowerOptions, MotionKind};
//! let text = "TOOL PATH/OP,TOOL,BALL\nTLDATA/MILL,10,5,75,0,0\nRAPID\nGOTO/0,0,10\n\
//!             FEDRAT/MMPM,500\nGOTO/0,0,0,0,0,1,3.5355,0,1.4645\nGOTO/4,3,0\nEND-OF-PATH\n";
//! let program = lower_records(&parse_str(text).unwrap(), LowerOptions::default()).unwrap();
//! let path = &program.paths[0];
//! assert_eq!(path.postures[0].motion, MotionKind::Rapid);
//! assert_eq!(path.postures[2].feed_mm_min, Some(500.0));
//! // The 9-number GOTO has a CC point; its normal points to the ball centre (0, 0, 5).
//! let contact = path.postures[1].contact.as_ref().unwrap();
//! assert!(contact.normal_derived && (contact.normal.z - 0.7071).abs() < 1e-4);
//! assert_eq!((path.stats.length_mm, path.stats.cutting_length_mm), (15.0, 15.0));
//! ```

use crate::math::{Point3, Vec3};

pub mod geom;
pub mod lower;
pub mod moves;
pub mod regions;
pub mod write;

pub use geom::Spline;
pub use lower::{
    CONTRADICTORY_UNITS, LowerError, LowerOptions, Lowerer, PostureSink, derive_normal,
    lower_records,
};
pub use moves::{MoveCounts, Moves};
pub use write::{ClsfWriter, Contact12Writer};

/// A whole file: one or more tool paths and the warnings met while reading it.
#[derive(Debug, Clone, Default)]
pub struct Program {
    /// Tool paths in file order (`TOOL PATH/ … END-OF-PATH` blocks; a contact12 file gives one).
    pub paths: Vec<Toolpath>,
    /// Non-fatal findings (unknown records, derived normals, …), in file order.
    pub warnings: Vec<Warning>,
}

/// A non-fatal finding, with the place in the source file it refers to.
#[derive(Debug, Clone, PartialEq)]
pub struct Warning {
    /// Where: line and column (line 0 when not tied to a line, column 0 when not tied to a
    /// column).
    pub at: crate::parse::Span,
    /// What was found, lower case.
    pub message: String,
}

/// Milling tool data from `TLDATA/MILL` (lengths in mm, angles in radians).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ToolData {
    /// Tool kind word (`MILL`, `DRILL`, …).
    pub kind: String,
    /// Tool diameter, mm.
    pub diameter_mm: f64,
    /// Lower (corner) radius, mm: equal to the radius for a ball end.
    pub corner_radius_mm: f64,
    /// Tool length, mm.
    pub length_mm: f64,
    /// Taper angle, rad.
    pub taper_rad: f64,
    /// Tip angle, rad.
    pub tip_rad: f64,
    /// The seven APT cutter parameters of `CUTTER/d,r,e,f,a,b,h`, when the file gives all
    /// seven: diameter d, corner radius r, the corner centre's distance e from the axis and
    /// f above the tip, the end angle a and the side angle b (rad), the height h (lengths
    /// mm). Diameter, corner radius, length, tip and taper angles above are filled from it.
    /// NX's seven-value `TLDATA/MILL,D,R1,L,B,A,X1,Y1` fills it as `[D, R1, X1, Y1, A, B, L]`.
    pub apt: Option<[f64; 7]>,
}

impl ToolData {
    /// The APT parameters when they describe more than a ball, bull nose or flat end as
    /// `CUTTER/d,r` writes them (no angles, the corner centre at (d/2 − r, r) or left at
    /// zero): a cone, a taper, an offset corner.
    pub fn apt_profile(&self) -> Option<[f64; 7]> {
        let p = self.apt?;
        let [d, r, e, f, a, b, _] = p;
        let tol = 1e-6 * d.max(1.0);
        let standard = (e - (0.5 * d - r)).abs() <= tol && (f - r).abs() <= tol;
        let lazy = e == 0.0 && f == 0.0;
        (!(a == 0.0 && b == 0.0 && (standard || lazy))).then_some(p)
    }
}

/// How the tool reached a posture: the move kind.
///
/// Lowering gives every move one kind (see [`lower`]'s `kinds` module for the sources: NX's
/// `PAINT/COLOR`, `RAPID`, feed changes). Rapid, approach and departure moves are rapids;
/// engage, cut and retract moves are feed moves; only cut moves define the reference surface
/// and are simulated by default ([`Moves`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MotionKind {
    /// `FROM` start point (no move into it).
    From,
    /// A rapid move (GOTO after `RAPID`) that is not part of an approach or departure.
    Rapid,
    /// A rapid towards the material before an engage or cut (NX colour 211 before the cut).
    Approach,
    /// A feed move into the material before the cut (NX colour 42, or a slower feed right
    /// before the cutting feed).
    Engage,
    /// A cutting move (NX colours 31 and 36, or any feed move nothing marks otherwise).
    Cut,
    /// A feed move out of the material after the cut (NX colour 37, or a slower feed right
    /// after the cutting feed).
    Retract,
    /// A rapid away from the material after the cut (NX colour 211 after the cut).
    Departure,
    /// A hole position inside `CYCLE/… CYCLE/OFF`.
    Cycle,
    /// `GOHOME` return point.
    GoHome,
}

impl MotionKind {
    /// The six move kinds `inspect` counts, in path order.
    pub const MOVES: [MotionKind; 6] = [
        MotionKind::Rapid,
        MotionKind::Approach,
        MotionKind::Engage,
        MotionKind::Cut,
        MotionKind::Retract,
        MotionKind::Departure,
    ];

    /// A move at the programmed feed (engage, cut, retract).
    pub fn is_feed(self) -> bool {
        matches!(
            self,
            MotionKind::Engage | MotionKind::Cut | MotionKind::Retract
        )
    }

    /// A rapid move (rapid, approach, departure).
    pub fn is_rapid(self) -> bool {
        matches!(
            self,
            MotionKind::Rapid | MotionKind::Approach | MotionKind::Departure
        )
    }

    /// The name at the interface (`rapid`, `approach`, `engage`, `cut`, `retract`,
    /// `departure`, `from`, `cycle`, `gohome`).
    pub fn name(self) -> &'static str {
        match self {
            MotionKind::From => "from",
            MotionKind::Rapid => "rapid",
            MotionKind::Approach => "approach",
            MotionKind::Engage => "engage",
            MotionKind::Cut => "cut",
            MotionKind::Retract => "retract",
            MotionKind::Departure => "departure",
            MotionKind::Cycle => "cycle",
            MotionKind::GoHome => "gohome",
        }
    }

    /// NX's default display colour of the kind (`PAINT/COLOR,n`), as the writers print it.
    pub fn nx_colour(self) -> Option<u32> {
        match self {
            MotionKind::From | MotionKind::Rapid | MotionKind::GoHome => Some(186),
            MotionKind::Approach | MotionKind::Departure => Some(211),
            MotionKind::Engage => Some(42),
            MotionKind::Cut => Some(31),
            MotionKind::Retract => Some(37),
            MotionKind::Cycle => None,
        }
    }
}

/// The arc that leads into a posture (`CIRCLE` followed by `GOTO`).
#[derive(Debug, Clone, PartialEq)]
pub struct ArcMove {
    /// Arc centre, mm.
    pub centre: Point3,
    /// Unit axis. The motion is **clockwise about this axis** (NX convention, clsf.md §2).
    pub axis: Vec3,
    /// Radius, mm.
    pub radius_mm: f64,
    /// Full turns added (`TIMES,n` gives n − 1 extra turns).
    pub extra_turns: u32,
}

/// Contact data attached to a posture: the cutter-contact point and surface normal.
#[derive(Debug, Clone, PartialEq)]
pub struct Contact {
    /// CC point, mm.
    pub point: Point3,
    /// Unit surface normal at the CC point, out of the material.
    pub normal: Vec3,
    /// True when the normal was derived from the cutter rather than read from the file.
    pub normal_derived: bool,
}

/// One posture of the tool at the end of a move.
#[derive(Debug, Clone, PartialEq)]
pub struct Posture {
    /// CL point (tool tip), mm.
    pub position: Point3,
    /// Unit tool axis, from the tip towards the spindle.
    pub axis: Vec3,
    /// How the tool got here.
    pub motion: MotionKind,
    /// The arc leading here, if the move was circular.
    pub arc: Option<ArcMove>,
    /// Contact data, when the file has it.
    pub contact: Option<Contact>,
    /// Modal programmed feed at this move, mm/min (None before any FEDRAT).
    pub feed_mm_min: Option<f64>,
    /// Modal spindle speed, rpm (None before any SPINDL).
    pub spindle_rpm: Option<f64>,
    /// 1-based source line of the record that produced this posture.
    pub line: u32,
}

/// One tool path (one NX operation).
#[derive(Debug, Clone, Default)]
pub struct Toolpath {
    /// Operation name from `TOOL PATH/<op>`.
    pub name: String,
    /// Tool name from `TOOL PATH/…,TOOL,<name>`.
    pub tool_name: String,
    /// Tool data from the last `TLDATA`, if any.
    pub tool: Option<ToolData>,
    /// MSYS frame: origin, X axis, Y axis (as written), if any.
    pub msys: Option<[f64; 9]>,
    /// Postures in order (empty when lowered with `keep_postures: false`).
    pub postures: Vec<Posture>,
    /// True when MSYS has been applied: positions are in the absolute frame.
    pub msys_applied: bool,
    /// Record counts, lengths and modal values seen while lowering.
    pub stats: PathStats,
    /// Unknown records kept raw (at most 1000 per path).
    pub raw_records: Vec<RawRecord>,
    /// `PPRINT`/`TPRINT` texts, kept as comments (at most 1000 per path).
    pub prints: Vec<RawRecord>,
}

/// What lowering counted in one tool path.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PathStats {
    /// `GOTO` records (contact12: data lines).
    pub gotos: usize,
    /// `RAPID` records.
    pub rapids: usize,
    /// `CIRCLE` records.
    pub circles: usize,
    /// `NURBS` blocks.
    pub nurbs: usize,
    /// Postures produced (NURBS blocks give several).
    pub postures: usize,
    /// Length of all moves, mm (arcs and splines along the curve; not into FROM).
    pub length_mm: f64,
    /// Length of cutting moves (`MotionKind::Cut`), mm.
    pub cutting_length_mm: f64,
    /// Length of all feed moves (engage, cut, retract), mm: the cutting length of
    /// `--moves all`.
    pub feed_length_mm: f64,
    /// Postures of each move kind, and the groups of consecutive postures of one kind.
    pub moves: MoveCounts,
    /// Distinct programmed feeds, mm/min, in order of appearance (at most 64).
    pub feeds_mm_min: Vec<f64>,
    /// Distinct spindle speeds, rpm, in order of appearance (at most 64).
    pub spindles_rpm: Vec<f64>,
}

/// An unknown record kept as written.
#[derive(Debug, Clone, PartialEq)]
pub struct RawRecord {
    /// 1-based line.
    pub line: u32,
    /// The logical record text.
    pub text: String,
}

impl Toolpath {
    /// Maximal runs of consecutive cutting moves, as index ranges into `postures`.
    ///
    /// A run starts at the posture the first cutting move leaves from and ends at the
    /// last posture reached by cutting, so `range.len() >= 2` and every posture after the
    /// first in a range has `motion == MotionKind::Cut`.
    pub fn cutting_runs(&self) -> Vec<std::ops::Range<usize>> {
        let mut runs = Vec::new();
        let mut start: Option<usize> = None;
        for (i, p) in self.postures.iter().enumerate() {
            let cut = p.motion == MotionKind::Cut && i > 0;
            match (cut, start) {
                (true, None) => start = Some(i - 1),
                (false, Some(s)) => {
                    runs.push(s..i);
                    start = None;
                }
                _ => {}
            }
        }
        if let Some(s) = start {
            runs.push(s..self.postures.len());
        }
        runs
    }
}

/// Write a program as NX-style CLSF with contact data (GOTO with 12 numbers: CL, axis, CC,
/// normal, where the posture has contact data; 9 numbers when the normal was derived).
pub fn write_clsf(program: &Program, out: &mut dyn std::io::Write) -> std::io::Result<()> {
    let mut w = ClsfWriter::new();
    for path in &program.paths {
        w.begin_path(path, out)?;
        for p in &path.postures {
            w.posture(p, out)?;
        }
        w.end_path(out)?;
    }
    Ok(())
}

/// Write one tool path as contact12 CSV with header `x,y,z,i,j,k,cx,cy,cz,nx,ny,nz`:
/// cutting moves with contact data only, or every posture when `all_moves` (CC and normal
/// empty where there is no contact).
pub fn write_contact12(
    path: &Toolpath,
    all_moves: bool,
    out: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    let mut w = Contact12Writer::new(all_moves);
    w.header(out)?;
    for p in &path.postures {
        w.posture(p, out)?;
    }
    w.flush(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn posture(motion: MotionKind) -> Posture {
        Posture {
            position: Point3::origin(),
            axis: Vec3::z(),
            motion,
            arc: None,
            contact: None,
            feed_mm_min: None,
            spindle_rpm: None,
            line: 0,
        }
    }

    #[test]
    fn cutting_runs_split_at_rapids() {
        use MotionKind::*;
        let kinds = [From, Rapid, Cut, Cut, Rapid, Cut, GoHome];
        let path = Toolpath {
            postures: kinds.iter().map(|k| posture(*k)).collect(),
            ..Default::default()
        };
        assert_eq!(path.cutting_runs(), vec![1..4, 4..6]);
    }
}
