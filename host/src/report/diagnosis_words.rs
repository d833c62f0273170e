//! A diagnose document in words, for the first screen ([`super::summary`]): each effect found
//! with its evidence, the floor verdict, the aliased pairs.

use serde_json::Value;

use super::summary::{f, pct, AliasedPair, FoundEffect};
use crate::plot::summary::fmt_mm;

/// The effects of a diagnose document, each with its evidence in words.
pub fn found_effects(doc: &Value) -> Vec<FoundEffect> {
    let Some(list) = doc.get("effects").and_then(Value::as_array) else {
        return Vec::new();
    };
    list.iter()
        .map(|e| {
            let sigma = e
                .get("sigma")
                .or_else(|| e.get("uncertainty"))
                .and_then(Value::as_object);
            let values = e
                .get("parameters")
                .and_then(Value::as_object)
                .map(|o| {
                    o.iter()
                        .filter_map(|(k, v)| {
                            let s = sigma.and_then(|s| s.get(k)).and_then(Value::as_f64);
                            Some((k.clone(), v.as_f64()?, s))
                        })
                        .collect()
                })
                .unwrap_or_default();
            FoundEffect {
                id: e
                    .get("id")
                    .and_then(Value::as_str)
                    .unwrap_or("?")
                    .to_string(),
                values,
                evidence: evidence_words(e),
            }
        })
        .collect()
}

fn evidence_words(e: &Value) -> String {
    let mut parts = Vec::new();
    if let (Some(b), Some(a)) = (
        f(e, "validation_mean_mm_before"),
        f(e, "validation_mean_mm_after"),
    ) {
        match pct(b, a) {
            Some(p) if p >= 0.0 => parts.push(format!(
                "removes {p:.0} % of the held-out mean error ({} -> {} mm)",
                fmt_mm(b),
                fmt_mm(a)
            )),
            _ => parts.push(format!(
                "held-out mean error {} -> {} mm (not lower)",
                fmt_mm(b),
                fmt_mm(a)
            )),
        }
    }
    if let (Some(b), Some(a)) = (f(e, "cv_mean_mm_before"), f(e, "cv_mean_mm_after")) {
        parts.push(format!("cross-validated {} -> {} mm", fmt_mm(b), fmt_mm(a)));
    }
    if let Some(p) = f(e, "p_value") {
        if p < 1e-16 {
            parts.push("F-test p < 1e-16".to_string());
        } else {
            parts.push(format!("F-test p = {p:.1e}"));
        }
    }
    if let Some(d) = f(e, "delta_bic") {
        parts.push(format!("BIC {d:+.1}"));
    }
    if parts.is_empty() {
        e.get("evidence")
            .and_then(Value::as_str)
            .unwrap_or("")
            .to_string()
    } else {
        parts.join("; ")
    }
}

