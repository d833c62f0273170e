//! Measured poses with their optional times, as the diagnosis uses them.

use std::path::Path;

use nalgebra::Vector3;

use crate::calib::Poses;
use crate::io::pose_csv::{read_poses, PoseCsvError, PoseSpec};
use crate::model::Model;

/// Measured poses (joints, positions) and, when the file has a `t` column, the time of each
/// measurement (s since the start of the session).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Dataset {
    /// Joint readings and measured positions.
    pub poses: Poses,
    /// Time of every pose (s), `None` without a `t` column.
    pub t_s: Option<Vec<f64>>,
}

impl Dataset {
    /// Poses without times.
    pub fn from_poses(poses: Poses) -> Self {
        Self { poses, t_s: None }
    }

    /// Reads a pose file with measured positions for `model` (joint count and limits checked).
    /// `t` is used only if every row has it.
    pub fn read(path: &Path, model: &Model) -> Result<Self, PoseCsvError> {
        let file = read_poses(path, &PoseSpec::for_model(model, true))?;
        let poses = Poses::from_pose_file(&file).unwrap_or_default();
        let t: Option<Vec<f64>> = file.poses.iter().map(|p| p.t_s).collect();
        Ok(Self { poses, t_s: t })
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// Whether there is no pose.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
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
        let q_deg = indices
            .iter()
            .map(|&k| self.poses.q_deg[k].clone())
            .collect();
        let xyz_mm: Vec<Vector3<f64>> = indices.iter().map(|&k| self.poses.xyz_mm[k]).collect();
        let t_s = self
            .t_s
            .as_ref()
            .map(|t| indices.iter().map(|&k| t[k]).collect());
        Self {
            poses: Poses { q_deg, xyz_mm },
            t_s,
        }
    }
}
