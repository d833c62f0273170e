//! The CSV table reader behind every CSV input of the crate (pose files, joint-tilt readings,
//! compensation paths, pencil traces, jig files, fused samples): a header naming the columns,
//! one record per row, `#` comment lines and blank lines skipped, lines and fields trimmed, no
//! quoting. Every problem is a [`TableError`] (bad input) naming the file, the physical line
//! (1-based) and, where there is one, the column.
//!
//! Readers look columns up by name ([`Table::find`] for optional ones, [`Table::need`] for
//! required ones) and parse numbers with [`Table::number`] / [`Table::numbers`] /
//! [`Table::optional_number`]; a check of their own on a field reports through [`Table::bad`].

use std::path::Path;

use crate::error::{Classify, ErrorKind};
use crate::io::dialect::{sniff, Dialect};
use crate::io::ranges::Quantity;

/// A problem with a CSV table (always bad input, exit code 2).
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    /// The file could not be read.
    #[error("cannot read {file}: {source}")]
    Read {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// Nothing but comments and blank lines.
    #[error("{file}: no header row")]
    NoHeader { file: String },
    /// A header and no data row; `line` is the header's.
    #[error("{file}: no data rows")]
    NoRows { file: String, line: usize },
    /// A required column is not in the header (`line` is the header's).
    #[error("{file}:{line}: column `{column}` is missing from the header")]
    MissingColumn {
        file: String,
        line: usize,
        column: String,
    },
    /// The header names a column twice.
    #[error("{file}:{line}: column `{column}` appears twice in the header")]
    DuplicateColumn {
        file: String,
        line: usize,
        column: String,
    },
    /// A row with more or fewer fields than the header.
    #[error("{file}:{line}: {found} fields, the header has {expected}")]
    FieldCount {
        file: String,
        line: usize,
        expected: usize,
        found: usize,
    },
    /// The file is not in the declared separator / decimal mark (`hint` says what it looks
    /// like and which flags read it).
    #[error("{file}:{line}: {hint}")]
    Dialect {
        file: String,
        line: usize,
        hint: String,
    },
    /// A field that is not what its column needs.
    #[error("{file}:{line}: column `{column}`: {problem} (`{value}`)")]
    BadValue {
        file: String,
        line: usize,
        column: String,
        value: String,
        problem: String,
    },
}

impl Classify for TableError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::BadInput
    }
}

/// One data row: its physical line number and its trimmed fields.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Line number in the file (1-based).
    pub line: usize,
    /// The fields, as many as the header has columns.
    pub fields: Vec<String>,
}

/// A parsed table.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// File name used in messages.
    pub file: String,
    /// Line of the header row (1-based).
    pub header_line: usize,
    /// Column names, all different.
    pub header: Vec<String>,
    /// Data rows (at least one), each with one field per column.
    pub rows: Vec<Row>,
}

impl Table {
    /// Reads and parses `path` (named in messages as `path.display()`).
    pub fn read(path: &Path) -> Result<Self, TableError> {
        let file = path.display().to_string();
        let text = crate::io::read::read_text_capped(path, crate::io::read::CAP_TABLE).map_err(
            |source| TableError::Read {
                file: file.clone(),
                source,
            },
        )?;
        Self::parse(&text, &file)
    }

    /// Parses table text; `file` names it in messages. A file that looks `;`- or
    /// tab-separated is refused with the flags that read it ([`Self::parse_dialect`]).
    pub fn parse(text: &str, file: &str) -> Result<Self, TableError> {
        Self::parse_dialect(text, file, Dialect::default())
    }

