//! Model files written ([`Model::to_toml_string`], [`Model::write_file`]): the chain as
//! elementary transforms with every current value (numbers round-trip exact), so that reading
//! the file back ([`super::toml_file`]) gives the identical model.

use std::fmt::Write as _;
use std::path::Path;

use super::chain::{Axis, GammaLaw, Model, Motion};
use super::changes::StepKind;
use super::error::ModelError;
use super::param::ParamKind;
use super::time_terms::TimeTerms;
use super::transmission::JointTerms;

/// The `op` of an elementary transform.
pub(super) fn op_name(motion: Motion, axis: Axis) -> &'static str {
    match (motion, axis) {
        (Motion::Rot, Axis::X) => "rx",
        (Motion::Rot, Axis::Y) => "ry",
        (Motion::Rot, Axis::Z) => "rz",
        (Motion::Trans, Axis::X) => "tx",
        (Motion::Trans, Axis::Y) => "ty",
        (Motion::Trans, Axis::Z) => "tz",
    }
}

/// `s` as a TOML basic string (quotes included): every character TOML does not take literally
/// (`"`, `\`, control characters, DEL) escaped, so that any name reads back identically.
pub fn toml_string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Round-trip-exact decimal form of a finite f64 that TOML reads as a float.
pub(super) fn fmt_f64(v: f64) -> String {
    format!("{v:?}")
}

fn write_joint_terms(s: &mut String, t: &JointTerms, i: usize) {
    let (scale, hyst, comp) = t.joint_values(i);
    for (key, v) in [
        ("joint_scale", scale),
        ("hysteresis_deg", hyst),
        ("compliance_deg_per_kgfm", comp),
    ] {
        if v != 0.0 {
            let _ = writeln!(s, "{key} = {}", fmt_f64(v));
        }
    }
    let row: Vec<String> = t
        .coupling
        .get(i)
        .into_iter()
        .flatten()
        .enumerate()
        .filter(|(_, c)| **c != 0.0)
        .map(|(k, c)| format!("j{} = {}", k + 1, fmt_f64(*c)))
        .collect();
    if !row.is_empty() {
        let _ = writeln!(s, "joint_coupling = {{ {} }}", row.join(", "));
    }
}

impl Model {
    /// The model as a model file: the chain as elementary transforms with the current values,
    /// joints, masses, and the non-zero base/tool/encoder/payload/scale parameters.
    pub fn to_toml_string(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# rigctl model file (format: see rigctl::model::toml_file)"
        );
        let _ = writeln!(s, "name = {}", toml_string(&self.name));
        let law = match self.gamma_law {
            GammaLaw::Linear => "linear",
            GammaLaw::Atan2 => "atan2",
        };
        let _ = writeln!(s, "gamma_law = \"{law}\"");
        for e in &self.elems[self.robot_elems.clone()] {
            let p = &self.params[e.param];
            let _ = writeln!(s, "\n[[chain]]\nop = \"{}\"", op_name(e.motion, e.axis));
            if let Some(j) = e.joint {
                let _ = writeln!(s, "joint = {}", j + 1);
            }
            let _ = writeln!(
                s,
                "name = {}\nvalue = {}",
                toml_string(&p.name),
                fmt_f64(p.value)
            );
        }
        let tilt = self.tilt_values();
        for (j, joint) in self.joints.iter().enumerate() {
            if let Some(n) = self.joint_names.get(j) {
                let _ = writeln!(s, "\n[[joint]]\nname = {}", toml_string(n));
            } else {
                let _ = writeln!(s, "\n[[joint]]");
            }
            let _ = writeln!(
                s,
                "min = {}\nmax = {}",
                fmt_f64(joint.limits[0]),
                fmt_f64(joint.limits[1])
            );
            if let Some(t) = tilt.as_ref().and_then(|t| t.get(j)) {
                let _ = writeln!(
                    s,
                    "clearance_deg = {}\nbacklash_deg = {}\nstiffness_kgfm_per_deg = {}",
                    fmt_f64(t.clearance_deg),
                    fmt_f64(t.backlash_deg),
                    fmt_f64(t.stiffness_kgfm_per_deg)
                );
            }
            write_joint_terms(&mut s, &self.transmission, j);
            let lateral = self.lateral_compliance_at(j);
            if lateral != 0.0 {
                let _ = writeln!(s, "lateral_compliance_deg_per_kgfm = {}", fmt_f64(lateral));
            }
        }
        if self.masses_assumed && !self.masses.is_empty() {
            s.push_str(
                "\n# The link masses below are ASSUMED by rigctl (the model declared none): one per\n\
                 # joint, mid-segment, in proportion to the segment lengths. Replace them with the\n\
                 # robot's own masses for compliance values in real units.\n",
            );
        }
        for m in &self.masses {
            let c = m.com_mm;
            let _ = writeln!(
                s,
                "\n[[mass]]\njoint = {}\nafter = {}\nkg = {}\ncom_mm = [{}, {}, {}]",
                m.joint + 1,
                m.after,
                fmt_f64(m.mass_kg),
                fmt_f64(c.x),
                fmt_f64(c.y),
                fmt_f64(c.z)
            );
        }
        let time = &self.time_terms;
        // the laws of the pose time (the changes within the session are rows of their own)
        let laws = TimeTerms {
            changes: Vec::new(),
            ..time.clone()
        };
        if laws.is_active() {
            let list = |v: &[f64]| v.iter().map(|x| fmt_f64(*x)).collect::<Vec<_>>().join(", ");
            let _ = writeln!(
                s,
                "\n[time]\nthermal_ppm = {}\nthermal_tau_min = {}\ndrift_mm_per_h = [{}]",
                fmt_f64(time.thermal_ppm),
                fmt_f64(time.thermal_tau_min),
                list(time.drift_mm_per_h.as_slice())
            );
            if time.joint_drift_deg_per_h.iter().any(|r| *r != 0.0) {
                let _ = writeln!(
                    s,
                    "joint_drift_deg_per_h = [{}]",
                    list(&time.joint_drift_deg_per_h)
                );
            }
        }
        for step in time.changes.iter().filter(|c| c.is_active()) {
            let what = match step.kind {
                StepKind::Tool(d) => format!(
                    "tool_mm = [{}, {}, {}]",
                    fmt_f64(d.x),
                    fmt_f64(d.y),
                    fmt_f64(d.z)
                ),
                StepKind::Payload(kg) => format!("payload_kg = {}", fmt_f64(kg)),
            };
            let _ = writeln!(s, "\n[[change]]\nt_s = {}\n{what}", fmt_f64(step.t_s));
        }
        let _ = writeln!(s, "\n[params]");
        let extra = |k: ParamKind| {
            matches!(
                k,
                ParamKind::Base
                    | ParamKind::Tool
                    | ParamKind::EncoderHarmonic
                    | ParamKind::Payload
                    | ParamKind::Scale
            )
        };
        for p in self
            .params
            .iter()
            .filter(|p| extra(p.kind) && p.value != 0.0)
        {
            let _ = writeln!(s, "{} = {}", p.name, fmt_f64(p.value));
        }
        s
    }

    /// Writes [`Model::to_toml_string`] to `path` atomically.
    pub fn write_file(&self, path: &Path) -> Result<(), ModelError> {
        crate::io::atomic::write_text_atomic(
            path,
            crate::io::finite::TextFormat::Toml,
            &self.to_toml_string(),
        )?;
        Ok(())
    }
}
