//! Named model parameters: every constant of the chain, plus the base, tool, encoder-harmonic,
//! tilting, payload and scale parameters that calibration and diagnosis may select.

/// The unit a parameter value is given in (files, `--set`, reports, Jacobian columns).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// Degrees (angles, offsets, twists, tilt clearance/backlash, harmonic amplitudes).
    Deg,
    /// Millimetres (lengths, base and tool offsets; a prismatic joint offset).
    Mm,
    /// Kilograms (payload).
    Kg,
    /// Parts per million (measurement scale).
    Ppm,
    /// Kilogram-force metre per degree (joint stiffness).
    KgfmPerDeg,
}

impl Unit {
    /// Short unit label, e.g. `"deg"`.
    pub fn label(self) -> &'static str {
        match self {
            Unit::Deg => "deg",
            Unit::Mm => "mm",
            Unit::Kg => "kg",
            Unit::Ppm => "ppm",
            Unit::KgfmPerDeg => "kgf.m/deg",
        }
    }
}

/// What a parameter describes; lets callers select groups (e.g. the thesis's 12 geometric ones
/// are the `JointOffset` and `Twist` parameters of the Katana).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamKind {
    /// Joint offset `dth_i` (or a prismatic joint's offset).
    JointOffset,
    /// A constant rotation of the chain (`al_i`, `be_i`, DH `alpha`).
    Twist,
    /// A constant translation of the chain (`a_i`, `d_i`, the mount position).
    Length,
    /// Base placement in frame R (`base_x/y/z`, `base_rx/ry`).
    Base,
    /// Tool-point offset in the last frame (`tool_dx/dy/dz`).
    Tool,
    /// Encoder harmonic coefficient `enc_j<i>_h<n>_sin` / `_cos`.
    EncoderHarmonic,
    /// Joint-tilting value (`clearance_j<i>`, `backlash_j<i>`, `stiffness_j<i>`).
    Tilt,
    /// Payload point mass at the tool point (`payload_kg`).
    Payload,
    /// Measurement scale error about the origin of R (`scale_ppm`).
    Scale,
}

/// One named parameter and its current value.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Unique name, e.g. `"dth2"`, `"a3"`, `"clearance_j1"`.
    pub name: String,
    /// Current value, in `unit`.
    pub value: f64,
    /// Unit of `value`.
    pub unit: Unit,
    /// Group the parameter belongs to.
    pub kind: ParamKind,
}
