//! The first screen of the report, as data: the robot and the data, the held-out error at each
//! stage (nominal, calibrated, with the effects found), each effect with its values, sigma and
//! evidence in words, the floor verdict, aliased pairs and what to do next (the diagnose
//! document's words are [`super::diagnosis_words`]'s). Built from the `calibrate*.json` and
//! `diagnose*.json` documents; every key newer than the first FORMATS.md (`floor`, `aliased`,
//! `unexplained.depends_on`, `effects[].sigma`, ...) is optional.

use serde_json::Value;

use super::Figure;
use crate::plot::summary::fmt_mm;

/// Mean and RMS error of one model on one pose or sample set.
#[derive(Debug, Clone, PartialEq)]
pub struct Stage {
    /// What the model is ("nominal model", "calibrated (tilting)", ...).
    pub label: String,
    /// Mean Euclidean error (mm).
    pub mean_mm: f64,
    /// RMS error (mm).
    pub rms_mm: f64,
    /// File the numbers come from.
    pub source: String,
}

/// The error on one set at each stage, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct Headline {
    /// The set, e.g. "60 held-out poses".
    pub set: String,
    /// Whether the set was held out of every fit.
    pub held_out: bool,
    /// Number of poses or samples.
    pub n: usize,
    /// Stages, first = before: the input model with only the instrument frame fitted when a
    /// document has it (`registered`), else the nominal model.
    pub stages: Vec<Stage>,
    /// The input model as it is, the instrument frame not fitted, when the first stage is the
    /// registered one: shown apart (it measures the frames' distance as much as the robot).
    pub unregistered: Option<Stage>,
}

/// One effect found by `diagnose`, in words.
#[derive(Debug, Clone, PartialEq)]
pub struct FoundEffect {
    /// Effect id (FORMATS.md).
    pub id: String,
    /// `(name, value, sigma)` in the final fit.
    pub values: Vec<(String, f64, Option<f64>)>,
    /// The evidence in a sentence.
    pub evidence: String,
}

/// A pair of effects or parameters the data cannot tell apart.
#[derive(Debug, Clone, PartialEq)]
pub struct AliasedPair {
    /// First (an accepted effect or a declared parameter).
    pub a: String,
    /// Second.
    pub b: String,
    /// Correlation of their columns, if given.
    pub correlation: Option<f64>,
    /// Why it matters.
    pub note: String,
}

/// What one diagnosis found.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnosis {
    /// File name.
    pub source: String,
    /// "poses" or "samples".
    pub noun: &'static str,
    /// Effects found, in the order added (empty: nothing found).
    pub effects: Vec<FoundEffect>,
    /// The floor verdict in a sentence.
    pub verdict: Option<String>,
    /// Pairs the data cannot tell apart.
    pub aliased: Vec<AliasedPair>,
}

/// The answer, shown before any table.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Summary {
    /// Robot and where the data come from, one sentence each.
    pub about: Vec<String>,
    /// Error before -> after, one per set (held-out sets first).
    pub headlines: Vec<Headline>,
    /// The chart of the first headline.
    pub figure: Option<Figure>,
    /// One per diagnose document.
    pub diagnoses: Vec<Diagnosis>,
    /// What to do next, one sentence each.
    pub next_steps: Vec<String>,
    /// The answer in one sentence: how good now, what was wrong, what to do.
    pub sentence: String,
    /// "N of M parameters identified", one per calibrate document.
    pub identified: Vec<super::answer::Identified>,
    /// The held-out error through the exported URDF beside the best model's, when they differ.
    pub urdf: Option<super::answer::UrdfAccuracy>,
}

pub(super) fn f(v: &Value, k: &str) -> Option<f64> {
    v.get(k).and_then(Value::as_f64)
}

fn stats(v: Option<&Value>) -> Option<(usize, f64, f64)> {
    let v = v?;
    Some((
        v.get("n")?.as_u64()? as usize,
        f(v, "mean_mm")?,
        f(v, "rms_mm")?,
    ))
}

fn push_stage(h: &mut Headline, label: &str, st: (usize, f64, f64), source: &str) {
    // the same numbers reached by another route (e.g. the declared fit in diagnose and the
    // calibrated declared model) are shown once
    let same = h
        .stages
        .iter()
        .any(|s| (s.mean_mm - st.1).abs() <= 0.02 * s.mean_mm.abs().max(1e-12));
    if !same {
        h.stages.push(Stage {
            label: label.to_string(),
            mean_mm: st.1,
            rms_mm: st.2,
            source: source.to_string(),
        });
    }
}

/// A diagnosis's final stage: the last model it reached, so after its declared fit even when an
/// earlier document reached the same numbers (that stage is taken out, not kept before it).
fn push_last(h: &mut Headline, label: &str, st: (usize, f64, f64), source: &str) {
    h.stages
        .retain(|s| (s.mean_mm - st.1).abs() > 0.02 * s.mean_mm.abs().max(1e-12));
    push_stage(h, label, st, source);
}

fn headline<'a>(
    list: &'a mut Vec<Headline>,
    n: usize,
    held_out: bool,
    noun: &str,
) -> &'a mut Headline {
    let pos = list.iter().position(|h| h.n == n && h.held_out == held_out);
    let k = pos.unwrap_or_else(|| {
        let set = if held_out {
            format!("{n} held-out {noun}")
        } else {
            format!("{n} calibration {noun} (fitted, not held out)")
        };
        list.push(Headline {
            set,
            held_out,
            n,
            stages: Vec::new(),
            unregistered: None,
        });
        list.len() - 1
    });
    &mut list[k]
}

