//! The core of a [`MeasuredSet`]: the joint readings and the first measured point of every
//! pose ([`PosePoints`]), and the set's measured points one by one ([`Measurement`]).

use nalgebra::Vector3;

use super::MeasuredSet;

/// The joint readings (deg, one vector per pose) and the first measured point (mm, frame R) of
/// every pose of a [`MeasuredSet`] ([`MeasuredSet::poses`]; the set adds the further points,
/// measured directions, times, ids, lines, approach directions and inertial moments). What the
/// identification on full positions reads pose by pose (the accumulation of
/// [`crate::calib::accumulate`] and its helper thread, which copies its half), and the
/// one-pose-per-point view of a set ([`MeasuredSet::as_poses`]) for error statistics. Readers of
/// data build a [`MeasuredSet`] ([`MeasuredSet::from_points`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PosePoints {
    /// Joint readings `q1..qN` of every pose (deg).
    pub q_deg: Vec<Vec<f64>>,
    /// Measured tool point of every pose (mm).
    pub xyz_mm: Vec<Vector3<f64>>,
}

impl PosePoints {
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
        Some(PosePoints {
            q_deg: file.joints(),
            xyz_mm: xyz.into_iter().map(Vector3::from).collect(),
        })
    }

    /// The poses `keep` (indices, in that order).
    pub fn subset(&self, keep: &[usize]) -> PosePoints {
        PosePoints {
            q_deg: keep.iter().map(|&k| self.q_deg[k].clone()).collect(),
            xyz_mm: keep.iter().map(|&k| self.xyz_mm[k]).collect(),
        }
    }
}

/// One measured point of a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// Index of the pose.
    pub pose: usize,
    /// Slot of the point: 0 = the tool point ([`PosePoints::xyz_mm`]), k = [`MeasuredSet::markers`]`[k]`.
    pub slot: usize,
    /// Measured position (mm, frame R).
    pub xyz_mm: Vector3<f64>,
}

impl MeasuredSet {
    /// Number of point slots (1 with one point per pose).
    pub fn n_slots(&self) -> usize {
        1 + self.further_mm.first().map_or(0, Vec::len)
    }

    /// The measured points, grouped by pose in pose order, slots in order.
    pub fn points(&self) -> impl Iterator<Item = Measurement> + '_ {
        let none: &[Vector3<f64>] = &[];
        self.poses
            .xyz_mm
            .iter()
            .enumerate()
            .flat_map(move |(pose, &xyz_mm)| {
                let more = self.further_mm.get(pose).map_or(none, Vec::as_slice);
                std::iter::once(Measurement {
                    pose,
                    slot: 0,
                    xyz_mm,
                })
                .chain(more.iter().enumerate().map(move |(k, &xyz_mm)| {
                    Measurement {
                        pose,
                        slot: k + 1,
                        xyz_mm,
                    }
                }))
            })
    }

    /// Number of measured points.
    pub fn n_points(&self) -> usize {
        self.len() + self.further_mm.iter().map(Vec::len).sum::<usize>()
    }

    /// One pose per measured point (its joints and its point), e.g. for error statistics.
    pub fn as_poses(&self) -> PosePoints {
        if self.further_mm.is_empty() {
            return self.poses.clone();
        }
        let (q_deg, xyz_mm) = self
            .points()
            .map(|m| (self.poses.q_deg[m.pose].clone(), m.xyz_mm))
            .unzip();
        PosePoints { q_deg, xyz_mm }
    }

    /// Residual rows per pose (3 per measured point), in row order: the blocks left out together
    /// by [`crate::calib::press`].
    pub fn row_blocks(&self) -> Vec<usize> {
        vec![3 * self.n_slots(); self.len()]
    }

    /// The name of slot `slot`'s offset coordinate `axis` (0..3): `marker<k>_x_mm` with the
    /// file's 1-based point number k.
    pub fn offset_name(&self, slot: usize, axis: usize) -> String {
        format!(
            "marker{}_{}_mm",
            self.markers.get(slot).map_or(slot, |m| *m) + 1,
            ["x", "y", "z"][axis.min(2)]
        )
    }
}
