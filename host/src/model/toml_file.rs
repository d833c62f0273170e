//! Model files (TOML): a robot described as elementary transforms and/or DH / MDH / MDH+beta
//! rows, with joint limits, tilting values, link masses and parameter overrides.
//!
//! ```toml
//! name = "my_arm"
//! gamma_law = "linear"            # optional: "linear" (declared, default) or "atan2"
//!
//! # The chain, in order from frame R (after the automatic base elements) to the last frame
//! # (before the automatic tool elements). Each entry is one of:
//! [[chain]]                       # a constant elementary transform
//! op = "tx"                       # rx ry rz (deg) | tx ty tz (mm)
//! name = "mount_x"                # parameter name (letters, digits, _), unique
//! value = 55.0
//!
//! [[chain]]                       # a joint: op "rz" (revolute) or "tz" (prismatic)
//! op = "rz"
//! joint = 1                       # joints numbered 1..N in chain order
//! name = "dth1"                   # the joint offset parameter
//! value = 0.0                     # offset (default 0)
//!
//! [[chain]]                       # standard DH row: Rz(q+theta) Tz(d) Tx(a) Rx(alpha)
//! op = "dh"                       # parameters dth<j> d<j> a<j> al<j>
//! joint = 2
//! theta = 0.0
//! d = 0.0
//! a = 190.0
//! alpha = 0.0
//!
//! [[chain]]                       # modified DH row: Rx(alpha) Tx(a) [Ry(beta)] Rz(q+theta) Tz(d)
//! op = "mdh"                      # parameters al<j> a<j> [be<j>] dth<j> d<j>; beta optional
//! joint = 3
//! alpha = 0.0
//! a = 139.0
//! beta = 0.0
//! theta = 0.0
//! d = 0.0
//!
//! [[joint]]                       # one per joint, in order (limits in deg, mm if prismatic)
//! name = "shoulder"               # optional, for all joints or none: pose-file joint columns
//! min = -169.5
//! max = 169.5
//! clearance_deg = 0.022           # tilting values: optional, but for all joints or none
//! backlash_deg = 0.063
//! stiffness_kgfm_per_deg = 122.0
//! joint_scale = 1.0e-4            # transmission terms (optional, see below): q *= 1 + s
//! joint_coupling = { j2 = 0.002 } # this joint's angle += c x joint 2's reading (deg/deg)
//! hysteresis_deg = 0.03           # += b x direction of approach (pose order)
//! compliance_deg_per_kgfm = 0.01  # += g x gravity torque about the axis (needs [[mass]])
//! lateral_compliance_deg_per_kgfm = 0.02  # bend Rx(c eta_x) Ry(c eta_y) at joint frame i (needs [[mass]])
//!
//! [[mass]]                        # a link mass carried by `joint`, in the frame `after`
//! joint = 2                       # elements past the joint's element (0 = joint frame;
//! after = 0                       # a "dh" row expands to Rz Tz Tx Rx, "mdh" to Rx Tx [Ry] Rz Tz)
//! kg = 1.03
//! com_mm = [100.0, 0.0, 0.0]
//!
//! [time]                          # terms of the pose time t (optional; FORMATS.md effects)
//! thermal_ppm = 120.0             # thermal: every length x (1 + s 1e-6 (1 - exp(-t / tau)))
//! thermal_tau_min = 25.0          #   (tau in min, > 0)
//! drift_mm_per_h = [0.0, 0.0, 0.05]               # time_drift: measured position += v t
//! joint_drift_deg_per_h = [0.0, 0.01, 0.0, 0.0, 0.0]  # time_drift:j<i>: offsets += r t
//!
//! [[change]]                      # a change within the session (tool_change, payload_change)
//! t_s = 585.0                     # from this pose time on (s) ...
//! tool_mm = [0.06, -0.05, 0.06]   # ... the tool point moves (last frame), or payload_kg = 0.5
//!
//! [params]                        # overrides of any parameter, by name (deg / mm / kg / ppm)
//! tool_dz = 12.5
//! dth2 = 0.03
//! ```
//!
//! Every model also gets the base, tool, encoder-harmonic, tilting, payload and scale
//! parameters listed in the [`super`] module doc; set them in `[params]`.
//! [`Model::to_toml_string`] (`toml_write.rs`) writes the chain as elementary transforms with all current values,
//! so writing and reading back gives the identical model.
//!
//! The transmission keys of a `[[joint]]` entry (all optional, default 0; FORMATS.md effects
//! `joint_scale:j<i>`, `joint_coupling:j<i>:j<k>`, `hysteresis:j<i>`, `compliance:j<i>`) map the
//! joint readings to the angles the joints take, once per pose before the chain
//! ([`super::transmission::JointTerms`]): `q_eff_i = q_i + s_i q_i + sum_k c_ik q_k + b_i d_i +
//! g_i tau_i(q)`, `d_i` the direction in which joint i last moved (file order, or `t`), `tau_i`
//! the gravity torque of the link masses (kgf.m). `compliance_deg_per_kgfm` needs masses
//! (`[[mass]]` rows; the `ur5` preset writes its published masses as such rows).

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

