//! Link masses for the `compliance:j<i>` candidate: the gravity torque about each joint axis.
//!
//! A model with its own link masses (the Katana, MODEL.md table 4.2) uses them. The `ur5` preset
//! carries none; for it the masses and centres of gravity published by Universal Robots for the
//! CB3 UR5 are used ("Parameters for calculations of kinematics and dynamics", Universal Robots
//! support article 45257, universal-robots.com/articles/ur/application-installation/
//! dh-parameters-for-calculations-of-kinematics-and-dynamics): link masses 3.7, 8.393, 2.33,
//! 1.219, 1.219, 0.1879 kg; centres of mass in DH frame i (after row i) (0, -25.61, 1.93),
//! (212.5, 0, 113.36), (150, 0, 26.5), (0, -1.8, 16.34), (0, 1.8, 16.34), (0, 0, -1.159) mm.
//! Only the shape of the torque matters to the diagnosis (the compliance is fitted), so small
//! differences between UR5 generations do not change the result.
//!
//! Gravity acts along -z of frame R (1 kgf per kg, MODEL.md).

use nalgebra::Vector3;

use crate::model::{Model, ModelError, GRAVITY_KGF_PER_KG};

/// UR5 (CB3) link masses, kg (Universal Robots).
pub const UR5_LINK_MASS_KG: [f64; 6] = [3.7, 8.393, 2.33, 1.219, 1.219, 0.1879];
/// UR5 (CB3) centres of mass in DH frame i, mm (Universal Robots).
pub const UR5_LINK_COM_MM: [[f64; 3]; 6] = [
    [0.0, -25.61, 1.93],
    [212.5, 0.0, 113.36],
    [150.0, 0.0, 26.5],
    [0.0, -1.8, 16.34],
    [0.0, 1.8, 16.34],
    [0.0, 0.0, -1.159],
];

/// One link mass: the element whose following frame carries it, kg, centre of mass there (mm).
#[derive(Debug, Clone, PartialEq)]
pub struct LinkMass {
    /// Index of the element after which the mass sits ([`Model::elems`]).
    pub frame: usize,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of mass in that frame, mm.
    pub com_mm: Vector3<f64>,
}

/// The masses used for gravity torques.
#[derive(Debug, Clone, PartialEq)]
pub struct GravityModel {
    /// Link masses.
    pub masses: Vec<LinkMass>,
}

impl GravityModel {
    /// The model's own masses, or the published UR5 masses for the `ur5` preset (6 revolute DH
    /// rows), or `None`.
    pub fn for_model(model: &Model) -> Option<Self> {
        if !model.masses().is_empty() {
            let masses = model
                .masses()
                .iter()
                .map(|m| LinkMass {
                    frame: model.joints()[m.joint].elem + m.after,
                    mass_kg: m.mass_kg,
                    com_mm: m.com_mm,
                })
                .collect();
            return Some(Self { masses });
        }
        if model.name() == "ur5" && model.n_joints() == 6 {
            // DH row i is Rz Tz Tx Rx: DH frame i is 3 elements past the joint's element.
            let mut masses = Vec::new();
            for (j, joint) in model.joints().iter().enumerate() {
                let frame = joint.elem + 3;
                if frame >= model.elems().len() {
                    return None;
                }
                masses.push(LinkMass {
                    frame,
                    mass_kg: UR5_LINK_MASS_KG[j],
                    com_mm: Vector3::from(UR5_LINK_COM_MM[j]),
                });
            }
            return Some(Self { masses });
        }
        None
    }

    /// Gravity torque about every joint axis (kgf.m), untilted chain at `q_deg`: the axis
    /// component of `sum over masses after joint i of (c - o_i) x m g`.
    pub fn axis_torques_kgfm(&self, model: &Model, q_deg: &[f64]) -> Result<Vec<f64>, ModelError> {
        let fr = model.frames(q_deg, None)?;
        let points: Vec<(usize, f64, Vector3<f64>)> = self
            .masses
            .iter()
            .map(|m| {
                (
                    m.frame,
                    m.mass_kg,
                    fr.rot[m.frame] * m.com_mm + fr.pos_mm[m.frame],
                )
            })
            .collect();
        Ok(model
            .joints()
            .iter()
            .map(|j| {
                let o = fr.pos_mm[j.elem];
                let axis = fr.rot[j.elem].column(2).into_owned();
                let moment: Vector3<f64> = points
                    .iter()
                    .filter(|(k, _, _)| *k >= j.elem)
                    .map(|(_, m, c)| ((c - o) * 1e-3).cross(&(GRAVITY_KGF_PER_KG * *m)))
                    .sum();
                axis.dot(&moment)
            })
            .collect())
    }
}

/// The joint readings deflected by compliance; the law lives in
/// [`super::transmission::compliance_deflection_deg`] (re-exported here for the callers that
/// found it in this module).
pub use super::transmission::compliance_deflected;
