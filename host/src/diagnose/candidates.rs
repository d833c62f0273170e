//! The candidate library: every effect of the effect table ([`crate::model::effect`]) that the
//! model and the data offer, as a set of unknowns to free, and the conversion of fitted unknowns
//! to the effect's own parameters (the table's `labels`, `report`).
//!
//! Unknowns that the declared fit already frees are dropped from a candidate (e.g. the UR5's
//! link lengths and tool point are declared parameters), and a candidate with nothing left is not
//! offered.

use super::extended::{ExtModel, Unknown, Values};
use crate::calib::fit::Fit;
use crate::calib::MeasuredSet;
use crate::model::effect::{self, EffectId, Offers, Report};
use crate::model::harmonic_amplitude_phase;

/// One candidate effect.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// FORMATS.md effect id, e.g. `encoder_harmonic:j2:h1`.
    pub id: String,
    /// The same, parsed.
    pub effect: EffectId,
    /// The unknowns it frees.
    pub unknowns: Vec<Unknown>,
    /// The joint it acts on (0-based), for joint-angle plots.
    pub joint: Option<usize>,
}

impl Candidate {
    /// The candidate `effect` on `ext`, freeing its unknowns that are not in `current`; `None`
    /// when none is left.
    pub fn new(effect: EffectId, ext: &ExtModel, current: &[Unknown]) -> Option<Self> {
        let unknowns: Vec<Unknown> = effect
            .unknowns(&ext.model)
            .into_iter()
            .flatten()
            .filter(|u| !current.contains(u))
            .collect();
        (!unknowns.is_empty()).then(|| Candidate {
            id: effect.to_string(),
            joint: effect.joint(),
            effect,
            unknowns,
        })
    }
}

/// All candidates for `ext` and `data`, minus the unknowns in `current`.
pub fn library(ext: &ExtModel, current: &[Unknown], data: &MeasuredSet) -> Vec<Candidate> {
    library_for(ext, current, data.has_approach(), data.has_time())
}

/// All candidates for `ext` minus the unknowns in `current`, with the path-dependent ones
/// (`hysteresis:j<i>` when `approach`, `time_drift`, `time_drift:j<i>`, `thermal` when `time`):
/// every effect id `diagnose` can report, for a reader of its JSON that has no data set
/// (`plan --from-diagnose`).
pub fn library_for(
    ext: &ExtModel,
    current: &[Unknown],
    approach: bool,
    time: bool,
) -> Vec<Candidate> {
    effect::library(&ext.model, Offers { approach, time })
        .into_iter()
        // the extended model decides whether gravity torques can be evaluated
        .filter(|e| {
            ext.gravity.is_some()
                || !matches!(e, EffectId::Compliance(_) | EffectId::LateralCompliance(_))
        })
        .filter_map(|e| Candidate::new(e, ext, current))
        .collect()
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
pub fn effect_values(
    cand: &Candidate,
    before: &ExtModel,
    fit: &Fit<ExtModel, Unknown>,
) -> EffectValues {
    let after = &fit.model;
    let delta = |u: Unknown| after.value(u) - before.value(u);
    let sig = |u: Unknown| fit.sigma_of(u);
    let mut values = Vec::new();
    let mut sigma = Vec::new();
    let mut add = |name: &str, v: f64, s: f64| {
        values.push((name.to_string(), v));
        sigma.push((name.to_string(), s));
    };
    let row = cand.effect.row();
    let u = &cand.unknowns;
    // every value the effect names on the model, in the order of the row's labels (a candidate
    // frees only those the declared fit does not)
    let all = cand.effect.unknowns(&after.model);
    match row.report {
        Report::Harmonic if u.len() == 2 => {
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
            add(row.labels[0], amp, sa);
            add(row.labels[1], phi, sp);
        }
        // both values are the effect's own (the declared model has none of it)
        Report::Value if u.len() == all.len() => {
            for (label, &x) in row.labels.iter().zip(u) {
                add(label, after.value(x), sig(x));
            }
        }
        // the size of the change, then its time (placed by the scan of the splits between pose
        // times, not by the least squares: its sigma is the half-gap `diagnose` reports)
        Report::Step if u.len() + 1 == row.labels.len() => {
            for (label, &x) in row.labels.iter().zip(u) {
                add(label, after.value(x), sig(x));
            }
            let t_s = match u.first() {
                Some(Unknown::ToolStep { slot, .. }) | Some(Unknown::PayloadStep(slot)) => {
                    after.model.steps().get(*slot).map_or(f64::NAN, |s| s.t_s)
                }
                _ => f64::NAN,
            };
            add(row.labels[u.len()], t_s, f64::INFINITY);
        }
        Report::ValueAndDelta if u.len() == 1 => {
            add(row.labels[0], after.value(u[0]), sig(u[0]));
            add(row.labels[1], delta(u[0]), sig(u[0]));
        }
        Report::Delta if all.len() == row.labels.len() && all.len() > 1 => {
            for (label, x) in row.labels.iter().zip(&all) {
                match x {
                    Some(p) => add(label, delta(*p), sig(*p)),
                    None => add(label, 0.0, f64::INFINITY),
                }
            }
        }
        _ => {
            if let ([one], [label]) = (u.as_slice(), row.labels) {
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
    use crate::calib::measured::PosePoints;
    use crate::model::katana450;

    #[test]
    fn katana_library_has_every_formats_family() {
        let ext = ExtModel::new(katana450(200.0).unwrap());
        let data = MeasuredSet {
            poses: PosePoints::default(),
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
