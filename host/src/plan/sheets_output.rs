//! The `sheets` object of `plan.json` and the table `rigctl plan --sheets` prints.
//!
//! `"sheets": {"noise_mm", "measured" (fused | trace | plane), "samples_per_path", "tried", "reachable", "parameters": [str],
//! "ranked": [entry], "pairs": [{"rank", "sheets": [i, j], "n_samples", "identifiable",
//! "blind", "condition_number", "median_sigma", "median_scaled_sigma", "sigma"}]}` with
//! `entry = {"index", "rank", "placement": {"origin_mm", "x_axis", "y_axis", "normal",
//! "azimuth_deg", "distance_mm", "height_mm", "tilt_deg"}, "path", "n_samples",
//! "identifiable", "blind", "condition_number", "median_sigma", "median_scaled_sigma",
//! "sigma": {name: f | null}}` (`index` is the sheet's position in `ranked`'s own order of
//! reachability, which `pairs[].sheets` refer to; `median_sigma` in parameter units over the
//! identifiable parameters; `null` for infinite). Only the best [`PAIRS_KEPT`] pairs are written.

use std::fmt::Write as _;

use serde_json::{json, Map, Value};

use super::metrics::median;
use super::sheets::{SheetRanking, SheetScore};

/// Pairs written to the JSON and the table.
pub const PAIRS_KEPT: usize = 20;
/// Single sheets printed in the table.
pub const SINGLES_PRINTED: usize = 12;

fn num(v: f64) -> Value {
    serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)
}

fn score_json(r: &SheetRanking, s: &SheetScore, rank: usize) -> Map<String, Value> {
    let mut sig = Map::new();
    for (n, v) in r.parameters.iter().zip(&s.sigma) {
        sig.insert(n.clone(), num(*v));
    }
    let finite: Vec<f64> = s.sigma.iter().copied().filter(|v| v.is_finite()).collect();
    let mut m = Map::new();
    m.insert("rank".into(), json!(rank));
    m.insert("n_samples".into(), json!(s.n_samples));
    m.insert("identifiable".into(), json!(s.identifiable));
    m.insert("blind".into(), json!(s.blind));
    m.insert("condition_number".into(), num(s.condition_number));
    m.insert("median_sigma".into(), num(median(&finite)));
    m.insert("median_scaled_sigma".into(), num(s.median_scaled_sigma));
    m.insert("sigma".into(), Value::Object(sig));
    m
}

/// The `sheets` value of `plan.json`.
pub fn sheets_json(r: &SheetRanking, noise_mm: f64) -> Value {
    let ranked: Vec<Value> = r
        .singles
        .iter()
        .enumerate()
        .map(|(rank, s)| {
            let i = s.sheets[0];
            let spec = &r.sheets[i].spec;
            let pl = spec.placement();
            let mut m = score_json(r, s, rank + 1);
            m.insert("index".into(), json!(i));
            m.insert("label".into(), json!(spec.label()));
            m.insert("path".into(), json!(spec.path.as_str()));
            m.insert(
                "placement".into(),
                json!({
                    "origin_mm": pl.origin_mm.as_slice(),
                    "x_axis": pl.x_axis.as_slice(),
                    "y_axis": pl.y_axis.as_slice(),
                    "normal": pl.normal().as_slice(),
                    "azimuth_deg": spec.azimuth_deg,
                    "distance_mm": spec.distance_mm,
                    "height_mm": spec.height_mm,
                    "tilt_deg": spec.tilt_deg,
                }),
            );
            Value::Object(m)
        })
        .collect();
    let pairs: Vec<Value> = r
        .pairs
        .iter()
        .take(PAIRS_KEPT)
        .enumerate()
        .map(|(rank, s)| {
            let mut m = score_json(r, s, rank + 1);
            m.insert("sheets".into(), json!(s.sheets));
            let labels: Vec<String> = s.sheets.iter().map(|&i| r.sheets[i].spec.label()).collect();
            m.insert("labels".into(), json!(labels));
            Value::Object(m)
        })
        .collect();
    json!({
        "noise_mm": noise_mm,
        "measured": r.rows.as_str(),
        "samples_per_path": super::sheets::SHEET_SAMPLES,
        "tried": r.tried,
        "reachable": r.sheets.len(),
        "pairs_total": r.pairs.len(),
        "parameters": r.parameters,
        "ranked": ranked,
        "pairs": pairs,
    })
}

fn blind_text(s: &SheetScore) -> String {
    if s.blind.is_empty() {
        "-".into()
    } else {
        s.blind.join(", ")
    }
}

/// The table on stdout: the best single sheets and pairs.
pub fn sheets_table(r: &SheetRanking) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "\nsheets: {} of {} candidate placements and paths reachable; {} parameters; measured: {}",
        r.sheets.len(),
        r.tried,
        r.parameters.len(),
        r.rows.as_str()
    );
    let _ = writeln!(
        out,
        "{:>4} {:<30} {:>6} {:>8} {:>10}  blind",
        "rank", "sheet", "ident", "cond", "med.sigma"
    );
    for (k, s) in r.singles.iter().take(SINGLES_PRINTED).enumerate() {
        let _ = writeln!(
            out,
            "{:>4} {:<30} {:>6} {:>8.1} {:>10.4}  {}",
            k + 1,
            r.sheets[s.sheets[0]].spec.label(),
            s.identifiable.len(),
            s.condition_number,
            s.median_scaled_sigma,
            blind_text(s)
        );
    }
    let _ = writeln!(out, "best pairs of sheets:");
    for (k, s) in r.pairs.iter().take(SINGLES_PRINTED).enumerate() {
        let labels: Vec<String> = s.sheets.iter().map(|&i| r.sheets[i].spec.label()).collect();
        let _ = writeln!(
            out,
            "{:>4} {:<62} {:>3} {:>8.1} {:>10.4}  {}",
            k + 1,
            labels.join(" + "),
            s.identifiable.len(),
            s.condition_number,
            s.median_scaled_sigma,
            blind_text(s)
        );
    }
    let _ = writeln!(
        out,
        "(med.sigma: median expected sigma of the identifiable parameters in mm of tool point, samples taken as independent)"
    );
    out
}
