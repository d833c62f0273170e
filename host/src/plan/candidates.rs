//! The candidate set of `rigctl plan`: random joint configurations within the joint limits that
//! satisfy the workspace constraints (table clearance, an optional box, an optional line of
//! sight to a tracker).

use nalgebra::Vector3;
use rand::Rng;

use super::PlanError;
use crate::calib::MeasuredSet;
use crate::model::{Model, Tilt};

pub use super::workspace::{
    usable_range_with, Workspace, KATANA_TABLE_CLEARANCE_MM, LIMIT_MARGIN_DEG,
};

/// Tries per wanted candidate before giving up on the constraints.
pub(super) const TRIES_PER_CANDIDATE: usize = 200;

/// One candidate pose: joint readings and the nominal (declared, rigid) tool point.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidatePose {
    /// Joint readings, deg.
    pub q_deg: Vec<f64>,
    /// Nominal tool point of the declared model without tilting, mm (frame R).
    pub nominal_mm: Vector3<f64>,
}

impl CandidatePose {
    /// The configuration `q_deg` with its nominal tool point, and the tool's z axis.
    fn with_axis(model: &Model, q_deg: Vec<f64>) -> Result<(Self, Vector3<f64>), PlanError> {
        let fk = model.fk(&q_deg, Tilt::Off)?;
        let axis = fk.rotation.column(2).into_owned();
        Ok((
            Self {
                q_deg,
                nominal_mm: fk.position_mm,
            },
            axis,
        ))
    }

    /// The configuration `q_deg` with its nominal tool point (declared model, no tilt).
    pub fn at(model: &Model, q_deg: Vec<f64>) -> Result<Self, PlanError> {
        Ok(Self::with_axis(model, q_deg)?.0)
    }

    /// As [`CandidatePose::at`], when the tool point and axis satisfy `ws` (`None` otherwise).
    pub fn admitted(
        model: &Model,
        q_deg: Vec<f64>,
        ws: &Workspace,
    ) -> Result<Option<Self>, PlanError> {
        let (pose, axis) = Self::with_axis(model, q_deg)?;
        let ok = ws
            .violation(model, &pose.q_deg, &pose.nominal_mm, &axis)?
            .is_none();
        Ok(ok.then_some(pose))
    }
}

/// `count` random configurations, joints uniform within the limits (less
/// [`LIMIT_MARGIN_DEG`]), kept when the declared model's tool point satisfies `ws`.
pub fn draw_candidates(
    model: &Model,
    count: usize,
    ws: &Workspace,
    rng: &mut impl Rng,
) -> Result<Vec<CandidatePose>, PlanError> {
    let limits = model.joint_limits();
    let mut out = Vec::with_capacity(count);
    let max_tries = TRIES_PER_CANDIDATE * count.max(1);
    let mut tries = 0usize;
    while out.len() < count {
        tries += 1;
        if tries > max_tries {
            return Err(PlanError::Candidates {
                wanted: count,
                found: out.len(),
                loosen: "--box / --visible-from",
                tries: max_tries,
            });
        }
        let q = random_configuration(&limits, ws, rng);
        out.extend(CandidatePose::admitted(model, q, ws)?);
    }
    Ok(out)
}

/// One configuration, every joint uniform within its limits less `ws`'s margin (the lower
/// usable end where the range is empty).
pub(super) fn random_configuration(
    limits: &[[f64; 2]],
    ws: &Workspace,
    rng: &mut impl Rng,
) -> Vec<f64> {
    limits
        .iter()
        .map(|l| {
            let (lo, hi) = ws.usable_range(l);
            if hi > lo && (hi - lo).is_finite() {
                rng.gen_range(lo..hi)
            } else {
                lo
            }
        })
        .collect()
}

/// The configurations `pool` (joint readings, deg; e.g. the poses a robot can reach safely, or
/// poses already measured) as candidates, in order, kept when the declared model's tool point
/// satisfies `ws`; with the index of each kept configuration in `pool`.
pub fn pool_candidates(
    model: &Model,
    pool: &[Vec<f64>],
    ws: &Workspace,
) -> Result<(Vec<CandidatePose>, Vec<usize>), PlanError> {
    let (mut out, mut index) = (Vec::new(), Vec::new());
    for (k, q) in pool.iter().enumerate() {
        if let Some(c) = CandidatePose::admitted(model, q.clone(), ws)? {
            out.push(c);
            index.push(k);
        }
    }
    Ok((out, index))
}

/// Most structured candidates: `3^joints` up to 7 joints; none beyond.
pub const MAX_STRUCTURED: usize = 2187;

/// The joint range a pose may use: the limits less [`LIMIT_MARGIN_DEG`] (the midpoint when the
/// range is narrower than twice the margin).
pub fn usable_range(limit: &[f64; 2]) -> (f64, f64) {
    usable_range_with(limit, LIMIT_MARGIN_DEG)
}

/// The structured candidates: every combination of each joint at its lower usable limit, its
/// mid-range and its upper usable limit ([`usable_range`]), kept when `ws` admits the tool point
/// (optimal designs sit at such extremes, which uniform draws rarely reach in every joint at
/// once). Empty when there would be more than [`MAX_STRUCTURED`].
pub fn structured_candidates(
    model: &Model,
    ws: &Workspace,
) -> Result<Vec<CandidatePose>, PlanError> {
    let ranges: Vec<(f64, f64)> = model
        .joint_limits()
        .iter()
        .map(|l| ws.usable_range(l))
        .collect();
    let total = 3usize
        .checked_pow(ranges.len() as u32)
        .unwrap_or(usize::MAX);
    if ranges.is_empty() || total > MAX_STRUCTURED {
        return Ok(Vec::new());
    }
    let mut out = Vec::new();
    for code in 0..total {
        let mut rest = code;
        let q: Vec<f64> = ranges
            .iter()
            .map(|&(lo, hi)| {
                let level = rest % 3;
                rest /= 3;
                lo + (hi - lo) * 0.5 * level as f64
            })
            .collect();
        out.extend(CandidatePose::admitted(model, q, ws)?);
    }
    Ok(out)
}

/// The poses `q` as a dataset (positions unused).
pub fn joints_dataset(q: &[Vec<f64>]) -> MeasuredSet {
    MeasuredSet::from_points(q.to_vec(), vec![Vector3::zeros(); q.len()])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_table_and_cone() {
        let ws = Workspace {
            min_z_mm: Some(40.0),
            box_mm: Some([0.0, 0.0, 0.0, 100.0, 100.0, 100.0]),
            visible_from_mm: Some(Vector3::new(50.0, 50.0, 1000.0)),
            cone_half_angle_deg: 30.0,
            ..Workspace::default()
        };
        let up = Vector3::z();
        assert!(ws.admits(&Vector3::new(50.0, 50.0, 50.0), &up));
        assert!(!ws.admits(&Vector3::new(50.0, 50.0, 30.0), &up), "table");
        assert!(!ws.admits(&Vector3::new(150.0, 50.0, 50.0), &up), "box");
        assert!(
            !ws.admits(&Vector3::new(50.0, 50.0, 50.0), &-up),
            "facing away"
        );
        assert!(
            !ws.admits(&Vector3::new(50.0, 50.0, 50.0), &Vector3::x()),
            "cone"
        );
    }
}
