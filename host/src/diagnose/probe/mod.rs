//! The probe for what no candidate describes: after the last accepted effect, a smooth function
//! of the joint angles (and of the time, when the poses carry times) is fitted to the final
//! residual under k-fold cross-validation, and the terms it needs say where the unexplained
//! error lives ("depends on q2 and on q1 with q3").
//!
//! **Model** ([`basis`]): a constant, additive one-variable terms (Fourier terms `sin, cos(k q)`,
//! `k = 1..`[`basis::MAIN_HARMONICS`], for a joint observed over a wide range; the cosine series
//! over the observed range for a narrow joint and for the time) and pairwise interaction terms
//! (products of the first [`basis::PAIR_HARMONICS`] harmonics of each variable), each with three
//! coefficients (x, y, z, mm) per basis function, fitted to the **measured part** of the residual
//! (all three components of a full position, the two measured directions of a traced sample).
//!
//! **Selection** ([`select`]): forward selection of terms by cross-validated error (random
//! folds for independent poses, contiguous blocks for samples along a path, as the effect
//! selection), continued while a further term explains a significant share out of sample: a
//! term enters only when adding it lowers the held-out squared error by at least
//! [`ProbeConfig::min_gain`] of the current one, with a one-sided paired t-test over the poses
//! (the t statistic divided by the square root of the autocorrelation time of the differences
//! for serial data) significant at [`ProbeConfig::alpha`] after a Bonferroni correction over the
//! terms tried at that step, and (when a floor is given) explains at least
//! [`ProbeConfig::floor_min_ratio`] x the floor in RMS per coordinate.
//!
//! **Cost**: one pass over the poses builds the per-fold normal equations ([`design`]); every
//! candidate then costs `O(s^3)` per fold plus `O(n s)`; above [`ProbeConfig::max_poses`] poses an
//! evenly strided subset is used. Pure noise gives no term and `explainable_share = 0`.

pub mod basis;
pub mod design;
pub mod model;
mod physical;
pub mod plot;
pub mod select;

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use serde::Serialize;

use super::decide::{block_fold_assignment, fold_assignment};
use super::extended::{ExtModel, Unknown};
use crate::calib::MeasuredSet;
use crate::model::ModelError;
use basis::{point, Domain, Term};
use design::Design;
pub use model::{hybrid_report, HybridReport, ResidualModel};

/// Settings of the probe.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeConfig {
    /// Number of cross-validation folds.
    pub folds: usize,
    /// Seed of the random folds (independent poses).
    pub seed: u64,
    /// Family-wise significance of a term's paired test (Bonferroni over the terms tried).
    pub alpha: f64,
    /// Smallest relative decrease of the held-out squared error for a term to enter.
    pub min_gain: f64,
    /// Most terms selected.
    pub max_terms: usize,
    /// Above this many poses an evenly strided subset is used.
    pub max_poses: usize,
    /// Floor of the measurement (one sigma per coordinate, mm), when known.
    pub floor_mm: Option<f64>,
    /// With a floor: smallest RMS per coordinate (x the floor) a term must explain.
    pub floor_min_ratio: f64,
}

impl Default for ProbeConfig {
    fn default() -> Self {
        Self {
            folds: 5,
            seed: 1,
            alpha: 0.01,
            min_gain: 0.02,
            max_terms: 10,
            max_poses: 3000,
            floor_mm: None,
            floor_min_ratio: 0.2,
        }
    }
}

/// One selected term and the share of the residual's squared error (out of sample) it removed
/// when it entered.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TermShare {
    /// `const`, `q2`, `q1:q3`, `t` or `t:q2`.
    pub term: String,
    /// Share of the residual's held-out squared error it removed.
    pub share: f64,
    /// Paired t statistic when it entered.
    pub t: f64,
}

/// What the probe found.
#[derive(Debug, Clone)]
pub struct ProbeResult {
    /// Variables (`q2`, `t`) and pairs (`q1:q3`, `t:q2`) of the selected terms, in the order they
    /// entered.
    pub depends_on: Vec<String>,
    /// Share of the residual's squared error the selected function explains out of sample
    /// (>= 0).
    pub explainable_share: f64,
    /// Whether some term entered (structure out of sample).
    pub structured: bool,
    /// The selected terms with their shares.
    pub terms: Vec<TermShare>,
    /// Held-out RMS per measured component before (predicting nothing), mm.
    pub cv_rms_before_mm: f64,
    /// Held-out RMS per measured component with the selected terms, mm.
    pub cv_rms_after_mm: f64,
    /// The selected function fitted on all the poses used.
    pub model: ResidualModel,
    /// Poses used (after subsampling) and folds.
    pub poses: usize,
    /// Number of folds.
    pub folds: usize,
    /// Variables of the poses used (joint angles in deg, then the time in s when the probe
    /// used it; [`basis::point`]), for the plots.
    pub points: Vec<Vec<f64>>,
    /// Measured part of their residual (mm).
    pub residual_mm: Vec<Vector3<f64>>,
    /// Projector on their measured directions (`None`: full position).
    pub projectors: Vec<Option<Matrix3<f64>>>,
    /// Whether the time was one of the variables (the poses carry times that differ).
    pub with_time: bool,
    /// Held-out RMS per measured component (mm) of the physical model alone under the same
    /// folds (its fitted parameters refitted without each fold, linearised at the final fit;
    /// [`design::Design::physical_cv`]); NaN when the probe did not run.
    pub physical_cv_rms_mm: f64,
    /// Number of measured components of the poses used.
    pub n_components: usize,
    /// Expected ratio of the physical cross-validated to the residual sum of squares for a right
    /// model ([`design::Design::physical_cv`]; 1 when the probe did not run).
    pub physical_cv_inflation: f64,
    /// Number of fitted physical parameters given to the probe.
    pub n_parameters: usize,
    /// How many parameter combinations the poses support (truncated-SVD fit chosen by the same
    /// cross-validation, [`design::Design::supported_parameters`]); `None` without Jacobians.
    pub supported_parameters: Option<usize>,
}

