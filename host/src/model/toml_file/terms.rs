//! The terms on the joint readings and on the pose time a model file declares: the
//! transmission keys of its `[[joint]]` entries and its `[time]` table, checked.

use super::super::time_terms::TimeTerms;
use super::super::transmission::JointTerms;
use super::{JointEntry, TimeEntry};

/// The transmission terms of the `[[joint]]` entries (all zero when none is given).
pub(super) fn joint_terms(joints: &[JointEntry]) -> Result<JointTerms, String> {
    let n = joints.len();
    let mut t = JointTerms::zeros(n);
    for (i, e) in joints.iter().enumerate() {
        let at = |msg: String| format!("[[joint]] entry {}: {msg}", i + 1);
        let finite = |v: Option<f64>, key: &str| -> Result<f64, String> {
            match v {
                Some(x) if !x.is_finite() => Err(at(format!("`{key}` = {x} is not finite"))),
                Some(x) => Ok(x),
                None => Ok(0.0),
            }
        };
        t.scale[i] = finite(e.joint_scale, "joint_scale")?;
        t.hysteresis_deg[i] = finite(e.hysteresis_deg, "hysteresis_deg")?;
        t.compliance_deg_per_kgfm[i] =
            finite(e.compliance_deg_per_kgfm, "compliance_deg_per_kgfm")?;
        for (key, &c) in &e.joint_coupling {
            let k = key
                .strip_prefix('j')
                .and_then(|d| d.parse::<usize>().ok())
                .filter(|k| (1..=n).contains(k) && *k != i + 1 && format!("j{k}") == *key)
                .ok_or_else(|| {
                    at(format!(
                        "joint_coupling key `{key}`: use j<k> with k another joint in 1..={n}"
                    ))
                })?;
            t.coupling[i][k - 1] = finite(Some(c), "joint_coupling")?;
        }
    }
    Ok(t)
}

/// The `[time]` table (FORMATS.md `thermal`, `time_drift`, `time_drift:j<i>`).
pub(super) fn time_terms(e: &TimeEntry, n_joints: usize) -> Result<TimeTerms, String> {
    let mut t = TimeTerms::zeros(n_joints);
    let finite = |v: f64, key: &str| -> Result<f64, String> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(format!("[time] `{key}` = {v} is not finite"))
        }
    };
    if let Some(v) = e.thermal_ppm {
        t.thermal_ppm = finite(v, "thermal_ppm")?;
    }
    if let Some(v) = e.thermal_tau_min {
        if finite(v, "thermal_tau_min")? <= 0.0 {
            return Err(format!(
                "[time] thermal_tau_min = {v}: a time constant must be > 0 min"
            ));
        }
        t.thermal_tau_min = v;
    }
    if let Some(d) = e.drift_mm_per_h {
        for (k, v) in d.iter().enumerate() {
            t.drift_mm_per_h[k] = finite(*v, "drift_mm_per_h")?;
        }
    }
    if let Some(r) = &e.joint_drift_deg_per_h {
        if r.len() != n_joints {
            return Err(format!(
                "[time] joint_drift_deg_per_h has {} values for {n_joints} joints",
                r.len()
            ));
        }
        for (j, v) in r.iter().enumerate() {
            t.joint_drift_deg_per_h[j] = finite(*v, "joint_drift_deg_per_h")?;
        }
    }
    Ok(t)
}
