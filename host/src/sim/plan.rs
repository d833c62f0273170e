//! Pose plans: the ISO 9283 calibration sequence and random validation poses.
//!
//! Tool orientation of a calibration position: the downward normal of the diagonal plane that
//! holds it (the tool stands normal to the plane, as the pencil does on the thesis's circle);
//! if that is out of reach within the joint limits, the downward normals of the other three
//! diagonal planes, then straight down, then the four horizontal axis directions, then a fan of
//! directions (elevation -60, -30, 0, +30 deg, azimuth every 30 deg) are tried in turn; the first
//! reachable one is used (thesis fig. 4.8 shows varied orientations). With d5 = 200 mm every
//! position is reached by one of the first ten; the fan is for longer tools.
//!
//! Order: the sequence starts at P1, then repeatedly goes to the unvisited pose whose smallest
//! joint change from the current one is largest (ties: lowest index), so that "all five joints
//! angles have to be changed when moving from one pose to another" (section 4.4.2), and ends at
//! P1 again (the ISO cycle). The greedy order is then improved by swaps that raise the smallest
//! joint change over all moves (bottleneck), until no swap with an end of the worst move helps.

use nalgebra::Vector3;
use rand::Rng;

use super::iso9283::{distinct_positions, Cube};
use crate::model::ik::ToolTarget;
use crate::model::ik::{solve, tool_target, IkError, IkTilt};
use crate::model::{Model, ModelError};

/// A planned pose: its name, the commanded joints and the Cartesian target they reach on the
/// declared (rigid) model.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedPose {
    /// Pose name (`P1`, `D<plane>_<i>_<j>`, `V<k>`).
    pub id: String,
    /// Commanded joint readings, deg.
    pub q_deg: Vec<f64>,
    /// Target tool point and axis on the declared model.
    pub target: ToolTarget,
}

pub use crate::model::ik::KATANA_SEED_DEG;

/// Why a plan could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// A calibration position that no tried orientation reaches.
    #[error("ISO 9283 position {id} at {position_mm:?} mm is not reachable with any tried tool orientation")]
    Unreachable { id: String, position_mm: [f64; 3] },
    /// Random validation poses could not be found.
    #[error("could not draw {wanted} validation poses clear of the table and the calibration poses ({found} found)")]
    Validation { wanted: usize, found: usize },
    /// The model failed.
    #[error(transparent)]
    Model(#[from] ModelError),
}

impl crate::error::Classify for PlanError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            PlanError::Model(e) => e.kind(),
            _ => crate::error::ErrorKind::Failure,
        }
    }
}

fn orientation_candidates(cube: &Cube, plane: usize) -> Vec<Vector3<f64>> {
    let planes = cube.diagonal_planes();
    let mut out = vec![planes[plane].normal_down()];
    out.extend(
        planes
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != plane)
            .map(|(_, p)| p.normal_down()),
    );
    out.push(-Vector3::z());
    out.extend([Vector3::x(), -Vector3::x(), Vector3::y(), -Vector3::y()]);
    // then a fan over the lower hemisphere and the horizon: elevation -60, -30, 0, +30 deg,
    // azimuth every 30 deg
    for el_deg in [-60.0f64, -30.0, 0.0, 30.0] {
        for k in 0..12 {
            let az = (30.0 * k as f64).to_radians();
            let el = el_deg.to_radians();
            out.push(Vector3::new(
                el.cos() * az.cos(),
                el.cos() * az.sin(),
                el.sin(),
            ));
        }
    }
    out
}

/// The 117 distinct ISO positions with their reachable orientations and joints, unordered.
pub fn iso_poses(model: &Model, cube: &Cube) -> Result<Vec<PlannedPose>, PlanError> {
    let mut out = Vec::new();
    for pos in distinct_positions(cube) {
        let mut found = None;
        for axis in orientation_candidates(cube, pos.plane) {
            let target = ToolTarget {
                position_mm: pos.position_mm,
                axis,
            };
            match solve(model, &target, &KATANA_SEED_DEG, IkTilt::Off) {
                Ok(q) => {
                    found = Some(PlannedPose {
                        id: pos.id.clone(),
                        q_deg: q,
                        target,
                    });
                    break;
                }
                Err(IkError::Unreachable { .. }) => continue,
                Err(IkError::Model(e)) => return Err(e.into()),
            }
        }
        out.push(found.ok_or_else(|| PlanError::Unreachable {
            id: pos.id.clone(),
            position_mm: pos.position_mm.into(),
        })?);
    }
    Ok(out)
}

