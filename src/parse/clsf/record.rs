//! The CLSF records: what one logical record says (syntax only) and where it starts.

use crate::parse::number::Form;
use std::fmt;

/// At most this many numbers in one fixed-size record (a GOTO with contact data).
pub const MAX_NUMBERS: usize = 12;

/// A short list of numbers stored inline (no allocation): GOTO, FROM, GOHOME, CONTACT,
/// CIRCLE and CNTRL arguments.
#[derive(Clone, Copy, PartialEq)]
pub struct Numbers {
    pub(super) values: [f64; MAX_NUMBERS],
    pub(super) len: u8,
}

impl Numbers {
    /// Copy up to [`MAX_NUMBERS`] values; `None` when there are more.
    pub fn from_slice(values: &[f64]) -> Option<Numbers> {
        if values.len() > MAX_NUMBERS {
            return None;
        }
        let mut n = Numbers {
            values: [0.0; MAX_NUMBERS],
            len: values.len() as u8,
        };
        n.values[..values.len()].copy_from_slice(values);
        Some(n)
    }

    /// The values.
    pub fn as_slice(&self) -> &[f64] {
        &self.values[..self.len as usize]
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// True when there are no values.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Three values starting at `k` (caller checks the length).
    pub fn triple(&self, k: usize) -> [f64; 3] {
        [self.values[k], self.values[k + 1], self.values[k + 2]]
    }
}

impl fmt::Debug for Numbers {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

/// Bytes of a GOTO's numbers that a [`Written`] keeps: twelve short numbers (at most 16
/// bytes each) and their commas fit.
pub const WRITTEN_ROOM: usize = 224;

/// A `GOTO` line's numbers as written: the text after `GOTO/` up to the line end, each
/// number's [`Form`] and value, and the line. A writer that would print a posture made of
/// exactly these values the same way copies the text instead of printing the numbers
/// (`crest convert` to contact12; see [`crate::toolpath::Contact12Writer`]).
#[derive(Clone, Copy)]
pub struct Written {
    /// The line (1-based); 0 when nothing is kept (the text did not fit).
    pub line: u32,
    /// The values, as read.
    pub numbers: Numbers,
    /// How each number is written: the [`Form::bits`] of number `k` in bits `4k..4k + 4`
    /// (see [`Written::form`]), zeros above the last.
    pub forms: u64,
    text: [u8; WRITTEN_ROOM],
    len: u8,
}

impl Default for Written {
    fn default() -> Self {
        Written {
            line: 0,
            numbers: Numbers {
                values: [0.0; MAX_NUMBERS],
                len: 0,
            },
            forms: 0,
            text: [0; WRITTEN_ROOM],
            len: 0,
        }
    }
}

impl Written {
    /// Keep `text` (the numbers of `line`, read as `numbers` with `forms`); nothing is kept
    /// (`line` 0) when it is longer than [`WRITTEN_ROOM`].
    pub(super) fn keep(&mut self, text: &[u8], line: u32, numbers: Numbers) {
        match self.text.get_mut(..text.len()) {
            Some(t) => {
                t.copy_from_slice(text);
                self.len = text.len() as u8;
                self.line = line;
                self.numbers = numbers;
            }
            None => self.line = 0,
        }
    }

    /// How number `k` is written.
    pub fn form(&self, k: usize) -> Form {
        if k < self.numbers.len() {
            Form::from_bits((self.forms >> (4 * k)) as u8)
        } else {
            Form::OTHER
        }
    }

    /// The numbers as written: bare commas between them, no line end.
    pub fn text(&self) -> &[u8] {
        &self.text[..usize::from(self.len)]
    }
}

impl fmt::Debug for Written {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Written")
            .field("line", &self.line)
            .field("text", &String::from_utf8_lossy(self.text()))
            .finish()
    }
}

/// A generic argument: a number or a word/name as written.
#[derive(Debug, Clone, PartialEq)]
pub enum Arg {
    /// A number.
    Num(f64),
    /// Anything else, trimmed (words are kept as written; compare case-insensitively).
    Word(String),
}

impl Arg {
    /// True when this is a word equal to `w` ignoring ASCII case.
    pub fn is_word(&self, w: &str) -> bool {
        matches!(self, Arg::Word(s) if s.eq_ignore_ascii_case(w))
    }
}

/// Feed-rate unit word of `FEDRAT`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FeedUnit {
    /// mm per minute.
    Mmpm,
    /// inch per minute.
    Ipm,
    /// mm per revolution.
    Mmpr,
    /// inch per revolution.
    Ipr,
    /// per minute in the file's length unit.
    Permin,
    /// per revolution in the file's length unit.
    Perrev,
}

impl FeedUnit {
    pub(super) fn from_word(w: &str) -> Option<FeedUnit> {
        Some(match w.to_ascii_uppercase().as_str() {
            "MMPM" => FeedUnit::Mmpm,
            "IPM" => FeedUnit::Ipm,
            "MMPR" => FeedUnit::Mmpr,
            "IPR" => FeedUnit::Ipr,
            "PERMIN" => FeedUnit::Permin,
            "PERREV" => FeedUnit::Perrev,
            _ => return None,
        })
    }