/// The floor verdict of a diagnose document: at the floor, or what the model still lacks.
pub fn verdict(doc: &Value) -> Option<String> {
    let un = doc.get("unexplained");
    let structured = un
        .and_then(|u| u.get("structured"))
        .and_then(Value::as_bool);
    let depends = super::markup::strings(un.and_then(|u| u.get("depends_on")));
    let share = un.and_then(|u| f(u, "explainable_share"));
    let (used, floor_words) = floor_words(doc);
    let structured = structured?;
    if doc.get("converged").and_then(Value::as_bool) == Some(false) {
        return Some(format!(
            "The final fit did not converge (its iteration budget was spent while it still \
             improved): no verdict{floor_words}."
        ));
    }
    let verdict = doc.get("verdict");
    let kind = verdict.and_then(|v| v.get("kind")).and_then(Value::as_str);
    match kind {
        Some("overfitting") => {
            let counts = parameter_counts(verdict);
            return Some(format!(
                "Overfitting: the calibration residual is at the floor but the poses left out are not{floor_words}{counts}. Measure more poses or fit fewer parameters."
            ));
        }
        Some("instrument") => {
            return Some(format!(
                "Consistent with a worse instrument than stated{floor_words}: what is left has no structure that a smooth function of the joint angles or the time explains. Check the instrument figure by measuring some poses twice."
            ));
        }
        Some("change_between_sets") => {
            return Some(format!(
                "A change between the sets: the calibration poses and their cross-validation are at the floor, the held-out set is not{floor_words} (drift, another day, another tool mounting or base)."
            ));
        }
        Some("floor") => {
            let mut s = format!("At the {used} floor{floor_words}");
            if structured && !depends.is_empty() {
                s.push_str(&format!(
                    "; a smooth function of {} still explains part of the residual out of sample, below what the floor test can call missing",
                    depends.join(", ")
                ));
            } else {
                s.push_str(": the residual left has no structure");
            }
            s.push('.');
            return Some(s);
        }
        _ => {}
    }
    if !structured {
        return Some(format!(
            "At the {used} floor: the residual left has no structure{floor_words}."
        ));
    }
    let mut s = String::from("The model still lacks something");
    if !depends.is_empty() {
        s.push_str(&format!(": the residual depends on {}", depends.join(", ")));
        if let Some(x) = share {
            s.push_str(&format!(
                " ({:.0} % of it explainable out of sample)",
                100.0 * x
            ));
        }
    } else if let Some(note) = un.and_then(|u| u.get("note")).and_then(Value::as_str) {
        if !note.is_empty() {
            s.push_str(&format!(": {note}"));
        }
    }
    s.push_str(&floor_words);
    s.push('.');
    Some(s)
}

/// The floor the diagnosis used (`noise`, `instrument`, `repeatability`) and the words of the
/// final residual against it (` (final residual ... x the ... floor ...)`, or the residual
/// sigma when the document has no floor ratio).
fn floor_words(doc: &Value) -> (&str, String) {
    let floor = doc.get("floor");
    let ratio = floor.and_then(|fl| f(fl, "final_over_floor"));
    let used = floor
        .and_then(|fl| fl.get("used"))
        .and_then(Value::as_str)
        .unwrap_or("noise");
    let floor_mm = floor.and_then(|fl| match used {
        "instrument" => f(fl, "instrument_mm"),
        "repeatability" => f(fl, "repeatability_mm"),
        _ => f(fl, "residual_mm"),
    });
    let floor_words = match (ratio, floor_mm) {
        (Some(r), Some(m)) => format!(
            " (final residual {r:.2} x the {used} floor of {} mm)",
            fmt_mm(m)
        ),
        (Some(r), None) => format!(" (final residual {r:.2} x the {used} floor)"),
        _ => doc
            .get("noise")
            .and_then(|n| f(n, "sigma_mm"))
            .map(|s| format!(" (residual sigma {} mm per coordinate)", fmt_mm(s)))
            .unwrap_or_default(),
    };
    (used, floor_words)
}

/// `: P parameters fitted, the poses support about R` of an overfitting verdict.
fn parameter_counts(verdict: Option<&Value>) -> String {
    let fitted = verdict
        .and_then(|v| v.get("fitted_parameters"))
        .and_then(Value::as_u64);
    let supported = verdict
        .and_then(|v| v.get("supported_parameters"))
        .and_then(Value::as_u64);
    match (fitted, supported) {
        (Some(p), Some(r)) => {
            format!(": {p} parameters fitted, the poses support about {r}")
        }
        (Some(p), None) => format!(": {p} parameters fitted"),
        _ => String::new(),
    }
}

/// The aliased pairs of a diagnose document.
pub fn aliased(doc: &Value) -> Vec<AliasedPair> {
    doc.get("aliased")
        .and_then(Value::as_array)
        .map(|a| {
            a.iter()
                .filter_map(|p| {
                    Some(AliasedPair {
                        a: p.get("a")?.as_str()?.to_string(),
                        b: p.get("b")?.as_str()?.to_string(),
                        correlation: f(p, "correlation"),
                        note: p
                            .get("note")
                            .and_then(Value::as_str)
                            .unwrap_or("")
                            .to_string(),
                    })
                })
                .collect()
        })
        .unwrap_or_default()
}
