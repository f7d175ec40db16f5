//! Syntax of NX CLSF (and the wider APT family), of the 12-column contact file (contact12)
//! and of ISO G-code: grammars that turn text into records or blocks with spans (line,
//! column). No geometry, no units.
//!
//! The accepted grammars are written in `grammars/clsf.ebnf`, `grammars/contact12.ebnf`
//! and `grammars/gcode.ebnf`.
//! Both readers stream: they hold one line at a time, so any file size reads in constant
//! memory. A syntax error is a [`Located`]: the [`Span`] (1-based line and column), what was
//! expected, what was found and the offending line.
//!
//! ```
//! use crest::parse::clsf::{parse_str, RecordKind};
//! let records = parse_str("TOOL PATH/OP,TOOL,BALL\nRAPID\nGOTO/1,2,3\nEND-OF-PATH\n").unwrap();
//! assert_eq!(records.len(), 4);
//! assert!(matches!(records[2].kind, RecordKind::Goto(ref n) if n.as_slice() == [1.0, 2.0, 3.0]));
//! assert_eq!((records[2].line, records[2].column), (3, 1));
//! ```

pub mod clsf;
pub mod contact12;
pub mod error;
pub mod gcode;
pub mod number;
pub mod position;

pub use clsf::{Arg, ClsfReader, FeedUnit, LengthUnit, Numbers, Record, RecordKind, Written};
pub use contact12::{Contact12Reader, Contact12Row, looks_like_contact12};
pub use error::ParseError;
pub use gcode::{Block, GcodeReader, looks_like_gcode};
pub use position::{Located, Problem, Span, line_column};
