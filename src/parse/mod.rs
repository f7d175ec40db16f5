//! Syntax of NX CLSF and of the 12-column contact file (contact12): nom grammars that
//! turn text into records with spans (line, column). No geometry, no units.
//!
//! The accepted grammars are written in `grammars/clsf.ebnf` and `grammars/contact12.ebnf`.
