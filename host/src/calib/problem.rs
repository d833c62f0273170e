//! Position errors of a model, and the geometric identification as a least-squares
//! [`Problem`].

use nalgebra::{DMatrix, DVector, Vector3};

use super::lm::Problem;
use super::measured::PosePoints;
use crate::model::{Data, Model, ModelError, Tilt, Wrt};

/// The tilt mode used for the declared model: static gravity tilting when `tilt` is set.
pub fn tilt_mode(tilt: bool) -> Tilt<'static> {
    if tilt {
        Tilt::Static
    } else {
        Tilt::Off
    }
}

/// Norms of error vectors (mm).
pub fn norms_mm(errors_mm: &[Vector3<f64>]) -> Vec<f64> {
    errors_mm.iter().map(|e| e.norm()).collect()
}

/// The values of the parameters `cols` of `model`, as a vector (NaN for an index that is not a
/// parameter: writing it back then fails with [`ModelError::ParamIndex`]).
pub fn param_vector(model: &Model, cols: &[usize]) -> DVector<f64> {
    let params = model.params();
    DVector::from_iterator(
        cols.len(),
        cols.iter()
            .map(|&c| params.get(c).map_or(f64::NAN, |p| p.value)),
    )
}

/// Writes `x` into the parameters `cols` of `model` (in order).
pub fn set_params(model: &mut Model, cols: &[usize], x: &DVector<f64>) -> Result<(), ModelError> {
    for (&c, &v) in cols.iter().zip(x.iter()) {
        model.set_param_at(c, v)?;
    }
    Ok(())
}

/// The unknowns of an identification: a copy of a model whose parameters `cols` (model
/// indices, parameter units) are the unknowns; all others stay at their values.
#[derive(Debug, Clone)]
pub struct Unknowns {
    model: Model,
    cols: Vec<usize>,
}

impl Unknowns {
    /// The parameters `cols` of a copy of `model`.
    pub fn new(model: &Model, cols: Vec<usize>) -> Self {
        Self {
            model: model.clone(),
            cols,
        }
    }

    /// The model with the unknowns last set.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The unknowns' model indices.
    pub fn cols(&self) -> &[usize] {
        &self.cols
    }

    /// The model with the unknowns last set.
    pub fn into_model(self) -> Model {
        self.model
    }
}

impl SetUnknowns for Unknowns {
    fn n_unknowns(&self) -> usize {
        self.cols.len()
    }

    fn set(&mut self, x: &DVector<f64>) -> Result<(), ModelError> {
        set_params(&mut self.model, &self.cols, x)
    }
}

/// What a solver's vector is written into: the unknowns of a model state, in order
/// ([`Unknowns`], [`super::unknown::Freed`], [`super::tree_fit::TreeUnknowns`]; a plain vector
/// is the state of a problem written directly in its unknowns).
pub trait SetUnknowns {
    /// Number of unknowns.
    fn n_unknowns(&self) -> usize;
    /// Writes `x` into the state.
    fn set(&mut self, x: &DVector<f64>) -> Result<(), ModelError>;
}

impl SetUnknowns for DVector<f64> {
    fn n_unknowns(&self) -> usize {
        self.len()
    }

    fn set(&mut self, x: &DVector<f64>) -> Result<(), ModelError> {
        self.copy_from(x);
        Ok(())
    }
}

/// The residual rows of a set of measurements as a function of a state `S`: writes
/// `predicted - measured` at the state's current values into `r` and, when `jac` is given, their
/// Jacobian wrt the state's unknowns.
pub trait Rows<S>:
    FnMut(&S, &mut DVector<f64>, Option<&mut DMatrix<f64>>) -> Result<(), ModelError>
{
}

impl<S, F> Rows<S> for F where
    F: FnMut(&S, &mut DVector<f64>, Option<&mut DMatrix<f64>>) -> Result<(), ModelError>
{
}

/// An identification as a least-squares [`Problem`]: the unknowns of a state `S`
/// ([`SetUnknowns`]) and the residual rows of the measurements at its values ([`Rows`]). Every
/// identification of `calibrate` and `diagnose` on the tall Jacobian is one (full positions,
/// projected measurements, point offsets and compliance, the extended model).
pub struct ModelProblem<S, F> {
    state: S,
    n_residuals: usize,
    rows: F,
}

impl<S, F> ModelProblem<S, F>
where
    S: SetUnknowns,
    F: FnMut(&S, &mut DVector<f64>, Option<&mut DMatrix<f64>>) -> Result<(), ModelError>,
{
    /// The problem of `n_residuals` rows `rows` on the unknowns of `state`.
    pub fn new(state: S, n_residuals: usize, rows: F) -> Self {
        Self {
            state,
            n_residuals,
            rows,
        }
    }
}

