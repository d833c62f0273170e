//! The safety options of `rigctl plan`: table plane, keep-out boxes, joint-limit margin,
//! collision geometry from a URDF (`--urdf --tip-link [--base-link] [--package-path]
//! [--srdf]`), the segment check's step, and the outputs of the ordered plan (`--trajectory`,
//! the robot in `--plot`).

use std::path::PathBuf;
use std::sync::Arc;

use rigctl::model::Model;
use rigctl::plan::collision::{model_joint_origins_mm, Collider, GeometrySource};
use rigctl::plan::workspace::{SharedCollider, DEFAULT_CLEARANCE_MM, LIMIT_MARGIN_DEG};
use rigctl::plan::{PlanConfig, Workspace};

use super::CliError;

#[derive(clap::Args, Debug)]
pub struct SafetyArgs {
    /// Height of the table plane (z in R, mm): the tool point, every link frame origin and
    /// every moving link's collision shape stay above it.
    #[arg(
        long,
        value_name = "MM",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub table_z_mm: f64,
    /// No table plane (a robot mounted on a wall or a pedestal with nothing below).
    #[arg(long)]
    pub no_table: bool,
    /// A keep-out box (mm, R; repeat for several): no tool point, link origin or link shape in it.
    #[arg(
        long = "keep-out",
        value_name = "X0,Y0,Z0,X1,Y1,Z1",
        allow_hyphen_values = true
    )]
    pub keep_out: Vec<String>,
    /// Every joint stays this far inside its limits (deg; mm for prismatic joints).
    #[arg(long, value_name = "DEG", default_value_t = LIMIT_MARGIN_DEG)]
    pub limit_margin_deg: f64,
    /// The robot's URDF: its <collision> geometry is checked (and, without --model/--robot,
    /// its chain --base-link .. --tip-link is the model). On a chain with --tip-link; on a
    /// tree model the tree's own joints and tips.
    #[arg(long, value_name = "FILE.urdf")]
    pub urdf: Option<PathBuf>,
    /// Last link of the chain in --urdf.
    #[arg(long, value_name = "LINK")]
    pub tip_link: Option<String>,
    /// First link of the chain in --urdf (default: the root link).
    #[arg(long, value_name = "LINK")]
    pub base_link: Option<String>,
    /// Folder searched for package:// meshes (repeatable; then ROS_PACKAGE_PATH, then the
    /// URDF's own folders).
    #[arg(long, value_name = "DIR")]
    pub package_path: Vec<PathBuf>,
    /// An SRDF whose disable_collisions pairs are not checked (default: adjacent links and
    /// links within the clearance at the home configuration).
    #[arg(long, value_name = "FILE.srdf", requires = "urdf")]
    pub srdf: Option<PathBuf>,
    /// Smallest distance between collision shapes (links, table, keep-out boxes), mm.
    #[arg(long, value_name = "MM", default_value_t = DEFAULT_CLEARANCE_MM)]
    pub clearance_mm: f64,
    /// Largest joint step between the configurations checked on the way between two
    /// consecutive poses, deg (mm for prismatic joints).
    #[arg(long, value_name = "DEG", default_value_t = rigctl::plan::order::DEFAULT_STEP_DEG)]
    pub segment_step_deg: f64,
    /// Write the ordered poses as a ROS JointTrajectory (YAML).
    #[arg(long, value_name = "TRAJ.yaml")]
    pub trajectory: Option<PathBuf>,
    /// Largest joint speed for the trajectory's times, deg/s.
    #[arg(long, value_name = "DEG_S", default_value_t = rigctl::plan::trajectory::DEFAULT_MAX_SPEED_DEG_S)]
    pub max_joint_speed_deg_s: f64,
    /// Standstill at every pose in the trajectory, s.
    #[arg(long, value_name = "S", default_value_t = rigctl::plan::trajectory::DEFAULT_DWELL_S)]
    pub dwell_s: f64,
}

fn positive(flag: &str, v: f64, zero_ok: bool) -> Result<(), CliError> {
    if v.is_finite() && (v > 0.0 || (zero_ok && v == 0.0)) && v < 1e6 {
        Ok(())
    } else {
        Err(CliError::bad_input(format!(
            "{flag} {v}: a {} number",
            if zero_ok { "non-negative" } else { "positive" }
        )))
    }
}

impl SafetyArgs {
    /// The chain of --urdf as the model (when neither --model nor --robot is given).
    pub fn urdf_model(&self) -> Result<Option<Model>, CliError> {
        let (Some(path), Some(tip)) = (&self.urdf, &self.tip_link) else {
            return Ok(None);
        };
        let urdf = rigctl::urdf::Urdf::from_file(path)?;
        let imported = rigctl::urdf::import_chain_with_masses(
            &urdf,
            &rigctl::urdf::ImportOptions {
                base_link: self.base_link.as_deref(),
                tip_link: tip,
                tool_mm: [0.0; 3],
            },
        )?;
        Ok(Some(imported.model))
    }

