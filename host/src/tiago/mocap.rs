//! Reader of the TIAGo static-posture files (`qualisys_*_static_postures.csv`, data README):
//! header line, comma separated; `x1,y1,z1 .. x4,y4,z4` the hand rigid body's points BL, BR,
//! TR, TL (m, in the Qualisys `base_frame` body); one column per joint named as in the URDF
//! (`torso_lift_joint` in m, `arm_<i>_joint` in rad); `marker_std_mm`; other columns ignored.

use nalgebra::Vector3;

use crate::calib::Poses;
use crate::error::{Classify, ErrorKind};
use crate::model::Model;

/// Number of hand points per row (BL, BR, TR, TL).
pub const N_MARKERS: usize = 4;

/// Errors reading a posture file.
#[derive(Debug, thiserror::Error)]
pub enum MocapError {
    /// The file cannot be read.
    #[error("cannot read {path}: {source}")]
    Read {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The header lacks a needed column.
    #[error("{file}: no column `{column}` in the header")]
    MissingColumn { file: String, column: String },
    /// A cell that is not a finite number, or a short row.
    #[error("{file}:{line}: column `{column}`: `{text}` is not a finite number")]
    Value {
        file: String,
        line: usize,
        column: String,
        text: String,
    },
    /// The joint names do not match the model's joints.
    #[error("{given} joint names given for a model with {expected} joints")]
    JointCount { given: usize, expected: usize },
}

impl Classify for MocapError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::BadInput
    }
}

/// One static posture.
#[derive(Debug, Clone, PartialEq)]
pub struct Posture {
    /// Joint readings in model units (deg, mm for prismatic joints), model joint order.
    pub q: Vec<f64>,
    /// The 4 hand points BL, BR, TR, TL (mm, Qualisys `base_frame`).
    pub markers_mm: [Vector3<f64>; N_MARKERS],
    /// Largest marker standard deviation over the averaging window (mm), if the column exists.
    pub marker_std_mm: Option<f64>,
}

/// The postures of one file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PostureSet {
    pub postures: Vec<Posture>,
}

impl PostureSet {
    /// Reads `path` for `model`, whose joint `i` is the file's column `joint_names[i]`
    /// (prismatic columns m -> mm, revolute rad -> deg).
    pub fn read(
        path: &std::path::Path,
        model: &Model,
        joint_names: &[String],
    ) -> Result<Self, MocapError> {
        let text = std::fs::read_to_string(path).map_err(|source| MocapError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, &path.display().to_string(), model, joint_names)
    }

    /// Parses the text of a posture file (`file` names it in messages).
    pub fn parse(
        text: &str,
        file: &str,
        model: &Model,
        joint_names: &[String],
    ) -> Result<Self, MocapError> {
        if joint_names.len() != model.n_joints() {
            return Err(MocapError::JointCount {
                given: joint_names.len(),
                expected: model.n_joints(),
            });
        }
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let header: Vec<&str> = lines
            .next()
            .map(|(_, h)| h.split(',').map(str::trim).collect())
            .unwrap_or_default();
        let col = |name: &str| {
            header
                .iter()
                .position(|h| *h == name)
                .ok_or_else(|| MocapError::MissingColumn {
                    file: file.to_string(),
                    column: name.to_string(),
                })
        };
        let mut marker_cols = Vec::new();
        for k in 1..=N_MARKERS {
            for axis in ["x", "y", "z"] {
                let name = format!("{axis}{k}");
                marker_cols.push((col(&name)?, name));
            }
        }
        let joint_cols = joint_names
            .iter()
            .map(|n| col(n).map(|c| (c, n.clone())))
            .collect::<Result<Vec<_>, _>>()?;
        let std_col = col("marker_std_mm").ok();
        let mut postures = Vec::new();
        for (i, line) in lines {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            let value = |c: usize, name: &str| -> Result<f64, MocapError> {
                let text = cells.get(c).copied().unwrap_or("");
                match text.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    _ => Err(MocapError::Value {
                        file: file.to_string(),
                        line: i + 1,
                        column: name.to_string(),
                        text: text.to_string(),
                    }),
                }
            };
            let mut markers_mm = [Vector3::zeros(); N_MARKERS];
            for (k, (c, name)) in marker_cols.iter().enumerate() {
                markers_mm[k / 3][k % 3] = value(*c, name)? * 1e3;
            }
            let mut q = Vec::with_capacity(joint_cols.len());
            for ((c, name), joint) in joint_cols.iter().zip(model.joints()) {
                let v = value(*c, name)?;
                q.push(if joint.prismatic {
                    v * 1e3
                } else {
                    v.to_degrees()
                });
            }
            let marker_std_mm = std_col.map(|c| value(c, "marker_std_mm")).transpose()?;
            postures.push(Posture {
                q,
                markers_mm,
                marker_std_mm,
            });
        }
        Ok(Self { postures })
    }

    /// Number of postures.
    pub fn len(&self) -> usize {
        self.postures.len()
    }

    /// Whether there is no posture.
    pub fn is_empty(&self) -> bool {
        self.postures.is_empty()
    }

    /// The poses of hand point `marker` (0 = BL, the point FIGAROH calibrates with).
    pub fn poses(&self, marker: usize) -> Poses {
        let marker = marker.min(N_MARKERS - 1);
        Poses {
            q_deg: self.postures.iter().map(|p| p.q.clone()).collect(),
            xyz_mm: self.postures.iter().map(|p| p.markers_mm[marker]).collect(),
        }
    }
}
