//! `--from-diagnose` designs robust to the unknown value of the effects to separate.
//!
//! The identification Jacobian of an effect that is not linear in its own value depends on that
//! value, and the declared model (where the plan would linearise) has every effect at zero.
//! The Katana's payload is the case in point: it acts through the joint moments on the
//! clearance tilt of MODEL.md eq. 5.16-5.18, whose contact direction
//! `gamma = (pi/2) |eta_x| / (|eta_x| + |eta_y|)` has a derivative of order `1 / (|eta_x| +
//! |eta_y|)`: where a joint's own moment nearly vanishes (the centre of mass beyond it on its
//! vertical) the payload column at zero payload is 40-200 mm/kg, but a payload of a few grams
//! already turns the contact fully and the tilt saturates at the clearance C; at 0.5 kg the same
//! poses move by 0.03-0.06 mm/kg. A design linearised at zero collects exactly those poses (expected payload
//! sigma 8e-5 kg, while the sigma at the true 0.5 kg on the same poses is 0.039 kg and a
//! Monte-Carlo over the noise gives 0.024 kg), and `diagnose`, which screens every candidate
//! linearly at zero as well, then does not even refit the payload.
//!
//! What `diagnose` needs is narrower than information: it screens every candidate effect
//! linearly at the current fit (where the effect is zero), refits the best ones from there and
//! accepts one only when the fit and the cross-validation confirm it. A pose helps that only
//! where the effect is linear in its value over the plausible range: the derivative at zero
//! must predict the displacement the effect really produces there. So with `--from-diagnose`
//! a pose (candidate, or a refinement move) is **admissible** only when, for every
//! [`Member`] (the unknowns of interest moved together by `t * magnitude`, `t` in
//! [`MEMBER_FRACTIONS`]), the displacement predicted by the derivative at zero and the true one
//! differ by at most [`LINEARITY_RTOL`] of the larger of the two ([`Linearity::admits`]).
//! The design itself stays the (As/Ds) design at the declared model, on the admissible poses.
//! An effect linear in its value (a link length, a joint offset) leaves every pose admissible;
//! a pose whose information exists only in an infinitesimal neighbourhood of zero, or where a
//! plausible value of the effect flips a joint's contact (a step, not a slope), is left out.
//!
//! The magnitude of an unknown: its change in the diagnosis when the diagnose JSON reports a
//! fitted value for it (`effects[].model_parameters`), otherwise the value whose tool-point
//! displacement, RMS over the candidates, equals the diagnosis's declared calibration RMS error
//! (`declared.calibration.rms_mm`: the size of what the declared model left unexplained, which
//! an effect it lacks can reach but hardly exceed; [`DEFAULT_EFFECT_RMS_MM`] when the JSON
//! lacks it), found by a fixed-point iteration on the true (nonlinear) displacement.

use nalgebra::{DVector, Vector3};

use super::candidates::{joints_dataset, CandidatePose};
use super::PlanError;
use crate::diagnose::extended::{ExtModel, Unknown, Values};
use crate::model::effect::bound;

/// The values of the unknowns of interest, as fractions of their magnitudes, at which the
/// linearity of a pose is checked.
pub const MEMBER_FRACTIONS: [f64; 4] = [-1.0, -0.5, 0.5, 1.0];

/// Largest relative difference between the displacement the derivative at zero predicts and
/// the true one at an admissible pose.
pub const LINEARITY_RTOL: f64 = 0.25;

/// Smallest share of the candidates admitted (the most linear ones) when fewer pass
/// [`LINEARITY_RTOL`].
pub const MIN_ADMISSIBLE_SHARE: f64 = 0.05;

/// Tool-point RMS displacement (mm) of an effect of plausible size when the diagnose JSON gives
/// no declared residual.
pub const DEFAULT_EFFECT_RMS_MM: f64 = 0.1;

/// Candidates used to size an effect (the first ones: uniform draws).
const SIZING_POSES: usize = 1000;

/// Iterations and relative tolerance of the sizing.
const SIZING_ITERATIONS: usize = 12;
const SIZING_RTOL: f64 = 0.02;

/// The true tool-point displacement of a member at a pose and the one the derivative at zero
/// predicts (mm).
type Displacement = (Vector3<f64>, Vector3<f64>);

/// The model at one plausible value of the unknowns of interest.
#[derive(Debug, Clone)]
pub struct Member {
    /// The model with the unknowns of interest moved.
    pub ext: ExtModel,
    /// The changes of the unknowns of interest (same order as [`Linearity::unknowns`]).
    pub delta: Vec<f64>,
    /// The common ratio of the true displacement to the one the derivative at zero predicts,
    /// over the candidates ([`Linearity::calibrate`]; 1 before): a nonlinearity shared by every
    /// pose (e.g. a stiffness, which acts through its inverse) scales the effect's signature
    /// without changing its shape, so diagnose's screen still ranks it right.
    pub factor: f64,
}

