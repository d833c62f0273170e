//! Joint moments of a model in motion (thesis eq. 5.14): recursive Newton-Euler on the model's
//! chain ([`super::rnea`]), with link masses from the model.
//!
//! # Inertia assumptions
//! Table 4.2 gives each link's mass and centre of gravity only. [`Inertia::PointMass`] treats
//! each link as a point mass at its COG (no rotational inertia about the COG);
//! [`Inertia::SlenderRod`] (the default for trajectories) treats it as a uniform slender rod from
//! its joint frame's origin through the COG to twice the COG distance, so the COG is the rod's
//! middle: inertia `m L^2 / 12` normal to the rod, 0 along it. The payload is always a point
//! mass at the tool point. Link 1 is massless (MODEL.md). Gravity is -z of R (it acts on the
//! chain as placed by `base_rx/base_ry`, so a tilted base changes it in robot coordinates).

use nalgebra::Vector3;

use super::rnea::{joint_moments_kgfm, Body, RneaLink};
use super::{Model, ModelError};

/// How link inertia about the COG is modelled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Inertia {
    /// Point masses: only `m a` of the COG.
    PointMass,
    /// Uniform slender rods from the joint origin through the COG (see the module docs).
    #[default]
    SlenderRod,
}

/// Gravity direction in frame R (the table is level).
pub fn gravity_dir() -> Vector3<f64> {
    -Vector3::z()
}

/// The per-link state for [`joint_moments_kgfm`] at joints `q_deg`, on the untilted chain.
pub fn rnea_links(
    model: &Model,
    q_deg: &[f64],
    inertia: Inertia,
) -> Result<Vec<RneaLink>, ModelError> {
    let fr = model.frames(q_deg, None)?;
    let mut links: Vec<RneaLink> = model
        .joints()
        .iter()
        .map(|j| RneaLink {
            origin_mm: fr.pos_mm[j.elem],
            rotation: nalgebra::Rotation3::from_matrix_unchecked(fr.rot[j.elem]),
            bodies: Vec::new(),
        })
        .collect();
    for m in model.masses() {
        let k = model.joints()[m.joint].elem + m.after;
        let cog = fr.rot[k] * m.com_mm + fr.pos_mm[k];
        let origin = links[m.joint].origin_mm;
        let body = match inertia {
            Inertia::PointMass => Body::point(m.mass_kg, cog),
            Inertia::SlenderRod => Body::slender_rod(m.mass_kg, origin, cog * 2.0 - origin),
        };
        links[m.joint].bodies.push(body);
    }
    let payload = model.params()[model.payload_param()].value;
    if payload != 0.0 {
        if let Some(last) = links.last_mut() {
            last.bodies.push(Body::point(payload, fr.tool_mm()));
        }
    }
    Ok(links)
}

/// Joint moments `eta_i` (kgf.m, joint frame i) of a chain of revolute joints at joints
/// `q_deg` (deg, one per joint) moving with rates
/// `qd_deg_s` (deg/s) and accelerations `qdd_deg_s2` (deg/s^2).
pub fn moments_kgfm(
    model: &Model,
    q_deg: &[f64],
    qd_deg_s: &[f64],
    qdd_deg_s2: &[f64],
    inertia: Inertia,
) -> Result<Vec<Vector3<f64>>, ModelError> {
    let links = rnea_links(model, q_deg, inertia)?;
    // the chain turns by the effective joint angle: d(value)/dq scales the rates (the
    // curvature term of an encoder harmonic, d2(value)/dq2 qd^2, is neglected)
    let rad = std::f64::consts::PI / 180.0;
    let mut qd = Vec::with_capacity(q_deg.len());
    let mut qdd = Vec::with_capacity(q_deg.len());
    for (j, q) in q_deg.iter().enumerate() {
        let dv = model.joint_value(j, *q).1;
        qd.push(qd_deg_s.get(j).copied().unwrap_or(0.0) * dv * rad);
        qdd.push(qdd_deg_s2.get(j).copied().unwrap_or(0.0) * dv * rad);
    }
    Ok(joint_moments_kgfm(&links, &qd, &qdd, gravity_dir()))
}
