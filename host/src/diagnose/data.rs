//! Measurements as the diagnosis uses them: full positions (a pose file) or **partial** ones
//! (the fused samples of the low-cost rig, `rigctl fuse`), with their times.
//!
//! A pose carries its joint readings and a measured point. For a partial measurement only some
//! components of that point are measured: the projections on the orthonormal directions of
//! [`Dataset::directions`] (for a fused sample the across-path direction `u` in the sheet plane
//! and the sheet normal `n`); the stored point is the fusing model's nominal point moved by the
//! measured deviations, so its component along the path (not measured) is the nominal one and is
//! projected out of every error, Jacobian and statistic. The error of a pose is the **measured
//! part** `sum_d (d . (measured - predicted)) d` of the error vector (all of it for a full
//! position), and each measured direction is one residual.
//!
//! Samples taken densely along a traced path are serially correlated; the selection rule
//! accounts for that ([`Dataset::is_serial`], [`super::decide`]).

use std::path::Path;

use nalgebra::{DMatrix, Vector3};

use crate::calib::Poses;
use crate::fusion::FusedSample;
use crate::io::pose_csv::{read_poses, PoseCsvError, PoseSpec};
use crate::model::motion::moments_in_motion;
use crate::model::transmission::approach_directions;
use crate::model::{Model, ModelError};

/// Measured poses and, when known, the time of each measurement (s since the start of the
/// session).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Dataset {
    /// Joint readings and measured positions (partial measurements: see the module docs).
    pub poses: Poses,
    /// Time of every pose (s), `None` without a `t` column.
    pub t_s: Option<Vec<f64>>,
    /// Measured directions of every pose (orthonormal, frame R); `None` when every pose is a
    /// full position. An empty list at a pose means all three axes.
    pub directions: Option<Vec<Vec<Vector3<f64>>>>,
    /// Inertial joint moments (kgf.m, joint frames) at every pose: the moments in motion along
    /// a logged trajectory minus the static ones, both of the model the samples were read with.
    /// The declared tilting is driven by the static moments of the model being fitted (which
    /// follow its payload and base tilt) plus these ([`crate::model::Tilt::StaticPlus`]);
    /// `None`: static moments only.
    pub moments_kgfm: Option<Vec<Vec<Vector3<f64>>>>,
    /// Direction in which every joint last moved before each pose (+1 up, -1 down, 0 no
    /// history), from the pose order ([`crate::model::transmission::approach_directions`]); `None` until computed
    /// ([`Dataset::with_approach`]). Kept through [`Dataset::subset`], so a fold keeps the
    /// history of the full visit order.
    pub approach: Option<Vec<Vec<f64>>>,
    /// Pose names (`id` column), when every row has one: poses measured more than once
    /// ([`super::floor::repeatability_mm`]).
    pub ids: Option<Vec<String>>,
    /// Line of every pose in its file (1-based), when read from a pose file: names the poses
    /// left out as gross errors.
    pub lines: Option<Vec<usize>>,
}

impl Dataset {
    /// Poses without times.
    pub fn from_poses(poses: Poses) -> Self {
        Self {
            poses,
            ..Self::default()
        }
    }

    /// Reads a pose file with measured positions for `model` (joint count and limits checked).
    /// `t` is used only if every row has it.
    pub fn read(path: &Path, model: &Model) -> Result<Self, PoseCsvError> {
        Self::read_with(path, &PoseSpec::for_model(model, true))
    }

    /// As [`Dataset::read`] with the file's expectations `spec` (units, joint names, which
    /// measured point of a file with several is the pose's point).
    pub fn read_with(path: &Path, spec: &PoseSpec) -> Result<Self, PoseCsvError> {
        let file = read_poses(path, spec)?;
        let poses = Poses::from_pose_file(&file).unwrap_or_default();
        let t: Option<Vec<f64>> = file.poses.iter().map(|p| p.t_s).collect();
        let ids: Option<Vec<String>> = file.poses.iter().map(|p| p.id.clone()).collect();
        Ok(Self {
            poses,
            t_s: t,
            ids,
            lines: Some(file.poses.iter().map(|p| p.line).collect()),
            ..Self::default()
        }
        .with_approach())
    }