/// The linearity test of the unknowns of interest (see the module docs).
#[derive(Debug, Clone)]
pub struct Linearity {
    /// The model the design is linearised at.
    pub ext: ExtModel,
    /// The unknowns of interest that were sized.
    pub unknowns: Vec<Unknown>,
    /// Their magnitudes (unknown units).
    pub magnitudes: Vec<f64>,
    /// The models at the plausible values.
    pub members: Vec<Member>,
    /// The largest nonlinearity admitted: [`LINEARITY_RTOL`], or higher when fewer than
    /// [`MIN_ADMISSIBLE_SHARE`] of the candidates pass it ([`Linearity::admissible`]).
    pub threshold: f64,
}

/// Whether `v` is a physical value of `u` (the effect table's bounds: a negative payload,
/// stiffness, clearance, backlash or compliance is not).
fn physical(ext: &ExtModel, u: Unknown, v: f64) -> bool {
    bound(u, &ext.model).is_none_or(|b| b.admits(v))
}

/// The largest change of `u` considered: its own value for a quantity that cannot be negative
/// (a change of more than 100 %), none otherwise.
fn magnitude_cap(ext: &ExtModel, u: Unknown) -> f64 {
    let v = ext.value(u);
    match bound(u, &ext.model) {
        Some(b) if b.min == 0.0 && v > 0.0 => v,
        _ => f64::INFINITY,
    }
}

/// `ext` with `u` moved by `delta`, when that is a physical value the model accepts.
fn moved(ext: &ExtModel, u: Unknown, delta: f64) -> Option<ExtModel> {
    let v = ext.value(u) + delta;
    let mut m = ext.clone();
    (physical(ext, u, v) && m.set_value(u, v).is_ok()).then_some(m)
}

impl Linearity {
    /// The test for `unknowns` of `ext` with `magnitudes`; members with an unphysical value
    /// (a negative payload: [`physical`]) or one the model rejects are left out.
    pub fn new(ext: &ExtModel, unknowns: Vec<Unknown>, magnitudes: Vec<f64>) -> Self {
        let mut members = Vec::with_capacity(MEMBER_FRACTIONS.len());
        'member: for t in MEMBER_FRACTIONS {
            let mut model = ext.clone();
            let mut delta = Vec::with_capacity(unknowns.len());
            for (&u, m) in unknowns.iter().zip(&magnitudes) {
                match moved(&model, u, t * m) {
                    Some(next) => model = next,
                    None => continue 'member,
                }
                delta.push(t * m);
            }
            members.push(Member {
                ext: model,
                delta,
                factor: 1.0,
            });
        }
        Self {
            ext: ext.clone(),
            unknowns,
            magnitudes,
            members,
            threshold: LINEARITY_RTOL,
        }
    }

    /// Per member: the true displacement of the tool point at `q_deg` and the one the
    /// derivative at zero predicts (mm).
    fn displacements(&self, q_deg: &[f64]) -> Result<Vec<Displacement>, PlanError> {
        let data = joints_dataset(&[q_deg.to_vec()]);
        let (p0, jac) = self.ext.predict_with_jacobian(&data, 0, &self.unknowns)?;
        self.members
            .iter()
            .map(|m| {
                let truth = m.ext.predict_pose(&data, 0)? - p0;
                let p = &jac * DVector::from_column_slice(&m.delta);
                Ok((truth, Vector3::new(p[0], p[1], p[2])))
            })
            .collect()
    }

    /// The nonlinearity of the configuration `q_deg`: the largest over the members of the
    /// difference between the true displacement and the one the derivative at zero predicts
    /// (times the member's common [`Member::factor`]), relative to the larger of the two (0:
    /// linear; 1 or more: one of them is nil or they oppose).
    pub fn nonlinearity(&self, q_deg: &[f64]) -> Result<f64, PlanError> {
        let pairs = self.displacements(q_deg)?;
        Ok(self
            .members
            .iter()
            .zip(pairs)
            .map(|(m, (t, p))| relative_gap(&t, &(p * m.factor)))
            .fold(0.0, f64::max))
    }

    /// Whether the configuration `q_deg` is admissible: its [`Linearity::nonlinearity`] is at
    /// most [`Linearity::threshold`].
    pub fn admits(&self, q_deg: &[f64]) -> Result<bool, PlanError> {
        Ok(self.members.is_empty() || self.nonlinearity(q_deg)? <= self.threshold)
    }

    /// Sets each member's common [`Member::factor`]: the median over the candidates `cands`
    /// (those where the predicted displacement is at least 1 % of its RMS) of the projection
    /// ratio `truth . predicted / |predicted|^2`.
    pub fn calibrate(&mut self, cands: &[CandidatePose]) -> Result<(), PlanError> {
        let pairs: Vec<Vec<Displacement>> = cands
            .iter()
            .map(|c| self.displacements(&c.q_deg))
            .collect::<Result<_, _>>()?;
        for (k, m) in self.members.iter_mut().enumerate() {
            let n2: Vec<f64> = pairs.iter().map(|p| p[k].1.norm_squared()).collect();
            let rms2 = n2.iter().sum::<f64>() / n2.len().max(1) as f64;
            let mut ratios: Vec<f64> = pairs
                .iter()
                .zip(&n2)
                .filter(|(_, n)| **n > 1e-4 * rms2 && **n > 0.0)
                .map(|(p, n)| p[k].0.dot(&p[k].1) / n)
                .collect();
            ratios.sort_by(f64::total_cmp);
            if let Some(r) = ratios
                .get(ratios.len() / 2)
                .filter(|r| r.is_finite() && **r > 0.0)
            {
                m.factor = *r;
            }
        }
        Ok(())
    }

    /// Calibrates the test on `cands` ([`Linearity::calibrate`]) and returns which of them are
    /// admissible. When fewer than [`MIN_ADMISSIBLE_SHARE`] of them pass [`LINEARITY_RTOL`],
    /// the threshold is raised to admit that share, the most linear ones.
    pub fn admissible(&mut self, cands: &[CandidatePose]) -> Result<Vec<bool>, PlanError> {
        if self.members.is_empty() {
            return Ok(vec![true; cands.len()]);
        }
        self.calibrate(cands)?;
        let nl: Vec<f64> = cands
            .iter()
            .map(|c| self.nonlinearity(&c.q_deg))
            .collect::<Result<_, _>>()?;
        let mut sorted = nl.clone();
        sorted.sort_by(f64::total_cmp);
        let need = ((MIN_ADMISSIBLE_SHARE * cands.len() as f64).ceil() as usize).max(1);
        self.threshold = match sorted.get(need - 1) {
            Some(&q) if q > LINEARITY_RTOL => q,
            _ => LINEARITY_RTOL,
        };
        Ok(nl.iter().map(|v| *v <= self.threshold).collect())
    }
}

