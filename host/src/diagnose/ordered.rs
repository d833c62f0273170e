//! A map that keeps its insertion order in JSON (the parameters of a model, in the model's
//! order), for the `diagnose --json` document and the probe's report.

use serde::ser::{SerializeMap, Serializer};
use serde::Serialize;

/// A map that keeps its insertion order in JSON.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Ordered<T>(pub Vec<(String, T)>);

impl<T: Serialize> Serialize for Ordered<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

impl<T> FromIterator<(String, T)> for Ordered<T> {
    fn from_iter<I: IntoIterator<Item = (String, T)>>(iter: I) -> Self {
        Self(iter.into_iter().collect())
    }
}

impl<T: Copy> Ordered<T> {
    /// The value called `name`.
    pub fn get(&self, name: &str) -> Option<T> {
        self.0.iter().find(|(k, _)| k == name).map(|(_, v)| *v)
    }
}
