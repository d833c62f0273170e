//! What an effect frees on a model ([`EffectId::unknowns`]) and which effects the library
//! offers on a model and its data ([`library`], the rows' `offered`).

use super::{is_link_length_name, EffectId, Kind, Offered, TABLE};
use crate::model::changes::{StepKind, TOOL_PARAMS};
use crate::model::unknown::Unknown;
use crate::model::{Model, ParamKind, TiltParams};

impl EffectId {
    /// The unknowns it frees on `model`, in the order of its row's labels; `None` for a value
    /// the model does not have (a parameter it lacks, a joint beyond its chain).
    pub fn unknowns(&self, model: &Model) -> Vec<Option<Unknown>> {
        let idx = |name: &str| model.param_index(name).map(Unknown::Param);
        let n = model.n_joints();
        let joint = |j: usize, u: Unknown| (j < n).then_some(u);
        let tilt = |j: usize, pick: fn(&TiltParams) -> usize| {
            model
                .tilt_params()
                .and_then(|tp| tp.get(j))
                .map(|t| Unknown::Param(pick(t)))
        };
        match self {
            EffectId::LinkLength(name) => vec![idx(name)],
            EffectId::EncoderHarmonic { joint, order } => {
                match model
                    .joints()
                    .get(*joint)
                    .and_then(|jt| jt.harmonics.iter().find(|h| h.order == *order))
                {
                    Some(h) => vec![
                        Some(Unknown::Param(h.sin_param)),
                        Some(Unknown::Param(h.cos_param)),
                    ],
                    None => vec![None, None],
                }
            }
            EffectId::ToolOffset => vec![idx("tool_dx"), idx("tool_dy"), idx("tool_dz")],
            EffectId::ToolLength => vec![idx("tool_dz")],
            EffectId::BaseOffset => vec![idx("base_x"), idx("base_y"), idx("base_z")],
            EffectId::BaseTilt => vec![idx("base_rx"), idx("base_ry")],
            EffectId::Payload => vec![Some(Unknown::Param(model.payload_param()))],
            EffectId::Stiffness(j) => vec![tilt(*j, |t| t.stiffness)],
            EffectId::Backlash(j) => vec![tilt(*j, |t| t.backlash)],
            EffectId::Clearance(j) => vec![tilt(*j, |t| t.clearance)],
            EffectId::Compliance(j) => vec![joint(*j, Unknown::Compliance(*j))],
            EffectId::LateralCompliance(j) => vec![joint(*j, Unknown::LateralCompliance(*j))],
            EffectId::Scale => vec![Some(Unknown::Param(model.scale_param()))],
            EffectId::JointScale(j) => vec![joint(*j, Unknown::JointScale(*j))],
            EffectId::JointCoupling(i, k) => {
                vec![(*i < n && *k < n).then_some(Unknown::Coupling(*i, *k))]
            }
            EffectId::Hysteresis(j) => vec![joint(*j, Unknown::Hysteresis(*j))],
            EffectId::TimeDrift => (0..3).map(|a| Some(Unknown::PositionDrift(a))).collect(),
            EffectId::JointDrift(j) => vec![joint(*j, Unknown::JointDrift(*j))],
            EffectId::Thermal => vec![Some(Unknown::ThermalPpm), Some(Unknown::ThermalTauMin)],
            // the model's last change slot of the kind (`diagnose` opens one at its scanned time)
            EffectId::ToolChange => {
                let slot = last_slot(model, |k| matches!(k, StepKind::Tool(_)));
                let tool = TOOL_PARAMS.iter().all(|n| model.param_index(n).is_some());
                (0..3)
                    .map(|axis| {
                        slot.filter(|_| tool)
                            .map(|slot| Unknown::ToolStep { slot, axis })
                    })
                    .collect()
            }
            EffectId::PayloadChange => {
                vec![last_slot(model, |k| matches!(k, StepKind::Payload(_)))
                    .map(Unknown::PayloadStep)]
            }
        }
    }
}

/// The index of the model's last change of a kind.
fn last_slot(model: &Model, is: fn(&StepKind) -> bool) -> Option<usize> {
    model.steps().iter().rposition(|s| is(&s.kind))
}

/// What the data offers the library: joints that move between poses, pose times.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Offers {
    /// Directions of approach (the joints move between poses).
    pub approach: bool,
    /// Pose times (`t`).
    pub time: bool,
}

/// Every effect the library offers on `model` with data that `offers`, in the table's order
/// (within a kind: by parameter, joint, harmonic, joint pair).
pub fn library(model: &Model, offers: Offers) -> Vec<EffectId> {
    let n = model.n_joints();
    let tilting = model.tilt_params().is_some();
    let gravity = !model.masses().is_empty();
    let mut out = Vec::new();
    for row in &TABLE {
        let on = match row.offered {
            Offered::Always => true,
            Offered::WithTilting => tilting,
            Offered::WithGravity => gravity && !tilting,
            Offered::WithApproach => offers.approach,
            Offered::WithTime => offers.time,
            Offered::WithTimeAndTilting => offers.time && tilting,
        };
        if !on {
            continue;
        }
        match row.kind {
            Kind::LinkLength => out.extend(
                model
                    .params()
                    .iter()
                    .filter(|p| p.kind == ParamKind::Length && is_link_length_name(&p.name))
                    .map(|p| EffectId::LinkLength(p.name.clone())),
            ),
            Kind::EncoderHarmonic => {
                for (joint, jt) in model.joints().iter().enumerate() {
                    out.extend(jt.harmonics.iter().map(|h| EffectId::EncoderHarmonic {
                        joint,
                        order: h.order,
                    }));
                }
            }
            // the tilting values of a joint are listed together, joint by joint
            Kind::Stiffness => {
                let joints = model.tilt_params().map_or(0, <[_]>::len);
                for j in 0..joints {
                    out.extend([
                        EffectId::Stiffness(j),
                        EffectId::Backlash(j),
                        EffectId::Clearance(j),
                    ]);
                }
            }
            Kind::Backlash | Kind::Clearance => {}
            Kind::Compliance => out.extend((0..n).map(EffectId::Compliance)),
            Kind::LateralCompliance => out.extend((0..n).map(EffectId::LateralCompliance)),
            Kind::JointScale => out.extend((0..n).map(EffectId::JointScale)),
            Kind::JointCoupling => {
                for i in 0..n {
                    out.extend(
                        (0..n)
                            .filter(|&k| k != i)
                            .map(|k| EffectId::JointCoupling(i, k)),
                    );
                }
            }
            Kind::Hysteresis => out.extend((0..n).map(EffectId::Hysteresis)),
            Kind::JointDrift => out.extend((0..n).map(EffectId::JointDrift)),
            Kind::ToolOffset => out.push(EffectId::ToolOffset),
            Kind::ToolLength => out.push(EffectId::ToolLength),
            Kind::BaseOffset => out.push(EffectId::BaseOffset),
            Kind::BaseTilt => out.push(EffectId::BaseTilt),
            Kind::Payload => out.push(EffectId::Payload),
            Kind::Scale => out.push(EffectId::Scale),
            Kind::TimeDrift => out.push(EffectId::TimeDrift),
            Kind::Thermal => out.push(EffectId::Thermal),
            Kind::ToolChange => out.push(EffectId::ToolChange),
            Kind::PayloadChange => out.push(EffectId::PayloadChange),
        }
    }
    out
}
