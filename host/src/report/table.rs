//! Thesis table 4.5: minimum / maximum / average of |dX| |dY| |dZ| |dP| per model column.

use nalgebra::Vector3;
use serde_json::Value;

use crate::calib::stats::{AxisExtremes, Stats};

/// Row labels of the quantities, in table order.
pub const QUANTITIES: [&str; 4] = ["|dX|", "|dY|", "|dZ|", "|dP|"];

/// One table: `rows[r].values[c]` for column `c` (mm); `None` where the source lacks it.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorTable {
    /// Caption (which poses).
    pub title: String,
    /// Number of poses or samples.
    pub n: usize,
    /// What is counted: "poses" or "samples" (fused files).
    pub noun: &'static str,
    /// Column headings (before, after standard, after chosen...).
    pub columns: Vec<String>,
    /// Rows: (statistic, quantity, one value per column).
    pub rows: Vec<TableRow>,
    /// Where the numbers come from.
    pub source: String,
}

/// One row of an [`ErrorTable`].
#[derive(Debug, Clone, PartialEq)]
pub struct TableRow {
    /// `Minimum`, `Maximum`, `Average` or `RMS`.
    pub statistic: &'static str,
    /// One of [`QUANTITIES`].
    pub quantity: &'static str,
    /// Value per column (mm).
    pub values: Vec<Option<f64>>,
}

/// The numbers of one column: stats and (when known) per-axis extremes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Column {
    /// FORMATS.md stats.
    pub stats: Stats,
    /// Per-axis extremes (not in the JSON documents).
    pub extremes: Option<AxisExtremes>,
}

impl Column {
    /// From error vectors (measured - model).
    pub fn from_errors(errors_mm: &[Vector3<f64>]) -> Self {
        Self {
            stats: Stats::from_errors(errors_mm),
            extremes: Some(AxisExtremes::from_errors(errors_mm)),
        }
    }

    /// From a FORMATS.md stats object; `None` if a key is missing or not a number.
    pub fn from_json(v: &Value) -> Option<Self> {
        let f = |k: &str| v.get(k).and_then(Value::as_f64);
        Some(Self {
            stats: Stats {
                n: v.get("n").and_then(Value::as_u64)? as usize,
                mean_mm: f("mean_mm")?,
                rms_mm: f("rms_mm")?,
                max_mm: f("max_mm")?,
                min_mm: f("min_mm")?,
                mean_abs_x_mm: f("mean_abs_x_mm")?,
                mean_abs_y_mm: f("mean_abs_y_mm")?,
                mean_abs_z_mm: f("mean_abs_z_mm")?,
            },
            extremes: None,
        })
    }
}

impl ErrorTable {
    /// A table of `columns` (heading, numbers); `n` is taken from the first column.
    pub fn new(title: &str, source: &str, columns: &[(String, Column)]) -> Self {
        let mut rows = Vec::new();
        for statistic in ["Minimum", "Maximum", "Average"] {
            for (k, quantity) in QUANTITIES.iter().enumerate() {
                let values = columns
                    .iter()
                    .map(|(_, c)| {
                        let s = &c.stats;
                        match (statistic, k) {
                            ("Minimum", 3) => Some(s.min_mm),
                            ("Maximum", 3) => Some(s.max_mm),
                            ("Average", 3) => Some(s.mean_mm),
                            ("Average", 0) => Some(s.mean_abs_x_mm),
                            ("Average", 1) => Some(s.mean_abs_y_mm),
                            ("Average", _) => Some(s.mean_abs_z_mm),
                            ("Minimum", _) => c.extremes.map(|e| e.min_abs_mm[k]),
                            _ => c.extremes.map(|e| e.max_abs_mm[k]),
                        }
                    })
                    .collect();
                rows.push(TableRow {
                    statistic,
                    quantity,
                    values,
                });
            }
        }
        rows.push(TableRow {
            statistic: "RMS",
            quantity: "|dP|",
            values: columns.iter().map(|(_, c)| Some(c.stats.rms_mm)).collect(),
        });
        Self {
            title: title.to_string(),
            n: columns.first().map_or(0, |(_, c)| c.stats.n),
            noun: "poses",
            columns: columns.iter().map(|(h, _)| h.clone()).collect(),
            rows,
            source: source.to_string(),
        }
    }