/// The probe's summary in the `diagnose --json` document (extra key `probe`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProbeReport {
    pub terms: Vec<TermShare>,
    pub cv_rms_before_mm: f64,
    pub cv_rms_after_mm: f64,
    pub poses: usize,
    pub folds: usize,
    pub rule: String,
    /// The change-point scan of the residual in time ([`crate::diagnose::changes`]), when a
    /// step explains a significant part of it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub change_point: Option<crate::diagnose::changes::ChangePoint>,
}

impl ProbeResult {
    /// A probe that found nothing (too few poses).
    pub fn empty(poses: usize, folds: usize) -> Self {
        Self {
            depends_on: Vec::new(),
            explainable_share: 0.0,
            structured: false,
            terms: Vec::new(),
            cv_rms_before_mm: f64::NAN,
            cv_rms_after_mm: f64::NAN,
            model: ResidualModel::default(),
            poses,
            folds,
            points: Vec::new(),
            residual_mm: Vec::new(),
            projectors: Vec::new(),
            with_time: false,
            physical_cv_rms_mm: f64::NAN,
            n_components: 0,
            physical_cv_inflation: 1.0,
            n_parameters: 0,
            supported_parameters: None,
        }
    }

    /// "depends on q2 and on q1 with q3", or that nothing was found.
    pub fn sentence(&self) -> String {
        if !self.structured {
            return format!(
                "a smooth function of the joint angles{} fitted to it under {}-fold cross-validation explains none of it out of sample",
                if self.with_time { " and the time" } else { "" },
                self.folds
            );
        }
        let mut parts: Vec<String> = self
            .model
            .terms
            .iter()
            .filter(|t| **t != Term::Const)
            .map(Term::phrase)
            .collect();
        let constant = self.model.terms.contains(&Term::Const);
        let mut s = if parts.is_empty() {
            "it holds a constant offset".to_string()
        } else {
            let first = parts.remove(0);
            let mut s = format!("it depends on {first}");
            for p in parts {
                s.push_str(&format!(" and on {p}"));
            }
            if constant {
                s.push_str(" (plus a constant offset)");
            }
            s
        };
        s.push_str(&format!(
            ": a smooth function of the joint angles{} explains {:.0} % of it out of sample \
             ({}-fold cross-validated RMS per component {:.4} -> {:.4} mm)",
            if self.with_time { " and the time" } else { "" },
            100.0 * self.explainable_share,
            self.folds,
            self.cv_rms_before_mm,
            self.cv_rms_after_mm
        ));
        s
    }

    /// The JSON summary.
    pub fn report(&self, cfg: &ProbeConfig) -> ProbeReport {
        ProbeReport {
            terms: self.terms.clone(),
            cv_rms_before_mm: self.cv_rms_before_mm,
            cv_rms_after_mm: self.cv_rms_after_mm,
            poses: self.poses,
            folds: self.folds,
            rule: rule_text(cfg),
            change_point: None,
        }
    }
}

/// One-line statement of the probe's rule.
pub fn rule_text(cfg: &ProbeConfig) -> String {
    format!(
        "forward selection (at most {} terms) of a constant, one-variable terms (sin, cos(k q), k = 1..{} for a joint observed over >= {:.0} deg; \
         the cosine series cos(k pi s), k = 1..{}, over the observed range for a narrower joint and for the time t when the poses carry it) \
         and pairwise products (the first {} functions of each variable) fitted to the final residual; a term enters while {}-fold \
         cross-validation lowers the held-out squared error by >= {:.0} % with a paired one-sided t-test p < {:.0e} (Bonferroni over the terms tried){}",
        cfg.max_terms,
        basis::MAIN_HARMONICS,
        basis::PERIODIC_MIN_RANGE_DEG,
        2 * basis::MAIN_HARMONICS,
        2 * basis::PAIR_HARMONICS,
        cfg.folds,
        100.0 * cfg.min_gain,
        cfg.alpha,
        match cfg.floor_mm {
            Some(f) => format!(
                " and explains >= {:.2} x the floor ({f:.4} mm) in RMS per component",
                cfg.floor_min_ratio
            ),
            None => String::new(),
        }
    )
}

