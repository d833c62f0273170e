//! The pose-file expectations of a model: its joint count and limits (FORMATS.md "Pose files").

use super::Model;
use crate::io::pose_csv::PoseSpec;

impl PoseSpec {
    /// The model's joint count, limits, joint names and joint kinds; internal units, point 1.
    pub fn for_model(model: &Model, require_xyz: bool) -> Self {
        Self {
            n_joints: model.n_joints(),
            limits: model.joint_limits(),
            require_xyz,
            joint_names: model.joint_names().to_vec(),
            prismatic: model.joints().iter().map(|j| j.prismatic).collect(),
            units: Default::default(),
            marker: 0,
            dialect: Default::default(),
        }
    }
}
