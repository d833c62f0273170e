//! The geometric identification on normal equations: the [`Accumulator`] of
//! [`super::accumulator`] (per-pose accumulation in reusable workspaces, chunked, deterministic)
//! over a set, and as a [`NormalProblem`] with a second core ([`super::helper`]).

use nalgebra::DVector;

pub use super::accumulator::{
    error_norms_mm, position_errors, Accumulator, JointTrig, CHUNK_POSES, THREADS,
};
use super::accumulator::{n_chunks, Work};
use super::helper::Helper;
use super::measured::PosePoints;
use super::normal::{Normal, NormalProblem};
use super::problem::{SetUnknowns, Unknowns};
use crate::model::{Model, ModelError};

/// The normal equations (symmetric) of `model - measured` over `poses` wrt the parameters `cols`.
pub fn normal_equations(
    model: &Model,
    poses: &PosePoints,
    cols: &[usize],
    tilt: bool,
) -> Result<Normal, ModelError> {
    normal_equations_with(model, poses, None, cols, tilt)
}

/// [`normal_equations`] with the poses' [`JointTrig`].
pub fn normal_equations_with(
    model: &Model,
    poses: &PosePoints,
    trig: Option<&JointTrig>,
    cols: &[usize],
    tilt: bool,
) -> Result<Normal, ModelError> {
    let mut acc = Accumulator::new(model, poses.len(), cols);
    let mut eq = Normal::zeros(cols.len());
    acc.normal_with(model, poses, trig, tilt, &mut eq)?;
    eq.symmetrise();
    Ok(eq)
}

/// The geometric identification ([`super::problem::position_problem`]) as a [`NormalProblem`],
/// on two cores when there are several chunks (a [`Helper`] thread for the problem's lifetime).
pub struct PositionNormalProblem<'a> {
    unknowns: Unknowns,
    poses: &'a PosePoints,
    trig: JointTrig,
    tilt: bool,
    acc: Accumulator,
    helper: Option<Helper>,
}

impl<'a> PositionNormalProblem<'a> {
    /// A problem on a copy of `model` with the parameters `cols` as unknowns.
    pub fn new(model: &Model, poses: &'a PosePoints, cols: Vec<usize>, tilt: bool) -> Self {
        Self::with_trig(model, poses, JointTrig::new(poses), cols, tilt)
    }

    /// [`PositionNormalProblem::new`] with the poses' [`JointTrig`] already computed.
    pub fn with_trig(
        model: &Model,
        poses: &'a PosePoints,
        trig: JointTrig,
        cols: Vec<usize>,
        tilt: bool,
    ) -> Self {
        let chunks = n_chunks(poses.len());
        let unknowns = Unknowns::new(model, cols);
        let helper = (chunks > 1 && THREADS > 1)
            .then(|| Helper::spawn(&unknowns, poses, tilt, chunks.div_ceil(2), chunks))
            .flatten();
        let threads = if helper.is_some() { 1 } else { THREADS };
        let acc = Accumulator::with_threads(model, poses.len(), unknowns.cols(), threads);
        Self {
            unknowns,
            poses,
            trig,
            tilt,
            acc,
            helper,
        }
    }

    /// The model and its unknowns.
    pub fn into_unknowns(self) -> Unknowns {
        self.unknowns
    }

    /// `work` at `x`: the first half of the chunks here, the second on the helper.
    fn evaluate(&mut self, x: &DVector<f64>, work: Work) -> Result<(), ModelError> {
        self.unknowns.set(x)?;
        let chunks = n_chunks(self.poses.len());
        let (model, poses, trig, tilt) = (
            self.unknowns.model(),
            self.poses,
            Some(&self.trig),
            self.tilt,
        );
        let Some(helper) = self.helper.as_mut() else {
            return match work {
                Work::Normal => self.acc.normal_chunks_threaded(model, poses, trig, tilt),
                Work::SumSq => self.acc.sum_sq_with(model, poses, trig, tilt).map(|_| ()),
            };
        };
        let half = chunks.div_ceil(2);
        helper.start(x, work, half..chunks)?;
        let here = self.acc.run_here(model, poses, trig, tilt, work, 0..half);
        let (normals, sums) = self.acc.partial_mut();
        let there = helper.finish(work, normals, sums);
        here.and(there)
    }
}

impl NormalProblem for PositionNormalProblem<'_> {
    type Error = ModelError;

    fn n_params(&self) -> usize {
        self.unknowns.cols().len()
    }

    fn n_residuals(&self) -> usize {
        3 * self.poses.len()
    }

    fn sum_sq(&mut self, x: &DVector<f64>) -> Result<f64, ModelError> {
        self.evaluate(x, Work::SumSq)?;
        Ok(self.acc.partial_mut().1.iter().sum())
    }

    fn normal(&mut self, x: &DVector<f64>, eq: &mut Normal) -> Result<(), ModelError> {
        self.evaluate(x, Work::Normal)?;
        self.acc.total(eq);
        Ok(())
    }
}
