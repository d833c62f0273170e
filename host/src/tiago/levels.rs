//! Calibration levels of an imported chain on the TIAGo postures, as FIGAROH's held-out
//! protocol reports them (registration only, + joint offsets, full geometric parameters),
//! each fitted on the training postures and scored on the validation postures.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;

use super::mocap::{MocapError, PostureSet};
use crate::calib::fit::{fit_parameters, Fit};
use crate::calib::identifiability::DEFAULT_RTOL;
use crate::calib::lm::LmConfig;
use crate::calib::{position_errors, CalibError, Poses, Stats};
use crate::model::{Model, ParamKind};
use crate::urdf::{import_chain, import_chain_with_masses, ImportOptions, Urdf, UrdfError};

/// Data directory below the shared directory.
pub const DATA_DIR: &str = "data/real/thanhndv212__figaroh-examples/examples/tiago";
/// The URDF, relative to [`DATA_DIR`].
pub const URDF_FILE: &str = "urdf/tiago_48_schunk.urdf";
/// Training postures (protocol v1 role `training`, 37 rows), relative to [`DATA_DIR`].
pub const TRAINING_FILE: &str = "data/calibration/mocap/qualisys_2021-11-30_static_postures.csv";
/// Validation postures (protocol v1 role `validation`, 62 rows), relative to [`DATA_DIR`].
pub const VALIDATION_FILE: &str = "data/calibration/mocap/qualisys_2021-11-26_static_postures.csv";
/// Base link of the calibrated chain (data README).
pub const BASE_LINK: &str = "base_footprint";
/// Tip link: the observed point is fixed in it.
pub const TIP_LINK: &str = "wrist_ft_tool_link";
/// The observed hand point (BL), as in FIGAROH.
pub const MARKER: usize = 0;

/// Errors of loading the TIAGo data.
#[derive(Debug, thiserror::Error)]
pub enum TiagoError {
    #[error(transparent)]
    Urdf(#[from] UrdfError),
    #[error(transparent)]
    Mocap(#[from] MocapError),
    #[error(transparent)]
    Calib(#[from] CalibError),
}

impl crate::error::Classify for TiagoError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            TiagoError::Urdf(e) => e.kind(),
            TiagoError::Mocap(e) => e.kind(),
            TiagoError::Calib(e) => e.kind(),
        }
    }
}

/// The nominal model and both posture sets.
#[derive(Debug, Clone)]
pub struct TiagoData {
    /// `base_footprint` .. `wrist_ft_tool_link` of the URDF (joints: torso mm, arm deg).
    pub model: Model,
    /// The same chain with the URDF link masses (for gravity torques, [`super::terms`]).
    pub mass_model: Model,
    /// URDF joint names in model order (`torso_lift_joint`, `arm_1_joint` .. `arm_7_joint`).
    pub joint_names: Vec<String>,
    /// Training postures.
    pub training: PostureSet,
    /// Validation postures.
    pub validation: PostureSet,
}

impl TiagoData {
    /// Loads the data set from `dir` (the [`DATA_DIR`] below the shared directory).
    pub fn load(dir: &Path) -> Result<Self, TiagoError> {
        let urdf = Urdf::from_file(&dir.join(URDF_FILE))?;
        let opts = ImportOptions {
            base_link: Some(BASE_LINK),
            tip_link: TIP_LINK,
            tool_mm: [0.0; 3],
        };
        let imported = import_chain(&urdf, &opts)?;
        let mass_model = import_chain_with_masses(&urdf, &opts)?.model;
        let read = |f: &str| PostureSet::read(&dir.join(f), &imported.model, &imported.joint_names);
        Ok(Self {
            training: read(TRAINING_FILE)?,
            validation: read(VALIDATION_FILE)?,
            model: imported.model,
            mass_model,
            joint_names: imported.joint_names,
        })
    }

    /// `shared/DATA_DIR`.
    pub fn dir_in(shared: &Path) -> PathBuf {
        shared.join(DATA_DIR)
    }
}

/// What a level fits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// Base frame (6 dof: `base_x/y/z`, `base_rx/ry/rz`) and the marker point (`tool_d*`).
    Registration,
    /// Registration + every joint offset.
    JointOffsets,
    /// Joint offsets + every constant of the chain (joint origins, tip transform).
    Full,
    /// Joint offsets + the chain constants chosen on the training data by leave-one-out
    /// forward selection ([`run_selected`]; [`selection`] gives the candidates, as `Full`).
    Selected,
}

