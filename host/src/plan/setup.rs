//! The identification Jacobian of every candidate pose, restricted to what the whole candidate
//! set can identify, with its columns scaled.

use nalgebra::DMatrix;

pub use super::candidates::joints_dataset;
use super::candidates::CandidatePose;
use super::robust::Linearity;
use super::PlanError;
use crate::calib::default_selection;
use crate::calib::identifiability::{analyse, DEFAULT_RTOL};
use crate::diagnose::extended::{ExtModel, Unknown};
use crate::model::Model;

/// The design problem: scaled Jacobian blocks of the candidates (and of the poses already
/// measured), the unknowns and their names.
#[derive(Debug, Clone)]
pub struct Setup {
    /// The model (with the declared tilting when it has tilting data) the Jacobians are taken at.
    pub ext: ExtModel,
    /// The identifiable unknowns, in column order.
    pub unknowns: Vec<Unknown>,
    /// Their names (model parameter names; `compliance_j2_deg_per_kgfm` for compliance).
    pub names: Vec<String>,
    /// Unidentifiable parameters or combinations on the whole candidate set (`"dth5+be4"`).
    pub unidentifiable: Vec<String>,
    /// Column scale: RMS norm of each column's 3-row block over the candidates (unknown units
    /// to "per pose").
    pub scale: Vec<f64>,
    /// Scaled Jacobian of the candidates, 3 rows per candidate.
    pub b: DMatrix<f64>,
    /// Scaled Jacobian of the poses already measured (0 rows for none).
    pub prior_rows: DMatrix<f64>,
    /// Columns whose separation is wanted (Ds-optimality); empty: all (D-optimality).
    pub interest: Vec<usize>,
    /// The linearity test of the unknowns of interest over their plausible values
    /// ([`super::robust`]; `--from-diagnose`), `None`: every pose is admissible.
    pub linearity: Option<Linearity>,
    /// Per candidate, whether it passes that test (empty: all do).
    pub admissible: Vec<bool>,
}

impl Setup {
    /// The scaled Jacobian block (3 x p, same columns and scale as [`Setup::b`]) of one
    /// configuration `q_deg` (deg), e.g. a pose moved off the candidate set.
    pub fn block_at(&self, q_deg: &[f64]) -> Result<DMatrix<f64>, PlanError> {
        self.scaled_jacobian(&self.ext, &[q_deg.to_vec()])
    }

    /// The scaled Jacobian (3 rows per configuration of `q`, the columns and scale of
    /// [`Setup::b`]) of the model `ext` (e.g. a moved one).
    pub fn scaled_jacobian(
        &self,
        ext: &ExtModel,
        q: &[Vec<f64>],
    ) -> Result<DMatrix<f64>, PlanError> {
        let (jac, _) = ext.stacked(&joints_dataset(q), &self.unknowns)?;
        Ok(DMatrix::from_fn(jac.nrows(), jac.ncols(), |r, c| {
            jac[(r, c)] / self.scale[c]
        }))
    }

    /// Whether the configuration `q_deg` passes the linearity test ([`Setup::linearity`]).
    pub fn admits(&self, q_deg: &[f64]) -> Result<bool, PlanError> {
        match &self.linearity {
            Some(l) => l.admits(q_deg),
            None => Ok(true),
        }
    }

    /// The declared identification: [`default_selection`] with the declared tilting, its
    /// contact direction held fixed in the Jacobian ([`Model::set_tilt_direction_frozen`]).
    pub fn declared(
        model: &Model,
        cands: &[CandidatePose],
        prior_q: &[Vec<f64>],
    ) -> Result<Self, PlanError> {
        Self::declared_with_base(model, cands, prior_q, false)
    }

