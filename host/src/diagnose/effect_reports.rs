//! One report per accepted effect (`diagnose --json` `effects[]`) and the data of its plot.

use super::bounds::BoundReport;
use super::candidates::effect_values;
use super::decide::{contribution, DecideConfig, Selection};
use super::extended::Values;
use super::report::{self, EffectReport};
use super::residual::{self, best_regressor, explain};
use super::DiagnoseError;
use crate::calib::{MeasuredSet, Stats};
use nalgebra::Vector3;

/// One accepted effect with what the plots need.
#[derive(Debug, Clone)]
pub struct EffectTrace {
    /// Effect id.
    pub id: String,
    /// Index of the regressor that traced it in [`Diagnosis::regressors`].
    pub regressor: usize,
    /// Calibration errors before and after the effect (mm, per pose).
    pub errors_before: Vec<Vector3<f64>>,
    /// Calibration errors after.
    pub errors_after: Vec<Vector3<f64>>,
    /// Its contribution per pose (mm).
    pub contribution: Vec<Vector3<f64>>,
}

/// One report (and plot trace) per accepted effect: its final values and sigmas, its values at
/// entry, the before/after statistics and the evidence in words.
pub(super) fn of_selection(
    selection: &Selection,
    regs: &[residual::Regressor],
    cal: &MeasuredSet,
    val: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<(Vec<EffectReport>, Vec<EffectTrace>), DiagnoseError> {
    let mut effects = Vec::new();
    let mut traces = Vec::new();
    for step in &selection.steps {
        let t = &step.trial;
        let vb = step.before.model.errors(val)?;
        let va = step.after.model.errors(val)?;
        let cb = step.before.model.errors(cal)?;
        let ca = step.after.model.errors(cal)?;
        let contrib = contribution(&step.before, &step.after, cal)?;
        let (ri, ex) = best_regressor(&contrib, regs).unwrap_or((0, explain(&contrib, &regs[0])));
        let values = effect_values(&t.candidate, &step.before.model, &step.after);
        let final_values = effect_values(&t.candidate, &step.before.model, &selection.last);
        let share = if t.rss_before_mm2 > 0.0 {
            1.0 - t.rss_after_mm2 / t.rss_before_mm2
        } else {
            0.0
        };
        let new_combos: Vec<String> = step
            .after
            .unidentifiable
            .iter()
            .filter(|c| !step.before.unidentifiable.contains(c))
            .cloned()
            .collect();
        let mut evidence = format!(
            "removes {:.0} % of the calibration residual sum of squares with {} new parameter(s) \
             (F = {:.1}, p = {:.1e}, BIC {:+.1}); {}-fold cross-validated mean error {:.4} -> {:.4} mm (paired t = {:.1}); \
             the part it explains follows {} (R^2 = {:.2})",
            100.0 * share,
            t.added,
            t.f,
            t.p_value,
            t.delta_bic,
            cfg.folds,
            t.cv_mean_mm[0],
            t.cv_mean_mm[1],
            t.cv_t,
            ex.regressor,
            ex.r2
        );
        if !new_combos.is_empty() {
            evidence.push_str(&format!(
                "; not separable from fitted parameters (held fixed): {}",
                new_combos.join(", ")
            ));
        }
        if !step.equivalent.is_empty() {
            evidence.push_str(&format!(
                "; equivalent on these poses (explain the same residual within noise): {}",
                step.equivalent.join(", ")
            ));
        }
        let opt = |v: &[(String, f64)]| -> report::Ordered<Option<f64>> {
            v.iter()
                .map(|(n, s)| (n.clone(), if s.is_finite() { Some(*s) } else { None }))
                .collect()
        };
        effects.push(EffectReport {
            id: t.candidate.id.clone(),
            parameters: final_values.values.iter().cloned().collect(),
            sigma: opt(&final_values.sigma),
            parameters_at_entry: values.values.iter().cloned().collect(),
            validation_mean_mm_before: mean_norm(&vb),
            validation_mean_mm_after: mean_norm(&va),
            evidence,
            equivalent: step.equivalent.clone(),
            uncertainty: final_values
                .sigma
                .iter()
                .map(|(n, s)| (n.clone(), if s.is_finite() { Some(*s) } else { None }))
                .collect(),
            calibration_mean_mm_before: mean_norm(&cb),
            calibration_mean_mm_after: mean_norm(&ca),
            cv_mean_mm_before: t.cv_mean_mm[0],
            cv_mean_mm_after: t.cv_mean_mm[1],
            p_value: t.p_value,
            f_statistic: t.f,
            delta_bic: t.delta_bic,
            added_parameters: t.added,
            regressor: ex.regressor.clone(),
            unidentifiable: new_combos,
            model_parameters: t
                .candidate
                .unknowns
                .iter()
                .map(|u| (u.name(&step.after.model.model), step.after.model.value(*u)))
                .collect(),
        });
        traces.push(EffectTrace {
            id: t.candidate.id.clone(),
            regressor: ri,
            errors_before: cb,
            errors_after: ca,
            contribution: contrib,
        });
    }

    Ok((effects, traces))
}

pub(super) fn mean_norm(e: &[Vector3<f64>]) -> f64 {
    Stats::from_errors(e).mean_mm
}

/// Each accepted effect's evidence told which of its parameters `reports` held at a bound.
pub(super) fn tell_bounds(effects: &mut [EffectReport], reports: &[BoundReport]) {
    for e in effects {
        let hit = reports
            .iter()
            .filter(|b| e.model_parameters.get(&b.parameter).is_some());
        for b in hit {
            e.evidence.push_str(&format!(
                "; {} fitted {:.4}, below its physical bound {}: held at {} and the others refitted",
                b.parameter, b.fitted_value, b.bound, b.held_value
            ));
        }
    }
}
