//! The JSON documents of a run directory as report pieces: identified parameters
//! (`calibrate*.json`), the diagnosis (`diagnose*.json`) and the simulation facts (`truth.json`).

use serde_json::Value;

use super::diagnosis_words::found_effects;
use super::table::{Column, ErrorTable};
use super::{DiagnoseSection, EffectRow, ParamRow, ParamTable};
use crate::model::Model;

pub(crate) fn simulation_facts(t: &Value) -> Vec<(String, String)> {
    [
        "format",
        "seed",
        "robot",
        "noise_mm",
        "tilt",
        "cal_poses",
        "val_poses",
        "effects",
        "time_drift",
    ]
    .iter()
    .filter_map(|k| t.get(*k).map(|v| (k.to_string(), compact(v))))
    .collect()
}

pub(crate) fn compact(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

pub(crate) fn param_table(
    name: &str,
    doc: &Value,
    decl: Option<&Model>,
    truth: Option<&Model>,
) -> Option<ParamTable> {
    let params = doc.get("parameters")?.as_object()?;
    let sigma = doc.get("sigma").and_then(Value::as_object);
    let rows = params
        .iter()
        .filter_map(|(k, v)| {
            Some(ParamRow {
                name: k.clone(),
                value: v.as_f64()?,
                sigma: sigma.and_then(|s| s.get(k)).and_then(Value::as_f64),
                nominal: decl.and_then(|m| m.param(k)),
                truth: truth.and_then(|m| m.param(k)),
                unit: decl.and_then(|m| {
                    m.param_index(k)
                        .map(|i| m.params()[i].unit.label().to_string())
                }),
            })
        })
        .collect();
    Some(ParamTable {
        source: name.to_string(),
        method: doc
            .get("method")
            .and_then(Value::as_str)
            .unwrap_or("")
            .to_string(),
        rows,
        unidentifiable: doc
            .get("unidentifiable")
            .and_then(Value::as_array)
            .map(|a| a.iter().map(compact).collect())
            .unwrap_or_default(),
        condition_number: doc.get("condition_number").and_then(Value::as_f64),
    })
}

/// The diagnose section of one document; `noun` counts its poses ("poses", "samples").
pub(crate) fn diagnose_section(name: &str, doc: &Value) -> DiagnoseSection {
    let partial = doc.get("measurements").and_then(Value::as_str) == Some("partial");
    let noun = if partial { "samples" } else { "poses" };
    let mut tables = Vec::new();
    for set in ["calibration", "validation"] {
        let cols: Vec<(String, Column)> = [
            ("declared", "calibrated declared model"),
            ("final", "with the effects found"),
        ]
        .iter()
        .filter_map(|(k, label)| {
            doc.get(*k)
                .and_then(|s| s.get(set))
                .and_then(Column::from_json)
                .map(|c| (label.to_string(), c))
        })
        .collect();
        if !cols.is_empty() {
            let title = if set == "calibration" {
                format!("Calibration {noun}")
            } else {
                format!("Held-out {noun}")
            };
            tables.push(ErrorTable::new(&title, name, &cols).with_noun(noun));
        }
    }
    let raw = doc.get("effects").and_then(Value::as_array);
    let effects = found_effects(doc)
        .into_iter()
        .enumerate()
        .map(|(k, fe)| {
            let e = raw.and_then(|a| a.get(k));
            let get = |key: &str| e.and_then(|e| e.get(key)).and_then(Value::as_f64);
            EffectRow {
                id: fe.id,
                parameters: fe
                    .values
                    .iter()
                    .map(|(n, v, s)| match s {
                        Some(s) => format!("{n} = {v:.6} \u{b1} {s:.6}"),
                        None => format!("{n} = {v:.6}"),
                    })
                    .collect::<Vec<_>>()
                    .join(", "),
                validation_mean_mm_before: get("validation_mean_mm_before"),
                validation_mean_mm_after: get("validation_mean_mm_after"),
                evidence: e
                    .and_then(|e| e.get("evidence"))
                    .map(compact)
                    .unwrap_or_default(),
            }
        })
        .collect();
    let unexplained = doc
        .get("unexplained")
        .map(|u| {
            let structured = u
                .get("structured")
                .and_then(Value::as_bool)
                .unwrap_or(false);
            let note = u.get("note").map(compact).unwrap_or_default();
            format!(
                "{}{note}",
                if structured {
                    "structured residual remains: "
                } else {
                    ""
                }
            )
        })
        .unwrap_or_default();
    DiagnoseSection {
        source: name.to_string(),
        tables,
        effects,
        unexplained,
        verdict_kind: doc
            .get("verdict")
            .and_then(|v| v.get("kind"))
            .and_then(Value::as_str)
            .map(String::from),
    }
}
