//! The top of the first screen: the one sentence (how good now, what was wrong, what to do),
//! the verdict in one line, "N of M parameters identified", and the held-out error a ROS user
//! gets through the exported URDF (geometry only) beside the best model's.

use serde_json::Value;

use super::summary::{stage_words, Diagnosis, Headline, Stage};
use crate::plot::summary::fmt_mm;

/// How many of a calibration's parameters the poses identified.
#[derive(Debug, Clone, PartialEq)]
pub struct Identified {
    /// The `calibrate*.json` document.
    pub source: String,
    /// Parameters fitted (finite sigma).
    pub identified: usize,
    /// Parameters in the selection (fitted and kept at their input value).
    pub total: usize,
    /// The parameters kept at their input value (not identifiable from these poses).
    pub kept: Vec<String>,
    /// The combinations the poses see only together (`unidentifiable`).
    pub combinations: Vec<String>,
}

/// "N of M parameters identified" of a `calibrate --json` document (`parameters`, `fixed`,
/// `unidentifiable`).
pub fn identified(source: &str, doc: &Value) -> Option<Identified> {
    let total = doc.get("parameters")?.as_object()?.len();
    let strings = |k: &str| super::markup::strings(doc.get(k));
    let kept = strings("fixed");
    Some(Identified {
        source: source.to_string(),
        identified: total.saturating_sub(kept.len()),
        total,
        kept,
        combinations: strings("unidentifiable"),
    })
}

/// The held-out error through the exported URDF (the geometry-only calibration) and through
/// the best model, when they differ.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfAccuracy {
    /// The geometry-only calibration (`standard` of a `calibrate*.json`), which a URDF holds.
    pub urdf: Stage,
    /// The best model of the run (the last stage of the headline).
    pub model: Stage,
    /// What the best model has that a URDF cannot hold.
    pub lacks: Vec<String>,
}

/// Whether a URDF holds the effect (the effect table's `urdf_holds`: frames and joint
/// origins); an id the table does not know is taken as not held.
fn urdf_holds(effect_id: &str) -> bool {
    effect_id
        .parse::<crate::model::effect::EffectId>()
        .is_ok_and(|e| e.row().urdf_holds)
}

/// What a document's model holds that a URDF cannot: non-geometric effects found by a
/// diagnosis, a calibration's tilting or its fitted terms (compliance).
fn beyond_urdf(doc: &Value) -> Vec<String> {
    let mut out: Vec<String> = doc
        .get("effects")
        .and_then(Value::as_array)
        .map(|a| {
            a.iter()
                .filter_map(|e| e.get("id").and_then(Value::as_str))
                .filter(|id| !urdf_holds(id))
                .map(String::from)
                .collect()
        })
        .unwrap_or_default();
    if doc.get("tilting_applied").and_then(Value::as_bool) == Some(true) {
        out.push("tilting".to_string());
    }
    if let Some(terms) = doc.get("terms").and_then(Value::as_object) {
        out.extend(
            terms
                .keys()
                .filter(|k| k.starts_with("compliance") || k.contains("compliance"))
                .cloned(),
        );
    }
    out
}

/// Whether a calibrate document's `standard` fit is geometry only (no fitted compliance term:
/// `--compliance` puts them in the standard fit too; a chain's are `terms`, a tree's
/// `parameters`).
fn standard_is_geometry(doc: &Value) -> bool {
    ["terms", "parameters"].iter().all(|key| {
        doc.get(key)
            .and_then(Value::as_object)
            .is_none_or(|t| !t.keys().any(|k| k.contains("compliance")))
    })
}

/// The best stage of a headline: the lowest mean error after the first (the "before").
pub fn best_stage(h: &Headline) -> Option<&Stage> {
    h.stages
        .iter()
        .skip(1)
        .min_by(|a, b| a.mean_mm.total_cmp(&b.mean_mm))
}

/// The URDF's held-out error beside the best model's, when the best model holds something a
/// URDF cannot and is better by more than 5 %. The URDF's figure is the geometry-only
/// calibration: `standard` of a `calibrate*.json` without compliance terms, else the
/// diagnosis's calibrated declared model when no calibration applied tilting (the declared
/// model then has none).
pub fn urdf_accuracy(
    h: &Headline,
    calibrate: &[(String, Value)],
    diagnose: &[(String, Value)],
) -> Option<UrdfAccuracy> {
    let model = best_stage(h)?.clone();
    let set = if h.held_out {
        "validation"
    } else {
        "calibration"
    };
    let tilting = calibrate
        .iter()
        .any(|(_, d)| d.get("tilting_applied").and_then(Value::as_bool) == Some(true));
    let of_n = |s: &Value| s.get("n").and_then(Value::as_u64) == Some(h.n as u64);
    let from_calibrate = calibrate.iter().find_map(|(name, d)| {
        let s = d.get("standard")?.get(set)?;
        (standard_is_geometry(d) && of_n(s)).then_some((
            name,
            s,
            "calibrated geometry (standard fit)",
        ))
    });
    let from_diagnose = || {
        diagnose.iter().find_map(|(name, d)| {
            let s = d.get("declared")?.get(set)?;
            (!tilting && of_n(s)).then_some((name, s, "calibrated declared model"))
        })
    };
    let (name, geo, label) = from_calibrate.or_else(from_diagnose)?;
    let urdf = Stage {
        label: label.to_string(),
        mean_mm: geo.get("mean_mm")?.as_f64()?,
        rms_mm: geo.get("rms_mm")?.as_f64()?,
        source: name.clone(),
    };
    let doc = calibrate
        .iter()
        .chain(diagnose)
        .find(|(n, _)| *n == model.source)
        .map(|(_, d)| d)?;
    let mut lacks = beyond_urdf(doc);
    // the declared model's tilting (a calibration that applied it) is in a diagnosis's model too
    if tilting && !lacks.iter().any(|l| l == "tilting") {
        lacks.push("tilting".to_string());
    }
    let better = model.mean_mm < 0.95 * urdf.mean_mm;
    (!lacks.is_empty() && better).then_some(UrdfAccuracy { urdf, model, lacks })
}

