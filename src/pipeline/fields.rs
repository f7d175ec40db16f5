//! How library messages name what the user gave: a request field written `‹name›` (its
//! snake-case name, e.g. `‹grid_um›`), never a command-line option, so that each front end
//! shows its own spelling: the command line `--grid-um` ([`for_cli`]), Python the keyword
//! `grid_um` ([`for_python`]). Every error, warning and check message of the library uses
//! this form; the architecture test refuses a `--option` in a library string.

use std::borrow::Cow;

/// Opening and closing marks of a field name.
const OPEN: char = '‹';
const CLOSE: char = '›';

/// `message` with each `‹name›` written by `spell` (the name as given, snake case).
fn render<'a>(message: &'a str, spell: impl Fn(&str, &mut String)) -> Cow<'a, str> {
    if !message.contains(OPEN) {
        return Cow::Borrowed(message);
    }
    let mut out = String::with_capacity(message.len() + 8);
    let mut rest = message;
    while let Some(i) = rest.find(OPEN) {
        out.push_str(&rest[..i]);
        let after = &rest[i + OPEN.len_utf8()..];
        match after.find(CLOSE) {
            Some(j) if is_name(&after[..j]) => {
                spell(&after[..j], &mut out);
                rest = &after[j + CLOSE.len_utf8()..];
            }
            _ => {
                out.push(OPEN);
                rest = after;
            }
        }
    }
    out.push_str(rest);
    Cow::Owned(out)
}

/// A field name: lower-case letters, digits and underscores, starting with a letter.
fn is_name(s: &str) -> bool {
    s.starts_with(|c: char| c.is_ascii_lowercase())
        && s.chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

/// The message as the command line shows it: `‹grid_um›` → `--grid-um`.
pub fn for_cli(message: &str) -> Cow<'_, str> {
    render(message, |name, out| {
        out.push_str("--");
        out.extend(name.chars().map(|c| if c == '_' { '-' } else { c }));
    })
}

/// The message as Python shows it: `‹grid_um›` → `grid_um` (the keyword).
pub fn for_python(message: &str) -> Cow<'_, str> {
    render(message, |name, out| out.push_str(name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_take_each_front_end_spelling() {
        let m = "‹grid_um› must be positive; give ‹part› PART.stl (or ‹fz_mm› and ‹teeth›)";
        assert_eq!(
            for_cli(m),
            "--grid-um must be positive; give --part PART.stl (or --fz-mm and --teeth)"
        );
        assert_eq!(
            for_python(m),
            "grid_um must be positive; give part PART.stl (or fz_mm and teeth)"
        );
    }

    #[test]
    fn text_without_a_field_is_left_as_it_is() {
        for m in ["", "plain", "‹ not a field ›", "‹Upper›", "open ‹only"] {
            assert_eq!(for_cli(m), m);
        }
        assert!(matches!(for_cli("no marks"), Cow::Borrowed(_)));
        // A field next to other text and a stray mark after it.
        assert_eq!(for_cli("—‹x›—"), "—--x—");
        assert_eq!(for_cli("‹a›‹"), "--a‹");
    }
}
