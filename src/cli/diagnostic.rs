//! How an error reaches people: miette's graphical report (colours, frames, the offending
//! line, wrapping at the terminal's width) only when stderr is a terminal; to a pipe or a
//! file, one plain line per cause, never wrapped, so that logs can be searched and tests do
//! not depend on the width of a terminal or the length of a path. Control characters that
//! came from an input (ESC, BEL, NUL, …) are shown escaped (`\x1b`) in the plain lines and in
//! the graphical report (which keeps only its own colour codes). An error that names a place
//! in an input carries one `crest::parse::Located`: its message is the plain line, and its
//! frame and label are the code frame of the graphical report.

use std::fmt::Write as _;
use std::io::IsTerminal;

/// The text to print on stderr for `e` (ending in a newline).
pub fn render(e: &miette::Report) -> String {
    // The library names request fields (`‹grid_um›`): here they are options (`--grid-um`).
    crest::pipeline::fields::for_cli(&render_as_is(e)).into_owned()
}

fn render_as_is(e: &miette::Report) -> String {
    if std::io::stderr().is_terminal() {
        // miette's own handler: it honours NO_COLOR (and FORCE_COLOR) and the terminal width.
        // Its own colour codes are kept (none under NO_COLOR); every other control character
        // (from a file name, a message or the offending line) is escaped.
        let colour = std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty());
        escape_graphical(&format!("{e:?}\n"), colour)
    } else {
        plain(e)
    }
}

/// `error: …`, then `  caused by: …` for each source and `  help: …`: one line each.
pub fn plain(e: &miette::Report) -> String {
    let mut out = String::new();
    for (i, cause) in e.chain().enumerate() {
        let label = if i == 0 { "error" } else { "  caused by" };
        let _ = writeln!(out, "{label}: {}", one_line(&cause.to_string()));
    }
    for related in e.related().into_iter().flatten() {
        let _ = writeln!(out, "error: {}", one_line(&related.to_string()));
    }
    if let Some(help) = e.help() {
        let _ = writeln!(out, "  help: {}", one_line(&help.to_string()));
    }
    out
}

/// A message on one line: its own line breaks become `; `, control characters are escaped.
fn one_line(text: &str) -> String {
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim_end)
        .filter(|l| !l.trim().is_empty())
        .collect();
    escape_controls(&lines.join("; "))
}

/// miette's graphical report with every control character escaped as in
/// [`escape_controls`], except line breaks and tabs and, when `colour`, the colour codes
/// miette writes (`ESC [ digits;… m`). A colour code from an input is then kept too (it can
/// only colour text); under NO_COLOR no escape character is left at all.
pub fn escape_graphical(text: &str, colour: bool) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(c) = rest.chars().next() {
        if colour && c == '\x1b' {
            let sgr = rest[1..].strip_prefix('[').and_then(|t| {
                let n = t.find(|d: char| !(d.is_ascii_digit() || d == ';'))?;
                t[n..].starts_with('m').then_some(2 + n + 1)
            });
            if let Some(len) = sgr {
                out.push_str(&rest[..len]);
                rest = &rest[len..];
                continue;
            }
        }
        if c == '\n' || c == '\t' {
            out.push(c);
        } else {
            out.push_str(&escape_controls(c.encode_utf8(&mut [0; 4])));
        }
        rest = &rest[c.len_utf8()..];
    }
    out
}

/// Every control character but the tab as `\xNN` (or `\u{NNNN}` beyond ASCII), as ripgrep
/// and git show them: text from an input file cannot move the cursor, clear the screen or
/// retitle the terminal.
pub fn escape_controls(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() && c != '\t' {
            if (c as u32) < 0x80 {
                let _ = write!(out, "\\x{:02x}", c as u32);
            } else {
                let _ = write!(out, "\\u{{{:04x}}}", c as u32);
            }
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error, miette::Diagnostic)]
    #[error("inner: bad\x1b]0;title\x07 value")]
    struct Inner;

    #[derive(Debug, thiserror::Error, miette::Diagnostic)]
    #[error("a/very/long/path/{0}/file.cls:12:3: expected a number, found `zz`")]
    #[diagnostic(help("check the line"))]
    struct Outer(String, #[source] Inner);

    #[test]
    fn plain_is_one_unwrapped_line_per_cause_with_controls_escaped() {
        let long = "x".repeat(300);
        let r = miette::Report::new(Outer(long.clone(), Inner));
        let text = plain(&r);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3, "{text}");
        assert_eq!(
            lines[0],
            format!("error: a/very/long/path/{long}/file.cls:12:3: expected a number, found `zz`")
        );
        assert_eq!(lines[1], "  caused by: inner: bad\\x1b]0;title\\x07 value");
        assert_eq!(lines[2], "  help: check the line");
        assert!(!text.contains('\x1b') && !text.contains('\x07'));
    }

    #[test]
    fn the_graphical_report_keeps_only_its_colours() {
        let t = "\x1b[31merror\x1b[0m: a\x1b]0;pwned\x07b\x1b[2Jc\0\n  │ next\tline\n";
        assert_eq!(
            escape_graphical(t, true),
            "\x1b[31merror\x1b[0m: a\\x1b]0;pwned\\x07b\\x1b[2Jc\\x00\n  │ next\tline\n"
        );
        let plain = escape_graphical(t, false);
        assert!(!plain.contains('\x1b') && !plain.contains('\x07') && !plain.contains('\0'));
        assert!(plain.starts_with("\\x1b[31merror"), "{plain}");
    }

    #[test]
    fn a_located_error_is_one_plain_line_or_a_frame_of_its_line() {
        use crest::parse::{Located, Span};
        let line = "GOTO/1,zz,3";
        let e = Located::expected(Span::in_line(12, line, 7..9), "a number", "`zz`", line)
            .in_file("a.cls");
        let r = miette::Report::new(e);
        assert_eq!(
            plain(&r),
            "error: a.cls:12:8: expected a number, found `zz`\n"
        );
        let mut out = String::new();
        miette::GraphicalReportHandler::new_themed(miette::GraphicalTheme::unicode_nocolor())
            .render_report(&mut out, r.as_ref())
            .unwrap();
        assert!(out.contains("[a.cls:12:8]"), "{out}");
        assert!(out.contains("12 │ GOTO/1,zz,3"), "{out}");
        assert!(out.contains("expected a number"), "{out}");
    }

    #[test]
    fn multi_line_messages_become_one_line() {
        let r = miette::miette!("first\n  second\n\nthird\u{9b}");
        assert_eq!(plain(&r), "error: first;   second; third\\u{009b}\n");
    }
}
