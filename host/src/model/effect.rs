//! Every effect, declared once: the effect ids of FORMATS.md (`diagnose --json` `effects[].id`,
//! `simulate --effect`, `plan --from-diagnose`) and, per kind, everything the rest of the tool
//! asks about it. No other module spells or parses an effect id (a test greps for that).
//!
//! | kind ([`Kind`]) | id grammar | what it frees ([`EffectId::unknowns`]) | reported `parameters` | `simulate` VALUE | offered ([`Offered`]) |
//! |---|---|---|---|---|---|
//! | link length | `link_length:<a_i or d_i>` | that length | `delta_mm` | mm | every length named `a<i>`/`d<i>` |
//! | encoder harmonic | `encoder_harmonic:j<i>:h<n>` | `enc_j<i>_h<n>_sin/_cos` | `A`, `phi` deg | `A[,phi]` deg | every harmonic the model carries |
//! | tool offset | `tool_offset` | `tool_dx/dy/dz` | `dx dy dz` mm | `dx,dy,dz` mm | always |
//! | tool length | `tool_length` | `tool_dz` (along z of the last frame: the flange normal) | `delta_mm` | mm | always |
//! | base offset | `base_offset` | `base_x/y/z` | `dx dy dz` mm | `dx,dy,dz` mm | always |
//! | base tilt | `base_tilt` | `base_rx/ry` | `rx ry` deg | `rx,ry` deg | always |
//! | payload | `payload` | `payload_kg` | `mass_kg` | kg | models with tilting |
//! | stiffness, backlash, clearance | `stiffness:j<i>` ... | that tilting value | value and `delta_*` | delta | models with tilting |
//! | compliance | `compliance:j<i>` | deflection per gravity torque | `deg_per_kgfm` | deg per kgf.m | link masses, no tilting |
//! | scale | `scale` | `scale_ppm` | `ppm` | ppm | always |
//! | joint scale | `joint_scale:j<i>` | `q_i += s q_i` | `s` | `s` | always |
//! | joint coupling | `joint_coupling:j<i>:j<k>` | `q_i += c q_k` | `c` deg/deg | `c` | always (i != k) |
//! | hysteresis | `hysteresis:j<i>` | `q_i += b d_i` | `b` deg | deg | joints that move between poses |
//! | position drift | `time_drift` | drift x, y, z | `v*_mm_per_h` | `v` or `vx,vy,vz` mm/h | poses with `t` |
//! | joint drift | `time_drift:j<i>` | joint-offset drift | `deg_per_h` | deg/h | poses with `t` |
//! | thermal | `thermal` | growth `s`, time constant `tau` | `s_ppm`, `tau_min` | `s,tau` | poses with `t` |
//! | tool change | `tool_change` | the tool point's offset after `t_s` (last frame) | `dx dy dz` mm, `t_s` | `dx,dy,dz,t_s` | poses with `t` |
//! | payload change | `payload_change` | a mass picked up (put down: < 0) at `t_s` | `mass_kg`, `t_s` | `kg,t_s` | poses with `t`, tilting |
//!
//! A change within the session ([`super::changes`]) frees its size; its time `t_s` is not an
//! unknown of the least-squares fit (the prediction is a step in it) but is found by `diagnose`
//! with a scan over the splits between distinct pose times (`diagnose::changes`).
//!
//! Besides: the rank of a kind in a tie between equally good candidates ([`Tie`]), the path
//! or time dependence that `plan` needs a measuring protocol for ([`Path`]), whether a URDF can
//! hold it (`urdf_holds`), the change it makes to a simulated truth ([`EffectId::change`],
//! [`Change`]), and the physical bound of every value an identification frees ([`bound`]).

use std::fmt;

use super::changes::{StepKind, TOOL_PARAMS};
use super::unknown::Unknown;
use super::{Model, ParamKind};

/// An effect kind: one row of [`TABLE`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kind {
    LinkLength,
    EncoderHarmonic,
    ToolOffset,
    ToolLength,
    BaseOffset,
    BaseTilt,
    Payload,
    Stiffness,
    Backlash,
    Clearance,
    Compliance,
    Scale,
    JointScale,
    JointCoupling,
    Hysteresis,
    TimeDrift,
    JointDrift,
    Thermal,
    ToolChange,
    PayloadChange,
}

