//! A small CSV table reader shared by `joints` and `compensate`: a header naming the columns,
//! one record per row, `#` comment lines and blank lines skipped, fields trimmed. Every problem
//! is a [`TableError`] (bad input) naming the file, the physical line (1-based) and the column.

use std::path::Path;

use crate::error::{Classify, ErrorKind};

/// A problem with a CSV table.
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    #[error("cannot read {file}: {source}")]
    Read {
        file: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: no header row")]
    NoHeader { file: String },
    #[error("{file}: no data rows")]
    NoRows { file: String },
    #[error("{file}:{line}: column `{column}` is missing from the header")]
    MissingColumn {
        file: String,
        line: usize,
        column: String,
    },
    #[error("{file}:{line}: column `{column}` appears twice in the header")]
    DuplicateColumn {
        file: String,
        line: usize,
        column: String,
    },
    #[error("{file}:{line}: {found} fields, the header has {expected}")]
    FieldCount {
        file: String,
        line: usize,
        expected: usize,
        found: usize,
    },
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
#[derive(Debug, Clone)]
pub struct Row {
    /// Line number in the file (1-based).
    pub line: usize,
    /// The fields, as many as the header has columns.
    pub fields: Vec<String>,
}

/// A parsed table.
#[derive(Debug, Clone)]
pub struct Table {
    /// File name used in messages.
    pub file: String,
    /// Line of the header row.
    pub header_line: usize,
    /// Column names.
    pub header: Vec<String>,
    /// Data rows (at least one).
    pub rows: Vec<Row>,
}

impl Table {
    /// Reads and parses `path`.
    pub fn read(path: &Path) -> Result<Self, TableError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| TableError::Read {
            file: file.clone(),
            source,
        })?;
        Self::parse(&text, &file)
    }

    /// Parses table text; `file` names it in messages.
    pub fn parse(text: &str, file: &str) -> Result<Self, TableError> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let (header_line, head) = lines
            .next()
            .ok_or_else(|| TableError::NoHeader { file: file.into() })?;
        let header: Vec<String> = head.split(',').map(|h| h.trim().to_string()).collect();
        for (i, h) in header.iter().enumerate() {
            if header[..i].contains(h) {
                return Err(TableError::DuplicateColumn {
                    file: file.into(),
                    line: header_line,
                    column: h.clone(),
                });
            }
        }
        let mut rows = Vec::new();
        for (line, l) in lines {
            let fields: Vec<String> = l.split(',').map(|f| f.trim().to_string()).collect();
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
            return Err(TableError::NoRows { file: file.into() });
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

    /// A [`TableError::BadValue`] for `row`'s field in column `col`.
    pub fn bad(&self, row: &Row, col: usize, problem: impl Into<String>) -> TableError {
        TableError::BadValue {
            file: self.file.clone(),
            line: row.line,
            column: self.header[col].clone(),
            value: row.fields[col].clone(),
            problem: problem.into(),
        }
    }

    /// The finite number in `row`'s column `col`; empty -> `None`.
    pub fn optional_number(&self, row: &Row, col: usize) -> Result<Option<f64>, TableError> {
        let raw = &row.fields[col];
        if raw.is_empty() {
            return Ok(None);
        }
        let v: f64 = raw
            .parse()
            .map_err(|_| self.bad(row, col, "not a number"))?;
        if !v.is_finite() {
            return Err(self.bad(row, col, "not a finite number"));
        }
        Ok(Some(v))
    }

    /// The finite number in `row`'s column `col` (required).
    pub fn number(&self, row: &Row, col: usize) -> Result<f64, TableError> {
        self.optional_number(row, col)?
            .ok_or_else(|| self.bad(row, col, "missing value"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_reports_line_and_column() {
        let t = Table::parse("# c\na,b\n1,2\n\n3, x\n", "f.csv").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(t.header, ["a", "b"]);
        assert_eq!(t.rows.len(), 2);
        assert_eq!(t.rows[1].line, 5);
        assert_eq!(t.number(&t.rows[0], 1).ok(), Some(2.0));
        let e = t.number(&t.rows[1], 1).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("f.csv:5") && e.contains("`b`"), "{e}");
        let e = Table::parse("a,b\n1\n", "g.csv")
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(e.contains("g.csv:2"), "{e}");
        assert!(Table::parse("a,a\n1,2\n", "h").is_err());
        assert!(Table::parse("a\n", "h").is_err());
    }
}
