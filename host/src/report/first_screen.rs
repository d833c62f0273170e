//! The first screen of the page, before any table, built as data ([`Summary`]): the robot and
//! the data, the error before -> after as sentences and a small bar chart, each effect found
//! with its values, sigma and evidence in words, the floor verdict, aliased pairs, and what to
//! do next. Its HTML is [`super::first_screen_html`].

use std::fmt::Write as _;

use serde_json::Value;

use super::answer::{best_stage, identified, one_sentence, urdf_accuracy};
use super::diagnosis_words::{aliased, found_effects, verdict};
use super::markup::figure_with;
use super::run_dir::RunDir;
use super::suggest::Suggest;
use super::summary::{headlines, Diagnosis, Headline, Stage, Summary};
use super::tree::{TreeFacts, POINTS};
use super::Report;
use crate::plot::summary::fmt_mm;
use crate::plot::StageBars;

fn about(
    run: &RunDir,
    robot: Option<&str>,
    tree: Option<&TreeFacts>,
    noun_of: &dyn Fn(usize) -> &'static str,
) -> Vec<String> {
    let mut out = Vec::new();
    let mut r = match tree {
        Some(t) => t.robot_line().trim_end_matches('.').to_string(),
        None => format!("Robot: {}", robot.unwrap_or("katana450 (default)")),
    };
    if let Some(t) = &run.truth_json {
        let mut facts = Vec::new();
        if let Some(s) = t.get("seed") {
            facts.push(format!("seed {s}"));
        }
        if let Some(n) = t.get("noise_mm").and_then(Value::as_f64) {
            facts.push(format!("noise {n} mm"));
        }
        match t.get("effects") {
            Some(Value::Array(a)) if !a.is_empty() => facts.push(format!(
                "undeclared effects put in: {}",
                a.iter().map(effect_text).collect::<Vec<_>>().join(", ")
            )),
            Some(Value::Object(o)) if !o.is_empty() => facts.push(format!(
                "undeclared effects put in: {}",
                o.iter()
                    .map(|(k, v)| format!("{k}={}", super::docs::compact(v)))
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
            _ => {}
        }
        let _ = write!(r, ", simulated ({})", facts.join(", "));
    }
    r.push('.');
    out.push(r);
    let n_of = |d: &Value, set: &str, k: &str| {
        d.get(k)
            .and_then(|v| v.get(set))
            .and_then(|s| s.get("n"))
            .and_then(Value::as_u64)
    };
    for (name, d) in &run.calibrate {
        let method = d.get("method").and_then(Value::as_str).unwrap_or("?");
        let Some(n) = n_of(d, "before", "calibration").or_else(|| {
            d.get("calibration")
                .and_then(|c| c.get("before"))
                .and_then(|s| s.get("n"))
                .and_then(Value::as_u64)
        }) else {
            continue;
        };
        let n = n as usize;
        let v = d
            .get("validation")
            .and_then(|c| c.get("before"))
            .and_then(|s| s.get("n"))
            .and_then(Value::as_u64);
        out.push(format!(
            "{name}: {method} calibration on {n} {}{}.",
            noun_of(n),
            v.map_or_else(
                || ", nothing held out".to_string(),
                |m| format!(", checked on {m} held-out {}", noun_of(m as usize))
            )
        ));
    }
    for (name, d) in &run.diagnose {
        let partial = d.get("measurements").and_then(Value::as_str) == Some("partial");
        let noun = if partial {
            "samples (partial measurements along a drawn path)"
        } else if tree.is_some() {
            POINTS
        } else {
            "poses"
        };
        let c = n_of(d, "calibration", "declared");
        let v = n_of(d, "validation", "declared");
        if let Some(c) = c {
            out.push(format!(
                "{name}: diagnosis on {c} {noun}{}.",
                v.map_or_else(String::new, |v| format!(", {v} held out"))
            ));
        }
    }
    out
}

/// A `truth.json` effect: `id=values` when it has them, else the JSON as written.
fn effect_text(e: &Value) -> String {
    match (
        e.get("id").and_then(Value::as_str),
        e.get("values").and_then(Value::as_array),
    ) {
        (Some(id), Some(v)) => format!(
            "{id}={}",
            v.iter()
                .map(super::docs::compact)
                .collect::<Vec<_>>()
                .join(",")
        ),
        (Some(id), None) => id.to_string(),
        _ => super::docs::compact(e),
    }
}

fn path_error_headline(report: &Report) -> Option<Headline> {
    let p = report.path_errors.as_ref()?;
    let s = &p.summary;
    let stage = |label: &str, x: &crate::plot::path_errors::SetSummary| Stage {
        label: label.to_string(),
        mean_mm: x.dp_mean_mm,
        rms_mm: x.dp_rms_mm,
        source: p.source.clone(),
    };
    Some(Headline {
        set: format!(
            "{} calibration samples along the drawn path (fitted, not held out)",
            s.n_samples
        ),
        held_out: false,
        n: s.n_samples,
        unregistered: None,
        stages: vec![
            stage("nominal model", &s.before),
            stage("calibrated model (standard)", &s.standard),
            stage(
                &format!(
                    "calibrated model {}",
                    p.after_label.trim_start_matches("after ")
                ),
                &s.after,
            ),
        ],
    })
}

/// One pose left out as a gross error: `FILE line N id ID (E mm)`.
fn outlier_text(o: &serde_json::Value) -> String {
    format!(
        "{} line {}{} ({} mm)",
        o.get("file")
            .and_then(serde_json::Value::as_str)
            .unwrap_or("?"),
        o.get("line")
            .and_then(serde_json::Value::as_u64)
            .map_or_else(|| "?".to_string(), |l| l.to_string()),
        o.get("id")
            .and_then(serde_json::Value::as_str)
            .map_or_else(String::new, |i| format!(" id {i}")),
        o.get("error_mm")
            .and_then(serde_json::Value::as_f64)
            .map_or_else(|| "?".to_string(), |e| format!("{e:.3}"))
    )
}

/// The next steps a diagnosis `d` calls for (overfitting, a change between the sets, something
/// left open), appended to `out`.
fn diagnosis_steps(d: &Diagnosis, suggest: &Suggest, out: &mut Vec<String>) {
    let lacking = d
        .verdict
        .as_deref()
        .is_some_and(|v| v.starts_with("The model still lacks"));
    let v = d.verdict.as_deref().unwrap_or("");
    if v.starts_with("Overfitting") {
        out.push(format!(
            "{}: the poses are too few for the parameters fitted. Measure more poses (`{}`) or fit fewer parameters.",
            d.source,
            suggest.plan("")
        ));
    } else if v.starts_with("A change between the sets") {
        out.push(format!(
            "{}: the held-out poses differ from the calibration poses. Check what changed between the two sets (tool mounting, base, temperature, day) before trusting either.",
            d.source
        ));
    }
    if !d.aliased.is_empty() {
        out.push(format!(
            "Measure poses that separate what {} leaves open: `{}`, then measure them and run diagnose again.",
            d.source,
            suggest.plan_from_diagnose(&d.source)
        ));
    } else if lacking {
        out.push(format!(
            "{}: the model still lacks something no effect names yet: measure more poses (`{}`) and run diagnose again.",
            d.source,
            suggest.plan_more()
        ));
    }
}

fn next_steps(
    run: &RunDir,
    suggest: &Suggest,
    report: &Report,
    diags: &[Diagnosis],
    held_out_missing: bool,
) -> Vec<String> {
    let mut out = Vec::new();
    // poses left out as gross errors, by any document
    for (name, doc) in run.calibrate.iter().chain(&run.diagnose) {
        let listed: Vec<String> = doc
            .get("outliers")
            .and_then(serde_json::Value::as_array)
            .map(|a| a.iter().map(outlier_text).collect())
            .unwrap_or_default();
        if !listed.is_empty() {
            out.push(format!(
                "{name} left {} pose(s) out as gross errors (their error is inconsistent with the others; the numbers above are without them): {}. Check these measurements.",
                listed.len(),
                listed.join(", ")
            ));
        }
    }
    for d in diags {
        diagnosis_steps(d, suggest, &mut out);
    }
    let extended: Vec<&str> = run
        .models
        .iter()
        .filter_map(|p| p.file_name().and_then(|n| n.to_str()))
        .filter(|n| n.contains("extended"))
        .collect();
    if diags.iter().any(|d| !d.effects.is_empty()) {
        if let Some(m) = extended.first() {
            out.push(format!("Use the extended model `{m}` (the declared model plus the effects found) instead of the calibrated one."));
        }
    }
    let unident: Vec<&str> = report
        .parameters
        .iter()
        .flat_map(|p| p.unidentifiable.iter().map(String::as_str))
        .collect();
    if !unident.is_empty() {
        out.push(format!(
            "Not identifiable from these poses: {}. `{}` says which of them no pose can identify (structural combinations: keep one parameter of each fixed) and chooses poses that identify the others.",
            unident.join(", "),
            suggest.plan("")
        ));
    }
    if run.diagnose.is_empty() && (run.cal_csv.is_some() || !run.calibrate.is_empty()) {
        out.push(match suggest.diagnose() {
            Some(c) => format!("Look for effects the declared model lacks: `{c}`."),
            None => "Look for effects the declared model lacks: `rigctl diagnose` with the calibration poses and a held-out set (`--validate`).".into(),
        });
    }
    if held_out_missing {
        out.push("Nothing was held out: measure a second set (poses or another sheet) and pass it as `--validate`, so that the error to expect is known.".into());
    }
    let all_at_floor = diags
        .iter()
        .all(|d| d.verdict.as_deref().is_none_or(|v| v.starts_with("At the")));
    if out.is_empty() && !diags.is_empty() && all_at_floor {
        out.push("Nothing left to find in these data: the model explains them down to the measurement floor.".into());
    }
    out
}

/// The first screen of `report`'s run directory `run`.
pub(crate) fn build_summary(
    run: &RunDir,
    robot: Option<&str>,
    tree: Option<&TreeFacts>,
    suggest: &Suggest,
    report: &Report,
    noun_of: &dyn Fn(usize) -> &'static str,
    notes: &mut Vec<String>,
) -> Summary {
    let mut heads = headlines(&run.calibrate, &run.diagnose, noun_of);
    if heads.is_empty() {
        heads.extend(path_error_headline(report));
    }
    let floor = run.diagnose.iter().find_map(|(_, d)| floor_of(d));
    let fig = heads.first().and_then(|h| {
        figure_with(
            stage_caption(h, floor.as_ref()),
            &StageBars {
                title: format!("Error on {}", h.set),
                stages: h.stages.iter().map(|s| s.label.clone()).collect(),
                mean_mm: h.stages.iter().map(|s| s.mean_mm).collect(),
                rms_mm: h.stages.iter().map(|s| s.rms_mm).collect(),
                floor_mm: floor.clone(),
            },
            vec![
                (
                    "mean".to_string(),
                    h.stages.iter().map(|s| s.mean_mm).collect(),
                ),
                (
                    "rms".to_string(),
                    h.stages.iter().map(|s| s.rms_mm).collect(),
                ),
                ("floor".to_string(), floor.iter().map(|f| f.1).collect()),
            ],
            notes,
        )
    });
    let diagnoses: Vec<Diagnosis> = run
        .diagnose
        .iter()
        .map(|(name, doc)| Diagnosis {
            source: name.clone(),
            noun: if doc.get("measurements").and_then(Value::as_str) == Some("partial") {
                "samples"
            } else if tree.is_some() {
                POINTS
            } else {
                "poses"
            },
            effects: found_effects(doc),
            verdict: verdict(doc),
            aliased: aliased(doc),
        })
        .collect();
    let held_out_missing = !heads.iter().any(|h| h.held_out);
    let next = next_steps(run, suggest, report, &diagnoses, held_out_missing);
    let model_file = chosen_model_file(run, heads.first());
    let sentence = one_sentence(
        heads.first(),
        &diagnoses,
        model_file.as_deref(),
        robot.unwrap_or("robot"),
    );
    let urdf = heads
        .first()
        .and_then(|h| urdf_accuracy(h, &run.calibrate, &run.diagnose));
    Summary {
        about: about(run, robot, tree, noun_of),
        headlines: heads,
        figure: fig,
        diagnoses,
        next_steps: next,
        sentence,
        identified: run
            .calibrate
            .iter()
            .filter_map(|(n, d)| identified(n, d))
            .collect(),
        urdf,
    }
}

/// The floor a diagnosis judged the residual against: its name and the RMS Euclidean error it
/// alone gives (mm), drawn as a line on the stage chart: the floor is one sigma per
/// coordinate, the chart's errors are Euclidean (RMS sqrt(3) x the per-coordinate sigma).
fn floor_of(d: &Value) -> Option<(String, f64)> {
    let fl = d.get("floor")?;
    let used = fl.get("used").and_then(Value::as_str).unwrap_or("residual");
    let key = match used {
        "instrument" => "instrument_mm",
        "repeatability" => "repeatability_mm",
        _ => "residual_mm",
    };
    let v = fl.get(key).and_then(Value::as_f64)?;
    Some((used.to_string(), v * 3f64.sqrt()))
}

/// The stage chart's caption, true to its bars: whether each stage lowers the error, and
/// where the last stage stands against the floor.
fn stage_caption(h: &Headline, floor: Option<&(String, f64)>) -> String {
    let lowers = h.stages.windows(2).all(|w| w[1].mean_mm <= w[0].mean_mm);
    let mut c = format!(
        "Error on {} at each stage, from the top (mean and RMS, logarithmic axis){}",
        h.set,
        if h.stages.len() < 2 {
            ".".to_string()
        } else if lowers {
            ": each stage lowers it.".to_string()
        } else {
            ": not every stage lowers it on these poses (a bar longer than the one above it is a stage that made the error worse here).".to_string()
        }
    );
    if let (Some((name, f)), Some(last)) = (floor, h.stages.last()) {
        c.push_str(&format!(
            " Dashed: the RMS error the {name} floor alone gives, {} mm; the last stage's RMS is {:.1} x it.",
            fmt_mm(*f),
            last.rms_mm / f
        ));
    }
    c
}

/// The model file to use: that of the best stage's document, the extended model for a
/// diagnosis (`*extended*.toml`), else a calibrated one (`*calibrated*.toml`).
fn chosen_model_file(run: &RunDir, h: Option<&Headline>) -> Option<String> {
    let names: Vec<String> = run
        .models
        .iter()
        .filter_map(|p| p.file_name().and_then(|n| n.to_str()).map(String::from))
        .collect();
    let best = h.and_then(best_stage)?;
    let from_diagnosis = run.diagnose.iter().any(|(n, _)| *n == best.source);
    let want = if from_diagnosis {
        "extended"
    } else {
        "calibrated"
    };
    names.iter().find(|n| n.contains(want)).cloned()
}