/// When the candidate library offers a kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Offered {
    /// On every model.
    Always,
    /// On models with tilting data.
    WithTilting,
    /// On models with link masses and no tilting (the tilting's stiffness covers compliance).
    WithGravity,
    /// When the joints move between poses (a direction of approach).
    WithApproach,
    /// When the poses carry `t`.
    WithTime,
    /// When the poses carry `t` and the model has tilting data (a payload's moments).
    WithTimeAndTilting,
}

/// A kind's rank in a tie between candidates that predict equally well (Occam's order).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tie {
    /// By its number of unknowns, then its harmonic order.
    Named,
    /// After every named effect: the transmission terms are n + n(n-1) + n more hypotheses of
    /// one unknown each, so one of them fits a given residual by chance far more often.
    Transmission,
}

/// What, besides the pose, an effect depends on (`plan` words a measuring protocol for it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Path {
    /// The pose alone.
    Pose,
    /// The direction each joint last moved (the order of the rows).
    Approach,
    /// The time of a reading.
    Time,
}

/// How the fitted values are reported (`diagnose --json` `effects[].parameters`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Report {
    /// The change of each unknown, under the row's labels (one label: one unknown).
    Delta,
    /// The fitted values themselves (the declared model has none of the effect).
    Value,
    /// A declared value that is off: the fitted value and its change.
    ValueAndDelta,
    /// `A`, `phi` of `A sin(n q + phi)` from the sine and cosine parameters.
    Harmonic,
    /// The size of a change within the session (its values: the change itself), then its time
    /// `t_s` (the last label).
    Step,
}

/// One row of the effect table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Row {
    /// The kind.
    pub kind: Kind,
    /// The id's first part (`encoder_harmonic`).
    pub family: &'static str,
    /// The id grammar (`encoder_harmonic:j<i>:h<n>`).
    pub grammar: &'static str,
    /// What it is, in a few words.
    pub what: &'static str,
    /// The reported parameter names with their units, in order.
    pub labels: &'static [&'static str],
    /// How they are reported.
    pub report: Report,
    /// Counts of `simulate --effect ID=VALUE` values accepted, and what they are.
    pub sim_values: (&'static [usize], &'static str),
    /// When the library offers it.
    pub offered: Offered,
    /// Its rank in a tie.
    pub tie: Tie,
    /// What it depends on besides the pose.
    pub path: Path,
    /// Whether a URDF can hold it (`model2urdf`; otherwise it is named on stderr).
    pub urdf_holds: bool,
}

