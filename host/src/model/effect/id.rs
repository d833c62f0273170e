//! Effect ids as text: the grammar of the table's rows parsed ([`EffectId`]'s `FromStr`) and
//! written (`Display`), and what an id names (its kind, row, joints). The one place an id is
//! spelled from its parts.

use std::fmt;

use super::{grammars, Kind, Report, Row, TABLE};
/// A parsed effect id. Joints are 0-based here and 1-based in the text (`j1`).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum EffectId {
    LinkLength(String),
    EncoderHarmonic { joint: usize, order: u32 },
    ToolOffset,
    ToolLength,
    BaseOffset,
    BaseTilt,
    Payload,
    Stiffness(usize),
    Backlash(usize),
    Clearance(usize),
    Compliance(usize),
    LateralCompliance(usize),
    Scale,
    JointScale(usize),
    JointCoupling(usize, usize),
    Hysteresis(usize),
    TimeDrift,
    JointDrift(usize),
    Thermal,
    ToolChange,
    PayloadChange,
}

/// An id that is not in the table's grammar.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown effect id `{id}`; known: {known}", known = grammars())]
pub struct UnknownEffectId {
    /// The text given.
    pub id: String,
}

/// `j<i>` (i >= 1, digits only) as a 0-based joint.
fn joint_of(s: &str) -> Option<usize> {
    let n = s.strip_prefix('j')?;
    if n.is_empty() || !n.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    n.parse::<usize>().ok().filter(|&n| n >= 1).map(|n| n - 1)
}

/// Whether `name` is a link length's name: `a` or `d` and digits.
pub fn is_link_length_name(name: &str) -> bool {
    let mut c = name.chars();
    matches!(c.next(), Some('a' | 'd')) && {
        let rest = c.as_str();
        !rest.is_empty() && rest.bytes().all(|b| b.is_ascii_digit())
    }
}

impl std::str::FromStr for EffectId {
    type Err = UnknownEffectId;

    fn from_str(id: &str) -> Result<Self, Self::Err> {
        let bad = || UnknownEffectId { id: id.to_string() };
        let parts: Vec<&str> = id.split(':').collect();
        let per_joint = |kind: Kind, j: &str| -> Option<EffectId> {
            let j = joint_of(j)?;
            Some(match kind {
                Kind::Stiffness => EffectId::Stiffness(j),
                Kind::Backlash => EffectId::Backlash(j),
                Kind::Clearance => EffectId::Clearance(j),
                Kind::Compliance => EffectId::Compliance(j),
                Kind::LateralCompliance => EffectId::LateralCompliance(j),
                Kind::JointScale => EffectId::JointScale(j),
                Kind::Hysteresis => EffectId::Hysteresis(j),
                Kind::JointDrift => EffectId::JointDrift(j),
                _ => return None,
            })
        };
        // the row whose grammar is `family` alone, or `family:j<i>`
        let row_of = |family: &str, with_joint: bool| {
            TABLE
                .iter()
                .find(|r| {
                    r.family == family
                        && if with_joint {
                            r.grammar.strip_prefix(family) == Some(":j<i>")
                        } else {
                            r.grammar == family
                        }
                })
                .map(|r| r.kind)
        };
        let parsed = match parts.as_slice() {
            [family] => match row_of(family, false) {
                Some(Kind::ToolOffset) => Some(EffectId::ToolOffset),
                Some(Kind::ToolLength) => Some(EffectId::ToolLength),
                Some(Kind::BaseOffset) => Some(EffectId::BaseOffset),
                Some(Kind::BaseTilt) => Some(EffectId::BaseTilt),
                Some(Kind::Payload) => Some(EffectId::Payload),
                Some(Kind::Scale) => Some(EffectId::Scale),
                Some(Kind::TimeDrift) => Some(EffectId::TimeDrift),
                Some(Kind::Thermal) => Some(EffectId::Thermal),
                Some(Kind::ToolChange) => Some(EffectId::ToolChange),
                Some(Kind::PayloadChange) => Some(EffectId::PayloadChange),
                _ => None,
            },
            [family, name] if *family == Kind::LinkLength.family() => {
                is_link_length_name(name).then(|| EffectId::LinkLength(name.to_string()))
            }
            [family, j] => row_of(family, true).and_then(|k| per_joint(k, j)),
            [family, j, h] if *family == Kind::EncoderHarmonic.family() => {
                let order = h
                    .strip_prefix('h')
                    .filter(|n| n.len() == 1)
                    .and_then(|n| n.parse::<u32>().ok())
                    .filter(|n| (1..=3).contains(n));
                match (joint_of(j), order) {
                    (Some(joint), Some(order)) => Some(EffectId::EncoderHarmonic { joint, order }),
                    _ => None,
                }
            }
            [family, i, k] if *family == Kind::JointCoupling.family() => {
                match (joint_of(i), joint_of(k)) {
                    (Some(i), Some(k)) if i != k => Some(EffectId::JointCoupling(i, k)),
                    _ => None,
                }
            }
            _ => None,
        };
        parsed.ok_or_else(bad)
    }
}