/// The verdict's first clause, for one line: up to the first " (" or "; " after its head.
pub fn verdict_line(v: &str) -> String {
    let cut = [" (", "; "]
        .iter()
        .filter_map(|p| v.find(p))
        .min()
        .unwrap_or(v.len());
    let head = v[..cut].trim_end_matches(['.', ':']);
    format!("{head}.")
}

/// The one sentence: how good now, what was wrong, what to do.
pub fn one_sentence(
    h: Option<&Headline>,
    diags: &[Diagnosis],
    model_file: Option<&str>,
    robot_noun: &str,
) -> String {
    let Some(h) = h else {
        return "No error statistics in this run directory: run calibrate with --json (and diagnose) in it.".to_string();
    };
    let (Some(first), Some(last)) = (h.stages.first(), best_stage(h).or(h.stages.first())) else {
        return String::new();
    };
    let now = if h.stages.len() > 1 {
        format!(
            "{} mm mean error on {} now with {} (was {} mm with {})",
            fmt_mm(last.mean_mm),
            h.set,
            stage_words(&last.label),
            fmt_mm(first.mean_mm),
            stage_words(&first.label)
        )
    } else {
        format!("{} mm mean error on {}", fmt_mm(last.mean_mm), h.set)
    };
    let effects: Vec<&str> = diags
        .iter()
        .flat_map(|d| d.effects.iter().map(|e| e.id.as_str()))
        .collect();
    let wrong = if !effects.is_empty() {
        format!(
            "the declared model of the {robot_noun} lacked {}",
            list_words(&effects)
        )
    } else if !diags.is_empty() {
        "nothing beyond the calibrated geometry was found".to_string()
    } else if h.stages.len() > 1 {
        format!(
            "the calibrated geometry removes {:.0} % of it",
            100.0 * (1.0 - last.mean_mm / first.mean_mm.max(1e-300))
        )
    } else {
        "only one model was evaluated".to_string()
    };
    let verdicts: Vec<&str> = diags.iter().filter_map(|d| d.verdict.as_deref()).collect();
    let todo = if !h.held_out {
        "measure a held-out set to know the error to expect".to_string()
    } else if verdicts.iter().any(|v| v.starts_with("Overfitting")) {
        "measure more poses or fit fewer parameters".to_string()
    } else if verdicts.iter().any(|v| v.starts_with("A change between")) {
        "check what changed between the two sets before trusting either".to_string()
    } else if verdicts
        .iter()
        .any(|v| v.starts_with("The model still lacks"))
    {
        match model_file {
            Some(m) => format!(
                "use {m}; something is still missing: measure poses that separate it (below)"
            ),
            None => {
                "something is still missing: measure poses that separate it (below)".to_string()
            }
        }
    } else if diags.is_empty() {
        match model_file {
            Some(m) => format!("use {m}, and run diagnose to look for what the model lacks"),
            None => "run diagnose to look for what the model lacks".to_string(),
        }
    } else {
        match model_file {
            Some(m) => format!("use {m}: nothing is left to find in these data"),
            None => "nothing is left to find in these data".to_string(),
        }
    };
    let mut s = format!("{now}: {wrong}; {todo}.");
    if let Some(c) = s.get(..1) {
        s = c.to_uppercase() + &s[1..];
    }
    s
}

/// `a`, `a and b`, `a, b and c`; more than four as `a, b, c and N more`.
fn list_words(items: &[&str]) -> String {
    match items {
        [] => String::new(),
        [a] => (*a).to_string(),
        _ if items.len() > 4 => format!("{} and {} more", items[..3].join(", "), items.len() - 3),
        _ => format!(
            "{} and {}",
            items[..items.len() - 1].join(", "),
            items[items.len() - 1]
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdict_line_keeps_the_head() {
        assert_eq!(
            verdict_line("The model still lacks something: the residual depends on q3:q4 (4 % of it explainable) (final residual 3.82 x)."),
            "The model still lacks something: the residual depends on q3:q4."
        );
        assert_eq!(
            verdict_line("At the instrument floor (final residual 1.02 x the instrument floor of 0.0150 mm): the residual left has no structure."),
            "At the instrument floor."
        );
    }

    #[test]
    fn identified_counts_the_kept_parameters() {
        let d = serde_json::json!({"parameters": {"a": 1.0, "b": 2.0, "c": 3.0},
            "fixed": ["c"], "unidentifiable": ["c+b"]});
        let i = identified("calibrate.json", &d).unwrap();
        assert_eq!((i.identified, i.total), (2, 3));
        assert_eq!(i.combinations, vec!["c+b".to_string()]);
    }

    #[test]
    fn lists_read_as_words() {
        assert_eq!(list_words(&["a", "b", "c"]), "a, b and c");
        assert_eq!(list_words(&["a", "b", "c", "d", "e"]), "a, b, c and 2 more");
    }
}
