//! Gravity torques about the joint axes, for the `compliance:j<i>` law: the axis components of
//! the static joint moments ([`Model::moments_kgfm`], the same statics as the tilting: the
//! model's link masses and its payload), so there is one statics in the model. A model without
//! link masses (model file without `[[mass]]` rows) has no gravity torques. The `ur5` preset
//! carries the masses Universal Robots publishes ([`super::UR5_LINK_MASS_KG`]).
//!
//! Gravity acts along -z of frame R (1 kgf per kg, MODEL.md).

use crate::model::{Model, ModelError};

/// The statics of a model that has link masses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GravityModel;

impl GravityModel {
    /// `Some` when `model` has link masses.
    pub fn for_model(model: &Model) -> Option<Self> {
        (!model.masses().is_empty()).then_some(Self)
    }

    /// Gravity torque about every joint axis (kgf.m), untilted chain at `q_deg`: the axis
    /// component of the static moment of the masses (and payload) beyond each joint.
    pub fn axis_torques_kgfm(&self, model: &Model, q_deg: &[f64]) -> Result<Vec<f64>, ModelError> {
        Ok(model.moments_kgfm(q_deg)?.iter().map(|m| m.z).collect())
    }
}
