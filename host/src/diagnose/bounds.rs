//! Physical bounds on the fitted values (JSON key `bounds`; the bounds are the effect table's,
//! [`crate::model::effect::bound`]): a compliance, a stiffness, a backlash, a clearance and a
//! payload mass cannot be negative, a payload is not heavier than the robot's links. A final
//! value outside its bound is never silently kept: it is held at the bound and the other unknowns are refitted (the
//! constrained least-squares optimum when one bound is active), repeated while another value
//! crosses its bound; when that refit fails the value is kept and reported `unphysical`. A
//! stiffness enters the model as its inverse (deflection = moment / stiffness), so its bound is
//! held as a rigid joint ([`crate::model::effect::RIGID_STIFFNESS_KGFM_PER_DEG`]).

use serde::Serialize;

use super::decide::{DecideConfig, Selection};
use super::extended::{self, Unknown, Values};
use crate::calib::MeasuredSet;
use crate::model::effect::bound_declared;
use crate::model::Model;

/// One value that fell outside its physical bound.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BoundReport {
    /// The parameter (`compliance_j2_deg_per_kgfm`, `payload_kg`, ...).
    pub parameter: String,
    /// Its value in the unconstrained fit.
    pub fitted_value: f64,
    /// The bound crossed (the smallest physical value, or the largest for a value above).
    pub bound: f64,
    /// The value it was held at (the bound; a rigid joint for a stiffness).
    pub held_value: f64,
    /// `held_at_bound` (the value set to the bound, the others refitted) or `unphysical` (the
    /// refit failed: the value is kept and is not physical).
    pub action: String,
}

/// Holds every final value of `selection` outside its bound at the bound and refits the others
/// on `cal` (the final fit is replaced); returns what was done. A payload `declared` declares
/// heavier than the links is within its bound ([`crate::model::effect::bound_declared`]).
pub fn enforce(
    selection: &mut Selection,
    declared: &Model,
    cal: &MeasuredSet,
    cfg: &DecideConfig,
) -> Vec<BoundReport> {
    let mut reports = Vec::new();
    // each pass fixes at least one more unknown: at most as many passes as unknowns
    for _ in 0..selection.last.fitted.len() {
        let model = &selection.last.model.model;
        // (unknown, fitted value, the bound crossed, the value held at)
        let outside: Vec<(Unknown, f64, f64, f64)> = selection
            .last
            .fitted
            .iter()
            .filter_map(|&u| {
                let b = bound_declared(u, model, declared)?;
                let v = selection.last.model.value(u);
                let hold = b.outside(v)?;
                Some((u, v, if b.below(v) { b.min } else { b.max }, hold))
            })
            .collect();
        if outside.is_empty() {
            break;
        }
        let mut start = selection.last.model.clone();
        let mut ok = true;
        for &(u, _, _, hold) in &outside {
            ok &= start.set_value(u, hold).is_ok();
        }
        let keep: Vec<Unknown> = selection
            .requested
            .iter()
            .copied()
            .filter(|u| !outside.iter().any(|(o, ..)| o == u))
            .collect();
        let refit = if ok {
            extended::fit(&start, cal, &keep, &cfg.lm, cfg.rtol, false).ok()
        } else {
            None
        };
        let action = if refit.is_some() {
            "held_at_bound"
        } else {
            "unphysical"
        };
        for &(u, v, crossed, hold) in &outside {
            reports.push(BoundReport {
                parameter: u.name(&selection.last.model.model),
                fitted_value: v,
                bound: crossed,
                held_value: hold,
                action: action.to_string(),
            });
        }
        match refit {
            Some(f) => {
                selection.last = f;
                selection.requested = keep;
            }
            None => break,
        }
    }
    reports
}

/// The sentence on the bounds, empty when no value crossed one.
pub fn sentence(reports: &[BoundReport]) -> String {
    let listed = |held: bool, above: bool| -> Vec<String> {
        reports
            .iter()
            .filter(|r| {
                (r.action == "held_at_bound") == held && (r.fitted_value > r.bound) == above
            })
            .map(|r| {
                if held {
                    format!("{} {:.4} -> {}", r.parameter, r.fitted_value, r.held_value)
                } else {
                    format!("{} = {:.4}", r.parameter, r.fitted_value)
                }
            })
            .collect()
    };
    let mut parts = Vec::new();
    for (above, side) in [(false, "below"), (true, "above")] {
        let held = listed(true, above);
        if !held.is_empty() {
            parts.push(format!(
                "{side} their physical bound, held at it and the others refitted: {}",
                held.join(", ")
            ));
        }
        let bad = listed(false, above);
        if !bad.is_empty() {
            parts.push(format!(
                "unphysical ({side} the physical bound; the constrained refit failed): {}",
                bad.join(", ")
            ));
        }
    }
    parts.join("; ")
}
