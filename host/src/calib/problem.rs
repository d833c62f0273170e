//! Measured poses, position errors of a model, and the geometric identification as a
//! least-squares [`Problem`].

use nalgebra::{DMatrix, DVector, Vector3};

use super::lm::Problem;
use crate::model::{Model, ModelError, Tilt};

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
    poses
        .q_deg
        .iter()
        .zip(&poses.xyz_mm)
        .map(|(q, m)| Ok(m - model.position_mm(q, tilt_mode(tilt))?))
        .collect()
}

/// Geometric identification: unknowns are the values of the parameters `cols` (model indices,
/// parameter units); residuals are `model - measured` (x, y, z of every pose, mm).
pub struct PositionProblem<'a> {
    model: Model,
    poses: &'a Poses,
    cols: Vec<usize>,
    tilt: bool,
}

impl<'a> PositionProblem<'a> {
    /// A problem on a copy of `model` (all other parameters stay at their values in `model`).
    pub fn new(model: &Model, poses: &'a Poses, cols: Vec<usize>, tilt: bool) -> Self {
        Self {
            model: model.clone(),
            poses,
            cols,
            tilt,
        }
    }

    /// Current values of the unknowns in the model.
    pub fn start(&self) -> DVector<f64> {
        let v = self.model.param_values();
        DVector::from_iterator(self.cols.len(), self.cols.iter().map(|&c| v[c]))
    }

    /// Writes `x` into the model.
    pub fn set(&mut self, x: &DVector<f64>) -> Result<(), ModelError> {
        for (&c, &v) in self.cols.iter().zip(x.iter()) {
            self.model.set_param_at(c, v)?;
        }
        Ok(())
    }

    /// The model with the unknowns last set.
    pub fn into_model(self) -> Model {
        self.model
    }
}

impl Problem for PositionProblem<'_> {
    type Error = ModelError;

    fn n_params(&self) -> usize {
        self.cols.len()
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
        self.set(x)?;
        let tilt = tilt_mode(self.tilt);
        match jac {
            Some(jac) => {
                for (i, (q, m)) in self.poses.q_deg.iter().zip(&self.poses.xyz_mm).enumerate() {
                    let (fk, j) = self.model.param_jacobian(q, tilt, &self.cols)?;
                    r.fixed_rows_mut::<3>(3 * i)
                        .copy_from(&(fk.position_mm - m));
                    jac.view_mut((3 * i, 0), (3, self.cols.len())).copy_from(&j);
                }
            }
            None => {
                for (i, (q, m)) in self.poses.q_deg.iter().zip(&self.poses.xyz_mm).enumerate() {
                    let p = self.model.position_mm(q, tilt)?;
                    r.fixed_rows_mut::<3>(3 * i).copy_from(&(p - m));
                }
            }
        }
        Ok(())
    }
}

/// The stacked identification Jacobian (3 rows per pose) of `model` wrt `cols`.
pub fn stacked_jacobian(
    model: &Model,
    poses: &Poses,
    cols: &[usize],
    tilt: bool,
) -> Result<DMatrix<f64>, ModelError> {
    let mut jac = DMatrix::zeros(3 * poses.len(), cols.len());
    for (i, q) in poses.q_deg.iter().enumerate() {
        let (_, j) = model.param_jacobian(q, tilt_mode(tilt), cols)?;
        jac.view_mut((3 * i, 0), (3, cols.len())).copy_from(&j);
    }
    Ok(jac)
}