    /// The word as written in CLSF.
    pub fn word(self) -> &'static str {
        match self {
            FeedUnit::Mmpm => "MMPM",
            FeedUnit::Ipm => "IPM",
            FeedUnit::Mmpr => "MMPR",
            FeedUnit::Ipr => "IPR",
            FeedUnit::Permin => "PERMIN",
            FeedUnit::Perrev => "PERREV",
        }
    }
}

/// Length unit of `UNITS`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthUnit {
    /// Millimetres.
    Mm,
    /// Inches (`INCH` or `INCHES`).
    Inch,
}

/// One logical CLSF record (syntax only).
#[derive(Debug, Clone, PartialEq)]
pub enum RecordKind {
    /// `TOOL PATH/<op>,TOOL,<tool>[,…]`.
    ToolPath {
        /// Operation name.
        name: String,
        /// Tool name (empty when the record has no `TOOL,<name>` part).
        tool: String,
    },
    /// `TLDATA/<kind>[,<subtype word>],args…`.
    Tldata {
        /// Tool kind word, upper case (`MILL`, `DRILL`, `TURN`, …).
        kind: String,
        /// Word after the kind (`TLDATA/DRILL,MILL,…`), upper case.
        subtype: Option<String>,
        /// The remaining arguments.
        args: Vec<Arg>,
    },
    /// `MSYS/ox,oy,oz,xi,xj,xk,yi,yj,yk`.
    Msys([f64; 9]),
    /// A whole-line `$$` comment (text after `$$`, trimmed).
    Comment(String),
    /// Contact data for the GOTO before it: `CONTACT/x,y,z[,nx,ny,nz]` or the same after
    /// `$$ ` (3 or 6 numbers).
    Contact(Numbers),
    /// `PAINT/<word>,args…`.
    Paint(Vec<Arg>),
    /// `FEDRAT/[unit,]value` (also `FEDRAT/value,unit`).
    Fedrat {
        /// Unit word, if written.
        unit: Option<FeedUnit>,
        /// Feed value as written.
        value: f64,
    },
    /// `RAPID`: the next GOTO only is a rapid move.
    Rapid,
    /// `GOTO/x,y,z[,i,j,k[,cx,cy,cz[,nx,ny,nz]]]` (3, 6, 9 or 12 numbers).
    Goto(Numbers),
    /// `FROM/x,y,z[,i,j,k]`.
    From(Numbers),
    /// `GOHOME/x,y,z[,i,j,k]`.
    GoHome(Numbers),
    /// `CIRCLE/xc,yc,zc,ai,aj,ak,r[,tol,intol,toolD,toolR][,TIMES,n]` (7 to 11 numbers).
    Circle {
        /// The numbers as written.
        numbers: Numbers,
        /// `TIMES,n`, if written.
        times: Option<u32>,
    },
    /// `NURBS/` (arguments, if any, are ignored).
    Nurbs,
    /// `KNOT/k1,…`.
    Knot(Vec<f64>),
    /// `CNTRL/x,y,z`.
    Cntrl([f64; 3]),
    /// `LOAD/TOOL,n[,…]` or `LOADTL/n[,…]`.
    LoadTool {
        /// Tool number.
        number: f64,
        /// Further arguments (`ADJUST,n`, …).
        args: Vec<Arg>,
    },
    /// `SELECT/TOOL,n[,…]`.
    SelectTool {
        /// Tool number.
        number: f64,
    },
    /// `SPINDL/…`: arguments as written.
    Spindl(Vec<Arg>),
    /// `CUTCOM/LEFT|RIGHT|ON|OFF[,…]`.
    Cutcom(Vec<Arg>),
    /// `CYCLE/<kind>[,…]` or `CYCLE/OFF`.
    Cycle(Vec<Arg>),
    /// `UNITS/MM|INCH|INCHES`.
    Units(LengthUnit),
    /// `END-OF-PATH`.
    EndOfPath,
    /// `PPRINT/text` or `TPRINT/text` (also without the slash): a comment kept as written.
    Print {
        /// `PPRINT` or `TPRINT`.
        word: String,
        /// The text after the slash (or the blank), trimmed.
        text: String,
    },
    /// `PARTNO text` (or `PARTNO/text`): the part or program name.
    Partno(String),
    /// `MULTAX`, `MULTAX/ON` (true) or `MULTAX/OFF` (false).
    Multax(bool),
    /// `CUTTER/d[,r[,e,f,a,b[,h]]]`: 1 to 7 numbers as written (APT cutter parameters).
    Cutter(Numbers),
    /// `TLAXIS/i,j,k`: the tool axis of the following moves.
    Tlaxis([f64; 3]),
    /// `INDIRV/i,j,k`: the initial direction of the next move (no effect on postures).
    Indirv([f64; 3]),
    /// `SET/MODE,ABSOL` (true) or `SET/MODE,INCR` (false).
    SetMode {
        /// Absolute (true) or incremental (false) GOTO coordinates.
        absolute: bool,
    },
    /// `FINI`: the end of the file.
    Fini,
    /// `END`: the end of a program section (no effect on postures).
    End,
    /// Any other record, kept raw.
    Unknown {
        /// Major word, upper case.
        word: String,
        /// The whole logical record text.
        text: String,
    },
}

/// A record with the position of its first character.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// What the record says.
    pub kind: RecordKind,
    /// 1-based line of the record's first character.
    pub line: u32,
    /// 1-based column of the record's first character.
    pub column: u32,
}
