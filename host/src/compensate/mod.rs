//! Trajectory correction (`rigctl compensate`; thesis eq. 5.22): the joints to command so that
//! the *calibrated* arm, tilting included, puts its tool point on a desired Cartesian path.
//!
//! The thesis corrects the nominal joints by one pseudo-inverse step,
//! `dtheta = J^T (J J^T)^-1 (P_tilting-geom - P_theor)` (eq. 5.22), and notes that the step can be
//! avoided by planning with the calibrated kinematics and the tilting directly. This module does
//! the latter: for every path point it solves the inverse kinematics on the calibrated model
//! ([`crate::model::ik::solve`], Gauss-Newton to convergence, i.e. eq. 5.22 iterated), with static
//! tilting on by default, seeded with the previous point's solution. The nominal model's rigid IK
//! joints (what an uncalibrated controller would command) are given alongside for comparison.
//! When the model carries transmission terms (model file `joint_scale`, `joint_coupling`,
//! `hysteresis_deg`, `compliance_deg_per_kgfm`), the IK gives the angles the joints must take
//! and the commands are the readings the terms map to them ([`transmission::commands_for`]).
//!
//! # Input: `PATH.csv`
//! | column | unit | meaning |
//! |---|---|---|
//! | `x y z` | mm | tool point in frame R (required) |
//! | `ax ay az` | - | tool-axis direction (optional, all three or none; normalised; default [`DEFAULT_TOOL_AXIS`]) |
//! | `t` | s | time (optional, copied to the output) |
//!
//! Other columns are ignored. `#` comment lines and blank lines are skipped.
//!
//! # Output: `JOINTS.csv`
//! `[t,]q1..qN[,q1_nominal..qN_nominal]`, deg, 9 decimals, one row per path point.

use std::fmt::Write as _;
use std::path::Path;

use nalgebra::Vector3;

use crate::error::{Classify, ErrorKind};
use crate::joints::table::{Table, TableError};
use crate::model::ik::ToolTarget;
use crate::model::ik::KATANA_SEED_DEG;
use crate::model::ik::{solve, IkError, IkTilt};
use crate::model::{Model, ModelError};

pub mod transmission;

/// Tool axis used when the path file has no `ax, ay, az` columns: straight down (-z of R).
pub const DEFAULT_TOOL_AXIS: [f64; 3] = [0.0, 0.0, -1.0];

/// One point of the desired path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathPoint {
    /// Line in the file (1-based; 0 for points made in code).
    pub line: usize,
    /// Time (s), when the file has `t`.
    pub t_s: Option<f64>,
    /// Tool point and unit tool axis.
    pub target: ToolTarget,
}

/// The joints for one path point.
#[derive(Debug, Clone, PartialEq)]
pub struct CompensatedPoint {
    /// Time (s), copied from the path point.
    pub t_s: Option<f64>,
    /// Joints to command (deg): the calibrated model, through its transmission terms when it
    /// has some, reaches the target with them.
    pub q_deg: Vec<f64>,
    /// The nominal model's rigid IK joints (deg), when a nominal model was given.
    pub q_nominal_deg: Option<Vec<f64>>,
    /// Joints (0-based) held at the previous command in a hysteresis dead band: they miss
    /// the angle by less than twice their hysteresis ([`transmission`]).
    pub held_joints: Vec<usize>,
}

