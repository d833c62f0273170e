//! The one name of every value an identification can free: a model parameter, a term of the
//! model's joint map ([`super::transmission::JointTerms`]), a time term
//! ([`super::time_terms::TimeTerms`]) or the offset of another measured point. Each fit
//! frees the unknowns its problem evaluates (`calibrate` its selection, `diagnose` the
//! candidates of the effect table, [`super::effect`]); the values live in the [`Model`]
//! (the point offsets in the measurement set). Physical bounds: [`super::effect::bound`].

use super::Model;

/// One unknown of an extended fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Unknown {
    /// A model parameter (index into [`Model::params`]), in its own unit.
    Param(usize),
    /// Measured-position drift along axis 0/1/2 of frame R, mm per hour.
    PositionDrift(usize),
    /// Drift of joint j's offset (0-based), deg per hour.
    JointDrift(usize),
    /// Compliance of joint j (0-based): deflection per gravity torque, deg per kgf.m.
    Compliance(usize),
    /// Lateral compliance of joint j (0-based): bend about the joint frame's x and y per gravity
    /// moment about them, deg per kgf.m ([`super::lateral`]).
    LateralCompliance(usize),
    /// Transmission-ratio error of joint j (0-based): `q_j += s q_j` (dimensionless).
    JointScale(usize),
    /// Coupling of joint i's angle to joint k's command (0-based `(i, k)`): `q_i += c q_k`
    /// (deg/deg).
    Coupling(usize, usize),
    /// Hysteresis of joint j (0-based): `q_j += b d_j`, `d_j` the direction in which joint j
    /// last moved before the pose (+1, -1, 0; `MeasuredSet::approach`), deg.
    Hysteresis(usize),
    /// Thermal growth at saturation, ppm ([`crate::model::time_terms::TimeTerms::thermal_ppm`]).
    ThermalPpm,
    /// Thermal time constant, min ([`crate::model::time_terms::TimeTerms::thermal_tau_min`]); non-linear.
    ThermalTauMin,
    /// Axis `axis` (0..3) of the tool point's offset after change `slot` of the model's
    /// changes within the session ([`super::changes`]), mm in the last link frame.
    ToolStep { slot: usize, axis: usize },
    /// The mass picked up at change `slot` of the model's changes within the session, kg.
    PayloadStep(usize),
    /// Coordinate `axis` (0..3) of point slot `slot` (>= 1) in the tool frame, mm: the other
    /// measured points of a pose ([`super::measured::MeasuredSet`]).
    Offset { slot: usize, axis: usize },
}

/// Start values tried for [`Unknown::ThermalTauMin`] (min), log-spaced over the warm-up times
/// of real arms; the fit then moves it freely.
const THERMAL_TAU_STARTS_MIN: [f64; 8] = [3.0, 6.0, 10.0, 16.0, 25.0, 40.0, 65.0, 100.0];

impl Unknown {
    /// A readable name: the model parameter's name, `drift_x_mm_per_h`, `drift_j2_deg_per_h`,
    /// `compliance_j2_deg_per_kgfm`, `thermal_ppm`.
    pub fn name(&self, model: &Model) -> String {
        match *self {
            Unknown::Param(i) => model
                .params()
                .get(i)
                .map(|p| p.name.clone())
                .unwrap_or_else(|| format!("param{i}")),
            Unknown::PositionDrift(a) => format!("drift_{}_mm_per_h", ["x", "y", "z"][a.min(2)]),
            Unknown::JointDrift(j) => format!("drift_j{}_deg_per_h", j + 1),
            Unknown::Compliance(j) => format!("compliance_j{}_deg_per_kgfm", j + 1),
            Unknown::LateralCompliance(j) => format!("lateral_compliance_j{}_deg_per_kgfm", j + 1),
            Unknown::JointScale(j) => format!("joint_scale_j{}", j + 1),
            Unknown::Coupling(i, k) => format!("coupling_j{}_j{}_deg_per_deg", i + 1, k + 1),
            Unknown::Hysteresis(j) => format!("hysteresis_j{}_deg", j + 1),
            Unknown::ThermalPpm => "thermal_ppm".into(),
            Unknown::ThermalTauMin => "thermal_tau_min".into(),
            Unknown::Offset { slot, axis } => {
                format!("point{slot}_{}_mm", ["x", "y", "z"][axis.min(2)])
            }
            Unknown::ToolStep { slot, axis } => {
                format!(
                    "change{}_tool_d{}_mm",
                    slot + 1,
                    ["x", "y", "z"][axis.min(2)]
                )
            }
            Unknown::PayloadStep(slot) => format!("change{}_payload_kg", slot + 1),
        }
    }

    /// The joint (0-based) whose angle this unknown moves, for unknowns that act on a joint
    /// angle before the chain.
    pub fn joint(&self) -> Option<usize> {
        match *self {
            Unknown::JointDrift(j)
            | Unknown::Compliance(j)
            | Unknown::JointScale(j)
            | Unknown::Coupling(j, _)
            | Unknown::Hysteresis(j) => Some(j),
            Unknown::Param(_)
            | Unknown::LateralCompliance(_)
            | Unknown::PositionDrift(_)
            | Unknown::ThermalPpm
            | Unknown::ThermalTauMin
            | Unknown::ToolStep { .. }
            | Unknown::PayloadStep(_)
            | Unknown::Offset { .. } => None,
        }
    }

    /// Start values to try for an unknown the prediction is not linear in, whose column
    /// vanishes where its partner is zero (`None`: start from the current value).
    pub fn start_values(&self) -> Option<&'static [f64]> {
        match self {
            Unknown::ThermalTauMin => Some(&THERMAL_TAU_STARTS_MIN),
            _ => None,
        }
    }
}
