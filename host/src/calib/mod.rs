//! Identification of a model's parameters from measured poses (`rigctl calibrate`).
//!
//! | module | holds |
//! |---|---|
//! | [`lm`] | Levenberg-Marquardt / Gauss-Newton on a generic least-squares problem |
//! | `lm_parts` | what every linearisation of the iteration shares: settings, termination and errors, the scaled SVD step, the damping, the column scaling |
//! | `iterate` | the Levenberg-Marquardt iteration itself (scaling, damping, stopping rules, budget by progress), generic over the linearisation |
//! | [`normal`] | the same iteration on normal equations accumulated per measurement (bounded memory, many poses) |
//! | [`identifiability`] | rank, condition number, unidentifiable parameters and their names |
//! | [`stats`] | the error statistics object of FORMATS.md |
//! | [`report`] | the `calibrate --json` document |
//! | [`accumulate`] | the geometric identification on normal equations: per-pose accumulation in reusable model workspaces, chunked on two threads |
//! | `accumulator` | the per-pose accumulation itself (FK and Jacobian per pose into `J^T J`, `J^T r`, `r^T r`, in fixed chunks, deterministic) and the position errors of a set |
//! | `helper` | the second core of an identification: a thread for the problem's lifetime that accumulates half of the chunks |
//! | [`problem`] | position errors, [`problem::ModelProblem`]: every identification on the tall Jacobian as one least-squares problem (the unknowns of a state and the residual rows of its measurements), the rows of a full position (`put_position_rows`) |
//! | [`projected`] | identification from partial measurements (projections on known directions, `calibrate --samples`), reached through `calibrate_poses`; the outlier rule around any fit |
//! | [`fit`] | identifiability + LM + covariance: the one result [`fit::Fit`] of every identification (`diagnose`'s extended fit included), the split of a selection ([`fit::Split`]) and its solve ([`fit::solve_split`], [`fit::fit_at_normal`]) |
//! | [`position_fit`] | the fit of model parameters on full positions ([`position_fit::fit_parameters`]): tall Jacobian or normal equations, the rank re-analysed at the solution, what it does not determine kept at its input |
//! | [`influence`] | influence-based identification (thesis eq. 3.7-3.8) |
//! | [`calibrate`] | the whole `calibrate` command: selection, methods, report |
//! | [`measured`] | the one measurement set: joint readings, one or several points per pose, partial projections, times, ids, file lines, approach directions, inertial moments; its readers and constructors; its core (`measured/points.rs`: [`measured::PosePoints`], the joint readings and first point of every pose, and the points one by one); a tree model's poses in the same set (`measured/tips.rs`: the tip of every point slot, unmeasured points, refused by chain identifications) |
//! | `components` | the measured components of a pose of the set: rows, measured part, residual, error, Jacobian rows |
//! | [`general`] | identification with point offsets and joint compliance (the prediction of several points per pose on [`state::ExtModel`]) |
//! | [`state`] | `ExtModel`, the one state of every identification (`calibrate`'s and `diagnose`'s): the model, its joint map and time terms, point offsets; its one `Values` impl in `state/values.rs` |
//! | [`unknown`] | the `Values` of a state named by `Unknown`s (declared in [`crate::model::unknown`]) and `Freed` (the unknowns a solver writes) |
//! | [`plausible`] | plausibility before any fit: the registration of a set onto its model (units, motion) |
//! | [`large_changes`] | plausibility after the fit: the robot's geometry changes beyond a real arm's errors |
//! | [`error`] | the identification's errors |
//! | [`outliers`] | gross errors in measured poses: the robust fit-and-flag rule shared by `calibrate` and `diagnose` |
//! | [`press`] | block-PRESS (leave-one-pose-out) forward selection |
//! | [`prior`] | the prior of ill-posed sets: scales per kind, the rows added to a problem, ridge PRESS, the weight's grid |
//! | [`regularise`] | the prior of an identification on full positions chosen: off on well-posed sets, else by cross-validation |
//! | [`predict`] | the prediction uncertainty of a fit at poses it was not fitted on (held-out gross errors vs extrapolation) |
//! | [`calibrate_general`] | `calibrate_poses`, the one library entry of `calibrate` on a [`MeasuredSet`]: the model's terms applied, then partial measurements, one point per pose, or several points, `--compliance`, `--select press` |
//! | [`registered`] | the input model with only the instrument's frame fitted (registration only): the report's "before" with `--base` |
//! | [`tree_fit`] | one identification over a tree model: its unknowns as a state (`TreeUnknowns`), the rows of every measured tip point of the tree's [`MeasuredSet`], [`position_fit::refine`] on them (`fit_tree`) |
//! | [`tree_read`] | a tree's pose file as its measured set: one point per tip, units and motion checked per tip |
//! | [`tree_calibrate`] | `calibrate` on a tree: the selection on every tip's chain, the fit, the same `calibrate --json` document |
//! | [`samples`] | the pencil rig's partial measurement: a fused sample (`FUSED.csv` row) |

pub mod accumulate;
mod accumulator;
pub mod calibrate;
pub mod calibrate_general;
mod components;
pub mod error;
pub mod fit;
pub mod general;
mod helper;
pub mod identifiability;
pub mod influence;
mod iterate;
pub mod large_changes;
pub mod lm;
mod lm_parts;
pub mod measured;
pub mod normal;
pub mod outliers;
pub mod plausible;
pub mod position_fit;
pub mod predict;
pub mod press;
pub mod prior;
pub mod problem;
pub mod projected;
pub mod registered;
pub mod regularise;
pub mod report;
pub mod samples;
pub mod state;
pub mod stats;
pub mod tree_calibrate;
pub mod tree_fit;
pub mod tree_held_out;
pub mod tree_read;
pub mod unknown;

pub use accumulator::position_errors;
pub use calibrate::{calibrate, default_selection, CalibrateOptions, Method, Outcome};
pub use error::CalibError;
pub use measured::MeasuredSet;
pub use stats::Stats;
