//! URDF import: any serial chain of a URDF file (base link to tip link) as a
//! [`crate::model::Model`], so every command can use it through a model file
//! (`rigctl urdf2model`, then `--model`).
//!
//! * [`Urdf::from_file`] / [`Urdf::parse`]: links and joints (URDF units), errors with
//!   `file:line:column`.
//! * [`import_chain`]`(&urdf, &ImportOptions) -> Imported { model, joint_names }`: the chain as
//!   elementary transforms; the structure and parameter names are documented in [`import`].
//! * [`import_tree`]`(&urdf, base_link, &[TipLink])`: several chains sharing joints as a
//!   [`crate::model::Tree`] ([`import_tree`](mod@import_tree)).

pub mod collision;
pub mod error;
pub mod export;
pub mod export_tree;
mod frame;
pub mod import;
pub mod import_tree;
pub mod parse;
pub mod rewrite;

pub use error::UrdfError;
pub use export::{model_to_urdf, Exported, Origin, OriginChange};
pub use export_tree::tree_to_urdf;
pub use import::{
    import_chain, import_chain_with_masses, param_stem, rpy_matrix, rpy_of, widen_limits,
    ImportOptions, Imported,
};
pub use import_tree::{import_tree, TipLink};
pub use parse::{JointType, LinkInertial, Urdf, UrdfJoint};
pub use rewrite::model_into_urdf;