fn min_joint_change(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(f64::INFINITY, f64::min)
}

/// Orders poses (first one first) so each move changes every joint as much as possible, and
/// returns to the first pose at the end.
pub fn order_for_joint_change(mut poses: Vec<PlannedPose>) -> Vec<PlannedPose> {
    if poses.is_empty() {
        return poses;
    }
    let first = poses.remove(0);
    let mut out = vec![first.clone()];
    while !poses.is_empty() {
        let cur = &out[out.len() - 1].q_deg;
        let mut best = 0;
        let mut best_v = f64::NEG_INFINITY;
        for (k, p) in poses.iter().enumerate() {
            let v = min_joint_change(cur, &p.q_deg);
            if v > best_v {
                best_v = v;
                best = k;
            }
        }
        out.push(poses.remove(best));
    }
    out.push(first);
    improve_bottleneck(&mut out);
    out
}

/// Smallest joint change over all consecutive moves, and the index of the first such move.
fn bottleneck(seq: &[PlannedPose]) -> (f64, usize) {
    let mut worst = (f64::INFINITY, 0);
    for k in 1..seq.len() {
        let v = min_joint_change(&seq[k - 1].q_deg, &seq[k].q_deg);
        if v < worst.0 {
            worst = (v, k);
        }
    }
    worst
}

/// Swaps inner poses (not the first or last) while that raises the bottleneck.
fn improve_bottleneck(seq: &mut [PlannedPose]) {
    let n = seq.len();
    if n < 4 {
        return;
    }
    for _ in 0..10 * n {
        let (current, k) = bottleneck(seq);
        let mut best: Option<(f64, usize, usize)> = None;
        for a in [k - 1, k].into_iter().filter(|&a| a > 0 && a < n - 1) {
            for b in 1..n - 1 {
                if b == a {
                    continue;
                }
                seq.swap(a, b);
                let (v, _) = bottleneck(seq);
                seq.swap(a, b);
                if v > current && best.is_none_or(|(bv, _, _)| v > bv) {
                    best = Some((v, a, b));
                }
            }
        }
        match best {
            Some((_, a, b)) => seq.swap(a, b),
            None => break,
        }
    }
}

/// The 118-pose ISO 9283 calibration sequence (see the module and [`super::iso9283`] docs).
pub fn iso_calibration_sequence(model: &Model, cube: &Cube) -> Result<Vec<PlannedPose>, PlanError> {
    Ok(order_for_joint_change(iso_poses(model, cube)?))
}

/// `count` random poses, joints uniform within the limits shrunk by 5 deg at each end, kept
/// when the tool point is at least 50 mm above the table (z in R) and every joint differs by at
/// least 2 deg from each pose of `avoid` in some joint (different from the calibration poses).
pub fn random_poses(
    model: &Model,
    count: usize,
    avoid: &[PlannedPose],
    rng: &mut impl Rng,
) -> Result<Vec<PlannedPose>, PlanError> {
    let limits = model.joint_limits();
    let mut out: Vec<PlannedPose> = Vec::with_capacity(count);
    let mut tries = 0usize;
    while out.len() < count {
        tries += 1;
        if tries > 1000 * count.max(1) {
            return Err(PlanError::Validation {
                wanted: count,
                found: out.len(),
            });
        }
        let q: Vec<f64> = limits
            .iter()
            .map(|l| {
                let (lo, hi) = (l[0] + 5.0, l[1] - 5.0);
                if hi > lo {
                    rng.gen_range(lo..hi)
                } else {
                    (l[0] + l[1]) / 2.0
                }
            })
            .collect();
        let target = tool_target(model, &q, IkTilt::Off)?;
        if target.position_mm.z < 50.0 {
            continue;
        }
        let clash = avoid
            .iter()
            .chain(out.iter())
            .any(|p| p.q_deg.iter().zip(&q).all(|(a, b)| (a - b).abs() < 2.0));
        if clash {
            continue;
        }
        out.push(PlannedPose {
            id: format!("V{}", out.len() + 1),
            q_deg: q,
            target,
        });
    }
    Ok(out)
}