/// The effect table, in the order the candidate library lists the kinds.
pub const TABLE: [Row; 20] = [
    Row {
        kind: Kind::LinkLength,
        family: "link_length",
        grammar: "link_length:<a_i|d_i>",
        what: "error of a link length",
        labels: &["delta_mm"],
        report: Report::Delta,
        sim_values: (&[1], "delta mm"),
        offered: Offered::Always,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: true,
    },
    Row {
        kind: Kind::EncoderHarmonic,
        family: "encoder_harmonic",
        grammar: "encoder_harmonic:j<i>:h<n>",
        what: "joint-angle error A sin(n q_i + phi), n = 1..3",
        labels: &["A", "phi"],
        report: Report::Harmonic,
        sim_values: (&[1, 2], "A[,phi] deg"),
        offered: Offered::Always,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: false,
    },
    Row {
        kind: Kind::ToolOffset,
        family: "tool_offset",
        grammar: "tool_offset",
        what: "tool point offset in the last link frame",
        labels: &["dx", "dy", "dz"],
        report: Report::Delta,
        sim_values: (&[3], "dx,dy,dz mm"),
        offered: Offered::Always,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: true,
    },
    Row {
        kind: Kind::ToolLength,
        family: "tool_length",
        grammar: "tool_length",
        what: "tool length error, along z of the last link frame (the flange normal)",
        labels: &["delta_mm"],
        report: Report::Delta,
        sim_values: (&[1], "delta mm"),
        offered: Offered::Always,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: true,
    },
    Row {
        kind: Kind::BaseOffset,
        family: "base_offset",
        grammar: "base_offset",
        what: "robot base translated in frame R",
        labels: &["dx", "dy", "dz"],
        report: Report::Delta,
        sim_values: (&[3], "dx,dy,dz mm"),
        offered: Offered::Always,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: true,
    },
    Row {
        kind: Kind::BaseTilt,
        family: "base_tilt",
        grammar: "base_tilt",
        what: "robot base rotated about x and y of frame R",
        labels: &["rx", "ry"],
        report: Report::Delta,
        sim_values: (&[2], "rx,ry deg"),
        offered: Offered::Always,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: true,
    },
    Row {
        kind: Kind::Payload,
        family: "payload",
        grammar: "payload",
        what: "unknown point mass at the tool point (moments, so tilting)",
        labels: &["mass_kg"],
        report: Report::Delta,
        sim_values: (&[1], "kg"),
        offered: Offered::WithTilting,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: false,
    },
    Row {
        kind: Kind::Stiffness,
        family: "stiffness",
        grammar: "stiffness:j<i>",
        what: "a declared joint stiffness that is off",
        labels: &["stiffness_kgfm_per_deg", "delta_kgfm_per_deg"],
        report: Report::ValueAndDelta,
        sim_values: (&[1], "delta kgf.m/deg"),
        offered: Offered::WithTilting,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: false,
    },
    Row {
        kind: Kind::Backlash,
        family: "backlash",
        grammar: "backlash:j<i>",
        what: "a declared joint backlash that is off",
        labels: &["backlash_deg", "delta_deg"],
        report: Report::ValueAndDelta,
        sim_values: (&[1], "delta deg"),
        offered: Offered::WithTilting,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: false,
    },
    Row {
        kind: Kind::Clearance,
        family: "clearance",
        grammar: "clearance:j<i>",
        what: "a declared joint clearance that is off",
        labels: &["clearance_deg", "delta_deg"],
        report: Report::ValueAndDelta,
        sim_values: (&[1], "delta deg"),
        offered: Offered::WithTilting,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: false,
    },
    Row {
        kind: Kind::Compliance,
        family: "compliance",
        grammar: "compliance:j<i>",
        what: "joint deflection per gravity torque",
        labels: &["deg_per_kgfm"],
        report: Report::Delta,
        sim_values: (&[1], "deg per kgf.m"),
        offered: Offered::WithGravity,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: false,
    },
    Row {
        kind: Kind::Scale,
        family: "scale",
        grammar: "scale",
        what: "scale error of the measuring instrument about the origin of frame R",
        labels: &["ppm"],
        report: Report::Delta,
        sim_values: (&[1], "ppm"),
        offered: Offered::Always,
        tie: Tie::Named,
        path: Path::Pose,
        urdf_holds: true,
    },
    Row {
        kind: Kind::JointScale,
        family: "joint_scale",
        grammar: "joint_scale:j<i>",
        what: "transmission-ratio error q_i += s q_i",
        labels: &["s"],
        report: Report::Delta,
        sim_values: (&[1], "s"),
        offered: Offered::Always,
        tie: Tie::Transmission,
        path: Path::Pose,
        urdf_holds: false,
    },
    Row {
        kind: Kind::JointCoupling,
        family: "joint_coupling",
        grammar: "joint_coupling:j<i>:j<k>",
        what: "joint i's angle depends on joint k's command, q_i += c q_k",
        labels: &["c"],
        report: Report::Delta,
        sim_values: (&[1], "c deg/deg"),
        offered: Offered::Always,
        tie: Tie::Transmission,
        path: Path::Pose,
        urdf_holds: false,
    },
    Row {
        kind: Kind::Hysteresis,
        family: "hysteresis",
        grammar: "hysteresis:j<i>",
        what: "direction of approach, q_i += b d_i",
        labels: &["b"],
        report: Report::Delta,
        sim_values: (&[1], "b deg"),
        offered: Offered::WithApproach,
        tie: Tie::Transmission,
        path: Path::Approach,
        urdf_holds: false,
    },
    Row {
        kind: Kind::TimeDrift,
        family: "time_drift",
        grammar: "time_drift",
        what: "measured position drifting with t",
        labels: &["vx_mm_per_h", "vy_mm_per_h", "vz_mm_per_h"],
        report: Report::Delta,
        sim_values: (&[1, 3], "v or vx,vy,vz mm per hour"),
        offered: Offered::WithTime,
        tie: Tie::Named,
        path: Path::Time,
        urdf_holds: false,
    },
    Row {
        kind: Kind::JointDrift,
        family: "time_drift",
        grammar: "time_drift:j<i>",
        what: "joint-offset drift with t",
        labels: &["deg_per_h"],
        report: Report::Delta,
        sim_values: (&[1], "deg per hour"),
        offered: Offered::WithTime,
        tie: Tie::Named,
        path: Path::Time,
        urdf_holds: false,
    },
    Row {
        kind: Kind::Thermal,
        family: "thermal",
        grammar: "thermal",
        what: "warm-up growth 1 + s (1 - exp(-t / tau)) of every length from R to the tool point",
        labels: &["s_ppm", "tau_min"],
        report: Report::Value,
        sim_values: (&[2], "s,tau (ppm, min)"),
        offered: Offered::WithTime,
        tie: Tie::Named,
        path: Path::Time,
        urdf_holds: false,
    },
    Row {
        kind: Kind::ToolChange,
        family: "tool_change",
        grammar: "tool_change",
        what: "the tool point (marker) moves by an offset in the last link frame at time t_s",
        labels: &["dx", "dy", "dz", "t_s"],
        report: Report::Step,
        sim_values: (&[4], "dx,dy,dz mm then t_s s"),
        offered: Offered::WithTime,
        tie: Tie::Named,
        path: Path::Time,
        urdf_holds: false,
    },
    Row {
        kind: Kind::PayloadChange,
        family: "payload_change",
        grammar: "payload_change",
        what: "a payload picked up (put down: < 0) at the tool point at time t_s",
        labels: &["mass_kg", "t_s"],
        report: Report::Step,
        sim_values: (&[2], "kg then t_s s"),
        offered: Offered::WithTimeAndTilting,
        tie: Tie::Named,
        path: Path::Time,
        urdf_holds: false,
    },
];

