//! Where a calibration pose may be, and whether a configuration is safe: joints inside their
//! limits less a margin, the tool point and every link frame origin above the table plane and
//! outside the keep-out boxes, and (with a URDF's collision geometry, [`super::collision`]) no
//! link within the clearance of another, of the table or of a keep-out box.

use std::sync::Arc;

use nalgebra::Vector3;

use super::collision::{in_box, model_joint_origins_mm, Collider, Environment};
use super::PlanError;
use crate::model::Model;

/// Tool-tip height above the table (z in frame R) that the Katana must keep, mm (FORMATS.md).
pub const KATANA_TABLE_CLEARANCE_MM: f64 = 40.0;

/// Joint angles stay this far inside each limit by default, deg (mm for a prismatic joint): a
/// pose right on a limit is not commanded safely (`--limit-margin-deg`).
pub const LIMIT_MARGIN_DEG: f64 = 2.0;

/// Default smallest distance between collision shapes (links, table, keep-out boxes), mm.
pub const DEFAULT_CLEARANCE_MM: f64 = 10.0;

/// A shared collision model (compared by identity).
#[derive(Clone, Debug)]
pub struct SharedCollider(pub Arc<Collider>);

impl PartialEq for SharedCollider {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// Where a calibration pose may be.
#[derive(Debug, Clone, PartialEq)]
pub struct Workspace {
    /// Lowest allowed tool-point height (z in R), mm; `None`: the table plane's.
    pub min_z_mm: Option<f64>,
    /// The table plane (z in R, mm; default 0: the base plane): the tool point, every link
    /// frame origin and every moving link's collision shape stay above it; `None`: no table.
    pub table_z_mm: Option<f64>,
    /// Axis-aligned box `[x0, y0, z0, x1, y1, z1]` (mm, R) the tool point must lie in.
    pub box_mm: Option<[f64; 6]>,
    /// Keep-out boxes `[x0, y0, z0, x1, y1, z1]` (mm, R): no tool point, link origin or (with
    /// collision geometry) link shape in them.
    pub keep_out_mm: Vec<[f64; 6]>,
    /// A tracker at this point (mm, R) must see the tool point: the direction from the tool
    /// point to it lies within `cone_half_angle_deg` of the tool's z axis.
    pub visible_from_mm: Option<Vector3<f64>>,
    /// Acceptance half-angle of the target (e.g. a reflector on the tool), deg.
    pub cone_half_angle_deg: f64,
    /// Every joint stays this far inside its limits, deg (mm for prismatic joints).
    pub limit_margin_deg: f64,
    /// The robot's collision geometry (from its URDF), or none: no collision check.
    pub collision: Option<SharedCollider>,
    /// On the way between poses, the tool point and (without collision geometry) the joint
    /// frames' origins may come this much closer to the table than a pose may (mm): a pose on
    /// the boundary could otherwise not be left.
    pub path_tolerance_mm: f64,
}

impl Default for Workspace {
    fn default() -> Self {
        Self {
            min_z_mm: None,
            table_z_mm: Some(0.0),
            box_mm: None,
            keep_out_mm: Vec::new(),
            visible_from_mm: None,
            cone_half_angle_deg: 60.0,
            limit_margin_deg: LIMIT_MARGIN_DEG,
            collision: None,
            path_tolerance_mm: DEFAULT_CLEARANCE_MM,
        }
    }
}

/// The joint range a pose may use: `limit` less `margin` at both ends (the midpoint when the
/// range is narrower than twice the margin).
pub fn usable_range_with(limit: &[f64; 2], margin: f64) -> (f64, f64) {
    let (lo, hi) = (limit[0] + margin, limit[1] - margin);
    if hi > lo {
        (lo, hi)
    } else {
        let mid = 0.5 * (limit[0] + limit[1]);
        (mid, mid)
    }
}

impl Workspace {
    /// The default constraints for `model`: the table plane at the base plane (z = 0 in R) for
    /// every robot; the Katana keeps its tool tip [`KATANA_TABLE_CLEARANCE_MM`] above it.
    pub fn for_model(model: &Model) -> Self {
        let katana = model.name().to_ascii_lowercase().starts_with("katana");
        Self {
            min_z_mm: katana.then_some(KATANA_TABLE_CLEARANCE_MM),
            ..Self::default()
        }
    }

    /// The joint range a pose may use ([`usable_range_with`] of the margin).
    pub fn usable_range(&self, limit: &[f64; 2]) -> (f64, f64) {
        usable_range_with(limit, self.limit_margin_deg)
    }

    /// The lowest tool-point height: `min_z_mm`, else the table's.
    pub fn tool_min_z_mm(&self) -> Option<f64> {
        match (self.min_z_mm, self.table_z_mm) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        }
    }