    /// The table counting `noun` ("poses", "samples").
    pub fn with_noun(mut self, noun: &'static str) -> Self {
        self.noun = noun;
        self
    }

    /// Rows with at least one value (what was not computed is left out).
    pub fn computed_rows(&self) -> impl Iterator<Item = &TableRow> {
        self.rows
            .iter()
            .filter(|r| r.values.iter().any(Option::is_some))
    }

    /// Whether column `a` and column `b` hold the same numbers (mean and RMS of |dP| within
    /// 1e-4 relative, which a model file rounded to its printed digits keeps): the same model reached by two routes.
    fn same_column(&self, a: usize, other: &ErrorTable, b: usize) -> bool {
        ["Average", "RMS"].iter().all(|st| {
            match (self.get(st, "|dP|", a), other.get(st, "|dP|", b)) {
                (Some(x), Some(y)) => (x - y).abs() <= 1e-4 * x.abs().max(y.abs()).max(1e-12),
                _ => false,
            }
        })
    }

    /// Appends the columns of `other` (same rows) that are not already here.
    fn absorb(&mut self, other: &ErrorTable) {
        let mut added = false;
        for c in 0..other.columns.len() {
            if (0..self.columns.len()).any(|k| self.same_column(k, other, c)) {
                continue;
            }
            let mut label = other.columns[c].clone();
            if self.columns.contains(&label) {
                label = format!("{label} ({})", other.source);
            }
            self.columns.push(label);
            for (row, src) in self.rows.iter_mut().zip(&other.rows) {
                row.values.push(src.values.get(c).copied().flatten());
            }
            added = true;
        }
        if added && !self.source.split(", ").any(|s| s == other.source) {
            self.source = format!("{}, {}", self.source, other.source);
        }
    }

    /// The value of `statistic` / `quantity` in column `col`.
    pub fn get(&self, statistic: &str, quantity: &str, col: usize) -> Option<f64> {
        self.rows
            .iter()
            .find(|r| r.statistic == statistic && r.quantity == quantity)
            .and_then(|r| r.values.get(col).copied().flatten())
    }
}

/// The tables of one `calibrate --json` document: calibration (and validation) poses, columns
/// before / after standard / after the chosen method.
pub fn tables_from_calibrate_json(file: &str, doc: &Value) -> Vec<ErrorTable> {
    let method = doc
        .get("method")
        .and_then(Value::as_str)
        .unwrap_or("chosen");
    let mut out = Vec::new();
    for (set, title) in [
        ("calibration", "Calibration poses"),
        ("validation", "Held-out poses"),
    ] {
        let Some(ba) = doc.get(set) else { continue };
        let mut cols = Vec::new();
        if let Some(c) = ba.get("before").and_then(Column::from_json) {
            cols.push(("before".to_string(), c));
        }
        if let Some(c) = (method != "standard")
            .then(|| doc.get("standard"))
            .flatten()
            .and_then(|s| s.get(set))
            .and_then(Column::from_json)
        {
            cols.push(("after standard".to_string(), c));
        }
        if let Some(c) = ba.get("after").and_then(Column::from_json) {
            cols.push((format!("after {method}"), c));
        }
        if !cols.is_empty() {
            out.push(ErrorTable::new(title, file, &cols));
        }
    }
    out
}