/// `|a - b|` relative to the larger of `|a|`, `|b|` (0 when both are nil).
fn relative_gap(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let scale = a.norm().max(b.norm());
    if scale > 0.0 {
        (a - b).norm() / scale
    } else {
        0.0
    }
}

/// RMS over `q` of the tool-point displacement when `u` moves from its value in `ext` by
/// `delta` (NaN when that value is not physical).
fn displacement_rms_mm(ext: &ExtModel, u: Unknown, delta: f64, q: &[Vec<f64>]) -> f64 {
    let data = joints_dataset(q);
    let Some(moved) = moved(ext, u, delta) else {
        return f64::NAN;
    };
    let (Ok(a), Ok(b)) = (ext.errors(&data), moved.errors(&data)) else {
        return f64::NAN;
    };
    let ss: f64 = a.iter().zip(&b).map(|(x, y)| (x - y).norm_squared()).sum();
    (ss / q.len().max(1) as f64).sqrt()
}

/// The larger of the displacements of `+m` and `-m` (the physical ones).
fn displacement_either_way(ext: &ExtModel, u: Unknown, m: f64, q: &[Vec<f64>]) -> f64 {
    let (a, b) = (
        displacement_rms_mm(ext, u, m, q),
        displacement_rms_mm(ext, u, -m, q),
    );
    match (a.is_finite(), b.is_finite()) {
        (true, true) => a.max(b),
        (true, false) => a,
        (false, true) => b,
        _ => f64::NAN,
    }
}

/// The change of `u` (either way) whose tool-point displacement, RMS over `q`, is
/// `target_mm`, starting from `start` (e.g. from the linear column scale), at most the value of
/// a quantity that cannot be negative (a stiffness, a clearance); `None` when the unknown does
/// not move the tool point.
pub fn effect_magnitude(
    ext: &ExtModel,
    u: Unknown,
    q: &[Vec<f64>],
    target_mm: f64,
    start: f64,
) -> Option<f64> {
    let cap = magnitude_cap(ext, u);
    let mut m = if start.is_finite() && start > 0.0 {
        start.min(cap)
    } else {
        1.0_f64.min(cap)
    };
    for _ in 0..SIZING_ITERATIONS {
        let g = displacement_either_way(ext, u, m, q);
        if !g.is_finite() {
            return None;
        }
        if (g / target_mm - 1.0).abs() < SIZING_RTOL || (m >= cap && g < target_mm) {
            return Some(m);
        }
        let factor = if g > 0.0 { target_mm / g } else { 10.0 };
        m = (m * factor.clamp(0.1, 10.0)).min(cap);
    }
    let g = displacement_either_way(ext, u, m, q);
    (g.is_finite() && g > 0.0).then_some(m)
}

