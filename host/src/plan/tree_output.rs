//! A tree plan's `plan.csv`, `plan.json` and summary table.

use std::fmt::Write as _;

use serde_json::{json, Value};

use super::output::{named, num, sigma_table};
use super::tree::TreePlan;

/// `q1..qN` (the tree's joints in tree order, deg) then `nom_x<k>,nom_y<k>,nom_z<k>` per tip
/// (the nominal tip points, mm): the nominal columns keep the file from being taken for
/// measurements.
pub fn tree_plan_csv(plan: &TreePlan) -> String {
    let mut header: Vec<String> = (1..=plan.joints.len()).map(|j| format!("q{j}")).collect();
    for k in 1..=plan.tips.len() {
        header.extend([
            format!("nom_x{k}"),
            format!("nom_y{k}"),
            format!("nom_z{k}"),
        ]);
    }
    let mut out = header.join(",") + "\n";
    for p in &plan.poses {
        let mut cells: Vec<String> = p.q_deg.iter().map(|v| format!("{v:.9}")).collect();
        for t in &p.tips_mm {
            cells.extend(t.iter().map(|v| format!("{v:.6}")));
        }
        let _ = writeln!(out, "{}", cells.join(","));
    }
    out
}

/// The `plan --json` document of a tree plan.
pub fn tree_plan_json(plan: &TreePlan, noise_mm: f64, seed: u64) -> Value {
    json!({
        "robot": plan.tree,
        "tree": true,
        "tips": plan.tips,
        "joints": plan.joints,
        "n": plan.poses.len(),
        "candidates": plan.candidates,
        "candidate_tries": plan.tries,
        "seed": seed,
        "noise_mm": num(noise_mm),
        "parameters": plan.parameters,
        "unidentifiable": plan.unidentifiable,
        "expected_sigma": named(&plan.parameters, &plan.planned.sigma),
        "random_sigma": named(&plan.parameters, &plan.random.sigma),
        "condition_number": num(plan.planned.condition_number),
        "random_condition_number": num(plan.random.condition_number),
        "median_sigma_ratio": num(plan.median_sigma_ratio),
        "prediction_rms_mm": num(plan.prediction_rms_mm.0),
        "prediction_rms_random_mm": num(plan.prediction_rms_mm.1),
        "order": {"moves_verified": plan.moves_verified},
        "collisions_verified": plan.collisions_verified,
    })
}

/// The summary printed on stdout.
pub fn tree_summary(plan: &TreePlan, noise_mm: f64) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{} poses of {} candidates on the tree {} ({} tips, {} joints, {} parameters), noise {noise_mm} mm",
        plan.poses.len(),
        plan.candidates,
        plan.tree,
        plan.tips.len(),
        plan.joints.len(),
        plan.parameters.len()
    );
    out += &sigma_table(&plan.parameters, &plan.planned, &plan.random, 36);
    let _ = writeln!(
        out,
        "condition number {:.2} (random {:.2}), median sigma ratio {:.3}",
        plan.planned.condition_number, plan.random.condition_number, plan.median_sigma_ratio
    );
    let _ = writeln!(
        out,
        "expected prediction error over the candidates: {:.4} mm rms per coordinate (random designs {:.4} mm)",
        plan.prediction_rms_mm.0, plan.prediction_rms_mm.1
    );
    if !plan.unidentifiable.is_empty() {
        let _ = writeln!(
            out,
            "unidentifiable on any of these poses (a calibration keeps them): {}",
            plan.unidentifiable.join("; ")
        );
    }
    out
}
