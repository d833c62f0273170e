//! A tree's pose file read as a measured set: the joints of the whole tree and one point per
//! tip (`x1,y1,z1` on the first `[[tip]]`, `x2,..` on the second), with the units and the motion
//! checked per tip before any fit, as a chain's pose file is.

use std::path::Path;

use super::measured::MeasuredSet;
use super::tree_fit::check_tree_plausible;
use super::CalibError;
use crate::error::{Classify, ErrorKind};
use crate::io::dialect::Dialect;
use crate::io::pose_csv::{read_poses, PoseCsvError, PoseSpec};
use crate::io::units::Units;
use crate::model::Tree;

/// Why a tree's pose file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum TreeReadError {
    /// Not a pose file (the message names the file, line and field).
    #[error(transparent)]
    Csv(#[from] PoseCsvError),
    /// Not one point per tip.
    #[error(
        "{path}: {found} measured point(s) per pose for a tree of {tips} tips: give x1,y1,z1 .. \
         x{tips},y{tips},z{tips} (point k on the k-th [[tip]])"
    )]
    Points {
        path: String,
        found: usize,
        tips: usize,
    },
    /// Implausible units or motion at a tip.
    #[error(transparent)]
    Implausible(#[from] CalibError),
}

impl Classify for TreeReadError {
    fn kind(&self) -> ErrorKind {
        match self {
            TreeReadError::Csv(e) => e.kind(),
            TreeReadError::Points { .. } => ErrorKind::BadInput,
            TreeReadError::Implausible(e) => e.kind(),
        }
    }
}

/// Reads `path` as poses of `tree` (its joint names, limits and prismatic joints; every point a
/// full position) in `units` and `dialect`.
pub fn read_tree_set(
    path: &Path,
    tree: &Tree,
    units: Units,
    dialect: Dialect,
) -> Result<MeasuredSet, TreeReadError> {
    let spec = PoseSpec {
        n_joints: tree.n_joints(),
        limits: tree.joint_limits(),
        require_xyz: true,
        joint_names: tree.joint_names(),
        prismatic: tree.prismatic(),
        units,
        marker: 0,
        dialect,
    };
    let file = read_poses(path, &spec)?;
    if file.n_markers() != tree.tips.len() {
        return Err(TreeReadError::Points {
            path: path.display().to_string(),
            found: file.n_markers(),
            tips: tree.tips.len(),
        });
    }
    let set = MeasuredSet::from_tip_pose_file(&file);
    check_tree_plausible(tree, &set, &path.display().to_string())?;
    Ok(set)
}