    /// Parses table text written with `dialect`'s separator and decimal mark; a file that
    /// looks written otherwise (its header one field under `dialect`'s separator, or decimal
    /// commas not declared) is [`TableError::Dialect`] naming what it looks like.
    pub fn parse_dialect(text: &str, file: &str, dialect: Dialect) -> Result<Self, TableError> {
        // A UTF-8 byte-order mark (spreadsheet exports) is not part of the header.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        check_dialect(text, file, dialect)?;
        let text = dialect.normalize(text);
        let text = text.as_ref();
        let split =
            |l: &str| -> Vec<String> { l.split(',').map(|f| f.trim().to_string()).collect() };
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let (header_line, head) = lines
            .next()
            .ok_or_else(|| TableError::NoHeader { file: file.into() })?;
        let header = split(head);
        let mut seen = std::collections::HashSet::with_capacity(header.len());
        for h in &header {
            if !seen.insert(h.as_str()) {
                return Err(TableError::DuplicateColumn {
                    file: file.into(),
                    line: header_line,
                    column: h.clone(),
                });
            }
        }
        let mut rows = Vec::new();
        for (line, l) in lines {
            let fields = split(l);
            if fields.len() != header.len() {
                return Err(TableError::FieldCount {
                    file: file.into(),
                    line,
                    expected: header.len(),
                    found: fields.len(),
                });
            }
            rows.push(Row { line, fields });
        }
        if rows.is_empty() {
            return Err(TableError::NoRows {
                file: file.into(),
                line: header_line,
            });
        }
        Ok(Self {
            file: file.into(),
            header_line,
            header,
            rows,
        })
    }

    /// Index of column `name`, if present.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// Index of column `name`, or [`TableError::MissingColumn`].
    pub fn need(&self, name: &str) -> Result<usize, TableError> {
        self.find(name).ok_or_else(|| TableError::MissingColumn {
            file: self.file.clone(),
            line: self.header_line,
            column: name.into(),
        })
    }

    /// A [`TableError::BadValue`] for `row`'s field in column `col` (an index from
    /// [`Self::find`] / [`Self::need`]).
    pub fn bad(&self, row: &Row, col: usize, problem: impl Into<String>) -> TableError {
        TableError::BadValue {
            file: self.file.clone(),
            line: row.line,
            column: self.header[col].clone(),
            value: row.fields[col].clone(),
            problem: problem.into(),
        }
    }

    /// The finite number in `row`'s column `col`; an empty field is `None`. A field that does
    /// not parse is "not a number"; NaN and infinities are refused as "NaN" / "infinite", and a
    /// value outside the physical range of the column's kind ([`Quantity::of_column`]) as "out
    /// of physical range".
    pub fn optional_number(&self, row: &Row, col: usize) -> Result<Option<f64>, TableError> {
        let raw = &row.fields[col];
        if raw.is_empty() {
            return Ok(None);
        }
        let v: f64 = raw
            .parse()
            .map_err(|_| self.bad(row, col, "not a number"))?;
        if v.is_nan() {
            Err(self.bad(row, col, "NaN"))
        } else if v.is_infinite() {
            Err(self.bad(row, col, "infinite"))
        } else if let Some(problem) = Quantity::of_column(&self.header[col]).check(v) {
            Err(self.bad(row, col, problem))
        } else {
            Ok(Some(v))
        }
    }

    /// The finite number in `row`'s column `col` (required: empty is "missing value").
    pub fn number(&self, row: &Row, col: usize) -> Result<f64, TableError> {
        self.optional_number(row, col)?
            .ok_or_else(|| self.bad(row, col, "missing value"))
    }

    /// The finite numbers in `row`'s columns `cols`, parsed in that order (the first bad one is
    /// reported).
    pub fn numbers<const N: usize>(
        &self,
        row: &Row,
        cols: [usize; N],
    ) -> Result<[f64; N], TableError> {
        let mut out = [0.0; N];
        for (v, col) in out.iter_mut().zip(cols) {
            *v = self.number(row, col)?;
        }
        Ok(out)
    }
}