    /// Checks the options and sets the table, the keep-out boxes, the limit margin and the
    /// clearance of `ws` (no collision geometry).
    pub fn workspace(&self, ws: &mut Workspace) -> Result<(), CliError> {
        positive("--limit-margin-deg", self.limit_margin_deg, true)?;
        positive("--clearance-mm", self.clearance_mm, true)?;
        positive("--segment-step-deg", self.segment_step_deg, false)?;
        positive("--max-joint-speed-deg-s", self.max_joint_speed_deg_s, false)?;
        positive("--dwell-s", self.dwell_s, true)?;
        if !(self.table_z_mm.is_finite() && self.table_z_mm.abs() < 1e5) {
            return Err(CliError::bad_input(format!(
                "--table-z-mm {}: a finite height (mm)",
                self.table_z_mm
            )));
        }
        ws.table_z_mm = (!self.no_table).then_some(self.table_z_mm);
        ws.limit_margin_deg = self.limit_margin_deg;
        ws.path_tolerance_mm = self.clearance_mm;
        for text in &self.keep_out {
            let v: Vec<f64> = text
                .split(',')
                .map(|p| p.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| CliError::bad_input(format!("--keep-out {text}: 6 numbers")))?;
            let b: [f64; 6] = v
                .as_slice()
                .try_into()
                .ok()
                .filter(|b: &[f64; 6]| b.iter().all(|x| x.is_finite()))
                .ok_or_else(|| {
                    CliError::bad_input(format!(
                        "--keep-out {text}: 6 finite numbers X0,Y0,Z0,X1,Y1,Z1 (mm)"
                    ))
                })?;
            ws.keep_out_mm.push(b);
        }
        Ok(())
    }

    /// Sets the safety part of `cfg` for `model`; the lines that say what is checked.
    pub fn apply(&self, model: &Model, cfg: &mut PlanConfig) -> Result<Vec<String>, CliError> {
        if self.urdf.is_some() && self.tip_link.is_none() {
            return Err(CliError::bad_input(
                "--urdf on a chain needs --tip-link LINK (the chain's last link in the URDF)",
            ));
        }
        self.workspace(&mut cfg.workspace)?;
        let ws = &mut cfg.workspace;
        cfg.segment_step_deg = self.segment_step_deg;
        let mut lines = vec![format!(
            "safety: joints >= {} deg inside their limits; table plane {}; tool point z >= {}; {} keep-out box(es); segments checked every {} deg",
            self.limit_margin_deg,
            ws.table_z_mm.map_or("none".to_string(), |z| format!("z = {z} mm (R)")),
            ws.tool_min_z_mm().map_or("any".to_string(), |z| format!("{z} mm")),
            ws.keep_out_mm.len(),
            self.segment_step_deg
        )];
        match (&self.urdf, &self.tip_link) {
            (Some(urdf), Some(tip)) => {
                let mut package_paths = self.package_path.clone();
                if let Some(p) = std::env::var_os("ROS_PACKAGE_PATH") {
                    package_paths.extend(std::env::split_paths(&p));
                }
                let src = GeometrySource {
                    urdf: urdf.clone(),
                    base_link: self.base_link.clone(),
                    tip_link: tip.clone(),
                    package_paths,
                    srdf: self.srdf.clone(),
                };
                let c = Collider::from_urdf(&src, model, self.clearance_mm, ws.table_z_mm)?;
                lines.push(format!(
                    "collision check: {} links with shapes from {} (meshes as convex hulls), clearance {} mm",
                    c.n_bodies,
                    urdf.display(),
                    self.clearance_mm
                ));
                lines.extend(c.notes.iter().map(|n| format!("  {n}")));
                ws.collision = Some(SharedCollider(Arc::new(c)));
            }
            _ => lines.push(
                "NO COLLISION CHECK MADE: no collision geometry (give --urdf FILE --tip-link LINK); only the joint frames' origins and the tool point are kept above the table and out of the keep-out boxes".into(),
            ),
        }
        Ok(lines)
    }

    /// The collision geometry of --urdf for the tree model `tree` (its joints and tips; refused
    /// with --tip-link / --base-link), `None` without --urdf; the lines that say what is checked.
    pub fn tree_collider(
        &self,
        tree: &rigctl::model::Tree,
        table_z_mm: Option<f64>,
    ) -> Result<(Option<SharedCollider>, Vec<String>), CliError> {
        let Some(urdf) = &self.urdf else {
            return Ok((None, Vec::new()));
        };
        if self.tip_link.is_some() || self.base_link.is_some() {
            return Err(CliError::bad_input(
                "--tip-link / --base-link: a tree model's collision geometry follows its own \
                 joints and tips (leave them out)",
            ));
        }
        positive("--clearance-mm", self.clearance_mm, true)?;
        let mut package_paths = self.package_path.clone();
        if let Some(p) = std::env::var_os("ROS_PACKAGE_PATH") {
            package_paths.extend(std::env::split_paths(&p));
        }
        let src = GeometrySource {
            urdf: urdf.clone(),
            base_link: None,
            tip_link: tree
                .tips
                .first()
                .map(|t| t.name.clone())
                .unwrap_or_default(),
            package_paths,
            srdf: self.srdf.clone(),
        };
        let c = Collider::from_urdf_tree(&src, tree, self.clearance_mm, table_z_mm)?;
        let mut lines = vec![format!(
            "collision check: {} links with shapes from {} (meshes as convex hulls), clearance {} mm, every tree joint at the pose",
            c.n_bodies,
            urdf.display(),
            self.clearance_mm
        )];
        lines.extend(c.notes.iter().map(|n| format!("  {n}")));
        Ok((Some(SharedCollider(Arc::new(c))), lines))
    }

    /// The stick figure of the robot at `q`: the base, the link origins, the tool point (mm, R).
    pub fn stick(cfg: &PlanConfig, model: &Model, q: &[f64]) -> Result<Vec<[f64; 3]>, CliError> {
        let mut pts: Vec<[f64; 3]> = vec![[0.0; 3]];
        let origins = match &cfg.workspace.collision {
            Some(c) => c.0.chain_origins_mm(q),
            None => model_joint_origins_mm(model, q)?,
        };
        pts.extend(origins.iter().map(|p| [p.x, p.y, p.z]));
        let tool = model
            .position_mm(q, rigctl::model::Tilt::Off)
            .map_err(rigctl::plan::PlanError::from)?;
        pts.push([tool.x, tool.y, tool.z]);
        Ok(pts)
    }
}
