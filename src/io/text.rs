//! Reading a whole text file (configs, tables): UTF-8 checked with the line and column of the
//! first invalid byte, a leading byte-order mark dropped, errors naming the file.

use crate::parse::Span;
use std::path::Path;

/// Why a text file could not be read.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
pub enum TextError {
    /// The file could not be read within its budget.
    #[error(transparent)]
    Input(Box<super::input::InputError>),
    /// The file is not UTF-8 text.
    #[error(
        "{file}:{}:{}: the {what} is not UTF-8 text (invalid byte 0x{byte:02X})",
        at.line,
        at.column
    )]
    Encoding {
        /// File name as given.
        file: String,
        /// What the file is.
        what: String,
        /// The first invalid byte.
        at: Span,
        /// The byte.
        byte: u8,
    },
}

/// Read `path` (`-`: standard input) as UTF-8 text within `budget`
/// ([`super::input::read_staged`]: refused past it, or for a NUL byte in its first 64 KiB);
/// `what` names the kind of file in errors. A UTF-8 byte-order mark at the start is dropped.
pub fn read_text(
    path: &Path,
    what: &str,
    budget: super::input::Budget,
) -> Result<String, TextError> {
    let file = path.display().to_string();
    let bytes =
        super::input::read_staged(path, what, |head| super::input::text_stage(head, budget))
            .map_err(|e| TextError::Input(Box::new(e)))?;
    decode(bytes, &file, what)
}

/// Decode `bytes` read from `file` (see [`read_text`]).
pub fn decode(bytes: Vec<u8>, file: &str, what: &str) -> Result<String, TextError> {
    let mut text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let bytes = e.into_bytes();
        let before = String::from_utf8_lossy(&bytes[..at]);
        TextError::Encoding {
            file: file.to_string(),
            what: what.to_string(),
            at: Span::of(&before, at..at + 1),
            byte: bytes[at],
        }
    })?;
    if text.starts_with('\u{feff}') {
        text.drain(..'\u{feff}'.len_utf8());
    }
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_utf8_names_line_and_column() {
        let e = decode(b"rpm = 1\nfz = \xff\n".to_vec(), "p.toml", "process file").unwrap_err();
        let m = e.to_string();
        assert!(
            m.starts_with("p.toml:2:6: the process file is not UTF-8"),
            "{m}"
        );
    }

    #[test]
    fn a_byte_order_mark_is_dropped() {
        let t = decode(b"\xef\xbb\xbfrpm = 1\n".to_vec(), "p.toml", "process file").unwrap();
        assert_eq!(t, "rpm = 1\n");
    }
}
