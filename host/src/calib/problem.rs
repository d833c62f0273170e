//! Measured poses, position errors of a model, and the geometric identification as a
//! least-squares [`Problem`].

use nalgebra::{DMatrix, DVector, Vector3};

use super::lm::Problem;
use crate::model::{Data, Model, ModelError, Tilt, Wrt};

/// Measured poses: joint readings (deg, one vector per pose) and the measured tool point
/// (mm, frame R).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Poses {
    /// Joint readings `q1..qN` of every pose (deg).
    pub q_deg: Vec<Vec<f64>>,
    /// Measured tool point of every pose (mm).
    pub xyz_mm: Vec<Vector3<f64>>,
}

impl Poses {
    /// Number of poses.
    pub fn len(&self) -> usize {
        self.xyz_mm.len().min(self.q_deg.len())
    }

    /// Whether there is no pose.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The poses of a pose file read with `x, y, z` required (`None` if the file has no
    /// positions).
    pub fn from_pose_file(file: &crate::io::pose_csv::PoseFile) -> Option<Self> {
        let xyz = file.positions_mm()?;
        Some(Poses {
            q_deg: file.joints(),
            xyz_mm: xyz.into_iter().map(Vector3::from).collect(),
        })
    }

    /// Reads a pose file with measured positions for `model` (joint count and limits checked).
    pub fn read(
        path: &std::path::Path,
        model: &Model,
    ) -> Result<Self, crate::io::pose_csv::PoseCsvError> {
        use crate::io::pose_csv::{read_poses, PoseSpec};
        let file = read_poses(path, &PoseSpec::for_model(model, true))?;
        Ok(Self::from_pose_file(&file).unwrap_or_default())
    }

    /// The first `n` poses and the rest (for hold-out splits).
    /// The poses `keep` (indices, in that order).
    pub fn subset(&self, keep: &[usize]) -> Poses {
        Poses {
            q_deg: keep.iter().map(|&k| self.q_deg[k].clone()).collect(),
            xyz_mm: keep.iter().map(|&k| self.xyz_mm[k]).collect(),
        }
    }

    pub fn split_at(&self, n: usize) -> (Poses, Poses) {
        let n = n.min(self.len());
        (
            Poses {
                q_deg: self.q_deg[..n].to_vec(),
                xyz_mm: self.xyz_mm[..n].to_vec(),
            },
            Poses {
                q_deg: self.q_deg[n..].to_vec(),
                xyz_mm: self.xyz_mm[n..].to_vec(),
            },
        )
    }
}

/// The tilt mode used for the declared model: static gravity tilting when `tilt` is set.
pub fn tilt_mode(tilt: bool) -> Tilt<'static> {
    if tilt {
        Tilt::Static
    } else {
        Tilt::Off
    }
}

/// Position errors `measured - model` of every pose (mm).
pub fn position_errors(
    model: &Model,
    poses: &Poses,
    tilt: bool,
) -> Result<Vec<Vector3<f64>>, ModelError> {
    super::accumulate::position_errors(model, poses, tilt)
}

/// Norms of error vectors (mm).
pub fn norms_mm(errors_mm: &[Vector3<f64>]) -> Vec<f64> {
    errors_mm.iter().map(|e| e.norm()).collect()
}

/// Norm of the position error `measured - model` of every pose (mm).
pub fn error_norms_mm(model: &Model, poses: &Poses, tilt: bool) -> Result<Vec<f64>, ModelError> {
    Ok(norms_mm(&position_errors(model, poses, tilt)?))
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

    /// Writes `x` into the model.
    pub fn set(&mut self, x: &DVector<f64>) -> Result<(), ModelError> {
        set_params(&mut self.model, &self.cols, x)
    }

    /// The model with the unknowns last set.
    pub fn into_model(self) -> Model {
        self.model
    }
}

/// A least-squares [`Problem`] whose unknowns are parameters of a model ([`Unknowns`]), as
/// solved by [`super::fit::fit_problem`].
pub trait ModelProblem: Problem<Error = ModelError> {
    /// Gives the model and its unknowns back.
    fn into_unknowns(self) -> Unknowns;
}

/// Geometric identification: unknowns are the values of the parameters `cols` (model indices,
/// parameter units); residuals are `model - measured` (x, y, z of every pose, mm).
pub struct PositionProblem<'a> {
    unknowns: Unknowns,
    poses: &'a Poses,
    tilt: bool,
}

impl<'a> PositionProblem<'a> {
    /// A problem on a copy of `model` (all other parameters stay at their values in `model`).
    pub fn new(model: &Model, poses: &'a Poses, cols: Vec<usize>, tilt: bool) -> Self {
        Self {
            unknowns: Unknowns::new(model, cols),
            poses,
            tilt,
        }
    }
}

impl ModelProblem for PositionProblem<'_> {
    fn into_unknowns(self) -> Unknowns {
        self.unknowns
    }
}

impl Problem for PositionProblem<'_> {
    type Error = ModelError;

    fn n_params(&self) -> usize {
        self.unknowns.cols.len()
    }

    fn n_residuals(&self) -> usize {
        3 * self.poses.len()
    }

    fn evaluate(
        &mut self,
        x: &DVector<f64>,
        r: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), ModelError> {
        self.unknowns.set(x)?;
        position_rows(
            &self.unknowns.model,
            self.poses,
            &self.unknowns.cols,
            self.tilt,
            r,
            jac,
        )
    }
}

/// Residuals `model - measured` of every pose (3 rows per pose, mm) into `r`, and with `jac`
/// their Jacobian wrt the parameters `cols` (`r` and `jac` have `3 * poses.len()` rows).
fn position_rows(
    model: &Model,
    poses: &Poses,
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
                r.fixed_rows_mut::<3>(3 * i)
                    .copy_from(&(d.position_mm() - m));
                for (k, col) in d.jacobian().iter().enumerate() {
                    jac.fixed_view_mut::<3, 1>(3 * i, k).copy_from(col);
                }
            }
        }
        None => {
            for (i, (q, m)) in rows {
                model.fk_with(&mut d, q, tilt)?;
                r.fixed_rows_mut::<3>(3 * i)
                    .copy_from(&(d.position_mm() - m));
            }
        }
    }
    Ok(())
}

/// The stacked identification Jacobian (3 rows per pose) of `model` wrt `cols`.
pub fn stacked_jacobian(
    model: &Model,
    poses: &Poses,
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
