//! Escaping text for markup (HTML pages, XML files such as URDF), so that a parser reads back
//! the text itself.

/// What to do with newline, carriage return and tab.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Blanks {
    /// Kept as they are (HTML text, where they are white space like any other).
    Literal,
    /// As character references (XML attribute values, which a parser would turn into spaces);
    /// the other control characters, which XML 1.0 cannot hold even as references, become
    /// U+FFFD.
    References,
}

/// `text` with `& < > " '` as entities, and the blanks as `blanks` says.
pub fn escape(text: &str, blanks: Blanks) -> String {
    let refs = blanks == Blanks::References;
    let mut s = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => s.push_str("&amp;"),
            '<' => s.push_str("&lt;"),
            '>' => s.push_str("&gt;"),
            '"' => s.push_str("&quot;"),
            '\'' => s.push_str("&#39;"),
            '\n' if refs => s.push_str("&#10;"),
            '\r' if refs => s.push_str("&#13;"),
            '\t' if refs => s.push_str("&#9;"),
            c if refs && c.is_control() => s.push('\u{FFFD}'),
            c => s.push(c),
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blanks_are_kept_or_referenced() {
        let t = "a&b<\"c\">\n'\t\u{7}";
        assert_eq!(
            escape(t, Blanks::Literal),
            "a&amp;b&lt;&quot;c&quot;&gt;\n&#39;\t\u{7}"
        );
        assert_eq!(
            escape(t, Blanks::References),
            "a&amp;b&lt;&quot;c&quot;&gt;&#10;&#39;&#9;\u{FFFD}"
        );
    }
}