/// The sizing target and the first candidates to size on.
pub fn sizing_poses(cands: &[CandidatePose]) -> Vec<Vec<f64>> {
    cands
        .iter()
        .take(SIZING_POSES)
        .map(|c| c.q_deg.clone())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{katana450, KATANA_TOOL_MM};
    use crate::plan::candidates::{draw_candidates, Workspace};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn katana_candidates(n: usize) -> (ExtModel, Vec<CandidatePose>) {
        let model = katana450(KATANA_TOOL_MM).unwrap();
        let ws = Workspace::for_model(&model);
        let cands = draw_candidates(&model, n, &ws, &mut ChaCha8Rng::seed_from_u64(5)).unwrap();
        (ExtModel::new(model), cands)
    }

    fn unknown(ext: &ExtModel, name: &str) -> Unknown {
        Unknown::Param(ext.model.param_index(name).unwrap())
    }

    /// A link length is linear in its value: every pose is admissible, and its size for a
    /// target displacement is found exactly.
    #[test]
    fn a_linear_effect_admits_every_pose_and_is_sized_exactly() {
        let (ext, cands) = katana_candidates(300);
        let a3 = unknown(&ext, "a3");
        let q = sizing_poses(&cands);
        let m = effect_magnitude(&ext, a3, &q, 0.1, 1.0).unwrap();
        let g = displacement_either_way(&ext, a3, m, &q);
        assert!((g / 0.1 - 1.0).abs() < SIZING_RTOL, "{m} mm gives {g}");
        let mut lin = Linearity::new(&ext, vec![a3], vec![m]);
        assert_eq!(lin.members.len(), MEMBER_FRACTIONS.len());
        assert!(lin.admissible(&cands).unwrap().iter().all(|a| *a));
        for c in cands.iter().take(20) {
            assert!(lin.nonlinearity(&c.q_deg).unwrap() < 1e-6);
        }
        assert!((lin.members[0].factor - 1.0).abs() < 1e-6);
    }

    /// The payload acts through the clearance tilt's contact direction, whose derivative is
    /// unbounded where a joint moment vanishes: the pose with the largest payload column at zero
    /// is not admissible, most poses are, and no member has a negative mass.
    #[test]
    fn payload_is_not_linear_where_a_joint_moment_vanishes() {
        let (ext, cands) = katana_candidates(500);
        let pay = unknown(&ext, "payload_kg");
        let mut lin = Linearity::new(&ext, vec![pay], vec![1.0]);
        assert!(!lin.members.is_empty() && lin.members.iter().all(|m| m.delta[0] > 0.0));
        let ok = lin.admissible(&cands).unwrap();
        let share = ok.iter().filter(|a| **a).count() as f64 / ok.len() as f64;
        assert!(share > 0.3 && share < 0.95, "admissible share {share}");
        let column = |q: &[f64]| {
            let data = joints_dataset(&[q.to_vec()]);
            ext.predict_with_jacobian(&data, 0, &[pay])
                .unwrap()
                .1
                .norm()
        };
        let worst = (0..cands.len())
            .max_by(|&a, &b| column(&cands[a].q_deg).total_cmp(&column(&cands[b].q_deg)))
            .unwrap();
        assert!(!ok[worst], "largest column {}", column(&cands[worst].q_deg));
        assert!(!lin.admits(&cands[worst].q_deg).unwrap());
    }

    /// A stiffness acts through its inverse: sized at most to its own value, and the common
    /// factor absorbs the nonlinearity shared by every pose.
    #[test]
    fn a_stiffness_is_capped_and_its_shared_nonlinearity_absorbed() {
        let (ext, cands) = katana_candidates(300);
        let k2 = unknown(&ext, "stiffness_j2");
        let q = sizing_poses(&cands);
        let m = effect_magnitude(&ext, k2, &q, 10.0, 1.0).unwrap();
        assert!(m <= ext.value(k2) + 1e-12, "{m}");
        let mut lin = Linearity::new(&ext, vec![k2], vec![0.5 * ext.value(k2)]);
        let ok = lin.admissible(&cands).unwrap();
        assert!(lin.members.iter().any(|m| (m.factor - 1.0).abs() > 0.1));
        let share = ok.iter().filter(|a| **a).count() as f64 / ok.len() as f64;
        assert!(share > 0.9, "admissible share {share}");
    }
}
