//! The measured components of a pose of a [`MeasuredSet`]: how many rows it gives, its
//! components and measured part, the residual and error every identification reads, and the
//! rows of a Jacobian along them (all three axes for a full position, the measured directions of
//! a partial one; see [`super::measured`]).

use nalgebra::{DMatrix, Vector3};

use super::measured::MeasuredSet;

impl MeasuredSet {
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

    /// The residuals `predicted - measured` of pose `k` along its measured components (3 for a
    /// full position, one per measured direction for a partial one): the residual of every
    /// identification on the set.
    pub fn residual(&self, k: usize, predicted_mm: &Vector3<f64>) -> Vec<f64> {
        self.components(k, &(predicted_mm - self.poses.xyz_mm[k]))
    }

    /// The measured part of the error `measured - predicted` of pose `k` (mm).
    pub fn error_mm(&self, k: usize, predicted_mm: &Vector3<f64>) -> Vector3<f64> {
        self.measured_part(k, &(self.poses.xyz_mm[k] - predicted_mm))
    }

    /// The measured directions of pose `k` (the three axes for a full position).
    pub fn directions_at(&self, k: usize) -> Vec<Vector3<f64>> {
        match self.directions.as_ref().and_then(|d| d.get(k)) {
            Some(d) if !d.is_empty() => d.clone(),
            _ => vec![Vector3::x(), Vector3::y(), Vector3::z()],
        }
    }

    /// The set with only the measured components `keep` (one flag per residual, pose by pose):
    /// a pose keeps the directions flagged, and is left out when none is.
    pub fn keep_components(&self, keep: &[bool]) -> Self {
        let mut flags = keep.iter().copied();
        let mut poses = Vec::with_capacity(self.len());
        let mut directions = Vec::with_capacity(self.len());
        for k in 0..self.len() {
            let all = self.directions_at(k);
            let kept: Vec<Vector3<f64>> = all
                .iter()
                .filter(|_| flags.next().unwrap_or(false))
                .copied()
                .collect();
            if kept.is_empty() {
                continue;
            }
            poses.push(k);
            directions.push(if kept.len() == self.rows(k) {
                self.directions
                    .as_ref()
                    .and_then(|d| d.get(k))
                    .cloned()
                    .unwrap_or_default()
            } else {
                kept
            });
        }
        let mut out = self.subset(&poses);
        if self.directions.is_some() || directions.iter().any(|d| !d.is_empty()) {
            out.directions = Some(directions);
        }
        out
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

    /// Writes the measured rows ([`MeasuredSet::jacobian_rows`]) of pose `k`'s 3 x c Jacobian `j`
    /// from row `row` of `jac`; returns the row after them.
    pub fn put_jacobian_rows(
        &self,
        k: usize,
        j: &DMatrix<f64>,
        row: usize,
        jac: &mut DMatrix<f64>,
    ) -> usize {
        if !self.has_directions(k) {
            // a full position: its three rows as they are (no copy of `j` first)
            jac.rows_mut(row, j.nrows()).copy_from(j);
            return row + j.nrows();
        }
        let rows = self.jacobian_rows(k, j);
        jac.rows_mut(row, rows.nrows()).copy_from(&rows);
        row + rows.nrows()
    }
}