use super::builder::ModelBuilder;
use super::chain::{Axis, GammaLaw, Model, Motion, TiltValues};
use super::changes::{Step, StepKind};
use super::error::ModelError;
use super::gravity::GravityModel;
pub use super::toml_write::toml_string;
use terms::{joint_terms, time_terms};

mod terms;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    name: String,
    #[serde(default)]
    gamma_law: Option<String>,
    chain: Vec<ChainEntry>,
    #[serde(default)]
    joint: Vec<JointEntry>,
    #[serde(default)]
    mass: Vec<MassEntry>,
    #[serde(default)]
    params: BTreeMap<String, f64>,
    #[serde(default)]
    time: Option<TimeEntry>,
    #[serde(default)]
    change: Vec<ChangeEntry>,
}

/// A `[[change]]` row: a change within the session at `t_s` (FORMATS.md effects extended by
/// `tool_change`, `payload_change`; docs/diagnose.md).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ChangeEntry {
    t_s: f64,
    tool_mm: Option<[f64; 3]>,
    payload_kg: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TimeEntry {
    thermal_ppm: Option<f64>,
    thermal_tau_min: Option<f64>,
    drift_mm_per_h: Option<[f64; 3]>,
    joint_drift_deg_per_h: Option<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ChainEntry {
    op: String,
    name: Option<String>,
    value: Option<f64>,
    joint: Option<usize>,
    theta: Option<f64>,
    d: Option<f64>,
    a: Option<f64>,
    alpha: Option<f64>,
    beta: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct JointEntry {
    #[serde(default)]
    name: Option<String>,
    min: f64,
    max: f64,
    clearance_deg: Option<f64>,
    backlash_deg: Option<f64>,
    stiffness_kgfm_per_deg: Option<f64>,
    joint_scale: Option<f64>,
    #[serde(default)]
    joint_coupling: BTreeMap<String, f64>,
    hysteresis_deg: Option<f64>,
    compliance_deg_per_kgfm: Option<f64>,
    lateral_compliance_deg_per_kgfm: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MassEntry {
    joint: usize,
    #[serde(default)]
    after: usize,
    kg: f64,
    com_mm: [f64; 3],
}

pub(super) fn parse_axis_op(op: &str) -> Option<(Motion, Axis)> {
    let motion = match op.as_bytes().first()? {
        b'r' => Motion::Rot,
        b't' => Motion::Trans,
        _ => return None,
    };
    let axis = match op.get(1..)? {
        "x" => Axis::X,
        "y" => Axis::Y,
        "z" => Axis::Z,
        _ => return None,
    };
    Some((motion, axis))
}

fn build(file: ModelFile) -> Result<Model, String> {
    let mut b = ModelBuilder::new(&file.name);
    match file.gamma_law.as_deref() {
        None | Some("linear") => {}
        Some("atan2") => {
            b.gamma_law(GammaLaw::Atan2);
        }
        Some(other) => {
            return Err(format!(
                "gamma_law = \"{other}\": use \"linear\" or \"atan2\""
            ))
        }
    }
    for (n, c) in file.chain.iter().enumerate() {
        chain_entry(&mut b, n, c, &file.joint)?;
    }
    if file.joint.len() != b.n_joints() {
        return Err(format!(
            "{} [[joint]] entries for {} joints in the chain",
            file.joint.len(),
            b.n_joints()
        ));
    }
    for (n, m) in file.mass.iter().enumerate() {
        b.mass(m.joint, m.after, m.kg, m.com_mm)
            .map_err(|e| format!("mass entry {}: {e}", n + 1))?;
    }
    let mut model = b.build().map_err(|e| e.to_string())?;
    let names: Vec<String> = file.joint.iter().filter_map(|j| j.name.clone()).collect();
    if !names.is_empty() && names.len() != file.joint.len() {
        return Err("[[joint]] name: give a name for every joint or for none".into());
    }
    model.set_joint_names(names).map_err(|e| e.to_string())?;
    for (name, &value) in &file.params {
        model
            .set_param(name, value)
            .map_err(|e| format!("[params] {e}"))?;
    }
    let terms = joint_terms(&file.joint)?;
    if terms.has_compliance() && GravityModel::for_model(&model).is_none() {
        return Err(
            "compliance_deg_per_kgfm needs link masses ([[mass]] rows) for the gravity torques"
                .into(),
        );
    }
    // no term: the same (empty) terms as a built-in model, so reading back is exact
    if terms.is_active() {
        model.set_transmission(terms);
    }
    for (j, e) in file.joint.iter().enumerate() {
        match e.lateral_compliance_deg_per_kgfm {
            Some(c) if !c.is_finite() => {
                return Err(format!(
                    "[[joint]] entry {}: `lateral_compliance_deg_per_kgfm` = {c} is not finite",
                    j + 1
                ))
            }
            Some(c) if c != 0.0 => {
                if GravityModel::for_model(&model).is_none() {
                    return Err(
                        "lateral_compliance_deg_per_kgfm needs link masses ([[mass]] \
                                rows) for the gravity moments"
                            .into(),
                    );
                }
                model
                    .set_lateral_compliance(j, c)
                    .map_err(|e| e.to_string())?;
            }
            _ => {}
        }
    }
    if let Some(t) = &file.time {
        model.set_time_terms(time_terms(t, model.n_joints())?);
    }
    for c in &file.change {
        let kind = match (c.tool_mm, c.payload_kg) {
            (Some(d), None) => StepKind::Tool(nalgebra::Vector3::from(d)),
            (None, Some(kg)) => StepKind::Payload(kg),
            _ => {
                return Err(format!(
                    "[[change]] at t_s = {}: give exactly one of tool_mm = [dx, dy, dz] and \
                     payload_kg",
                    c.t_s
                ))
            }
        };
        model
            .time_terms_mut()
            .changes
            .push(Step { t_s: c.t_s, kind });
    }
    model.check_steps().map_err(|e| format!("[[change]] {e}"))?;
    model.check_ranges()?;
    Ok(model)
}

/// The limits and tilting values of joint `j` (1-based) from its `[[joint]]` entry.
fn joint_info(joints: &[JointEntry], j: usize) -> Result<JointInfo, String> {
    // `joint = 0` in a file is refused here, not an underflow (found by fuzzing).
    let e = j
        .checked_sub(1)
        .and_then(|i| joints.get(i))
        .ok_or_else(|| format!("joint {j} has no [[joint]] entry (limits)"))?;
    let tilt = match (e.clearance_deg, e.backlash_deg, e.stiffness_kgfm_per_deg) {
        (None, None, None) => None,
        (Some(c), Some(b), Some(k)) => Some(TiltValues {
            clearance_deg: c,
            backlash_deg: b,
            stiffness_kgfm_per_deg: k,
        }),
        _ => {
            return Err(format!(
            "joint {j}: give all of clearance_deg, backlash_deg, stiffness_kgfm_per_deg or none"
        ))
        }
    };
    Ok(([e.min, e.max], tilt))
}

/// A joint's limits (deg or mm) and tilting values.
type JointInfo = ([f64; 2], Option<TiltValues>);

/// Chain entry `n` (0-based) added to `b`: a DH / MDH row or an elementary transform.
fn chain_entry(
    b: &mut ModelBuilder,
    n: usize,
    c: &ChainEntry,
    joints: &[JointEntry],
) -> Result<(), String> {
    let at = |msg: String| format!("chain entry {} (op = \"{}\"): {msg}", n + 1, c.op);
    match (c.op.as_str(), c.joint) {
        ("dh" | "mdh", None) => Err(at("missing `joint`".into())),
        ("dh" | "mdh", Some(j)) => row_entry(b, n, c, j, joints),
        (op, joint) => transform_entry(b, n, c, op, joint, joints),
    }
}

/// A `dh` / `mdh` row of joint `j`.
fn row_entry(
    b: &mut ModelBuilder,
    n: usize,
    c: &ChainEntry,
    j: usize,
    joints: &[JointEntry],
) -> Result<(), String> {
    let at = |msg: String| format!("chain entry {} (op = \"{}\"): {msg}", n + 1, c.op);
    let need = |v: Option<f64>, field: &str| v.ok_or_else(|| at(format!("missing `{field}`")));
    if c.name.is_some() || c.value.is_some() {
        return Err(at(
            "a row takes theta, d, a, alpha (beta), not name/value".into()
        ));
    }
    let (limits, tilt) = joint_info(joints, j).map_err(&at)?;
    let (theta, d, a, alpha) = (
        c.theta.unwrap_or(0.0),
        need(c.d, "d")?,
        need(c.a, "a")?,
        need(c.alpha, "alpha")?,
    );
    if c.op == "dh" {
        if c.beta.is_some() {
            return Err(at("`beta` belongs to an \"mdh\" row".into()));
        }
        b.dh_row(j, theta, d, a, alpha, limits, tilt)
            .map_err(|e| at(e.to_string()))?;
    } else {
        b.mdh_row(j, alpha, a, c.beta, theta, d, limits, tilt)
            .map_err(|e| at(e.to_string()))?;
    }
    Ok(())
}

/// An elementary transform (`rx` .. `tz`): a constant, or joint `joint` (`rz`, `tz`).
fn transform_entry(
    b: &mut ModelBuilder,
    n: usize,
    c: &ChainEntry,
    op: &str,
    joint: Option<usize>,
    joints: &[JointEntry],
) -> Result<(), String> {
    let at = |msg: String| format!("chain entry {} (op = \"{}\"): {msg}", n + 1, c.op);
    let need = |v: Option<f64>, field: &str| v.ok_or_else(|| at(format!("missing `{field}`")));
    let next_joint = b.n_joints() + 1;
    let (motion, axis) = parse_axis_op(op)
        .ok_or_else(|| at("op must be rx, ry, rz, tx, ty, tz, dh or mdh".into()))?;
    if c.theta.is_some() || c.d.is_some() || c.a.is_some() || c.alpha.is_some() || c.beta.is_some()
    {
        return Err(at(
            "an elementary transform takes name/value (and joint), not row fields".into(),
        ));
    }
    let name = c
        .name
        .as_deref()
        .ok_or_else(|| at("missing `name`".into()))?;
    match joint {
        None => {
            let value = need(c.value, "value")?;
            b.constant(motion, axis, name, value)
                .map_err(|e| at(e.to_string()))?;
        }
        Some(j) => {
            if axis != Axis::Z {
                return Err(at("a joint is rz (revolute) or tz (prismatic)".into()));
            }
            if j != next_joint {
                return Err(at(format!(
                    "joint {j}: joints must come in order, expected {next_joint}"
                )));
            }
            let (limits, tilt) = joint_info(joints, j).map_err(&at)?;
            b.joint(
                motion == Motion::Trans,
                name,
                c.value.unwrap_or(0.0),
                limits,
                tilt,
            )
            .map_err(|e| at(e.to_string()))?;
        }
    }
    Ok(())
}

/// The line (1-based) of the value a build message quotes (`... = VALUE: ...`): the first line
/// holding that number after an `=`.
fn locate(text: &str, message: &str) -> Option<usize> {
    let (_, rest) = message.split_once(" = ")?;
    let quoted = rest.split([':', ' ']).next()?;
    let value: f64 = quoted.parse().ok()?;
    text.lines()
        .position(|line| {
            let line = line.split('#').next().unwrap_or("");
            line.split(['=', ',', '{', '}', '[', ']'])
                .skip(1)
                .any(|v| v.trim().parse::<f64>().ok() == Some(value))
        })
        .map(|i| i + 1)
}

/// The `[[joint]]` transmission lines of joint `i` (only the non-zero terms).
impl Model {
    /// Parses a model file's text; `source` names it in error messages (with the line of the
    /// value a message is about, when it can be found).
    pub fn from_toml_str(text: &str, source: &str) -> Result<Model, ModelError> {
        let file_err = |message: String| ModelError::File {
            file: source.to_string(),
            message,
        };
        if super::tree_file::is_tree_text(text) {
            return Err(file_err(
                "a tree model ([[tip]] tables): this command takes one chain; `rigctl fk`, \
                 `calibrate`, `diagnose` and `model2urdf` take trees, `rigctl urdf2model --tree \
                 FILE --tip NAME` writes one tip's chain"
                    .into(),
            ));
        }
        let file: ModelFile = toml::from_str(text).map_err(|e| file_err(e.to_string()))?;
        build(file).map_err(|message| match locate(text, &message) {
            Some(line) => ModelError::File {
                file: format!("{source}:{line}"),
                message,
            },
            None => file_err(message),
        })
    }

    /// Reads a model file.
    pub fn from_file(path: &Path) -> Result<Model, ModelError> {
        let text = crate::io::read::read_text_capped(path, crate::io::read::CAP_SMALL_TEXT)
            .map_err(|source| ModelError::Read {
                path: path.to_path_buf(),
                source,
            })?;
        Self::from_toml_str(&text, &path.display().to_string())
    }
}
