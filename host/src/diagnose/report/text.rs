//! The text table `diagnose` prints on stdout (the same content as the JSON document of
//! [`super`], in words).

use std::fmt::Write as _;

use super::*;

fn fmt_params(p: &Ordered<f64>) -> String {
    p.0.iter()
        .map(|(k, v)| format!("{k}={v:.4}"))
        .collect::<Vec<_>>()
        .join(" ")
}

impl DiagnoseReport {
    /// The human-readable table printed on stdout.
    pub fn table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "diagnose: {} ({}), {} calibration / {} validation poses{}",
            self.robot,
            if self.tilting {
                "declared tilting"
            } else {
                "rigid"
            },
            self.declared.calibration.n,
            self.declared.validation.n,
            if self.measurements == "partial" {
                format!(
                    " (partial measurements: errors across the path and out of the sheet; {} outlier samples left out)",
                    self.outliers_left_out
                )
            } else {
                String::new()
            }
        );
        let _ = writeln!(
            s,
            "{:<28} {:>12} {:>12} {:>10}  parameters",
            "step", "cal mean mm", "val mean mm", "p-value"
        );
        let _ = writeln!(
            s,
            "{:<28} {:>12.4} {:>12.4} {:>10}  {}",
            "declared model",
            self.declared.calibration.mean_mm,
            self.declared.validation.mean_mm,
            "-",
            if self.declared_unidentifiable.is_empty() {
                String::new()
            } else {
                format!(
                    "(unidentifiable: {})",
                    self.declared_unidentifiable.join(", ")
                )
            }
        );
        for e in &self.effects {
            let _ = writeln!(
                s,
                "{:<28} {:>12.4} {:>12.4} {:>10.1e}  {}",
                format!("+ {}", e.id),
                e.calibration_mean_mm_after,
                e.validation_mean_mm_after,
                e.p_value,
                fmt_params(&e.parameters)
            );
        }
        for e in &self.effects {
            if !e.equivalent.is_empty() {
                let _ = writeln!(
                    s,
                    "  {} and {} explain the same residual within noise: equivalent on these poses (the simplest was taken)",
                    e.id,
                    e.equivalent.join(", ")
                );
            }
        }
        if let Some(x) = &self.simplest {
            let _ = writeln!(
                s,
                "  simplest explanation: {} ({} effects) does as well as the greedy {} ({}): cross-validated mean {:.4} vs {:.4} mm, BIC {:+.1}; taken{}",
                x.taken.join(" + "),
                x.taken.len(),
                x.greedy.join(" + "),
                x.greedy.len(),
                x.cv_mean_mm_taken,
                x.cv_mean_mm_greedy,
                x.delta_bic,
                if x.close.is_empty() {
                    String::new()
                } else {
                    format!(" (also close: {})", x.close.join("; "))
                }
            );
        }
        if self.effects.is_empty() {
            let _ = writeln!(s, "{}", no_effect_line(&self.verdict.kind));
        }
        let _ = writeln!(
            s,
            "{:<28} {:>12.4} {:>12.4}",
            "final", self.final_.calibration.mean_mm, self.final_.validation.mean_mm
        );
        let _ = writeln!(
            s,
            "verdict: {}: {}; floor: {}",
            self.verdict.kind,
            note_without_kind(&self.verdict.kind, &self.verdict.note),
            self.floor.note
        );
        if !self.aliased.is_empty() {
            let _ = writeln!(
                s,
                "not separable on these poses (more poses are needed: rigctl plan --from-diagnose):"
            );
            let max = crate::diagnose::alias::ALIAS_TEXT_MAX;
            for a in self.aliased.iter().take(max) {
                let tested = if a.tested { " (tested, rejected)" } else { "" };
                let _ = writeln!(s, "  {} ~ {}{tested}: {}", a.a, a.b, a.note);
            }
            if self.aliased.len() > max {
                let _ = writeln!(
                    s,
                    "  ... and {} more pairs, weaker or with declared parameters (all in the JSON `aliased`)",
                    self.aliased.len() - max
                );
            }
        }
        if !self.bounds.is_empty() {
            let _ = writeln!(
                s,
                "physical bounds: {}",
                crate::diagnose::bounds::sentence(&self.bounds)
            );
        }
        if let Some(h) = &self.residual_model {
            let _ = writeln!(
                s,
                "{:<28} {:>12} {:>12.4}  (residual model {}, not a physical effect)",
                "hybrid",
                "-",
                h.validation_hybrid.mean_mm,
                if h.terms.is_empty() {
                    "with no term".to_string()
                } else {
                    h.terms.join(" + ")
                }
            );
        }
        let _ = writeln!(
            s,
            "unexplained: structured = {}; {}",
            self.unexplained.structured, self.unexplained.note
        );
        for (label, list) in [
            ("outlier", &self.outliers),
            ("kept", &self.within_uncertainty),
        ] {
            for o in list {
                let _ = writeln!(
                    s,
                    "{label}: {} line {}: {}",
                    o.pose.file,
                    o.pose.line_and_id(),
                    o.note
                );
            }
        }
        if !self.outliers.is_empty() {
            let _ = writeln!(
                s,
                "the statistics leave these {} pose(s) out (--keep-outliers keeps every pose)",
                self.outliers.len()
            );
        }
        let all = &self.final_.validation_all;
        if all.n != self.final_.validation.n {
            let _ = writeln!(
                s,
                "held out over all {} poses (the listed ones included): mean {:.4} mm (declared model {:.4} mm)",
                all.n, all.mean_mm, self.declared.validation_all.mean_mm
            );
        }
        if let Some(note) = &self.outlier_note {
            let _ = writeln!(s, "gross errors: {note}");
        }
        s
    }
}

/// A verdict's note without the words of its kind in front ("overfitting: ..." after
/// `verdict: overfitting:`), so the text line names the kind once.
fn note_without_kind<'a>(kind: &str, note: &'a str) -> &'a str {
    let words = kind.replace('_', " ");
    ["", "a ", "at the "]
        .iter()
        .find_map(|lead| note.strip_prefix(&format!("{lead}{words}: ")))
        .unwrap_or(note)
}

#[cfg(test)]
mod where_to_look_tests {
    use super::*;

    #[test]
    fn the_verdict_line_names_its_kind_once() {
        assert_eq!(
            note_without_kind("overfitting", "overfitting: the calibration residual"),
            "the calibration residual"
        );
        assert_eq!(
            note_without_kind("missing_effect", "a missing effect: the model still lacks"),
            "the model still lacks"
        );
        assert_eq!(note_without_kind("floor", "at the floor: 1.0 x"), "1.0 x");
        assert_eq!(
            note_without_kind("instrument", "consistent with"),
            "consistent with"
        );
    }

    #[test]
    fn names_the_variables_of_the_strongest_regressors() {
        assert_eq!(variable_of("sin/cos(2 q6)").as_deref(), Some("q6"));
        assert_eq!(variable_of("t").as_deref(), Some("t"));
        assert_eq!(variable_of("tau_j2"), None);
        let mut u = Unexplained {
            structured: true,
            note: String::new(),
            depends_on: Vec::new(),
            explainable_share: 0.0,
            depends_on_shares: Vec::new(),
        };
        u.add_where_to_look(&[
            ("q1".into(), 0.01),
            ("sin/cos(1 q3)".into(), 0.2),
            ("q3".into(), 0.1),
            ("tau_j2".into(), 0.5),
            ("q5".into(), 0.05),
        ]);
        assert_eq!(u.depends_on, ["q3", "q5"]);
        assert!(u.note.contains("where to look: q3 (20 %"), "{}", u.note);
    }
}
