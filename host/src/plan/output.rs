//! `plan.csv` (FORMATS.md: `q1..qN,nom_x,nom_y,nom_z`) and `plan.json` (the conventions'
//! schema; non-finite numbers are written as `null`).

use std::fmt::Write as _;

use serde_json::{json, Map, Value};

use super::aliased::FromDiagnoseReport;
use super::metrics::{quantile, DesignStats};
use super::Plan;

/// The plan as CSV: joints with 9 decimals (deg), nominal tool point with 6 (mm).
pub fn plan_csv(plan: &Plan) -> String {
    let n_joints = plan.poses.first().map_or(0, |p| p.q_deg.len());
    let mut out = String::new();
    let header: Vec<String> = (1..=n_joints).map(|j| format!("q{j}")).collect();
    let _ = writeln!(out, "{},nom_x,nom_y,nom_z", header.join(","));
    for p in &plan.poses {
        let q: Vec<String> = p.q_deg.iter().map(|v| format!("{v:.9}")).collect();
        let _ = writeln!(
            out,
            "{},{:.6},{:.6},{:.6}",
            q.join(","),
            p.nominal_mm.x,
            p.nominal_mm.y,
            p.nominal_mm.z
        );
    }
    out
}

pub(super) fn num(v: f64) -> Value {
    serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)
}

pub(super) fn named(names: &[String], values: &[f64]) -> Value {
    let mut m = Map::new();
    for (n, v) in names.iter().zip(values) {
        m.insert(n.clone(), num(*v));
    }
    Value::Object(m)
}

fn from_diagnose_json(f: &FromDiagnoseReport) -> Value {
    json!({
        "file": f.file,
        "existing_poses": f.existing_poses,
        "effects": f.effects,
        "separated": f.interest,
        "aliased": f.pairs.iter().map(|p| json!({
            "a": p.a,
            "b": p.b,
            "correlation_diagnose": num(p.correlation_diagnose),
            "correlation_before": num(p.correlation_before),
            "correlation_after": num(p.correlation_after),
            "protocol": p.protocol,
        })).collect::<Vec<_>>(),
        "path_dependent": f.path_dependent.iter().map(|(id, protocol)| json!({
            "id": id,
            "protocol": protocol,
        })).collect::<Vec<_>>(),
        "magnitudes": f.magnitudes.iter().map(|(k, v)| (k.clone(), num(*v))).collect::<Map<_, _>>(),
        "admissible_candidates": f.admissible_candidates,
        "nonlinearity_threshold": num(f.nonlinearity_threshold),
    })
}

/// The `plan --json` document; `sheets`: the `--sheets` ranking when asked.
pub fn plan_json(plan: &Plan, noise_mm: f64, seed: u64, sheets: Option<Value>) -> Value {
    json!({
        "robot": plan.robot,
        "n": plan.poses.len(),
        "criterion": plan.criterion,
        "candidates": plan.candidates,
        "parameters": plan.parameters,
        "expected_sigma": named(&plan.parameters, &plan.planned.sigma),
        "random_sigma": named(&plan.parameters, &plan.random.sigma),
        "condition_number": num(plan.planned.condition_number),
        "random_condition_number": num(plan.random.condition_number),
        "median_sigma_ratio": num(plan.median_sigma_ratio),
        "unidentifiable": plan.unidentifiable,
        "from_diagnose": plan.from_diagnose.as_ref().map(from_diagnose_json),
        "sheets": sheets,
        "noise_mm": noise_mm,
        "seed": seed,
        "o1": num(plan.planned.o1),
        "random_o1": num(plan.random.o1),
        "min_singular_value": num(plan.planned.min_singular_value),
        "random_min_singular_value": num(plan.random.min_singular_value),
        "exchanges": plan.exchanges,
        "structured_candidates": plan.structured_candidates,
        "refinement": {
            "sweeps": plan.refinement.sweeps,
            "moves": plan.refinement.moves,
            "criterion_before": num(plan.refinement.criterion_before),
            "criterion_after": num(plan.refinement.criterion_after),
        },
        "median_sigma_direct": {
            "planned": num(plan.direct.planned),
            "random_mean": num(plan.direct.random_mean),
            "random_median": num(plan.direct.random_median),
            "ratio_to_mean": num(plan.direct.ratio_to_mean()),
            "ratio_to_median": num(plan.direct.ratio_to_median()),
        },
        "optimum": plan.optimum.as_ref().map(|o| json!({
            "iterations": o.optimum.iterations,
            "added_configurations": o.extension.added,
            "rounds": o.extension.rounds,
            "last_sensitivity_ratio": num(o.extension.last_excess),
            "support": o.optimum.support,
            "value": num(o.optimum.value),
            "bound": num(o.optimum.bound),
            "efficiency": num(o.efficiency),
            "efficiency_bound": num(o.efficiency_bound),
            "expected_sigma": named(&plan.parameters, &o.sigma),
            "median_sigma_ratio": num(o.median_sigma_ratio),
        })),
        "median_sigma_ratio_per_draw": {
            "draws": plan.ratio_per_draw.len(),
            "p10": num(quantile(&plan.ratio_per_draw, 0.1)),
            "p50": num(quantile(&plan.ratio_per_draw, 0.5)),
            "p90": num(quantile(&plan.ratio_per_draw, 0.9)),
        },
        "order": {
            "travel_deg": num(plan.order.travel_deg),
            "random_travel_deg": num(plan.order.random_travel_deg),
            "segments_checked": plan.order.segments_checked,
            "segments_unsafe": plan.order.segments_unsafe,
            "moves_verified": plan.order.unsafe_left.is_empty(),
            "unsafe_moves_left": plan.order.unsafe_left.iter().map(|(a, b, why)| serde_json::json!({"from": a, "to": b, "why": why})).collect::<Vec<_>>(),
            "configurations_checked": plan.order.configurations_checked,
            "step_deg": num(plan.order.step_deg),
            "via_before": plan.order.via_before,
            "via_q": plan.order.via_q,
        },
    })
}