impl Kind {
    /// Its row of [`TABLE`].
    pub fn row(self) -> &'static Row {
        TABLE.iter().find(|r| r.kind == self).unwrap_or(&TABLE[0])
    }

    /// Whether it changes the loads on the joints (the gravity moments) without moving the
    /// chain: a payload, a tilt of the base against gravity. Such an effect switches the sign
    /// steps of a declared law (the tilting's contact side) wherever its moments cross the
    /// arm's own, which a linearisation at zero cannot see.
    pub fn changes_loads(self) -> bool {
        matches!(self, Kind::Payload | Kind::BaseTilt)
    }

    /// The id's first part (`joint_scale`): also the name of the model's term it fits.
    pub fn family(self) -> &'static str {
        self.row().family
    }
}

/// Every id grammar of the table, for messages (`link_length:<a_i|d_i>, ...`).
pub fn grammars() -> String {
    TABLE
        .iter()
        .map(|r| r.grammar)
        .collect::<Vec<_>>()
        .join(", ")
}

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

    /// The unknowns it frees on `model`, in the order of its row's labels; `None` for a value
    /// the model does not have (a parameter it lacks, a joint beyond its chain).
    pub fn unknowns(&self, model: &Model) -> Vec<Option<Unknown>> {
        let idx = |name: &str| model.param_index(name).map(Unknown::Param);
        let n = model.n_joints();
        let joint = |j: usize, u: Unknown| (j < n).then_some(u);
        let tilt = |j: usize, pick: fn(&super::TiltParams) -> usize| {
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

mod bounds;
mod change;

pub use bounds::{bound, Bound, RIGID_STIFFNESS_KGFM_PER_DEG};
pub use change::{Change, ChangeError, JointTerm};

#[cfg(test)]
mod tests;
