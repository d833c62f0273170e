//! The "Path error along the drawn path (thesis fig. 5.12)" section: from the run directory's
//! `path_errors.csv` (the file `rigctl calibrate --samples FUSED.csv --errors-csv` writes, see
//! [`crate::plot::path_errors`]), the fig. 5.12 chart and a table of RMS / max / mean before,
//! after the standard calibration and after the chosen method.

use std::fmt::Write as _;
use std::path::Path;

use super::markup::{escape, render_figure};
use super::Figure;
use crate::plot::path_errors::{
    path_errors_svg, read_path_errors, PathErrorSummary, SetSummary, BEFORE_LABEL, STANDARD_LABEL,
};

pub use super::run_dir::PATH_ERRORS_FILE;

/// Heading of the section.
pub const HEADING: &str = "Path error along the drawn path (thesis fig. 5.12)";

/// What the section shows.
#[derive(Debug, Clone, PartialEq)]
pub struct PathErrorsSection {
    /// File name.
    pub source: String,
    /// Statistics of the three models.
    pub summary: PathErrorSummary,
    /// Column heading of the chosen method (`after (tilting)`, ...).
    pub after_label: String,
    /// The chart (absent if it could not be drawn; a note says why).
    pub figure: Option<Figure>,
}

/// The section of the path error file `path`; `method` (from `calibrate*.json`) names the
/// "after" column. An unusable file becomes a note and `None`.
pub fn path_errors_section(
    path: &Path,
    method: Option<&str>,
    notes: &mut Vec<String>,
) -> Option<PathErrorsSection> {
    let mut data = match read_path_errors(path) {
        Ok(d) => d,
        Err(e) => {
            notes.push(format!("path error section skipped: {e}"));
            return None;
        }
    };
    if let Some(m) = method {
        data.after_label = format!("after ({m})");
    }
    let source = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let summary = data.summary();
    let figure = match path_errors_svg(&data) {
        Ok(svg) => Some(Figure {
            caption: format!(
                "{HEADING}: |dP| of the measured error (across the path in the sheet plane and out of the sheet; the component along the path is not measured) at every sample of {source}, {} samples in {} segment(s) joined end to end; below, the two components before and after.",
                summary.n_samples, summary.n_segments
            ),
            svg,
            series: Vec::new(),
        }),
        Err(e) => {
            notes.push(format!("path error figure skipped: {e}"));
            None
        }
    };
    Some(PathErrorsSection {
        source,
        summary,
        after_label: data.after_label,
        figure,
    })
}

/// One statistic of a [`SetSummary`].
type Statistic = fn(&SetSummary) -> f64;

/// Appends the section to the page.
pub(crate) fn render(s: &mut String, sec: &PathErrorsSection) {
    let sum = &sec.summary;
    let _ = writeln!(
        s,
        "<table class=\"path-errors\"><tr><th>statistic</th><th class=\"num\">{}, mm</th><th class=\"num\">{}, mm</th><th class=\"num\">{}, mm</th></tr>",
        escape(BEFORE_LABEL),
        escape(STANDARD_LABEL),
        escape(&sec.after_label)
    );
    let rows: [(&str, Statistic); 5] = [
        ("RMS |dP|", |x| x.dp_rms_mm),
        ("Maximum |dP|", |x| x.dp_max_mm),
        ("Average |dP|", |x| x.dp_mean_mm),
        ("RMS dev_u (across the path)", |x| x.dev_u_rms_mm),
        ("RMS dev_n (out of the sheet)", |x| x.dev_n_rms_mm),
    ];
    for (name, value) in rows {
        let _ = write!(s, "<tr><th>{}</th>", escape(name));
        for set in [&sum.before, &sum.standard, &sum.after] {
            let _ = write!(s, "<td class=\"num\">{:.4}</td>", value(set));
        }
        s.push_str("</tr>\n");
    }
    let _ = writeln!(
        s,
        "</table>\n<p class=\"src\">{} samples in {} segment(s); source: <code>{}</code></p>",
        sum.n_samples,
        sum.n_segments,
        escape(&sec.source)
    );
    if let Some(f) = &sec.figure {
        render_figure(s, f);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::path_errors::tests::SAMPLE_CSV;
    use crate::report::{build_report, render_html, ReportError, ReportOptions};

    #[test]
    fn path_errors_csv_gets_a_section_with_hand_checked_numbers() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(PATH_ERRORS_FILE), SAMPLE_CSV).unwrap();
        // alone, it is enough for a report; the "after" column has the default name
        let r =
            build_report(dir.path(), &ReportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let sec = r.path_errors.as_ref().expect("path error section");
        assert_eq!(sec.after_label, crate::plot::path_errors::AFTER_LABEL);
        assert!(sec.figure.is_some(), "{:?}", r.notes);
        // with a calibrate document, the column is named after its method
        std::fs::write(
            dir.path().join("calibrate.json"),
            r#"{"method": "tilting", "parameters": {}}"#,
        )
        .unwrap();
        let r =
            build_report(dir.path(), &ReportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let sec = r.path_errors.as_ref().expect("path error section");
        // hand values of SAMPLE_CSV: RMS |dP| sqrt(13), sqrt(0.13), 1; max 5, 0.5, 1
        assert!((sec.summary.before.dp_rms_mm - 13f64.sqrt()).abs() < 1e-12);
        assert!((sec.summary.after.dp_rms_mm - 0.13f64.sqrt()).abs() < 1e-12);
        assert!((sec.summary.standard.dp_max_mm - 1.0).abs() < 1e-12);
        assert_eq!(sec.after_label, "after (tilting)");
        let file = r.files.iter().find(|f| f.name == PATH_ERRORS_FILE).unwrap();
        assert!(!file.role.is_empty());
        let html = render_html(&r);
        assert!(html.contains(HEADING));
        assert!(html.contains("<th class=\"num\">after (tilting), mm</th>"));
        // RMS |dP| row, then Maximum |dP| row: before / standard / after
        assert!(html.contains(
            "<th>RMS |dP|</th><td class=\"num\">3.6056</td><td class=\"num\">1.0000</td><td class=\"num\">0.3606</td>"
        ));
        assert!(html.contains(
            "<th>Maximum |dP|</th><td class=\"num\">5.0000</td><td class=\"num\">1.0000</td><td class=\"num\">0.5000</td>"
        ));
        assert!(
            html.contains("after (tilting), RMS 0.361 mm"),
            "chart inlined"
        );
    }

    #[test]
    fn a_malformed_path_error_file_is_a_note() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join(PATH_ERRORS_FILE),
            "path,t,err_before_mm,err_after_mm\ncircle,0,1,0.1\n",
        )
        .unwrap();
        match build_report(dir.path(), &ReportOptions::default()) {
            Err(ReportError::NothingUsable { notes, .. }) => {
                assert!(
                    notes
                        .iter()
                        .any(|n| n.contains("path_errors.csv:1") && n.contains("dev_u_before")),
                    "{notes:?}"
                );
            }
            other => panic!("expected NothingUsable, got {other:?}"),
        }
    }
}
