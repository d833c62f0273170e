//! The states a solver writes unknowns into: [`Values`] (a state whose values are named by
//! [`Unknown`]s, the one name of every value an identification can free, declared in
//! [`crate::model::unknown`]) and [`Freed`] (the unknowns of a state in a solver's order).
//! Which unknowns an effect frees, and their physical bounds, is the effect table's
//! ([`crate::model::effect`]).

use nalgebra::DVector;

use super::problem::SetUnknowns;
pub use crate::model::unknown::Unknown;
use crate::model::ModelError;

/// A model state whose values are named by [`Unknown`]s: the one state of every
/// identification ([`super::state::ExtModel`]).
pub trait Values {
    /// Current value of an unknown.
    fn value(&self, u: Unknown) -> f64;
    /// Sets an unknown.
    fn set_value(&mut self, u: Unknown, v: f64) -> Result<(), ModelError>;
}

/// The unknowns `unknowns` of a state: what a solver's vector is written into, in order.
#[derive(Debug, Clone)]
pub struct Freed<S> {
    /// The state with the unknowns last set.
    pub state: S,
    /// The unknowns, in the solver's order.
    pub unknowns: Vec<Unknown>,
}

impl<S: Values> Freed<S> {
    /// The unknowns `unknowns` of `state`.
    pub fn new(state: S, unknowns: Vec<Unknown>) -> Self {
        Self { state, unknowns }
    }

    /// The unknowns' current values (a solver's start).
    pub fn values(&self) -> DVector<f64> {
        DVector::from_iterator(
            self.unknowns.len(),
            self.unknowns.iter().map(|&u| self.state.value(u)),
        )
    }
}

impl<S: Values> SetUnknowns for Freed<S> {
    fn n_unknowns(&self) -> usize {
        self.unknowns.len()
    }

    fn set(&mut self, x: &DVector<f64>) -> Result<(), ModelError> {
        for (&u, &v) in self.unknowns.iter().zip(x.iter()) {
            self.state.set_value(u, v)?;
        }
        Ok(())
    }
}