impl Level {
    /// All levels, in increasing order.
    pub const ALL: [Level; 3] = [Level::Registration, Level::JointOffsets, Level::Full];

    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            Level::Registration => "registration",
            Level::JointOffsets => "joint_offsets",
            Level::Full => "full",
            Level::Selected => "full_selected",
        }
    }
}

/// The selected parameters of `level` (model indices), in fitting preference: base and tool
/// first, then joint offsets, then chain constants (the identifiability analysis fixes later
/// columns first).
pub fn selection(model: &Model, level: Level) -> Vec<usize> {
    let mut sel: Vec<usize> = [
        "base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz", "tool_dx", "tool_dy",
        "tool_dz",
    ]
    .iter()
    .filter_map(|n| model.param_index(n))
    .collect();
    if level != Level::Registration {
        sel.extend(model.params_of_kind(ParamKind::JointOffset));
    }
    if matches!(level, Level::Full | Level::Selected) {
        let mut constants = model.params_of_kind(ParamKind::Length);
        constants.extend(model.params_of_kind(ParamKind::Twist));
        constants.sort_unstable();
        constants.retain(|c| !sel.contains(c));
        sel.extend(constants);
    }
    sel
}

/// Position-error statistics in both conventions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scores {
    /// FORMATS.md statistics (`rms_mm` = RMS of the Euclidean error, FIGAROH's "norm RMSE").
    pub stats: Stats,
    /// RMS over all x, y, z coordinates (`rms_mm / sqrt(3)`).
    pub coordinate_rms_mm: f64,
}

impl Scores {
    /// Scores of `model` on `poses` (no tilting).
    pub fn of(model: &Model, poses: &Poses) -> Result<Self, CalibError> {
        let errors: Vec<Vector3<f64>> = position_errors(model, poses, false)?;
        let stats = Stats::from_errors(&errors);
        Ok(Self {
            stats,
            coordinate_rms_mm: stats.rms_mm / 3f64.sqrt(),
        })
    }
}

/// One level's result.
#[derive(Debug, Clone)]
pub struct LevelResult {
    pub level: Level,
    /// The identification (fitted model, fitted / fixed parameters, sigmas).
    pub fit: Fit,
    /// Scores on the training poses.
    pub training: Scores,
    /// Scores on the validation poses.
    pub validation: Scores,
}

/// Fits `level` on `training` starting from `start`, scores on both sets.
pub fn run_level(
    start: &Model,
    training: &Poses,
    validation: &Poses,
    level: Level,
) -> Result<LevelResult, CalibError> {
    let lm = LmConfig {
        max_iterations: 200,
        ..LmConfig::default()
    };
    let fit = fit_parameters(
        start,
        training,
        &selection(start, level),
        false,
        &lm,
        DEFAULT_RTOL,
    )?;
    Ok(LevelResult {
        level,
        training: Scores::of(&fit.model, training)?,
        validation: Scores::of(&fit.model, validation)?,
        fit,
    })
}

/// The "selected" level: starting from the joint-offset fit `offsets`, adds the chain
/// constants chosen by [`super::select::forward_select`] (leave-one-posture-out PRESS of the
/// linearised problem on the training poses only), then fits them all.
pub fn run_selected(
    offsets: &LevelResult,
    training: &Poses,
    validation: &Poses,
) -> Result<(LevelResult, Vec<usize>), CalibError> {
    let start = &offsets.fit.model;
    let full = selection(start, Level::Full);
    let jac = crate::calib::problem::stacked_jacobian(start, training, &full, false)?;
    let errors = position_errors(start, training, false)?;
    // Residuals model - measured, the sign of the identification problem.
    let r = nalgebra::DVector::from_iterator(
        3 * errors.len(),
        errors.iter().flat_map(|e| [-e.x, -e.y, -e.z]),
    );
    let always: Vec<usize> = offsets
        .fit
        .fitted
        .iter()
        .filter_map(|c| full.iter().position(|f| f == c))
        .collect();
    let candidates: Vec<usize> = (0..full.len()).collect();
    let added: Vec<usize> = super::select::forward_select(&jac, &r, 3, &always, &candidates)
        .into_iter()
        .map(|k| full[k])
        .collect();
    let mut sel = offsets.fit.fitted.clone();
    sel.extend(&added);
    let lm = LmConfig {
        max_iterations: 200,
        ..LmConfig::default()
    };
    let fit = fit_parameters(start, training, &sel, false, &lm, DEFAULT_RTOL)?;
    Ok((
        LevelResult {
            level: Level::Selected,
            training: Scores::of(&fit.model, training)?,
            validation: Scores::of(&fit.model, validation)?,
            fit,
        },
        added,
    ))
}
