//! Positions in text: the 1-based line and column (in characters) of a byte offset, the one
//! helper every reader of text input (CLSF, TOML configs, CSV tables) reports errors with,
//! and the column within one line that the line-by-line readers (G-code, contact12) use.

/// 1-based line and column (in characters) of byte offset `at` in `text`. An offset past the
/// end points just after the last character; an offset inside a multi-byte character points
/// at that character.
pub fn line_column(text: &str, at: usize) -> (usize, usize) {
    let at = at.min(text.len());
    let mut cut = at;
    while !text.is_char_boundary(cut) {
        cut -= 1;
    }
    let before = &text[..cut];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
}

/// 1-based column (in characters) of byte `at` of a single `line`; an offset past the end or
/// inside a multi-byte character counts the bytes before it.
pub fn column_in_line(line: &str, at: usize) -> u32 {
    let chars = line
        .get(..at.min(line.len()))
        .map_or(at, |s| s.chars().count());
    u32::try_from(chars).unwrap_or(u32::MAX).saturating_add(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_column_counts_characters() {
        let text = "a = 1\nµ = 2\n";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 6), (2, 1));
        // 'µ' is two bytes: the '=' after it is the third character.
        assert_eq!(line_column(text, 9), (2, 3));
        // Inside the two bytes of 'µ': the character itself.
        assert_eq!(line_column(text, 7), (2, 1));
        assert_eq!(line_column(text, 1000), (3, 1));
    }

    #[test]
    fn column_in_line_counts_characters_before_the_byte() {
        assert_eq!(column_in_line("G1 X1", 0), 1);
        assert_eq!(column_in_line("G1 X1", 3), 4);
        assert_eq!(column_in_line("µ,X", 3), 3); // 'µ' is two bytes, one character
        assert_eq!(column_in_line("ab", 10), 3); // past the end: after the last character
        assert_eq!(column_in_line("µb", 1), 2); // inside 'µ': the bytes before it
    }
}