    /// As [`Setup::declared`], with the base frame among the parameters when `base` (as
    /// `calibrate --base` identifies it).
    pub fn declared_with_base(
        model: &Model,
        cands: &[CandidatePose],
        prior_q: &[Vec<f64>],
        base: bool,
    ) -> Result<Self, PlanError> {
        let requested: Vec<Unknown> = default_selection(model, base)
            .into_iter()
            .map(Unknown::Param)
            .collect();
        // design on the Jacobian with the clearance tilt's direction held fixed: its slope is
        // unbounded where a joint's moment vanishes (see `Model::set_tilt_direction_frozen`)
        let mut ext = ExtModel::new(model.clone());
        ext.model.set_tilt_direction_frozen(true);
        Self::build(ext, cands, &requested, &[], prior_q)
    }

    /// The problem for the unknowns `requested` (earlier ones are kept when a combination is
    /// unidentifiable), wanting to separate `interest`, given poses `prior_q` already measured.
    pub fn build(
        ext: ExtModel,
        cands: &[CandidatePose],
        requested: &[Unknown],
        interest: &[Unknown],
        prior_q: &[Vec<f64>],
    ) -> Result<Self, PlanError> {
        let q: Vec<Vec<f64>> = cands.iter().map(|c| c.q_deg.clone()).collect();
        let (jac_all, _) = ext.stacked(&joints_dataset(&q), requested)?;
        let names_all: Vec<String> = requested.iter().map(|u| u.name(&ext.model)).collect();
        let Scaled {
            kept,
            unidentifiable,
            scale,
            b,
        } = Scaled::of(&jac_all, &names_all, cands.len());
        let scaled = |jac: &DMatrix<f64>| {
            DMatrix::from_fn(jac.nrows(), kept.len(), |r, c| jac[(r, kept[c])] / scale[c])
        };
        let prior_rows = if prior_q.is_empty() {
            DMatrix::zeros(0, kept.len())
        } else {
            scaled(&ext.stacked(&joints_dataset(prior_q), requested)?.0)
        };
        let unknowns: Vec<Unknown> = kept.iter().map(|&k| requested[k]).collect();
        let interest_cols = unknowns
            .iter()
            .enumerate()
            .filter(|(_, u)| interest.contains(u))
            .map(|(c, _)| c)
            .collect();
        Ok(Self {
            names: unknowns.iter().map(|u| u.name(&ext.model)).collect(),
            unknowns,
            unidentifiable,
            scale,
            b,
            prior_rows,
            interest: interest_cols,
            ext,
            linearity: None,
            admissible: Vec::new(),
        })
    }
}

/// The columns of a candidate set's Jacobian that the whole set identifies, scaled to unit RMS
/// per candidate so that degrees and millimetres compare (a chain's or a tree's).
#[derive(Debug, Clone)]
pub struct Scaled {
    /// The identifiable columns of the Jacobian, in order.
    pub kept: Vec<usize>,
    /// The unidentifiable combinations, by name.
    pub unidentifiable: Vec<String>,
    /// The scale of every kept column (its RMS per candidate; 1 for a zero column).
    pub scale: Vec<f64>,
    /// The kept columns divided by their scale.
    pub b: DMatrix<f64>,
}

impl Scaled {
    /// The identifiable, scaled columns of `jac_all` (the Jacobian of `n_cand` candidates, its
    /// columns named `names`).
    pub fn of(jac_all: &DMatrix<f64>, names: &[String], n_cand: usize) -> Self {
        let id = analyse(jac_all, DEFAULT_RTOL);
        let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let unidentifiable = id.combinations.iter().map(|c| c.name(&name_refs)).collect();
        let kept = id.kept;
        let root_n = (n_cand.max(1) as f64).sqrt();
        let scale: Vec<f64> = kept
            .iter()
            .map(|&k| {
                let s = jac_all.column(k).norm() / root_n;
                if s > 0.0 && s.is_finite() {
                    s
                } else {
                    1.0
                }
            })
            .collect();
        let b = DMatrix::from_fn(jac_all.nrows(), kept.len(), |r, c| {
            jac_all[(r, kept[c])] / scale[c]
        });
        Self {
            kept,
            unidentifiable,
            scale,
            b,
        }
    }
}