impl fmt::Display for EffectId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let family = self.kind().family();
        match self {
            EffectId::LinkLength(name) => write!(f, "{family}:{name}"),
            EffectId::EncoderHarmonic { joint, order } => {
                write!(f, "{family}:j{}:h{order}", joint + 1)
            }
            EffectId::JointCoupling(i, k) => write!(f, "{family}:j{}:j{}", i + 1, k + 1),
            EffectId::Stiffness(j)
            | EffectId::Backlash(j)
            | EffectId::Clearance(j)
            | EffectId::Compliance(j)
            | EffectId::LateralCompliance(j)
            | EffectId::JointScale(j)
            | EffectId::Hysteresis(j)
            | EffectId::JointDrift(j) => write!(f, "{family}:j{}", j + 1),
            EffectId::ToolOffset
            | EffectId::ToolLength
            | EffectId::BaseOffset
            | EffectId::BaseTilt
            | EffectId::Payload
            | EffectId::Scale
            | EffectId::TimeDrift
            | EffectId::Thermal
            | EffectId::ToolChange
            | EffectId::PayloadChange => f.write_str(family),
        }
    }
}

impl EffectId {
    /// Its kind.
    pub fn kind(&self) -> Kind {
        match self {
            EffectId::LinkLength(_) => Kind::LinkLength,
            EffectId::EncoderHarmonic { .. } => Kind::EncoderHarmonic,
            EffectId::ToolOffset => Kind::ToolOffset,
            EffectId::ToolLength => Kind::ToolLength,
            EffectId::BaseOffset => Kind::BaseOffset,
            EffectId::BaseTilt => Kind::BaseTilt,
            EffectId::Payload => Kind::Payload,
            EffectId::Stiffness(_) => Kind::Stiffness,
            EffectId::Backlash(_) => Kind::Backlash,
            EffectId::Clearance(_) => Kind::Clearance,
            EffectId::Compliance(_) => Kind::Compliance,
            EffectId::LateralCompliance(_) => Kind::LateralCompliance,
            EffectId::Scale => Kind::Scale,
            EffectId::JointScale(_) => Kind::JointScale,
            EffectId::JointCoupling(..) => Kind::JointCoupling,
            EffectId::Hysteresis(_) => Kind::Hysteresis,
            EffectId::TimeDrift => Kind::TimeDrift,
            EffectId::JointDrift(_) => Kind::JointDrift,
            EffectId::Thermal => Kind::Thermal,
            EffectId::ToolChange => Kind::ToolChange,
            EffectId::PayloadChange => Kind::PayloadChange,
        }
    }

    /// Its row of [`TABLE`].
    pub fn row(&self) -> &'static Row {
        self.kind().row()
    }

    /// The joint (0-based) whose angle plots show it against: the joint it acts on, for a
    /// coupling the commanding joint `k`.
    pub fn joint(&self) -> Option<usize> {
        match *self {
            EffectId::EncoderHarmonic { joint, .. } => Some(joint),
            EffectId::Stiffness(j)
            | EffectId::Backlash(j)
            | EffectId::Clearance(j)
            | EffectId::Compliance(j)
            | EffectId::LateralCompliance(j)
            | EffectId::JointScale(j)
            | EffectId::Hysteresis(j)
            | EffectId::JointDrift(j) => Some(j),
            EffectId::JointCoupling(_, k) => Some(k),
            _ => None,
        }
    }

    /// Every joint it names (0-based).
    pub fn joints(&self) -> Vec<usize> {
        match *self {
            EffectId::JointCoupling(i, k) => vec![i, k],
            _ => self.joint().into_iter().collect(),
        }
    }

    /// Whether it is a change within the session at a time (`tool_change`, `payload_change`).
    pub fn is_change(&self) -> bool {
        self.row().report == Report::Step
    }

    /// The harmonic order (0 for an effect that is not a harmonic).
    pub fn harmonic_order(&self) -> u32 {
        match self {
            EffectId::EncoderHarmonic { order, .. } => *order,
            _ => 0,
        }
    }
}