/// [`TableError::Dialect`] when the first lines of `text` do not look written with `dialect`.
fn check_dialect(text: &str, file: &str, dialect: Dialect) -> Result<(), TableError> {
    let err = |line: usize, hint: String| TableError::Dialect {
        file: file.into(),
        line,
        hint,
    };
    if dialect.sep == dialect.decimal {
        return Err(err(
            1,
            "--sep and --decimal are both `,`: a file with decimal commas separates its fields \
             with `;` (--sep ';')"
                .into(),
        ));
    }
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((line, head)) = lines.next() else {
        return Ok(());
    };
    let data = lines.next().map(|(_, l)| l);
    let Some(hint) = sniff(head, data, dialect) else {
        return Ok(());
    };
    let single = head.split(dialect.sep).count() == 1;
    let undeclared_commas = dialect.decimal == '.'
        && dialect.sep != ','
        && data.is_some_and(|d| d.split(dialect.sep).any(super::dialect::decimal_comma));
    if single || undeclared_commas {
        return Err(err(line, hint));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Table {
        Table::parse(text, "f.csv").unwrap_or_else(|e| panic!("{e}"))
    }

    fn parse_err(text: &str) -> String {
        Table::parse(text, "f.csv")
            .map(|_| ())
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn comments_and_blank_lines_are_skipped_with_physical_line_numbers() {
        let t = parse("# a comment\n\n  # indented comment\r\n a , b \r\n1,2\n\n# mid\n3, x\n");
        assert_eq!(
            (t.header_line, t.header.clone()),
            (4, vec!["a".into(), "b".into()])
        );
        let lines: Vec<usize> = t.rows.iter().map(|r| r.line).collect();
        assert_eq!(lines, [5, 8]);
        assert_eq!(t.rows[1].fields, ["3", "x"]);
    }

    #[test]
    fn columns_are_looked_up_by_name_and_a_missing_one_is_named() {
        let t = parse("# c\nx,y,note\n1,2,hello\n");
        assert_eq!((t.find("y"), t.find("z")), (Some(1), None));
        assert_eq!(t.need("note").ok(), Some(2));
        let e = t.need("z").unwrap_err();
        assert_eq!(e.kind(), ErrorKind::BadInput);
        assert_eq!(
            e.to_string(),
            "f.csv:2: column `z` is missing from the header"
        );
    }

    #[test]
    fn numbers_parse_and_bad_ones_name_line_and_column() {
        let t = parse("a,b,c\n1.5,-2e3,\n# c\nabc,NaN,inf\n");
        let (r0, r1) = (&t.rows[0], &t.rows[1]);
        assert_eq!(t.numbers(r0, [1, 0]).ok(), Some([-2000.0, 1.5]));
        assert_eq!(t.optional_number(r0, 2).ok(), Some(None));
        let cases = [
            (t.number(r0, 2), "f.csv:2: column `c`: missing value (``)"),
            (t.number(r1, 0), "f.csv:4: column `a`: not a number (`abc`)"),
            (t.number(r1, 1), "f.csv:4: column `b`: NaN (`NaN`)"),
            (t.number(r1, 2), "f.csv:4: column `c`: infinite (`inf`)"),
            // the first bad column in the order asked for
            (t.numbers(r1, [2, 0]).map(|v| v[0]), "f.csv:4: column `c`"),
        ];
        for (got, want) in cases {
            let e = got.unwrap_err();
            assert_eq!(e.kind(), ErrorKind::BadInput);
            assert!(e.to_string().starts_with(want), "`{e}` vs `{want}`");
        }
        let e = t.bad(r0, 1, "too negative").to_string();
        assert_eq!(e, "f.csv:2: column `b`: too negative (`-2e3`)");
    }

    #[test]
    fn structural_problems_are_refused_with_their_line() {
        assert_eq!(
            parse_err("a,b\n1,2\n1\n"),
            "f.csv:3: 1 fields, the header has 2"
        );
        assert_eq!(
            parse_err("a,b\n1,2,3\n"),
            "f.csv:2: 3 fields, the header has 2"
        );
        assert_eq!(
            parse_err("# c\na,b,a\n1,2,3\n"),
            "f.csv:2: column `a` appears twice in the header"
        );
        assert_eq!(parse_err("# only\n\n"), "f.csv: no header row");
        assert_eq!(parse_err(""), "f.csv: no header row");
        assert!(matches!(
            Table::parse("# c\na\n# c\n", "f.csv"),
            Err(TableError::NoRows { line: 2, .. })
        ));
        let e = Table::read(Path::new("/nonexistent/t.csv")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/t.csv"), "{e}");
        assert_eq!(e.kind(), ErrorKind::BadInput);
    }
}
