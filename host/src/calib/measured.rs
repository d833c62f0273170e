//! The one set of measurements that every identification reads (`calibrate`, `calibrate
//! --samples`, `diagnose`, the planner's checks): joint readings, one or several measured points
//! per pose, full positions or **partial** ones (the fused samples of the low-cost rig, `rigctl
//! fuse`), with the times, pose names, file lines, approach directions and inertial moments
//! that go with them.
//!
//! A pose carries its joint readings and a measured point ([`MeasuredSet::poses`]); a pose file
//! with several points per pose (e.g. motion-capture markers on the hand) gives the further
//! points in [`MeasuredSet::further_mm`], each slot with its own offset in the tool frame
//! ([`super::general`]). For a partial measurement only some components of the point are
//! measured: the projections on the orthonormal directions of [`MeasuredSet::directions`] (for
//! a fused sample the across-path direction `u` in the sheet plane and the sheet normal `n`);
//! the stored point is the fusing model's nominal point moved by the measured deviations, so its
//! component along the path (not measured) is the nominal one and is projected out of every
//! error, Jacobian and statistic. The error of a pose is the **measured part**
//! `sum_d (d . (measured - predicted)) d` of the error vector (all of it for a full position),
//! and each measured direction is one residual ([`MeasuredSet::residual`]).
//!
//! Samples taken densely along a traced path are serially correlated; the selection rules
//! account for that ([`MeasuredSet::is_serial`]).

use std::path::Path;

use nalgebra::Vector3;

use super::samples::FusedSample;
use crate::io::pose_csv::{read_poses, PoseCsvError, PoseFile, PoseSpec};
use crate::model::motion::moments_in_motion;
use crate::model::transmission::approach_directions;
use crate::model::{Model, ModelError};

mod points;
mod tips;
pub use points::{Measurement, PosePoints};

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

/// Measured poses and what is known with them (see the module docs).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeasuredSet {
    /// Joint readings and the first measured point of every pose (partial measurements: see
    /// the module docs).
    pub poses: PosePoints,
    /// The further measured points of every pose (slots 1.., mm, frame R); empty with one
    /// point per pose.
    pub further_mm: Vec<Vec<Vector3<f64>>>,
    /// The file's point number (0-based: 0 = `x1` or `x`) of every slot; empty = one point,
    /// the file's own.
    pub markers: Vec<usize>,
    /// The tip of the model's tree every slot's point is on (slot order); empty: a chain's set,
    /// every slot on its last frame ([`MeasuredSet::tip`]; see `measured/tips.rs`).
    pub tips: Vec<usize>,
    /// Per pose, whether every slot's point was measured (slot order); `None`: every point of
    /// every pose. An unmeasured point's coordinates are not read (NaN from the readers).
    pub present: Option<Vec<Vec<bool>>>,
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
    /// ([`MeasuredSet::with_approach`]). Kept through [`MeasuredSet::subset`], so a fold keeps the
    /// history of the full visit order.
    pub approach: Option<Vec<Vec<f64>>>,
    /// Pose names (`id` column), when every row has one: poses measured more than once
    /// (the repeatability of `diagnose`).
    pub ids: Option<Vec<String>>,
    /// Line of every pose in its file (1-based), when read from a pose file: names the poses
    /// left out as gross errors.
    pub lines: Option<Vec<usize>>,
}

impl MeasuredSet {
    /// Poses without times.
    pub fn from_poses(poses: PosePoints) -> Self {
        Self {
            poses,
            ..Self::default()
        }
    }

    /// Joint readings `q_deg` with one full measured point each (`xyz_mm`, mm, frame R), no
    /// times.
    pub fn from_points(q_deg: Vec<Vec<f64>>, xyz_mm: Vec<Vector3<f64>>) -> Self {
        Self::from_poses(PosePoints { q_deg, xyz_mm })
    }

    /// Reads a pose file with measured positions for `model` (joint count and limits checked).
    /// `t` is used only if every row has it.
    pub fn read(path: &Path, model: &Model) -> Result<Self, PoseCsvError> {
        Self::read_with(path, &PoseSpec::for_model(model, true))
    }

    /// As [`MeasuredSet::read`] with the file's expectations `spec` (units, joint names, which
    /// measured point of a file with several is the pose's point).
    pub fn read_with(path: &Path, spec: &PoseSpec) -> Result<Self, PoseCsvError> {
        Ok(Self::from_pose_file(&read_poses(path, spec)?))
    }

    /// The poses of a pose file with its pose point ([`PoseSpec::marker`]; no point if the file
    /// has no positions), times (when every row has one), ids (when every row has one), lines,
    /// and the approach directions of the file order.
    pub fn from_pose_file(file: &PoseFile) -> Self {
        let poses = PosePoints::from_pose_file(file).unwrap_or_default();
        Self::labelled(file, poses, Vec::new(), Vec::new())
    }

    /// The points `markers` (0-based file point numbers, in slot order; `None` = all) of every
    /// pose of `file`, with its times, ids, lines and approach directions.
    pub fn from_pose_points(
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
        let point = |p: &crate::io::pose_csv::Pose, m: usize| Vector3::from(p.markers_mm[m]);
        let poses = match markers.first() {
            Some(&first) => PosePoints {
                q_deg: file.joints(),
                xyz_mm: file.poses.iter().map(|p| point(p, first)).collect(),
            },
            None => PosePoints::default(),
        };
        let further_mm = if markers.len() > 1 {
            file.poses
                .iter()
                .map(|p| markers[1..].iter().map(|&m| point(p, m)).collect())
                .collect()
        } else {
            Vec::new()
        };
        Ok(Self::labelled(file, poses, further_mm, markers))
    }