/// One table per pose set: tables with the same title and count are merged into the first,
/// keeping each distinct column once (the recomputed columns, listed first, win).
pub fn merge_tables(tables: Vec<ErrorTable>) -> Vec<ErrorTable> {
    let mut out: Vec<ErrorTable> = Vec::new();
    for t in tables {
        match out
            .iter_mut()
            .find(|o| o.title == t.title && o.n == t.n && o.rows.len() == t.rows.len())
        {
            Some(o) => o.absorb(&t),
            None => out.push(t),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_from_errors_and_json_agree_where_both_exist() {
        let errs = [Vector3::new(3.0, -4.0, 0.0), Vector3::new(0.0, 0.0, -1.0)];
        let c = Column::from_errors(&errs);
        let json = serde_json::to_value(c.stats).unwrap();
        let j = Column::from_json(&json).unwrap();
        let t = ErrorTable::new("t", "s", &[("a".into(), c), ("b".into(), j)]);
        // |dP| = 5 and 1: hand values
        assert_eq!(t.get("Maximum", "|dP|", 0), Some(5.0));
        assert_eq!(t.get("Minimum", "|dP|", 1), Some(1.0));
        assert_eq!(t.get("Average", "|dP|", 1), Some(3.0));
        assert_eq!(t.get("Average", "|dX|", 0), Some(1.5));
        assert_eq!(t.get("Maximum", "|dY|", 0), Some(4.0));
        assert_eq!(t.get("Minimum", "|dX|", 0), Some(0.0));
        // per-axis extremes are not in the JSON
        assert_eq!(t.get("Maximum", "|dY|", 1), None);
        assert!((t.get("RMS", "|dP|", 0).unwrap() - 13f64.sqrt()).abs() < 1e-12);
        assert_eq!(t.n, 2);
    }

    #[test]
    fn merged_tables_keep_each_model_once_and_name_clashes() {
        let a = Column::from_errors(&[Vector3::new(1.0, 0.0, 0.0)]);
        let b = Column::from_errors(&[Vector3::new(0.5, 0.0, 0.0)]);
        // as read from a JSON document: no per-axis extremes
        let c = Column::from_json(
            &serde_json::to_value(Column::from_errors(&[Vector3::new(0.2, 0.0, 0.0)]).stats)
                .unwrap(),
        )
        .unwrap();
        let rec = ErrorTable::new(
            "Validation poses",
            "val.csv",
            &[("nominal".into(), a), ("cal".into(), b)],
        );
        let json = ErrorTable::new(
            "Validation poses",
            "calibrate.json",
            &[("before".into(), a), ("cal".into(), c)],
        );
        let other = ErrorTable::new("Calibration poses", "cal.csv", &[("nominal".into(), a)]);
        let m = merge_tables(vec![rec, json, other]);
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].columns, ["nominal", "cal", "cal (calibrate.json)"]);
        assert_eq!(m[0].source, "val.csv, calibrate.json");
        assert_eq!(m[0].get("Average", "|dP|", 2), Some(0.2));
        // the JSON column has no per-axis extremes: that row keeps a gap, not a made-up value
        assert_eq!(m[0].get("Maximum", "|dX|", 2), None);
        assert_eq!(m[0].get("Maximum", "|dX|", 1), Some(0.5));
    }

    #[test]
    fn a_standard_document_has_no_second_standard_column() {
        let st = serde_json::to_value(Column::from_errors(&[Vector3::new(1.0, 0.0, 0.0)]).stats)
            .unwrap();
        let doc = serde_json::json!({"method": "standard",
            "calibration": {"before": st, "after": st}, "standard": {"calibration": st}});
        let t = tables_from_calibrate_json("c.json", &doc);
        assert_eq!(t[0].columns, ["before", "after standard"]);
        // JSON tables have no per-axis extremes: those rows are left out when shown
        assert_eq!(t[0].computed_rows().count(), 7);
    }

    #[test]
    fn incomplete_stats_are_rejected() {
        assert!(Column::from_json(&serde_json::json!({"n": 3, "mean_mm": 1.0})).is_none());
    }
}
