//! File names (and other user text) as they are shown in messages: control characters
//! (newline, carriage return, ANSI `ESC`, DEL, the C1 range) and the Unicode bidirectional
//! controls (U+202A..U+202E, U+2066..U+2069, U+200E, U+200F, U+061C) are written as escapes
//! (`\n`, `\u{1b}`, `\u{202e}`), so a hostile name can neither fake a line of output, drive the
//! terminal nor reorder what the user reads.

use std::fmt::Write as _;
use std::path::Path;

/// Whether `c` is shown as an escape.
pub fn is_hidden(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}' | '\u{200e}' | '\u{200f}' | '\u{061c}'
        )
}

/// `text` with every [`is_hidden`] character escaped (a backslash is left as it is).
pub fn escape(text: &str) -> String {
    if !text.chars().any(is_hidden) {
        return text.to_string();
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if is_hidden(c) => {
                let _ = write!(out, "\\u{{{:x}}}", u32::from(c));
            }
            c => out.push(c),
        }
    }
    out
}

/// `text` with the hidden characters escaped except newline and tab: for whole messages whose
/// own lines (a parser's caret diagnostics) are kept.
pub fn escape_keep_lines(text: &str) -> String {
    if !text.chars().any(|c| is_hidden(c) && c != '\n' && c != '\t') {
        return text.to_string();
    }
    text.split('\n')
        .map(|line| line.split('\t').map(escape).collect::<Vec<_>>().join("\t"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// A path for a message: [`escape`] of its lossy UTF-8 form.
pub fn shown(path: &Path) -> String {
    escape(&path.to_string_lossy())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controls_and_bidi_overrides_are_escaped() {
        assert_eq!(escape("a.csv"), "a.csv");
        assert_eq!(escape("a\nb"), "a\\nb");
        assert_eq!(escape("\u{1b}[31mred"), "\\u{1b}[31mred");
        assert_eq!(escape("x\u{202e}vsc.exe"), "x\\u{202e}vsc.exe");
        assert_eq!(escape("del\u{7f}"), "del\\u{7f}");
        assert_eq!(escape("c1\u{9b}"), "c1\\u{9b}");
        assert_eq!(escape("caf\u{e9} \\ ok"), "caf\u{e9} \\ ok");
        assert_eq!(
            escape_keep_lines("line 1\n  | \u{1b}x\tq"),
            "line 1\n  | \\u{1b}x\tq"
        );
    }
}