impl<S, F> ModelProblem<S, F> {
    /// The state with the unknowns last set.
    pub fn into_state(self) -> S {
        self.state
    }
}

impl<S: SetUnknowns, F: Rows<S>> Problem for ModelProblem<S, F> {
    type Error = ModelError;

    fn n_params(&self) -> usize {
        self.state.n_unknowns()
    }

    fn n_residuals(&self) -> usize {
        self.n_residuals
    }

    fn evaluate(
        &mut self,
        x: &DVector<f64>,
        r: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), ModelError> {
        self.state.set(x)?;
        (self.rows)(&self.state, r, jac)
    }
}

/// An identification of model parameters: unknowns are the values of the parameters `cols` of
/// a copy of `model` (model indices, parameter units; all others stay at their values), the
/// `n_residuals` rows written by `rows` from that model and `cols` ([`Rows`]).
pub fn param_problem<'a, F>(
    model: &Model,
    cols: Vec<usize>,
    n_residuals: usize,
    mut rows: F,
) -> ModelProblem<Unknowns, impl Rows<Unknowns> + 'a>
where
    F: FnMut(
            &Model,
            &[usize],
            &mut DVector<f64>,
            Option<&mut DMatrix<f64>>,
        ) -> Result<(), ModelError>
        + 'a,
{
    let rows = move |u: &Unknowns, r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>| {
        rows(u.model(), u.cols(), r, jac)
    };
    ModelProblem::new(Unknowns::new(model, cols), n_residuals, rows)
}

/// Geometric identification ([`param_problem`]): residuals are `model - measured` (x, y, z of
/// every pose, mm).
pub fn position_problem<'a>(
    model: &Model,
    poses: &'a PosePoints,
    cols: Vec<usize>,
    tilt: bool,
) -> ModelProblem<Unknowns, impl Rows<Unknowns> + 'a> {
    param_problem(model, cols, 3 * poses.len(), move |m, cols, r, jac| {
        position_rows(m, poses, cols, tilt, r, jac)
    })
}

/// Writes the residual `predicted - measured` of one full position into rows `row..row + 3` of
/// `r` and, with `jac`, its Jacobian `columns` (one 3-vector per unknown) into the same rows: the
/// rows of a full position in every identification.
pub fn put_position_rows(
    row: usize,
    predicted_mm: &Vector3<f64>,
    measured_mm: &Vector3<f64>,
    r: &mut DVector<f64>,
    jac: Option<(&mut DMatrix<f64>, &mut dyn Iterator<Item = Vector3<f64>>)>,
) {
    r.fixed_rows_mut::<3>(row)
        .copy_from(&(predicted_mm - measured_mm));
    if let Some((jac, columns)) = jac {
        for (c, col) in columns.enumerate() {
            jac.fixed_view_mut::<3, 1>(row, c).copy_from(&col);
        }
    }
}

/// Residuals `model - measured` of every pose (3 rows per pose, mm) into `r`, and with `jac`
/// their Jacobian wrt the parameters `cols` (`r` and `jac` have `3 * poses.len()` rows).
fn position_rows(
    model: &Model,
    poses: &PosePoints,
    cols: &[usize],
    tilt: bool,
    r: &mut DVector<f64>,
    jac: Option<&mut DMatrix<f64>>,
) -> Result<(), ModelError> {
    let tilt = tilt_mode(tilt);
    let rows = poses.q_deg.iter().zip(&poses.xyz_mm).enumerate();
    let mut d = Data::new(model);
    match jac {
        Some(jac) => {
            let wrt: Vec<Wrt> = cols.iter().map(|&c| Wrt::Param(c)).collect();
            for (i, (q, m)) in rows {
                model.jacobian_with(&mut d, q, tilt, &wrt)?;
                let mut columns = d.jacobian().iter().copied();
                let jac = Some((
                    &mut *jac,
                    &mut columns as &mut dyn Iterator<Item = Vector3<f64>>,
                ));
                put_position_rows(3 * i, &d.position_mm(), m, r, jac);
            }
        }
        None => {
            for (i, (q, m)) in rows {
                model.fk_with(&mut d, q, tilt)?;
                put_position_rows(3 * i, &d.position_mm(), m, r, None);
            }
        }
    }
    Ok(())
}

/// The stacked identification Jacobian (3 rows per pose) of `model` wrt `cols`.
pub fn stacked_jacobian(
    model: &Model,
    poses: &PosePoints,
    cols: &[usize],
    tilt: bool,
) -> Result<DMatrix<f64>, ModelError> {
    let rows = 3 * poses.len();
    let mut jac = DMatrix::zeros(rows, cols.len());
    position_rows(
        model,
        poses,
        cols,
        tilt,
        &mut DVector::zeros(rows),
        Some(&mut jac),
    )?;
    Ok(jac)
}
