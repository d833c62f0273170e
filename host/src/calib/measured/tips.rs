//! A tree model's poses in the one [`MeasuredSet`]: the tip every point slot is on
//! ([`MeasuredSet::tips`]) and the points a pose leaves unmeasured ([`MeasuredSet::present`]).
//!
//! A chain is a tree of one tip: its set has no tips (every slot on the chain's last frame, the
//! further slots with offsets of their own) and every point measured, and a chain's
//! identification reads its slots densely ([`MeasuredSet::points`]). A tree's set holds the
//! joints of the whole tree in [`PosePoints::q_deg`], slot k's point on tip `tips[k]`
//! ([`super::PosePoints::xyz_mm`] slot 0, [`MeasuredSet::further_mm`] the others), and an
//! unmeasured point as NaN coordinates with `present[pose][slot] = false`. Chain
//! identifications refuse such a set ([`MeasuredSet::chain_only`]); the tree's reads the
//! measured points of a pose through [`MeasuredSet::measured_of`].

use nalgebra::Vector3;

use super::{MeasuredSet, Measurement, PosePoints};
use crate::calib::error::CalibError;
use crate::io::pose_csv::PoseFile;

impl MeasuredSet {
    /// A tree's poses: the joints of the whole tree `q_deg` (one vector per pose) and, per
    /// pose, the point of every tip in tree order (mm, frame R; `None`: not measured), slot k on
    /// tip k. Poses with fewer entries than the longest leave the missing tips unmeasured.
    pub fn from_tip_points(
        q_deg: Vec<Vec<f64>>,
        points_mm: Vec<Vec<Option<Vector3<f64>>>>,
    ) -> Self {
        let n_tips = points_mm.iter().map(Vec::len).max().unwrap_or(0);
        let nan = Vector3::repeat(f64::NAN);
        let at = |p: &[Option<Vector3<f64>>], t: usize| p.get(t).copied().flatten();
        let present: Vec<Vec<bool>> = points_mm
            .iter()
            .map(|p| (0..n_tips).map(|t| at(p, t).is_some()).collect())
            .collect();
        let first = |p: &Vec<Option<Vector3<f64>>>| at(p, 0).unwrap_or(nan);
        let further_mm = if n_tips > 1 {
            points_mm
                .iter()
                .map(|p| (1..n_tips).map(|t| at(p, t).unwrap_or(nan)).collect())
                .collect()
        } else {
            Vec::new()
        };
        let all = present.iter().all(|p| p.iter().all(|&m| m));
        Self {
            poses: PosePoints {
                xyz_mm: points_mm.iter().map(first).collect(),
                q_deg,
            },
            further_mm,
            markers: (0..n_tips).collect(),
            tips: (0..n_tips).collect(),
            present: (!all).then_some(present),
            ..Self::default()
        }
    }

    /// The poses of a tree's pose file (the joints of the whole tree; the file's point k on tip
    /// k, every one measured), with its times, ids, lines and approach directions.
    pub fn from_tip_pose_file(file: &PoseFile) -> Self {
        let all = Self::from_pose_points(file, None).unwrap_or_default();
        Self {
            tips: (0..all.n_slots()).collect(),
            ..all
        }
    }

    /// The tip slot `slot`'s point is on: 0 for a chain's set (its one tip, the last frame).
    pub fn tip(&self, slot: usize) -> usize {
        self.tips.get(slot).copied().unwrap_or(0)
    }

    /// Whether slot `slot` of pose `pose` was measured.
    pub fn is_present(&self, pose: usize, slot: usize) -> bool {
        self.present
            .as_ref()
            .and_then(|p| p.get(pose))
            .and_then(|s| s.get(slot))
            .copied()
            .unwrap_or(true)
    }

    /// The measured points of pose `pose`, slots in order (the unmeasured ones left out).
    pub fn measured_of(&self, pose: usize) -> impl Iterator<Item = Measurement> + '_ {
        let first = self.poses.xyz_mm.get(pose).copied();
        let more = self.further_mm.get(pose).map_or(&[][..], Vec::as_slice);
        first
            .into_iter()
            .chain(more.iter().copied())
            .enumerate()
            .filter(move |(slot, _)| self.is_present(pose, *slot))
            .map(move |(slot, xyz_mm)| Measurement { pose, slot, xyz_mm })
    }

    /// Number of measured points (the unmeasured ones of a tree's set left out).
    pub fn n_measured_points(&self) -> usize {
        match &self.present {
            None => self.n_points(),
            Some(p) => p.iter().map(|s| s.iter().filter(|&&m| m).count()).sum(),
        }
    }

    /// Whether the set is a tree's: slots on tips, or unmeasured points.
    pub fn has_tips(&self) -> bool {
        !self.tips.is_empty() || self.present.is_some()
    }

    /// Refuses ([`CalibError::NotChainSet`], `what` naming the set) a tree's set: a chain's
    /// identification reads one chain's joints and every point of every slot.
    pub fn chain_only(&self, what: &str) -> Result<(), CalibError> {
        if self.has_tips() {
            return Err(CalibError::NotChainSet { what: what.into() });
        }
        Ok(())
    }

    /// The set as the chain of tip `tip` sees it: one pose per measured point on that tip, its
    /// joints those of `path` (the tree joints of the tip's chain, [`crate::model::Tree::path`]).
    /// A chain's set (no tips, every point measured).
    pub fn tip_view(&self, tip: usize, path: &[usize]) -> Self {
        let (q, xyz): (Vec<Vec<f64>>, Vec<Vector3<f64>>) = (0..self.len())
            .flat_map(|k| self.measured_of(k))
            .filter(|m| self.tip(m.slot) == tip)
            .map(|m| {
                let q = &self.poses.q_deg[m.pose];
                let on_path = path.iter().filter_map(|&j| q.get(j).copied()).collect();
                (on_path, m.xyz_mm)
            })
            .unzip();
        Self::from_points(q, xyz)
    }

    /// The tips and measured points of `self` followed by `other`'s ([`MeasuredSet::concat`]):
    /// both sets' slots (`keep_slots`) when they are on the same tips; otherwise the first slot
    /// only, `other`'s first points unmeasured where they are on another tip than `self`'s.
    /// Called before the points themselves are joined.
    pub(super) fn concat_tips(&mut self, other: &MeasuredSet, keep_slots: bool) -> bool {
        let same_tips = self.tips == other.tips;
        let keep = keep_slots && same_tips;
        let other_on_first = other.tip(0) == self.tip(0);
        let slots = if keep { self.n_slots() } else { 1 };
        let mask = |set: &MeasuredSet, on: bool| -> Vec<Vec<bool>> {
            (0..set.len())
                .map(|k| (0..slots).map(|s| on && set.is_present(k, s)).collect())
                .collect()
        };
        if self.present.is_some() || other.present.is_some() || !other_on_first {
            let mut p = mask(self, true);
            p.extend(mask(other, keep || other_on_first));
            self.present = Some(p);
        }
        if !keep {
            self.tips.truncate(1);
        }
        keep
    }
}
