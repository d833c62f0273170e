//! Measured points of poses with several points per pose (pose files with `x1,y1,z1 .. xk,yk,zk`,
//! e.g. motion-capture markers on the hand): one measurement = (pose, point, xyz). Point slot 0
//! is the model's tool point (`tool_dx..dz`); every further point used has its own offset in the
//! tool frame (identified with the model, [`super::general`]).

use nalgebra::Vector3;

use super::problem::Poses;
use crate::io::pose_csv::PoseFile;
use crate::model::{Model, ModelError};

/// One measured point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// Index of the pose ([`Measurements::q_deg`]).
    pub pose: usize,
    /// Slot of the point: 0 = the tool point, k = [`Measurements::markers`]`[k]`.
    pub slot: usize,
    /// Measured position (mm, frame R).
    pub xyz_mm: Vector3<f64>,
}

/// Poses with one or several measured points each.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Measurements {
    /// Joint readings of every pose (deg; mm for prismatic joints).
    pub q_deg: Vec<Vec<f64>>,
    /// The measurements, grouped by pose in pose order.
    pub points: Vec<Measurement>,
    /// The file's point number (0-based: 0 = `x1` or `x`) of every slot.
    pub markers: Vec<usize>,
    /// The time of every pose, s from the start of the session, when every pose of the file
    /// has one (FORMATS.md `t`; the pose order is then by time).
    pub t_s: Option<Vec<f64>>,
}

/// A `--markers` choice that the file cannot satisfy.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: point {asked} asked for (--markers), the file has {available} measured point(s) per pose")]
pub struct MarkerChoiceError {
    pub file: String,
    pub asked: usize,
    pub available: usize,
}

impl crate::error::Classify for MarkerChoiceError {
    fn kind(&self) -> crate::error::ErrorKind {
        crate::error::ErrorKind::BadInput
    }
}

impl Measurements {
    /// The points `markers` (0-based file point numbers, in slot order; `None` = all) of every
    /// pose of `file`.
    pub fn from_pose_file(
        file: &PoseFile,
        markers: Option<&[usize]>,
    ) -> Result<Self, MarkerChoiceError> {
        let available = file.n_markers();
        let markers: Vec<usize> = match markers {
            Some(m) => m.to_vec(),
            None => (0..available).collect(),
        };
        if let Some(&bad) = markers.iter().find(|&&m| m >= available) {
            return Err(MarkerChoiceError {
                file: file.source.clone(),
                asked: bad + 1,
                available,
            });
        }
        let mut points = Vec::with_capacity(file.poses.len() * markers.len());
        for (i, p) in file.poses.iter().enumerate() {
            for (slot, &m) in markers.iter().enumerate() {
                if let Some(xyz) = p.markers_mm.get(m) {
                    points.push(Measurement {
                        pose: i,
                        slot,
                        xyz_mm: Vector3::from(*xyz),
                    });
                }
            }
        }
        Ok(Self {
            q_deg: file.joints(),
            points,
            markers,
            t_s: file.poses.iter().map(|p| p.t_s).collect(),
        })
    }

    /// The measurements as `model`'s chain sees them: the readings through its joint map
    /// ([`Model::effective_pose_joints`], hysteresis in the pose order) and the measured points
    /// through the inverse of its time terms ([`Model::chain_mm_for`]). Without terms, `self`.
    pub fn through_terms(&self, model: &Model) -> Result<Self, ModelError> {
        if !model.maps_joints() && !model.time_terms().is_active() {
            return Ok(self.clone());
        }
        let t_s = self.t_s.as_deref();
        let at = |pose: usize| t_s.and_then(|t| t.get(pose)).copied().unwrap_or(0.0);
        Ok(Self {
            q_deg: model.effective_pose_joints(&self.q_deg, t_s)?,
            points: self
                .points
                .iter()
                .map(|m| Measurement {
                    xyz_mm: model.chain_mm_for(&m.xyz_mm, at(m.pose)),
                    ..*m
                })
                .collect(),
            markers: self.markers.clone(),
            t_s: self.t_s.clone(),
        })
    }

    /// Single-point data from poses.
    pub fn from_poses(poses: &Poses) -> Self {
        Self {
            q_deg: poses.q_deg.clone(),
            points: poses
                .xyz_mm
                .iter()
                .enumerate()
                .map(|(pose, &xyz_mm)| Measurement {
                    pose,
                    slot: 0,
                    xyz_mm,
                })
                .collect(),
            markers: vec![0],
            t_s: None,
        }
    }

    /// Number of point slots.
    pub fn n_slots(&self) -> usize {
        self.markers.len()
    }

    /// Number of poses.
    pub fn n_poses(&self) -> usize {
        self.q_deg.len()
    }

    /// Number of measurements.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there is no measurement.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// One pose per measurement (its joints and its point), e.g. for error statistics.
    pub fn as_poses(&self) -> Poses {
        Poses {
            q_deg: self
                .points
                .iter()
                .map(|m| self.q_deg[m.pose].clone())
                .collect(),
            xyz_mm: self.points.iter().map(|m| m.xyz_mm).collect(),
        }
    }

    /// Residual rows per pose (3 per measured point), in row order: the blocks left out together
    /// by [`super::press`].
    pub fn row_blocks(&self) -> Vec<usize> {
        let mut blocks = vec![0; self.n_poses()];
        for m in &self.points {
            blocks[m.pose] += 3;
        }
        blocks.retain(|&b| b > 0);
        blocks
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