/// The table printed on stdout.
/// Every parameter's expected sigma planned and of random designs, and their ratio (names
/// `width` wide).
pub(super) fn sigma_table(
    names: &[String],
    planned: &DesignStats,
    random: &DesignStats,
    width: usize,
) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<width$} {:>14} {:>14} {:>7}",
        "parameter", "sigma planned", "sigma random", "ratio"
    );
    for (k, name) in names.iter().enumerate() {
        let (p, r) = (planned.sigma[k], random.sigma[k]);
        let _ = writeln!(out, "{name:<width$} {p:>14.6} {r:>14.6} {:>7.3}", p / r);
    }
    out
}

pub fn summary_table(plan: &Plan, noise_mm: f64) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{} {} poses of {} candidates ({} structured; refined: {} joint moves) on {} ({} parameters), noise {noise_mm} mm",
        plan.criterion,
        plan.poses.len(),
        plan.candidates,
        plan.structured_candidates,
        plan.refinement.moves,
        plan.robot,
        plan.parameters.len()
    );
    out += &sigma_table(&plan.parameters, &plan.planned, &plan.random, 28);
    let _ = writeln!(
        out,
        "condition number {:.2} (random {:.2}), O1 {:.4} (random {:.4}), median sigma ratio {:.3}",
        plan.planned.condition_number,
        plan.random.condition_number,
        plan.planned.o1,
        plan.random.o1,
        plan.median_sigma_ratio
    );
    let _ = writeln!(
        out,
        "median sigma ratio against each of {} other random designs: p10 {:.3}, p50 {:.3}, p90 {:.3}",
        plan.ratio_per_draw.len(),
        quantile(&plan.ratio_per_draw, 0.1),
        quantile(&plan.ratio_per_draw, 0.5),
        quantile(&plan.ratio_per_draw, 0.9)
    );
    let _ = writeln!(
        out,
        "median sigma over parameters (mixed units): planned {:.6}, random mean {:.6} / median {:.6} over draws (ratio {:.3} / {:.3})",
        plan.direct.planned,
        plan.direct.random_mean,
        plan.direct.random_median,
        plan.direct.ratio_to_mean(),
        plan.direct.ratio_to_median()
    );
    if let Some(o) = &plan.optimum {
        let pool = if o.extension.rounds == 0 {
            format!(
                "approximate optimum on the candidates, {} support poses",
                o.optimum.support
            )
        } else {
            format!(
                "approximate optimum on the candidates + {} configurations found by {} rounds of sensitivity climbs, {} support poses",
                o.extension.added, o.extension.rounds, o.optimum.support
            )
        };
        let _ = writeln!(
            out,
            "best possible ({pool}): median sigma ratio {:.3}; this plan's efficiency {:.3} of it, {:.3} of the bound no design on that pool can pass",
            o.median_sigma_ratio, o.efficiency, o.efficiency_bound
        );
    }
    if !plan.unidentifiable.is_empty() {
        let _ = writeln!(
            out,
            "unidentifiable on any pose: {}",
            plan.unidentifiable.join(", ")
        );
    }
    if let Some(f) = &plan.from_diagnose {
        for p in &f.pairs {
            if p.protocol.is_some() {
                let _ = writeln!(
                    out,
                    "aliased {} / {}: not separated by the choice of poses (see below)",
                    p.a, p.b
                );
                continue;
            }
            let _ = writeln!(
                out,
                "aliased {} / {}: correlation {:.3} on the {} measured poses -> {:.3} with the plan",
                p.a, p.b, p.correlation_before, f.existing_poses, p.correlation_after
            );
        }
        for (_, protocol) in &f.path_dependent {
            let _ = writeln!(out, "path-dependent: {protocol}");
        }
    }
    out
}