/// The first stage of a run whose instrument frame was fitted (`calibrate --base`).
pub const REGISTERED_LABEL: &str = "input model, frame fitted";

/// A stage's label in a sentence: "the nominal model", "the input model with only the
/// instrument frame fitted", "the 2 effects found".
pub fn stage_words(label: &str) -> String {
    if label == REGISTERED_LABEL {
        "the input model with only the instrument frame fitted".to_string()
    } else if label.starts_with("with ") {
        label.trim_start_matches("with ").to_string()
    } else {
        format!("the {label}")
    }
}

/// Stages from the calibrate documents (nominal, standard, chosen method), then from the
/// diagnosis (declared fit, with the effects found); held-out sets first, then the fitted set
/// of documents that held nothing out; `noun_of(n)` is "poses" or "samples".
pub fn headlines(
    calibrate: &[(String, Value)],
    diagnose: &[(String, Value)],
    noun_of: &dyn Fn(usize) -> &'static str,
) -> Vec<Headline> {
    let mut out: Vec<Headline> = Vec::new();
    for (held_out, set) in [(true, "validation"), (false, "calibration")] {
        for (name, doc) in calibrate {
            let method = doc
                .get("method")
                .and_then(Value::as_str)
                .unwrap_or("chosen");
            // the fitted set only for documents that held nothing out
            if !held_out && doc.get("validation").is_some() {
                continue;
            }
            let Some(ba) = doc.get(set) else { continue };
            let Some(before) = stats(ba.get("before")) else {
                continue;
            };
            let h = headline(&mut out, before.0, held_out, noun_of(before.0));
            let registered = stats(doc.get("registered").and_then(|r| r.get(set)));
            match registered {
                Some(reg) if h.stages.is_empty() => {
                    h.unregistered = Some(Stage {
                        label: "input model as it is (instrument frame not fitted)".to_string(),
                        mean_mm: before.1,
                        rms_mm: before.2,
                        source: name.clone(),
                    });
                    push_stage(h, REGISTERED_LABEL, reg, name);
                }
                _ => push_stage(h, "nominal model", before, name),
            }
            if method != "standard" {
                if let Some(st) = stats(doc.get("standard").and_then(|s| s.get(set))) {
                    push_stage(h, "calibrated model (standard)", st, name);
                }
            }
            if let Some(st) = stats(ba.get("after")) {
                let label = format!("calibrated model ({method}{})", not_converged_words(doc));
                push_stage(h, &label, st, name);
            }
        }
        for (name, doc) in diagnose {
            if !held_out
                && doc
                    .get("declared")
                    .and_then(|d| d.get("validation"))
                    .is_some()
            {
                continue;
            }
            let Some(decl) = stats(doc.get("declared").and_then(|d| d.get(set))) else {
                continue;
            };
            let noun = if doc.get("measurements").and_then(Value::as_str) == Some("partial") {
                "samples"
            } else {
                noun_of(decl.0)
            };
            let h = headline(&mut out, decl.0, held_out, noun);
            push_stage(h, "calibrated declared model", decl, name);
            let n_eff = doc
                .get("effects")
                .and_then(Value::as_array)
                .map_or(0, Vec::len);
            if let Some(fin) = stats(doc.get("final").and_then(|d| d.get(set))) {
                if n_eff > 0 {
                    let label = format!(
                        "with the {n_eff} effect{} found{}",
                        if n_eff == 1 { "" } else { "s" },
                        not_converged_words(doc)
                    );
                    push_last(h, &label, fin, name);
                }
            }
        }
    }
    out.retain(|h| !h.stages.is_empty());
    out
}

/// The sentence of a headline: "On 60 held-out poses the error goes from 1.12 mm (mean;
/// RMS 1.30) with the nominal model to 0.0155 mm (RMS 0.0190) with ...".
pub fn headline_sentence(h: &Headline) -> String {
    let (Some(first), Some(last)) = (h.stages.first(), h.stages.last()) else {
        return String::new();
    };
    if h.stages.len() == 1 {
        return format!(
            "On {}: mean error {} mm, RMS {} mm ({}).",
            h.set,
            fmt_mm(first.mean_mm),
            fmt_mm(first.rms_mm),
            first.label
        );
    }
    let mid: Vec<String> = h.stages[1..h.stages.len() - 1]
        .iter()
        .map(|s| format!("{} {} mm", s.label, fmt_mm(s.mean_mm)))
        .collect();
    format!(
        "On {} the mean error goes from {} mm (RMS {}) with {} to {} mm (RMS {}) {}{}.",
        h.set,
        fmt_mm(first.mean_mm),
        fmt_mm(first.rms_mm),
        stage_words(&first.label),
        fmt_mm(last.mean_mm),
        fmt_mm(last.rms_mm),
        if last.label.starts_with("with") {
            last.label.clone()
        } else {
            format!("with the {}", last.label)
        },
        if mid.is_empty() {
            String::new()
        } else {
            format!(" (in between: {})", mid.join("; "))
        }
    )
}

/// `", not converged"` for a document whose fit stopped on its iteration budget.
fn not_converged_words(doc: &Value) -> &'static str {
    if doc.get("converged").and_then(Value::as_bool) == Some(false) {
        ", not converged"
    } else {
        ""
    }
}

pub(super) fn pct(before: f64, after: f64) -> Option<f64> {
    (before > 0.0 && after.is_finite()).then(|| 100.0 * (before - after) / before)
}
