//! The field separator and decimal mark of a CSV input (`--sep`, `--decimal`): a spreadsheet in
//! a German or French locale exports `;`-separated fields with decimal commas. The text is
//! rewritten at the edge to the crate's comma-separated, decimal-point form before the table
//! reader sees it; [`sniff`] names what a file that was not declared so looks like.

use std::borrow::Cow;

/// Separator and decimal mark of a file (default `,` and `.`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dialect {
    /// Field separator: `,`, `;` or a tab.
    pub sep: char,
    /// Decimal mark: `.` or `,`.
    pub decimal: char,
}

impl Default for Dialect {
    fn default() -> Self {
        Self {
            sep: ',',
            decimal: '.',
        }
    }
}

/// A separator or decimal mark that cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct DialectError(pub String);

impl Dialect {
    /// A checked dialect: the separator one of `,` `;` tab (or `\t`), the decimal mark `.` or
    /// `,`, and the two different.
    pub fn new(sep: &str, decimal: &str) -> Result<Self, DialectError> {
        let sep = match sep {
            "," => ',',
            ";" => ';',
            "\t" | "\\t" | "tab" => '\t',
            other => {
                return Err(DialectError(format!(
                    "--sep `{other}`: expected `,`, `;` or `\\t` (tab)"
                )))
            }
        };
        let decimal = match decimal {
            "." => '.',
            "," => ',',
            other => {
                return Err(DialectError(format!(
                    "--decimal `{other}`: expected `.` or `,`"
                )))
            }
        };
        if sep == decimal {
            return Err(DialectError(
                "--sep and --decimal are both `,`: a file with decimal commas separates its \
                 fields with `;` (--sep ';')"
                    .into(),
            ));
        }
        Ok(Self { sep, decimal })
    }

    /// Whether this is the crate's own form (nothing to rewrite).
    pub fn is_default(self) -> bool {
        self == Self::default()
    }

    /// `text` in the comma-separated, decimal-point form: the decimal mark becomes `.`, the
    /// separator `,` (a comma that is neither, inside a text field, becomes a space).
    pub fn normalize(self, text: &str) -> Cow<'_, str> {
        if self.is_default() {
            return Cow::Borrowed(text);
        }
        let out: String = text
            .chars()
            .map(|c| {
                if c == self.decimal {
                    '.'
                } else if c == self.sep {
                    ','
                } else if c == ',' {
                    ' '
                } else {
                    c
                }
            })
            .collect();
        Cow::Owned(out)
    }
}

fn shown(sep: char) -> &'static str {
    match sep {
        ';' => ";",
        '\t' => "\\t",
        _ => ",",
    }
}

/// Whether `field` is a number written with a decimal comma (`-1,25`, `3,0e-3`).
pub(crate) fn decimal_comma(field: &str) -> bool {
    let f = field.trim().trim_start_matches(['-', '+']);
    match f.split_once(',') {
        Some((a, b)) => {
            !a.is_empty()
                && !b.is_empty()
                && a.bytes().all(|c| c.is_ascii_digit())
                && b.bytes()
                    .all(|c| c.is_ascii_digit() || matches!(c, b'e' | b'E' | b'-' | b'+'))
                && b.as_bytes()[0].is_ascii_digit()
        }
        None => false,
    }
}

/// What the file's header line and first data line look like when they are not in `declared`'s
/// form: `Some("the file looks like `;`-separated with decimal commas: use --sep ';' --decimal
/// ','")`, or `None` when nothing suggests another form.
pub fn sniff(header: &str, data: Option<&str>, declared: Dialect) -> Option<String> {
    let n_fields = |l: &str, sep: char| l.split(sep).count();
    // the separator: the one of , ; tab that splits the header into the most fields
    let sep = [',', ';', '\t']
        .into_iter()
        .max_by_key(|&s| n_fields(header, s))
        .filter(|&s| n_fields(header, s) > 1)?;
    let commas = data.is_some_and(|d| d.split(sep).any(decimal_comma));
    let decimal = if sep != ',' && commas { ',' } else { '.' };
    if sep == declared.sep && decimal == declared.decimal {
        return None;
    }
    if sep == declared.sep && sep == ',' {
        return None;
    }
    let what = match (sep, decimal) {
        (',', _) => "`,`-separated".to_string(),
        (s, ',') => format!("`{}`-separated with decimal commas", shown(s)),
        (s, _) => format!("`{}`-separated", shown(s)),
    };
    let mut flags = format!("--sep '{}'", shown(sep));
    if decimal != '.' || declared.decimal != '.' {
        flags.push_str(&format!(" --decimal '{decimal}'"));
    }
    Some(format!("the file looks like {what}: use {flags}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_german_export_is_rewritten_and_sniffed() {
        let d = Dialect::new(";", ",").unwrap();
        let text = "t;q1;note\n0,5;-12,25;a,b\n";
        assert_eq!(d.normalize(text), "t,q1,note\n0.5,-12.25,a.b\n");
        let hint = sniff("t;q1;q2", Some("0,5;-12,25;3"), Dialect::default()).unwrap();
        assert_eq!(
            hint,
            "the file looks like `;`-separated with decimal commas: use --sep ';' --decimal ','"
        );
        assert_eq!(
            sniff("t;q1", Some("0.5;1"), Dialect::default()).unwrap(),
            "the file looks like `;`-separated: use --sep ';'"
        );
        assert_eq!(sniff("t,q1", Some("0.5,1"), Dialect::default()), None);
        assert_eq!(sniff("t;q1", Some("0,5;1"), d), None);
        assert!(Dialect::new(",", ",").is_err());
        assert!(Dialect::new("|", ".").is_err());
        assert!(Dialect::default().normalize("a,b").is_borrowed_like());
    }

    trait Borrowed {
        fn is_borrowed_like(&self) -> bool;
    }
    impl Borrowed for Cow<'_, str> {
        fn is_borrowed_like(&self) -> bool {
            matches!(self, Cow::Borrowed(_))
        }
    }
}