    /// Whether a tool point `p` with tool z axis `axis` satisfies the constraints on the tool
    /// point (height, box, keep-out boxes, line of sight).
    pub fn admits(&self, p: &Vector3<f64>, axis: &Vector3<f64>) -> bool {
        if self.tool_min_z_mm().is_some_and(|z| p.z < z) {
            return false;
        }
        if self.box_mm.is_some_and(|b| !in_box(p, &b)) {
            return false;
        }
        if self.keep_out_mm.iter().any(|b| in_box(p, b)) {
            return false;
        }
        if let Some(t) = self.visible_from_mm {
            let d = t - p;
            let (dn, an) = (d.norm(), axis.norm());
            if dn <= 0.0 || an <= 0.0 {
                return false;
            }
            let cos = d.dot(axis) / (dn * an);
            if cos < self.cone_half_angle_deg.to_radians().cos() {
                return false;
            }
        }
        true
    }

    /// Why configuration `q` (tool point `p`, tool axis `axis`) is not safe, or `None`: joints
    /// within the limits less the margin, the tool-point constraints ([`Workspace::admits`]),
    /// every link frame origin above the table and outside the keep-out boxes, and no
    /// collision of the geometry.
    pub fn violation(
        &self,
        model: &Model,
        q: &[f64],
        p: &Vector3<f64>,
        axis: &Vector3<f64>,
    ) -> Result<Option<String>, PlanError> {
        self.check(model, q, p, axis, true)
    }

    /// As [`Workspace::violation`] for a configuration on the way between two poses: the safety
    /// checks only (the tool point above the table and out of the keep-out boxes; `--box` and
    /// `--visible-from` are about measuring, not about the way).
    pub fn path_violation(
        &self,
        model: &Model,
        q: &[f64],
        p: &Vector3<f64>,
    ) -> Result<Option<String>, PlanError> {
        self.check(model, q, p, &Vector3::z(), false)
    }

    /// With collision geometry: how far the links may move between two checked configurations
    /// on the way (the distance they keep there, mm) and how far they move from `qa` to `qb`
    /// at most (mm). `None` without geometry.
    pub fn path_motion_mm(&self, qa: &[f64], qb: &[f64]) -> Option<(f64, f64)> {
        self.collision.as_ref().map(|c| {
            let env = Environment {
                table_z_mm: self.table_z_mm,
                keep_out_mm: &self.keep_out_mm,
                slack_mm: self.path_tolerance_mm,
            };
            (c.0.kept_distance_mm(&env), c.0.motion_bound_mm(qa, qb))
        })
    }

    fn check(
        &self,
        model: &Model,
        q: &[f64],
        p: &Vector3<f64>,
        axis: &Vector3<f64>,
        measuring: bool,
    ) -> Result<Option<String>, PlanError> {
        for (k, (v, l)) in q.iter().zip(model.joint_limits()).enumerate() {
            let (lo, hi) = self.usable_range(&l);
            if !(*v >= lo - 1e-9 && *v <= hi + 1e-9) {
                return Ok(Some(format!(
                    "joint {} at {v} outside its limits less {} ({lo}..{hi})",
                    k + 1,
                    self.limit_margin_deg
                )));
            }
        }
        if measuring && !self.admits(p, axis) {
            return Ok(Some("tool point outside the workspace constraints".into()));
        }
        let slack = if measuring {
            0.0
        } else {
            self.path_tolerance_mm
        };
        if self.tool_min_z_mm().is_some_and(|z| p.z < z - slack) {
            return Ok(Some("tool point below its lowest height".into()));
        }
        if self.keep_out_mm.iter().any(|b| in_box(p, b)) {
            return Ok(Some("tool point in a keep-out box".into()));
        }
        match &self.collision {
            Some(c) => {
                let env = Environment {
                    table_z_mm: self.table_z_mm,
                    keep_out_mm: &self.keep_out_mm,
                    slack_mm: slack,
                };
                Ok(c.0.collision(q, &env))
            }
            None => {
                if self.table_z_mm.is_none() && self.keep_out_mm.is_empty() {
                    return Ok(None);
                }
                for (k, o) in model_joint_origins_mm(model, q)?.iter().enumerate() {
                    if self.table_z_mm.is_some_and(|z| o.z < z - slack) {
                        return Ok(Some(format!("joint {} frame below the table", k + 1)));
                    }
                    if self.keep_out_mm.iter().any(|b| in_box(o, b)) {
                        return Ok(Some(format!("joint {} frame in a keep-out box", k + 1)));
                    }
                }
                Ok(None)
            }
        }
    }
}