    /// Partial measurements from fused samples (one path): two measured directions per sample
    /// (`u`, and `n` made orthogonal to it), the samples' times, and the inertial part of the
    /// moments in motion of `model` along the logged joints.
    pub fn from_fused(samples: &[FusedSample], model: &Model) -> Result<Self, ModelError> {
        let mut q_deg = Vec::with_capacity(samples.len());
        let mut xyz_mm = Vec::with_capacity(samples.len());
        let mut t_s = Vec::with_capacity(samples.len());
        let mut directions = Vec::with_capacity(samples.len());
        for s in samples {
            let u = s.u.normalize();
            let n = (s.n - u * u.dot(&s.n)).normalize();
            if !(u.iter().chain(n.iter()).all(|v| v.is_finite())) {
                return Err(ModelError::NonFinite {
                    name: format!("measured directions of the sample at t = {} s", s.t_s),
                    value: f64::NAN,
                });
            }
            q_deg.push(s.q_deg.clone());
            xyz_mm.push(s.nominal_mm + s.u * s.dev_u_mm + s.n * s.dev_n_mm);
            t_s.push(s.t_s);
            directions.push(vec![u, n]);
        }
        let moments = moments_in_motion(model, &t_s, &q_deg)?
            .into_iter()
            .zip(&q_deg)
            .map(|(m, q)| {
                let stat = model.moments_kgfm(q)?;
                Ok(m.iter().zip(&stat).map(|(a, b)| a - b).collect())
            })
            .collect::<Result<Vec<Vec<Vector3<f64>>>, ModelError>>()?;
        Ok(Self {
            poses: Poses { q_deg, xyz_mm },
            t_s: Some(t_s),
            directions: Some(directions),
            moments_kgfm: Some(moments),
            approach: None,
            ids: None,
            lines: None,
        }
        .with_approach())
    }

    /// `self` followed by `other` (e.g. the samples of two sheets, or poses and samples). Times
    /// are kept only when both have them; directions and inertial moments when either has them
    /// (full positions get all three axes, poses at rest zero inertial moments).
    pub fn concat(mut self, other: Dataset) -> Self {
        let (n0, n1) = (self.len(), other.len());
        let a0 = self.approach_or_computed();
        let a1 = other.approach_or_computed();
        self.t_s = match (self.t_s.take(), other.t_s) {
            (Some(mut a), Some(b)) => {
                a.extend(b);
                Some(a)
            }
            _ => None,
        };
        self.directions = match (self.directions.take(), other.directions) {
            (None, None) => None,
            (a, b) => {
                let mut d = a.unwrap_or_else(|| vec![Vec::new(); n0]);
                d.extend(b.unwrap_or_else(|| vec![Vec::new(); n1]));
                Some(d)
            }
        };
        // poses without inertial moments are at rest: zero extra moments (static tilting)
        let zeros = |n: usize, like: &Vec<Vec<Vector3<f64>>>| {
            let nj = like.first().map_or(0, Vec::len);
            vec![vec![Vector3::zeros(); nj]; n]
        };
        self.moments_kgfm = match (self.moments_kgfm.take(), other.moments_kgfm) {
            (None, None) => None,
            (Some(mut a), Some(b)) => {
                a.extend(b);
                Some(a)
            }
            (Some(mut a), None) => {
                let z = zeros(n1, &a);
                a.extend(z);
                Some(a)
            }
            (None, Some(b)) => {
                let mut a = zeros(n0, &b);
                a.extend(b);
                Some(a)
            }
        };
        // each file keeps its own history (its first pose has none)
        self.approach = Some(a0.into_iter().chain(a1).collect());
        self.ids = match (self.ids.take(), other.ids) {
            (Some(mut a), Some(b)) => {
                a.extend(b);
                Some(a)
            }
            _ => None,
        };
        self.lines = match (self.lines.take(), other.lines) {
            (Some(mut a), Some(b)) => {
                a.extend(b);
                Some(a)
            }
            _ => None,
        };
        self.poses.q_deg.extend(other.poses.q_deg);
        self.poses.xyz_mm.extend(other.poses.xyz_mm);
        self
    }

