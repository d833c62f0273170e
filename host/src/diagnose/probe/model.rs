//! The probe's fitted function as a correction (`diagnose --residual-model`): a hybrid model,
//! the physical model plus this smooth function of the joint angles (and of the time), always reported apart from
//! the physical effects (JSON key `residual_model`, never in `effects`).

use nalgebra::{DMatrix, DVector, Vector3};
use serde::Serialize;

use super::basis::{point, Domain, Term};
use super::design::Design;
use crate::calib::MeasuredSet;
use crate::calib::Stats;
use crate::diagnose::ordered::Ordered;

/// A smooth function of the joint angles and the time (mm, frame R) made of the probe's terms.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ResidualModel {
    /// Its terms, in the order they entered.
    pub terms: Vec<Term>,
    /// Its variables and their observed ranges, which scale the basis.
    pub domain: Domain,
    /// Coefficients (mm) of every basis function of every term, in order.
    pub coefficients_mm: Vec<Vector3<f64>>,
    /// Change of the fitted physical parameters that goes with the function (their fit
    /// absorbed part of it): the hybrid model is the physical model with these added, plus the
    /// function. Empty when the probe was given no Jacobian.
    pub param_shift: Vec<f64>,
}

impl ResidualModel {
    /// Fits terms `selected` (indices into the design's terms) on all the poses of `design`;
    /// empty when nothing is selected or the system is singular.
    pub fn fit(design: &Design, selected: &[usize], domain: &Domain) -> Self {
        let cols = design.columns(selected);
        if cols.is_empty() {
            return Self::default();
        }
        let Some(w) = design.solve(&cols, None) else {
            return Self::default();
        };
        let shift = design.shift_matrix(&cols) * &w;
        Self {
            terms: selected.iter().map(|&t| design.terms()[t]).collect(),
            domain: domain.clone(),
            coefficients_mm: (0..cols.len())
                .map(|c| Vector3::new(w[3 * c], w[3 * c + 1], w[3 * c + 2]))
                .collect(),
            param_shift: shift.iter().map(|v| -v).collect(),
        }
    }

    /// Whether it has no term (predicts zero).
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// The contribution of each term at the variables `x` ([`point`]) of a pose (mm, frame R).
    pub fn term_contributions_mm(&self, x: &[f64]) -> Vec<Vector3<f64>> {
        let mut values = Vec::new();
        let mut c = 0;
        self.terms
            .iter()
            .map(|t| {
                values.clear();
                self.domain.push_values(*t, x, &mut values);
                let mut f = Vector3::zeros();
                for v in &values {
                    if let Some(w) = self.coefficients_mm.get(c) {
                        f += w * *v;
                    }
                    c += 1;
                }
                f
            })
            .collect()
    }

    /// The correction at the variables `x` ([`point`]) of a pose (mm, frame R): the sum of its
    /// terms.
    pub fn predict_mm(&self, x: &[f64]) -> Vector3<f64> {
        self.term_contributions_mm(x).iter().sum()
    }

    /// The correction at pose `k` of `data` (mm, frame R).
    pub fn predict_pose_mm(&self, data: &MeasuredSet, k: usize) -> Vector3<f64> {
        if k >= data.len() {
            return Vector3::zeros();
        }
        self.predict_mm(&point(data, k, self.domain.has_time()))
    }
}

/// One coefficient of the residual model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CoefficientReport {
    pub term: String,
    pub basis: String,
    pub xyz_mm: [f64; 3],
}

/// The `residual_model` key of `diagnose --json`: the correction and its held-out effect.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HybridReport {
    /// Terms of the correction (`const`, `q2`, `q1:q3`, `t`, `t:q2`).
    pub terms: Vec<String>,
    /// How the basis is built.
    pub basis: String,
    /// Observed range of every variable (deg; s for `t`), `q1: [lo, hi]`.
    pub ranges_deg: Ordered<[f64; 2]>,
    /// Coefficients, mm, frame R.
    pub coefficients: Vec<CoefficientReport>,
    /// Change of the fitted physical parameters that goes with the correction.
    pub parameter_shift: Ordered<f64>,
    /// Held-out statistics of the physical model alone (= `final.validation`).
    pub validation_physical: Stats,
    /// Held-out statistics of the physical model plus the correction.
    pub validation_hybrid: Stats,
    /// What this is and is not.
    pub note: String,
}

/// The hybrid model's report on the held-out set `val`, whose residuals under the final physical
/// model are `physical_val_mm` (measured parts) and whose Jacobians of the fitted parameters
/// are `val_jacobians` (3 x p each, as given to the probe; empty: no parameter shift).
pub fn hybrid_report(
    model: &ResidualModel,
    val: &MeasuredSet,
    physical_val_mm: &[Vector3<f64>],
    val_jacobians: &[DMatrix<f64>],
    param_names: &[String],
) -> HybridReport {
    let shift = DVector::from_column_slice(&model.param_shift);
    let hybrid: Vec<Vector3<f64>> = physical_val_mm
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let mut f = model.predict_pose_mm(val, k);
            if let Some(j) = val_jacobians.get(k).filter(|j| j.ncols() == shift.len()) {
                f += j * &shift;
            }
            val.measured_part(k, &(e - f))
        })
        .collect();
    let coefficients = {
        let mut out = Vec::new();
        let mut c = 0;
        for t in &model.terms {
            for name in model.domain.basis_names(*t) {
                if let Some(w) = model.coefficients_mm.get(c) {
                    out.push(CoefficientReport {
                        term: t.name(),
                        basis: name,
                        xyz_mm: [w.x, w.y, w.z],
                    });
                }
                c += 1;
            }
        }
        out
    };
    HybridReport {
        terms: model.terms.iter().map(Term::name).collect(),
        basis: model.domain.describe(),
        ranges_deg: model
            .domain
            .axes
            .iter()
            .map(|a| (a.var.name(), [a.lo, a.hi]))
            .collect(),
        coefficients,
        parameter_shift: param_names
            .iter()
            .cloned()
            .zip(model.param_shift.iter().copied())
            .collect(),
        validation_physical: Stats::from_errors(physical_val_mm),
        validation_hybrid: Stats::from_errors(&hybrid),
        note: "a non-physical correction fitted to the final calibration residual (the probe's \
               terms); reported apart from the physical effects and not part of the model file"
            .to_string(),
    }
}
