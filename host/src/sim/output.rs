//! The files of `rigctl simulate --out DIR`, all written atomically:
//!
//! - `cal.csv`, `val.csv`: pose files (FORMATS.md) with columns `q1..qN,x,y,z,t,id`; joints with
//!   9 decimals (deg), positions with 9 decimals (mm), `t` with 3 decimals (s);
//! - `truth.toml`: the truth model as a model file (`rigctl fk --model truth.toml --tilt`
//!   reproduces the noise-free positions when no time drift is simulated);
//! - `truth.json`: `{"format", "seed", "robot", "noise_mm", "noise", "tilt",
//!   "pose_interval_s", "geometric_errors": {"distribution", "sigma_deg", "deltas": {name: deg}},
//!   "effects": [{"id", "values", "parameters": {name: delta}}],
//!   "time_drift": {"position_mm_per_h": [x, y, z], "joint_deg_per_h": [...]},
//!   "truth_parameters": {name: value}, "cal_poses", "val_poses"}` where `truth_parameters`
//!   lists every parameter whose truth value differs from the declared one (the values to
//!   `--set` on the declared model).

use std::fmt::Write as _;
use std::path::Path;

use serde_json::{json, Map, Value};

use super::effects::{Change, JointTerm};
use super::simulate::{SimConfig, SimError, SimOutput, SimPose};
use crate::io::atomic::{check_text_for, write_bytes_atomic};
use crate::io::finite::TextFormat;

/// Every file `simulate` writes into its folder (plain and `--session`): a run's set replaces
/// the set of an earlier run, whose files the new set lacks are removed at the commit.
pub fn sim_file(name: &str) -> bool {
    matches!(
        name,
        "cal.csv"
            | "val.csv"
            | "truth.toml"
            | "truth.json"
            | "joints.csv"
            | "truth_path.csv"
            | "potjig.csv"
            | "placement.toml"
            | "pot.rec"
            | "scan.png"
            | "session.json"
    )
}

/// Format tag of `truth.json`.
pub const TRUTH_JSON_FORMAT: &str = "rigctl-simulate-truth/1";

/// The pose file text (header + one row per pose).
pub fn poses_csv(poses: &[SimPose], n_joints: usize) -> String {
    let mut s = String::new();
    let header: Vec<String> = (1..=n_joints)
        .map(|i| format!("q{i}"))
        .chain(["x", "y", "z", "t", "id"].map(String::from))
        .collect();
    let _ = writeln!(s, "{}", header.join(","));
    for p in poses {
        for q in &p.q_deg {
            let _ = write!(s, "{q:.9},");
        }
        let m = p.measured_mm;
        let _ = writeln!(s, "{:.9},{:.9},{:.9},{:.3},{}", m.x, m.y, m.z, p.t_s, p.id);
    }
    s
}

/// The `truth.json` document.
pub fn truth_json(out: &SimOutput, cfg: &SimConfig) -> Value {
    let deltas: Map<String, Value> = out
        .geometric_errors
        .iter()
        .map(|(n, d)| (n.clone(), json!(d)))
        .collect();
    let effects: Vec<Value> = cfg
        .effects
        .iter()
        .map(|e| {
            let params: Map<String, Value> = match &e.change {
                Change::Params(list) => list.iter().map(|(n, d)| (n.clone(), json!(d))).collect(),
                Change::Joint(term) => {
                    let (name, v) = match *term {
                        JointTerm::Scale(j, v) => (format!("joint_scale_j{}", j + 1), v),
                        JointTerm::Coupling(i, k, v) => {
                            (format!("coupling_j{}_j{}_deg_per_deg", i + 1, k + 1), v)
                        }
                        JointTerm::Hysteresis(j, v) => (format!("hysteresis_j{}_deg", j + 1), v),
                        JointTerm::Compliance(j, v) => {
                            (format!("compliance_j{}_deg_per_kgfm", j + 1), v)
                        }
                    };
                    std::iter::once((name, json!(v))).collect()
                }
                Change::LateralCompliance(j, v) => std::iter::once((
                    format!("lateral_compliance_j{}_deg_per_kgfm", j + 1),
                    json!(v),
                ))
                .collect(),
                _ => Map::new(),
            };
            json!({"id": e.id, "values": e.values, "parameters": params})
        })
        .collect();
    let truth_params: Map<String, Value> = out
        .truth
        .params()
        .iter()
        .zip(out.declared.params())
        .filter(|(t, d)| t.value != d.value)
        .map(|(t, _)| (t.name.clone(), json!(t.value)))
        .collect();
    let drift = out.truth.time_terms();
    let joint_drift: Vec<f64> = (0..out.truth.n_joints())
        .map(|j| drift.joint_drift_deg_per_h.get(j).copied().unwrap_or(0.0))
        .collect();
    json!({
        "format": TRUTH_JSON_FORMAT,
        "seed": cfg.seed,
        "robot": out.declared.name(),
        "noise_mm": cfg.noise_mm,
        "noise": "gaussian, independent per coordinate, standard deviation noise_mm",
        "tilt": out.tilt,
        "pose_interval_s": cfg.pose_interval_s,
        "geometric_errors": {"distribution": "gaussian", "sigma_deg": cfg.geometric_sigma_deg, "deltas": deltas},
        "effects": effects,
        "time_drift": {
            "position_mm_per_h": [drift.drift_mm_per_h.x, drift.drift_mm_per_h.y, drift.drift_mm_per_h.z],
            "joint_deg_per_h": joint_drift,
        },
        "truth_parameters": truth_params,
        "cal_poses": out.cal.len(),
        "val_poses": out.val.len(),
    })
}

/// Writes `cal.csv`, `val.csv`, `truth.toml` and `truth.json` into `dir` (created if missing).
pub fn write_outputs(dir: &Path, out: &SimOutput, cfg: &SimConfig) -> Result<(), SimError> {
    // no NaN or absurd coordinate in a written file
    let bad = out.cal.iter().chain(&out.val).find(|p| {
        !p.measured_mm
            .iter()
            .chain(&p.q_deg)
            .all(|v| v.is_finite() && v.abs() <= crate::io::ranges::MAX_POSITION_MM)
    });
    if let Some(p) = bad {
        return Err(SimError::Config(format!(
            "pose {}: the simulated measurement is beyond 100 m or not a number",
            p.id
        )));
    }
    // the four files of one run, never a mix of concurrent runs into the same directory
    let _lock = crate::io::atomic::lock_dir(dir)?;
    // written as one commit (crate::io::file_set)
    let set = crate::io::file_set::begin(dir, sim_file)?;
    let n = out.declared.n_joints();
    let json_text = serde_json::to_string_pretty(&truth_json(out, cfg))
        .map_err(|e| SimError::Config(format!("cannot serialise truth.json: {e}")))?;
    let texts = [
        ("cal.csv", TextFormat::Csv, poses_csv(&out.cal, n)),
        ("val.csv", TextFormat::Csv, poses_csv(&out.val, n)),
        ("truth.toml", TextFormat::Toml, out.truth.to_toml_string()),
    ];
    // every file checked before any is written
    for (name, format, text) in &texts {
        check_text_for(&dir.join(name), *format, text)?;
    }
    for (name, _, text) in &texts {
        write_bytes_atomic(&dir.join(name), text.as_bytes())?;
    }
    write_bytes_atomic(&dir.join("truth.json"), (json_text + "\n").as_bytes())?;
    set.commit()?;
    Ok(())
}
