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
//! | lateral compliance | `lateral_compliance:j<i>` | bend about the joint frame's x and y per gravity moment about them | `deg_per_kgfm` | deg per kgf.m | link masses, no tilting |
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
    LateralCompliance,
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
pub const TABLE: [Row; 21] = [
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
        kind: Kind::LateralCompliance,
        family: "lateral_compliance",
        grammar: "lateral_compliance:j<i>",
        what: "joint bend about the two axes across it per gravity moment about them",
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

mod bounds;
mod change;
mod id;
mod library;

pub use bounds::{
    bound, bound_declared, Bound, PAYLOAD_MAX_PER_LINK_MASS, RIGID_STIFFNESS_KGFM_PER_DEG,
};
pub use change::{Change, ChangeError, JointTerm};
pub use id::{is_link_length_name, EffectId, UnknownEffectId};
pub use library::{library, Offers};

#[cfg(test)]
mod tests;
