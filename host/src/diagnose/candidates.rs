//! The candidate library: every FORMATS.md effect id as a set of unknowns to free, and the
//! conversion of fitted unknowns to the effect's own parameters.
//!
//! | id | unknowns | reported `parameters` |
//! |---|---|---|
//! | `link_length:<a_i or d_i>` (any length named `a<i>`/`d<i>` not declared: a2 a3 d4 d5 on the Katana) | that length | `delta_mm` |
//! | `encoder_harmonic:j<i>:h<n>` (every revolute joint, n = 1..3) | `enc_j<i>_h<n>_sin/_cos` | `A` (deg), `phi` (deg) of `A sin(n q_i + phi)` |
//! | `tool_offset` | `tool_dx/dy/dz` | `dx dy dz` (mm, last frame) |
//! | `base_offset` | `base_x/y/z` | `dx dy dz` (mm, frame R) |
//! | `base_tilt` | `base_rx/ry` | `rx ry` (deg) |
//! | `payload` (models with tilting) | `payload_kg` | `mass_kg` |
//! | `scale` | `scale_ppm` | `ppm` |
//! | `stiffness:j<i>` `backlash:j<i>` `clearance:j<i>` (models with tilting) | that tilting value | `stiffness_kgfm_per_deg` / `backlash_deg` / `clearance_deg` (fitted value) and `delta_*` (change from the declared value) |
//! | `time_drift` (pose files with varying `t`) | position drift x, y, z | `vx_mm_per_h vy_mm_per_h vz_mm_per_h` |
//! | `time_drift:j<i>` (same) | joint-offset drift | `deg_per_h` |
//! | `thermal` (same) | warm-up growth `s` and time constant `tau` ([`crate::model::time_terms`]) | `s_ppm`, `tau_min` |
//! | `compliance:j<i>` (models without tilting but with link masses, e.g. `ur5`) | deflection per gravity torque | `deg_per_kgfm` |
//! | `joint_scale:j<i>` (every joint) | transmission-ratio error `q_i += s q_i` | `s` (dimensionless) |
//! | `joint_coupling:j<i>:j<k>` (every ordered pair) | `q_i += c q_k` | `c` (deg/deg) |
//! | `hysteresis:j<i>` (pose files whose joints move) | `q_i += b d_i`, `d_i` the direction of approach (pose order) | `b` (deg) |
//!
//! Unknowns that the declared fit already frees are dropped from a candidate (e.g. the UR5's
//! link lengths and tool point are declared parameters), and a candidate with nothing left is not
//! offered.

use super::extended::{ExtFit, ExtModel, Unknown, Values};
use crate::calib::MeasuredSet;
use crate::model::{harmonic_amplitude_phase, ParamKind};

/// One candidate effect.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// FORMATS.md effect id, e.g. `encoder_harmonic:j2:h1`.
    pub id: String,
    /// The unknowns it frees.
    pub unknowns: Vec<Unknown>,
    /// The joint it acts on (0-based), for joint-angle plots.
    pub joint: Option<usize>,
}

fn is_link_length_name(name: &str) -> bool {
    let mut c = name.chars();
    matches!(c.next(), Some('a' | 'd')) && {
        let rest: String = c.collect();
        !rest.is_empty() && rest.chars().all(|ch| ch.is_ascii_digit())
    }
}

/// The candidates being listed: each one with its unknowns that are not in `current`; one with
/// none left is not offered.
struct Listing<'a> {
    current: &'a [Unknown],
    out: Vec<Candidate>,
}

impl Listing<'_> {
    /// The candidate `id` freeing `unknowns` (`None`: a parameter the model lacks).
    fn push(&mut self, id: String, unknowns: Vec<Option<Unknown>>, joint: Option<usize>) {
        let unknowns: Vec<Unknown> = unknowns
            .into_iter()
            .flatten()
            .filter(|u| !self.current.contains(u))
            .collect();
        if !unknowns.is_empty() {
            self.out.push(Candidate {
                id,
                unknowns,
                joint,
            });
        }
    }

    /// One candidate `family:j<i>` per joint (`joints` of them), freeing `unknown(j)`.
    fn per_joint(&mut self, family: &str, joints: usize, unknown: fn(usize) -> Unknown) {
        for j in 0..joints {
            self.push(
                format!("{family}:j{}", j + 1),
                vec![Some(unknown(j))],
                Some(j),
            );
        }
    }
}

/// All candidates for `ext` and `data`, minus the unknowns in `current`.
pub fn library(ext: &ExtModel, current: &[Unknown], data: &MeasuredSet) -> Vec<Candidate> {
    library_for(ext, current, data.has_approach(), data.has_time())
}