/// The Jacobian (3 x unknowns, mm per unit) of `ext`'s prediction at every pose of `data` with
/// respect to `unknowns` (the fitted physical parameters), for [`probe_dataset`] and
/// [`hybrid_report`].
pub fn jacobians(
    ext: &ExtModel,
    data: &MeasuredSet,
    unknowns: &[Unknown],
) -> Result<Vec<DMatrix<f64>>, ModelError> {
    (0..data.len())
        .map(|k| Ok(ext.predict_with_jacobian(data, k, unknowns)?.1))
        .collect()
}

/// Runs the probe on the residual `residual_mm` (measured parts, one per pose of `data`) of a
/// fit of the physical parameters whose Jacobians at the poses are `jacobians` (3 x p each,
/// [`jacobians`]; empty: judge the residual as it is).
pub fn probe_dataset(
    data: &MeasuredSet,
    residual_mm: &[Vector3<f64>],
    jacobians: &[DMatrix<f64>],
    cfg: &ProbeConfig,
) -> ProbeResult {
    probe_dataset_with(data, residual_mm, jacobians, &[], cfg)
}

/// [`probe_dataset`], with `departure` the fitted parameters' departure from their starting
/// (declared) values, one per Jacobian column, for the number of parameters the poses support
/// (empty: not estimated).
pub fn probe_dataset_with(
    data: &MeasuredSet,
    residual_mm: &[Vector3<f64>],
    jacobians: &[DMatrix<f64>],
    departure: &[f64],
    cfg: &ProbeConfig,
) -> ProbeResult {
    let n = data.len().min(residual_mm.len());
    let folds = cfg.folds.max(2);
    let stride = n.div_ceil(cfg.max_poses.max(1)).max(1);
    let used: Vec<usize> = (0..n).step_by(stride).collect();
    if used.len() < 2 * folds {
        return ProbeResult::empty(used.len(), folds);
    }
    let with_time = data.has_time();
    let points: Vec<Vec<f64>> = used.iter().map(|&k| point(data, k, with_time)).collect();
    let m: Vec<Vector3<f64>> = used
        .iter()
        .map(|&k| data.measured_part(k, &residual_mm[k]))
        .collect();
    let projectors: Vec<Option<Matrix3<f64>>> = used
        .iter()
        .map(|&k| match data.directions.as_ref().and_then(|d| d.get(k)) {
            Some(d) if !d.is_empty() => Some(d.iter().map(|u| u * u.transpose()).sum()),
            _ => None,
        })
        .collect();
    let measured_jac: Vec<DMatrix<f64>> = if jacobians.len() >= n {
        used.iter()
            .zip(&projectors)
            .map(|(&k, p)| match p {
                Some(p) => {
                    let j = &jacobians[k];
                    let mut out = DMatrix::zeros(j.nrows(), j.ncols());
                    if j.nrows() == 3 {
                        out.copy_from(&(p * j));
                    }
                    out
                }
                None => jacobians[k].clone(),
            })
            .collect()
    } else {
        Vec::new()
    };
    let serial = data.is_serial();
    let fold = if serial {
        block_fold_assignment(used.len(), folds)
    } else {
        fold_assignment(used.len(), folds, cfg.seed)
    };
    let domain = Domain::of(&points, with_time);
    let terms = domain.candidate_terms();
    let design = Design::new(
        &terms,
        &domain,
        &points,
        &m,
        &projectors,
        &fold,
        folds,
        &measured_jac,
    );
    let n_components: usize = projectors
        .iter()
        .zip(&used)
        .map(|(p, &k)| if p.is_some() { data.rows(k) } else { 3 })
        .sum();
    let sel = select::forward(&design, serial, n_components, cfg);
    let model = ResidualModel::fit(&design, &sel.selected, &domain);
    let rms = |sse: f64| (sse / n_components.max(1) as f64).sqrt();
    let (physical_cv, physical_cv_inflation) = design.physical_cv(n_components);
    let physical_cv_rms_mm = rms(physical_cv.iter().map(|v| v.norm_squared()).sum());
    let supported_parameters = (departure.len() == design.n_physical())
        .then(|| design.supported_parameters(&DVector::from_column_slice(departure)))
        .flatten();
    let structured = !sel.selected.is_empty() && !model.terms.is_empty();
    ProbeResult {
        depends_on: model
            .terms
            .iter()
            .filter(|t| **t != Term::Const)
            .map(Term::name)
            .collect(),
        explainable_share: if sel.baseline_sse > 0.0 {
            (1.0 - sel.final_sse / sel.baseline_sse).max(0.0)
        } else {
            0.0
        },
        structured,
        terms: sel.shares,
        cv_rms_before_mm: rms(sel.baseline_sse),
        cv_rms_after_mm: rms(sel.final_sse),
        model,
        poses: used.len(),
        folds,
        points,
        residual_mm: m,
        projectors,
        with_time,
        physical_cv_rms_mm,
        n_components,
        physical_cv_inflation,
        n_parameters: design.n_physical(),
        supported_parameters,
    }
}