    fn labelled(
        file: &PoseFile,
        poses: PosePoints,
        further_mm: Vec<Vec<Vector3<f64>>>,
        markers: Vec<usize>,
    ) -> Self {
        Self {
            poses,
            further_mm,
            markers,
            t_s: file.poses.iter().map(|p| p.t_s).collect(),
            ids: file.poses.iter().map(|p| p.id.clone()).collect(),
            lines: Some(file.poses.iter().map(|p| p.line).collect()),
            ..Self::default()
        }
        .with_approach()
    }

    /// Partial measurements from fused samples (one path): two measured directions per sample
    /// (`u`, and `n` made orthogonal to it), the samples' times and approach directions. The one
    /// place where a fused sample becomes a measurement.
    pub fn from_fused(samples: &[FusedSample]) -> Result<Self, ModelError> {
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
        Ok(Self {
            poses: PosePoints { q_deg, xyz_mm },
            t_s: Some(t_s),
            directions: Some(directions),
            ..Self::default()
        }
        .with_approach())
    }

    /// `self` with the inertial part of the moments in motion of `model` along the logged
    /// joints ([`MeasuredSet::moments_kgfm`]: moments in motion minus the static ones).
    pub fn with_inertial_moments(mut self, model: &Model) -> Result<Self, ModelError> {
        let q_deg = &self.poses.q_deg;
        let moments = moments_in_motion(model, self.t_s.as_deref().unwrap_or(&[]), q_deg)?
            .into_iter()
            .zip(q_deg)
            .map(|(m, q)| {
                let stat = model.moments_kgfm(q)?;
                Ok(m.iter().zip(&stat).map(|(a, b)| a - b).collect())
            })
            .collect::<Result<Vec<Vec<Vector3<f64>>>, ModelError>>()?;
        self.moments_kgfm = Some(moments);
        Ok(self)
    }

    /// The set as `model`'s chain sees it: the readings through its joint map
    /// ([`Model::effective_pose_joints`], hysteresis in the pose order) and every measured point
    /// through the inverse of its time terms ([`Model::chain_mm_for`]). Without terms, `self`.
    pub fn through_terms(&self, model: &Model) -> Result<Self, ModelError> {
        if !model.maps_joints() && !model.time_terms().is_active() {
            return Ok(self.clone());
        }
        let t_s = self.t_s.as_deref();
        let at = |pose: usize| t_s.and_then(|t| t.get(pose)).copied().unwrap_or(0.0);
        let mut out = self.clone();
        out.poses.q_deg = model.effective_pose_joints(&self.poses.q_deg, t_s)?;
        for (k, p) in out.poses.xyz_mm.iter_mut().enumerate() {
            *p = model.chain_mm_for(p, at(k));
        }
        for (k, more) in out.further_mm.iter_mut().enumerate() {
            for p in more {
                *p = model.chain_mm_for(p, at(k));
            }
        }
        Ok(out)
    }

    /// The poses of `other` that repeat a pose of this set exactly (the same joint readings and
    /// the same measured points, bit for bit): `(index in other, index here)`. A real
    /// measurement never repeats to the last bit; such poses are a copy of the calibration data.
    pub fn repeats(&self, other: &MeasuredSet) -> Vec<(usize, usize)> {
        use std::collections::HashMap;
        let key = |set: &MeasuredSet, k: usize| -> Vec<u64> {
            let mut v: Vec<u64> = set.poses.q_deg[k].iter().map(|x| x.to_bits()).collect();
            v.extend(set.poses.xyz_mm[k].iter().map(|x| x.to_bits()));
            v
        };
        let mut here: HashMap<Vec<u64>, usize> = HashMap::new();
        for k in 0..self.poses.len() {
            here.entry(key(self, k)).or_insert(k);
        }
        (0..other.poses.len())
            .filter_map(|k| here.get(&key(other, k)).map(|&h| (k, h)))
            .collect()
    }

    /// `self` followed by `other` (e.g. the samples of two sheets, or poses and samples). Times
    /// are kept only when both have them; directions and inertial moments when either has them
    /// (full positions get all three axes, poses at rest zero inertial moments); the further
    /// points when both have as many slots on the same tips (otherwise the first point of every
    /// pose only).
    pub fn concat(mut self, other: MeasuredSet) -> Self {
        let (n0, n1) = (self.len(), other.len());
        let same_slots = self.n_slots() == other.n_slots();
        let keep_slots = self.concat_tips(&other, same_slots);
        let a0 = self.approach_or_computed();
        let a1 = other.approach_or_computed();
        self.t_s = both(self.t_s.take(), other.t_s);
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
        self.ids = both(self.ids.take(), other.ids);
        self.lines = both(self.lines.take(), other.lines);
        if keep_slots {
            self.further_mm.extend(other.further_mm);
        } else {
            self.further_mm.clear();
            self.markers.clear();
        }
        self.poses.q_deg.extend(other.poses.q_deg);
        self.poses.xyz_mm.extend(other.poses.xyz_mm);
        self
    }

    /// `self` with [`MeasuredSet::approach`] computed from the pose order when it is not set.
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
            poses: self.poses.subset(indices),
            further_mm: if self.further_mm.is_empty() {
                Vec::new()
            } else {
                pick(&self.further_mm)
            },
            markers: self.markers.clone(),
            tips: self.tips.clone(),
            present: self
                .present
                .as_ref()
                .map(|p| indices.iter().map(|&k| p[k].clone()).collect()),
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

/// `a` followed by `b` when both are known.
fn both<T>(a: Option<Vec<T>>, b: Option<Vec<T>>) -> Option<Vec<T>> {
    let (mut a, b) = (a?, b?);
    a.extend(b);
    Some(a)
}

#[cfg(test)]
mod tests;