/// All candidates for `ext` minus the unknowns in `current`, with the path-dependent ones
/// (`hysteresis:j<i>` when `approach`, `time_drift`, `time_drift:j<i>` when `time`): every
/// effect id `diagnose` can report, for a reader of its JSON that has no data set
/// (`plan --from-diagnose`).
pub fn library_for(
    ext: &ExtModel,
    current: &[Unknown],
    approach: bool,
    time: bool,
) -> Vec<Candidate> {
    let model = &ext.model;
    let idx = |name: &str| model.param_index(name).map(Unknown::Param);
    let mut list = Listing {
        current,
        out: Vec::new(),
    };
    for (i, p) in model.params().iter().enumerate() {
        if p.kind == ParamKind::Length && is_link_length_name(&p.name) {
            list.push(
                format!("link_length:{}", p.name),
                vec![Some(Unknown::Param(i))],
                None,
            );
        }
    }
    for (j, joint) in model.joints().iter().enumerate() {
        for h in &joint.harmonics {
            list.push(
                format!("encoder_harmonic:j{}:h{}", j + 1, h.order),
                vec![
                    Some(Unknown::Param(h.sin_param)),
                    Some(Unknown::Param(h.cos_param)),
                ],
                Some(j),
            );
        }
    }
    list.push(
        "tool_offset".into(),
        vec![idx("tool_dx"), idx("tool_dy"), idx("tool_dz")],
        None,
    );
    list.push(
        "base_offset".into(),
        vec![idx("base_x"), idx("base_y"), idx("base_z")],
        None,
    );
    list.push(
        "base_tilt".into(),
        vec![idx("base_rx"), idx("base_ry")],
        None,
    );
    if let Some(tp) = model.tilt_params() {
        list.push(
            "payload".into(),
            vec![Some(Unknown::Param(model.payload_param()))],
            None,
        );
        for (j, t) in tp.iter().enumerate() {
            list.push(
                format!("stiffness:j{}", j + 1),
                vec![Some(Unknown::Param(t.stiffness))],
                Some(j),
            );
            list.push(
                format!("backlash:j{}", j + 1),
                vec![Some(Unknown::Param(t.backlash))],
                Some(j),
            );
            list.push(
                format!("clearance:j{}", j + 1),
                vec![Some(Unknown::Param(t.clearance))],
                Some(j),
            );
        }
    } else if ext.gravity.is_some() {
        list.per_joint("compliance", model.n_joints(), Unknown::Compliance);
    }
    list.push(
        "scale".into(),
        vec![Some(Unknown::Param(model.scale_param()))],
        None,
    );
    let n = model.n_joints();
    list.per_joint("joint_scale", n, Unknown::JointScale);
    for i in 0..n {
        for k in (0..n).filter(|&k| k != i) {
            list.push(
                format!("joint_coupling:j{}:j{}", i + 1, k + 1),
                vec![Some(Unknown::Coupling(i, k))],
                Some(k),
            );
        }
    }
    if approach {
        list.per_joint("hysteresis", n, Unknown::Hysteresis);
    }
    if time {
        list.push(
            "time_drift".into(),
            (0..3).map(|a| Some(Unknown::PositionDrift(a))).collect(),
            None,
        );
        list.per_joint("time_drift", model.n_joints(), Unknown::JointDrift);
        list.push(
            "thermal".into(),
            vec![Some(Unknown::ThermalPpm), Some(Unknown::ThermalTauMin)],
            None,
        );
    }
    list.out
}

/// An effect's parameters in its own units (see the module table), with one standard deviation
/// each (infinite for a parameter held fixed as unidentifiable).
#[derive(Debug, Clone, PartialEq)]
pub struct EffectValues {
    /// `(name, value)` in the effect's units.
    pub values: Vec<(String, f64)>,
    /// `(name, one sigma)`, same names.
    pub sigma: Vec<(String, f64)>,
}

