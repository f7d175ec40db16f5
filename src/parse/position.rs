//! Positions in text: the 1-based line and column (in characters) of a byte offset, the one
//! helper every reader of text input (CLSF, TOML configs, CSV tables) reports errors with.

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
}