/// Why compensation failed.
#[derive(Debug, thiserror::Error)]
pub enum CompensateError {
    /// The path file is malformed.
    #[error(transparent)]
    Table(#[from] TableError),
    /// A path point the (calibrated or nominal) model cannot reach.
    #[error("{file}:{line}: {which} model: {source}")]
    Unreachable {
        file: String,
        line: usize,
        which: &'static str,
        #[source]
        source: IkError,
    },
    /// The model failed (e.g. tilting asked of a model without tilting data).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The model's transmission terms cannot be inverted at a path point.
    #[error("{file}:{line}: {source}")]
    Transmission {
        file: String,
        line: usize,
        #[source]
        source: transmission::InvertError,
    },
    /// The output could not be written.
    #[error(transparent)]
    Write(#[from] crate::io::atomic::AtomicWriteError),
}

impl Classify for CompensateError {
    fn kind(&self) -> ErrorKind {
        match self {
            CompensateError::Table(e) => e.kind(),
            CompensateError::Unreachable { source, .. } => match source {
                IkError::Model(e) => e.kind(),
                IkError::Unreachable { .. } => ErrorKind::BadInput,
            },
            CompensateError::Model(e) => e.kind(),
            CompensateError::Transmission { source, .. } => match source {
                transmission::InvertError::Model { source, .. } => source.kind(),
                transmission::InvertError::NotInvertible { .. } => ErrorKind::Failure,
            },
            CompensateError::Write(_) => ErrorKind::Failure,
        }
    }
}

/// Reads `PATH.csv`.
pub fn read_path(path: &Path) -> Result<Vec<PathPoint>, TableError> {
    parse_path(&Table::read(path)?)
}

/// Path points from a parsed table.
pub fn parse_path(table: &Table) -> Result<Vec<PathPoint>, TableError> {
    let xyz = [table.need("x")?, table.need("y")?, table.need("z")?];
    let axis_cols = match (table.find("ax"), table.find("ay"), table.find("az")) {
        (None, None, None) => None,
        _ => Some([table.need("ax")?, table.need("ay")?, table.need("az")?]),
    };
    let t_col = table.find("t");
    let mut out = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let mut p = Vector3::zeros();
        for (k, &c) in xyz.iter().enumerate() {
            p[k] = table.number(row, c)?;
        }
        let axis = match axis_cols {
            Some(cols) => {
                let mut a = Vector3::zeros();
                for (k, &c) in cols.iter().enumerate() {
                    a[k] = table.number(row, c)?;
                }
                if a.norm() < 1e-9 {
                    return Err(table.bad(row, cols[0], "tool axis (ax, ay, az) has zero length"));
                }
                a.normalize()
            }
            None => Vector3::from(DEFAULT_TOOL_AXIS),
        };
        let t_s = match t_col {
            Some(c) => Some(table.number(row, c)?),
            None => None,
        };
        out.push(PathPoint {
            line: row.line,
            t_s,
            target: ToolTarget {
                position_mm: p,
                axis,
            },
        });
    }
    Ok(out)
}

/// The first seed: the Katana's working pose when the model has its 5 joints, else zeros.
fn first_seed(model: &Model) -> Vec<f64> {
    if model.n_joints() == KATANA_SEED_DEG.len() {
        KATANA_SEED_DEG.to_vec()
    } else {
        vec![0.0; model.n_joints()]
    }
}

/// Joints for every point of `points` on the calibrated `model` (`tilt`: [`IkTilt::Static`] for
/// the arm as it really bends), each seeded with the previous solution (the first with the
/// nominal solution when `nominal` is given, else the Katana working pose). With `nominal`,
/// also its rigid IK joints. `file` names the path in messages.
pub fn compensate(
    model: &Model,
    nominal: Option<&Model>,
    points: &[PathPoint],
    tilt: IkTilt,
    file: &str,
) -> Result<Vec<CompensatedPoint>, CompensateError> {
    if tilt == IkTilt::Static && !model.has_tilt() {
        return Err(ModelError::NoTiltData {
            model: model.name().to_string(),
        }
        .into());
    }
    let unreachable = |p: &PathPoint, which, source| CompensateError::Unreachable {
        file: file.to_string(),
        line: p.line,
        which,
        source,
    };
    let mut seed = first_seed(model);
    let mut seed_nominal = nominal.map(first_seed);
    let mut out = Vec::with_capacity(points.len());
    for p in points {
        let q_nominal = match (nominal, &seed_nominal) {
            (Some(nom), Some(s)) => Some(
                solve(nom, &p.target, s, IkTilt::Off).map_err(|e| unreachable(p, "nominal", e))?,
            ),
            _ => None,
        };
        if out.is_empty() {
            if let Some(q) = &q_nominal {
                seed.clone_from(q);
            }
        }
        // the model's time terms at the point's time: the chain's position that a measurement
        // at t gives as the target
        let t_s = p.t_s.unwrap_or(0.0);
        let target = ToolTarget {
            position_mm: model.chain_mm_for(&p.target.position_mm, t_s),
            ..p.target
        };
        // the model as it is at t (its changes within the session: tool point, payload)
        let mut q = solve(&model.at_time(t_s), &target, &seed, tilt)
            .map_err(|e| unreachable(p, "calibrated", e))?;
        seed.clone_from(&q);
        for (j, v) in q.iter_mut().enumerate() {
            *v -= model.time_terms().joint_drift_deg(j, t_s);
        }
        if let Some(q) = &q_nominal {
            seed_nominal = Some(q.clone());
        }
        out.push(CompensatedPoint {
            t_s: p.t_s,
            q_deg: q,
            q_nominal_deg: q_nominal,
            held_joints: Vec::new(),
        });
    }
    apply_transmission(model, points, &mut out, file)?;
    Ok(out)
}

/// Replaces the joint angles of `out` by the commands that give them through `model`'s
/// transmission terms (pose order: by `t` when every point has one).
fn apply_transmission(
    model: &Model,
    points: &[PathPoint],
    out: &mut [CompensatedPoint],
    file: &str,
) -> Result<(), CompensateError> {
    if !model.transmission().is_active() {
        return Ok(());
    }
    let q_eff: Vec<Vec<f64>> = out.iter().map(|p| p.q_deg.clone()).collect();
    let t_s: Option<Vec<f64>> = points.iter().map(|p| p.t_s).collect();
    let commands = transmission::commands_for(model, &q_eff, t_s.as_deref()).map_err(|source| {
        let index = match &source {
            transmission::InvertError::NotInvertible { index, .. }
            | transmission::InvertError::Model { index, .. } => *index,
        };
        let line = points.get(index).map_or(0, |p| p.line);
        CompensateError::Transmission {
            file: file.to_string(),
            line,
            source,
        }
    })?;
    for (p, q) in out.iter_mut().zip(commands.q_deg) {
        p.q_deg = q;
    }
    for (k, j) in commands.held {
        if let Some(p) = out.get_mut(k) {
            p.held_joints.push(j);
        }
    }
    Ok(())
}

/// The output CSV text (see the module doc).
pub fn joints_csv(n_joints: usize, points: &[CompensatedPoint]) -> String {
    let with_t = points.iter().any(|p| p.t_s.is_some());
    let with_nominal = points.iter().all(|p| p.q_nominal_deg.is_some()) && !points.is_empty();
    let mut cols: Vec<String> = Vec::new();
    if with_t {
        cols.push("t".into());
    }
    cols.extend((1..=n_joints).map(|i| format!("q{i}")));
    if with_nominal {
        cols.extend((1..=n_joints).map(|i| format!("q{i}_nominal")));
    }
    let mut s = cols.join(",");
    s.push('\n');
    for p in points {
        let mut fields: Vec<String> = Vec::new();
        if with_t {
            fields.push(p.t_s.map(|t| format!("{t:.9}")).unwrap_or_default());
        }
        fields.extend(p.q_deg.iter().map(|v| format!("{v:.9}")));
        if with_nominal {
            if let Some(qn) = &p.q_nominal_deg {
                fields.extend(qn.iter().map(|v| format!("{v:.9}")));
            }
        }
        let _ = writeln!(s, "{}", fields.join(","));
    }
    s
}

/// Writes [`joints_csv`] atomically to `path`.
pub fn write_joints_csv(
    path: &Path,
    n_joints: usize,
    points: &[CompensatedPoint],
) -> Result<(), CompensateError> {
    crate::io::atomic::write_text_atomic(
        path,
        crate::io::finite::TextFormat::Csv,
        &joints_csv(n_joints, points),
    )?;
    Ok(())
}