/// The parameters of candidate `cand` after `fit`, relative to `before` (the model before the
/// effect was added).
pub fn effect_values(cand: &Candidate, before: &ExtModel, fit: &ExtFit) -> EffectValues {
    let after = &fit.ext;
    let delta = |u: Unknown| after.value(u) - before.value(u);
    let sig = |u: Unknown| fit.sigma_of(u);
    let mut values = Vec::new();
    let mut sigma = Vec::new();
    let mut add = |name: &str, v: f64, s: f64| {
        values.push((name.to_string(), v));
        sigma.push((name.to_string(), s));
    };
    let family = cand.id.split(':').next().unwrap_or("");
    let u = &cand.unknowns;
    match family {
        "encoder_harmonic" if u.len() == 2 => {
            let (s, c) = (after.value(u[0]), after.value(u[1]));
            let (amp, phi) = harmonic_amplitude_phase(s, c);
            let (ss, sc) = (sig(u[0]), sig(u[1]));
            let (sa, sp) = if amp > 0.0 {
                (
                    ((s * ss).powi(2) + (c * sc).powi(2)).sqrt() / amp,
                    (((c * ss).powi(2) + (s * sc).powi(2)).sqrt() / (amp * amp)).to_degrees(),
                )
            } else {
                (ss.max(sc), f64::INFINITY)
            };
            add("A", amp, sa);
            add("phi", phi, sp);
        }
        "tool_offset" | "base_offset" => {
            let names = if family == "tool_offset" {
                ["tool_dx", "tool_dy", "tool_dz"]
            } else {
                ["base_x", "base_y", "base_z"]
            };
            for (label, pname) in ["dx", "dy", "dz"].iter().zip(names) {
                match after.model.param_index(pname).map(Unknown::Param) {
                    Some(p) => add(label, delta(p), sig(p)),
                    None => add(label, 0.0, f64::INFINITY),
                }
            }
        }
        "base_tilt" => {
            for (label, pname) in [("rx", "base_rx"), ("ry", "base_ry")] {
                if let Some(p) = after.model.param_index(pname).map(Unknown::Param) {
                    add(label, delta(p), sig(p));
                }
            }
        }
        "time_drift" if u.len() == 3 => {
            for (a, label) in ["vx_mm_per_h", "vy_mm_per_h", "vz_mm_per_h"]
                .iter()
                .enumerate()
            {
                let p = Unknown::PositionDrift(a);
                add(label, delta(p), sig(p));
            }
        }
        "thermal" if u.len() == 2 => {
            // both values are the effect's own (the declared model has no warm-up)
            add("s_ppm", after.value(u[0]), sig(u[0]));
            add("tau_min", after.value(u[1]), sig(u[1]));
        }
        "stiffness" | "backlash" | "clearance" if u.len() == 1 => {
            let unit = if family == "stiffness" {
                "kgfm_per_deg"
            } else {
                "deg"
            };
            add(&format!("{family}_{unit}"), after.value(u[0]), sig(u[0]));
            add(&format!("delta_{unit}"), delta(u[0]), sig(u[0]));
        }
        _ => {
            let label = match family {
                "link_length" => "delta_mm",
                "payload" => "mass_kg",
                "scale" => "ppm",
                "time_drift" => "deg_per_h",
                "compliance" => "deg_per_kgfm",
                "joint_scale" => "s",
                "joint_coupling" => "c",
                "hysteresis" => "b",
                _ => "value",
            };
            if let [one] = u.as_slice() {
                add(label, delta(*one), sig(*one));
            } else {
                for x in u {
                    add(&x.name(&after.model), delta(*x), sig(*x));
                }
            }
        }
    }
    EffectValues { values, sigma }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::Poses;
    use crate::model::katana450;

    #[test]
    fn katana_library_has_every_formats_family() {
        let ext = ExtModel::new(katana450(200.0).unwrap());
        let data = MeasuredSet {
            poses: Poses::default(),
            t_s: Some(vec![0.0, 10.0]),
            ..MeasuredSet::default()
        };
        let ids: Vec<String> = library(&ext, &[], &data)
            .into_iter()
            .map(|c| c.id)
            .collect();
        for want in [
            "link_length:a2",
            "link_length:a3",
            "link_length:d4",
            "link_length:d5",
            "encoder_harmonic:j1:h1",
            "encoder_harmonic:j5:h3",
            "tool_offset",
            "base_offset",
            "base_tilt",
            "payload",
            "scale",
            "stiffness:j2",
            "backlash:j3",
            "clearance:j4",
            "time_drift",
        ] {
            assert!(ids.iter().any(|i| i == want), "{want} missing from {ids:?}");
        }
        assert!(!ids.iter().any(|i| i.starts_with("link_length:mount")));
        assert!(
            !ids.iter().any(|i| i.starts_with("compliance")),
            "the Katana's stiffness covers compliance"
        );
    }

    #[test]
    fn declared_unknowns_are_not_offered_again() {
        let ext = ExtModel::new(crate::model::ur5().unwrap());
        let m = &ext.model;
        let declared: Vec<Unknown> = ["tool_dx", "tool_dy", "tool_dz", "d4"]
            .iter()
            .map(|n| Unknown::Param(m.param_index(n).unwrap()))
            .collect();
        let ids: Vec<String> = library(&ext, &declared, &MeasuredSet::default())
            .into_iter()
            .map(|c| c.id)
            .collect();
        assert!(
            !ids.iter()
                .any(|i| i == "tool_offset" || i == "link_length:d4"),
            "{ids:?}"
        );
        assert!(ids.iter().any(|i| i == "compliance:j2"), "{ids:?}");
        assert!(
            !ids.iter().any(|i| i.starts_with("time_drift")),
            "no times, no drift: {ids:?}"
        );
    }
}