    /// `self` with [`Dataset::approach`] computed from the pose order when it is not set.
    pub fn with_approach(mut self) -> Self {
        if self.approach.as_ref().map(Vec::len) != Some(self.len()) {
            self.approach = Some(self.approach_or_computed());
        }
        self
    }

    fn approach_or_computed(&self) -> Vec<Vec<f64>> {
        match &self.approach {
            Some(a) if a.len() == self.len() => a.clone(),
            _ => approach_directions(&self.poses.q_deg, self.t_s.as_deref()),
        }
    }

    /// Direction joint `j` last moved before pose `k` (+1, -1, 0).
    pub fn approach(&self, k: usize, j: usize) -> f64 {
        self.approach
            .as_ref()
            .and_then(|a| a.get(k))
            .and_then(|d| d.get(j))
            .copied()
            .unwrap_or(0.0)
    }

    /// Whether some joint has a known direction of approach at some pose.
    pub fn has_approach(&self) -> bool {
        self.approach
            .as_ref()
            .is_some_and(|a| a.iter().any(|d| d.iter().any(|x| *x != 0.0)))
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// Whether there is no pose.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// Whether some poses are partial measurements (samples along a traced path, serially
    /// correlated).
    pub fn is_serial(&self) -> bool {
        self.directions
            .as_ref()
            .is_some_and(|d| d.iter().any(|v| !v.is_empty()))
    }

    /// Number of measured components of pose `k` (3 for a full position).
    pub fn rows(&self, k: usize) -> usize {
        match self.directions.as_ref().and_then(|d| d.get(k)) {
            Some(d) if !d.is_empty() => d.len(),
            _ => 3,
        }
    }

    /// Number of residuals (measured components) of all poses.
    pub fn n_residuals(&self) -> usize {
        (0..self.len()).map(|k| self.rows(k)).sum()
    }

    /// Dimension of the measured error space, when every pose has the same one (3 for full
    /// positions, 2 for fused samples).
    pub fn measured_dims(&self) -> usize {
        let first = if self.is_empty() { 3 } else { self.rows(0) };
        if (0..self.len()).all(|k| self.rows(k) == first) {
            first
        } else {
            3
        }
    }

    /// The measured components of `v` at pose `k`: `d . v` for every measured direction
    /// (`v` itself for a full position).
    pub fn components(&self, k: usize, v: &Vector3<f64>) -> Vec<f64> {
        match self.directions.as_ref().and_then(|d| d.get(k)) {
            Some(d) if !d.is_empty() => d.iter().map(|dir| dir.dot(v)).collect(),
            _ => vec![v.x, v.y, v.z],
        }
    }

    /// The measured part of `v` at pose `k` (`sum_d (d . v) d`; `v` for a full position).
    pub fn measured_part(&self, k: usize, v: &Vector3<f64>) -> Vector3<f64> {
        match self.directions.as_ref().and_then(|d| d.get(k)) {
            Some(d) if !d.is_empty() => d.iter().map(|dir| dir * dir.dot(v)).sum(),
            _ => *v,
        }
    }

    /// Whether pose `k` measures directions (a partial position) rather than the full position.
    pub fn has_directions(&self, k: usize) -> bool {
        matches!(self.directions.as_ref().and_then(|d| d.get(k)), Some(d) if !d.is_empty())
    }

    /// The measured rows of a 3 x c Jacobian at pose `k` (`d^T J` per direction).
    pub fn jacobian_rows(&self, k: usize, j: &DMatrix<f64>) -> DMatrix<f64> {
        match self.directions.as_ref().and_then(|d| d.get(k)) {
            Some(d) if !d.is_empty() => {
                let mut out = DMatrix::zeros(d.len(), j.ncols());
                for (r, dir) in d.iter().enumerate() {
                    out.row_mut(r).copy_from(&(dir.transpose() * j));
                }
                out
            }
            _ => j.clone(),
        }
    }

    /// The inertial joint moments at pose `k`, when the dataset carries them.
    pub fn moments(&self, k: usize) -> Option<&[Vector3<f64>]> {
        self.moments_kgfm
            .as_ref()
            .and_then(|m| m.get(k))
            .map(Vec::as_slice)
    }

    /// Time of pose `k` (s), 0 without times.
    pub fn t(&self, k: usize) -> f64 {
        self.t_s
            .as_ref()
            .and_then(|t| t.get(k))
            .copied()
            .unwrap_or(0.0)
    }

    /// Whether the poses carry times that differ (so drifts can be told apart from offsets).
    pub fn has_time(&self) -> bool {
        match &self.t_s {
            Some(t) => {
                let lo = t.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                hi > lo
            }
            None => false,
        }
    }

    /// The poses at `indices`, in that order.
    pub fn subset(&self, indices: &[usize]) -> Self {
        let pick = |v: &Vec<Vec<Vector3<f64>>>| indices.iter().map(|&k| v[k].clone()).collect();
        Self {
            poses: Poses {
                q_deg: indices
                    .iter()
                    .map(|&k| self.poses.q_deg[k].clone())
                    .collect(),
                xyz_mm: indices.iter().map(|&k| self.poses.xyz_mm[k]).collect(),
            },
            t_s: self
                .t_s
                .as_ref()
                .map(|t| indices.iter().map(|&k| t[k]).collect()),
            directions: self.directions.as_ref().map(pick),
            moments_kgfm: self.moments_kgfm.as_ref().map(pick),
            approach: self
                .approach
                .as_ref()
                .map(|a| indices.iter().map(|&k| a[k].clone()).collect()),
            ids: self
                .ids
                .as_ref()
                .map(|v| indices.iter().map(|&k| v[k].clone()).collect()),
            lines: self
                .lines
                .as_ref()
                .map(|v| indices.iter().map(|&k| v[k]).collect()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::katana450;

    fn sample(t: f64, dev_u: f64, dev_n: f64) -> FusedSample {
        FusedSample {
            t_s: t,
            q_deg: vec![-90.0 + t, 60.0, -60.0, 10.0, 90.0],
            nominal_mm: Vector3::new(100.0, -200.0, 150.0),
            dev_u_mm: dev_u,
            u: Vector3::new(1.0, 0.0, 0.0),
            dev_n_mm: dev_n,
            n: Vector3::new(0.0, 0.6, 0.8),
        }
    }

    /// A fused sample measures exactly its two deviations; the along-path component of any
    /// vector is projected out; full positions concatenated keep all three axes.
    #[test]
    fn partial_measurements_project_out_the_path_direction() {
        let model = katana450(330.0).unwrap();
        let s: Vec<FusedSample> = (0..5).map(|k| sample(k as f64 * 0.01, 0.1, -0.2)).collect();
        let d = Dataset::from_fused(&s, &model).unwrap();
        assert!(d.is_serial());
        assert_eq!(d.n_residuals(), 10);
        assert_eq!(d.measured_dims(), 2);
        let e = d.poses.xyz_mm[0] - s[0].nominal_mm;
        let c = d.components(0, &e);
        assert!(
            (c[0] - 0.1).abs() < 1e-12 && (c[1] + 0.2).abs() < 1e-12,
            "{c:?}"
        );
        let along = Vector3::new(0.0, 0.8, -0.6);
        assert!(d.measured_part(0, &along).norm() < 1e-12);
        let j = DMatrix::from_row_slice(3, 1, &[0.0, 0.8, -0.6]);
        assert!(d.jacobian_rows(0, &j).norm() < 1e-12);
        let full = Dataset::from_poses(Poses {
            q_deg: vec![vec![0.0; 5]],
            xyz_mm: vec![Vector3::new(1.0, 2.0, 3.0)],
        });
        let both = d.concat(full);
        assert_eq!(both.len(), 6);
        assert_eq!(both.n_residuals(), 13);
        assert_eq!(both.measured_dims(), 3);
        assert_eq!(both.measured_part(5, &along), along);
        assert!(both.t_s.is_none());
        let m = both.moments_kgfm.as_ref().unwrap();
        assert_eq!(m.len(), 6);
        assert!(m[5].len() == 5 && m[5].iter().all(|v| v.norm() == 0.0));
        let sub = both.subset(&[5, 0]);
        assert_eq!(sub.rows(0), 3);
        assert_eq!(sub.rows(1), 2);
    }
}
