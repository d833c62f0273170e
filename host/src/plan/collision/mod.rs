//! Collision geometry of a URDF robot for `rigctl plan` (parry3d-f64): every link below the
//! base link with its `<collision>` shapes (boxes, cylinders, spheres; STL meshes as their
//! convex hulls, a conservative volume), placed by the URDF's own joints (the chain's joints at
//! the pose, every other joint held at 0 within its limits). A configuration collides when two
//! links of different rigid bodies not in the disabled pairs, or a moving link and the table or
//! a keep-out box, come closer than the clearance. Broad phase: world AABBs loosened by the
//! clearance; exact: GJK distances.

use std::collections::{HashMap, HashSet};
use std::path::PathBuf;

use nalgebra::{Isometry3, Vector3};
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::query;
use parry3d_f64::shape::Cuboid;

use super::PlanError;
use crate::model::{Model, Tree};
use crate::urdf::collision::srdf_disabled_pairs;
use crate::urdf::{JointType, Urdf};

mod build;
#[cfg(test)]
mod tests;

use build::{build_bodies, build_nodes, Body, JointMotion, LinkNode};

/// Where the collision geometry comes from.
#[derive(Debug, Clone, PartialEq)]
pub struct GeometrySource {
    /// The URDF file.
    pub urdf: PathBuf,
    /// Base link of the model's chain (default: the root link).
    pub base_link: Option<String>,
    /// Tip link of the chain.
    pub tip_link: String,
    /// Folders searched for `package://` meshes (then the URDF's own folders).
    pub package_paths: Vec<PathBuf>,
    /// An SRDF whose `disable_collisions` pairs replace the automatic ones.
    pub srdf: Option<PathBuf>,
}

/// The robot's collision model (see the module docs).
#[derive(Clone)]
pub struct Collider {
    nodes: Vec<LinkNode>,
    bodies: Vec<Body>,
    pairs: Vec<(usize, usize)>,
    table_exempt: Vec<bool>,
    prismatic: Vec<bool>,
    /// The chain's links from the base to the tip (node indices): the stick figure.
    chain_nodes: Vec<usize>,
    /// Smallest allowed distance between shapes, mm.
    pub clearance_mm: f64,
    /// What is and is not checked (links without geometry, meshes not read, pairs disabled).
    pub notes: Vec<String>,
    /// Self-collision pairs checked.
    pub n_pairs: usize,
    /// Links with collision shapes.
    pub n_bodies: usize,
}

impl std::fmt::Debug for Collider {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Collider({} links with shapes, {} pairs, clearance {} mm)",
            self.bodies.len(),
            self.pairs.len(),
            self.clearance_mm
        )
    }
}

/// The environment of a check: the table plane (z in R, mm) and keep-out boxes.
#[derive(Debug, Clone, Copy)]
pub struct Environment<'a> {
    pub table_z_mm: Option<f64>,
    pub keep_out_mm: &'a [[f64; 6]],
    /// How much closer than the clearance the links may come (on the way between poses: a pose
    /// at the clearance must be leavable), never below half the clearance; 0 at a pose.
    pub slack_mm: f64,
}

fn geo_err(m: String) -> PlanError {
    PlanError::Geometry(m)
}

/// A keep-out box `[x0, y0, z0, x1, y1, z1]` as a parry cuboid and its placement.
pub fn box_shape(b: &[f64; 6]) -> (Isometry3<f64>, Cuboid) {
    let lo = Vector3::new(b[0].min(b[3]), b[1].min(b[4]), b[2].min(b[5]));
    let hi = Vector3::new(b[0].max(b[3]), b[1].max(b[4]), b[2].max(b[5]));
    (
        Isometry3::translation(
            0.5 * (lo.x + hi.x),
            0.5 * (lo.y + hi.y),
            0.5 * (lo.z + hi.z),
        ),
        Cuboid::new((hi - lo) * 0.5),
    )
}

/// Whether point `p` (mm) lies inside box `b`.
pub fn in_box(p: &Vector3<f64>, b: &[f64; 6]) -> bool {
    (0..3).all(|i| p[i] >= b[i].min(b[i + 3]) && p[i] <= b[i].max(b[i + 3]))
}

impl Collider {
    /// The collision model of `src` for `model` (its joints must be the chain's movable joints,
    /// in order), `clearance_mm` apart, the table at `table_z_mm` for the links that do not
    /// touch it at the home configuration.
    pub fn from_urdf(
        src: &GeometrySource,
        model: &Model,
        clearance_mm: f64,
        table_z_mm: Option<f64>,
    ) -> Result<Self, PlanError> {
        let joints = |urdf: &Urdf| -> Result<Vec<(String, bool)>, PlanError> {
            let chain = urdf.chain(src.base_link.as_deref(), &src.tip_link)?;
            let movable: Vec<(String, bool)> = chain
                .iter()
                .filter(|j| j.joint_type != JointType::Fixed)
                .map(|j| (j.name.clone(), j.joint_type == JointType::Prismatic))
                .collect();
            let listed = || {
                movable
                    .iter()
                    .map(|m| m.0.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            if movable.len() != model.n_joints() {
                return Err(geo_err(format!(
                    "{}: the chain to `{}` has {} movable joints, the model {}",
                    src.urdf.display(),
                    src.tip_link,
                    movable.len(),
                    model.n_joints()
                )));
            }
            let names = model.joint_names();
            if !names.is_empty() && names.iter().zip(&movable).any(|(a, b)| *a != b.0) {
                return Err(geo_err(format!(
                    "{}: the chain's joints ({}) are not the model's ({})",
                    src.urdf.display(),
                    listed(),
                    names.join(", ")
                )));
            }
            Ok(movable)
        };
        let home = home_of(&model.joint_limits());
        Self::build(src, joints, &home, clearance_mm, table_z_mm)
    }

    /// The collision model of `src` for the tree model `tree`: every tree joint is the URDF's
    /// movable joint of that name (tree order), every other joint held as on a chain;
    /// `src.tip_link` is the link whose chain [`Collider::chain_origins_mm`] draws.
    pub fn from_urdf_tree(
        src: &GeometrySource,
        tree: &Tree,
        clearance_mm: f64,
        table_z_mm: Option<f64>,
    ) -> Result<Self, PlanError> {
        let joints = |urdf: &Urdf| -> Result<Vec<(String, bool)>, PlanError> {
            tree.joint_names()
                .into_iter()
                .map(|name| {
                    let j = urdf
                        .joints
                        .iter()
                        .find(|j| j.name == name && j.joint_type != JointType::Fixed)
                        .ok_or_else(|| {
                            geo_err(format!(
                                "{}: the tree's joint `{name}` is not a movable joint of this URDF",
                                src.urdf.display()
                            ))
                        })?;
                    Ok((name, j.joint_type == JointType::Prismatic))
                })
                .collect()
        };
        let home = home_of(&tree.joint_limits());
        Self::build(src, joints, &home, clearance_mm, table_z_mm)
    }

    /// The collider of the links below the base of `src`'s URDF; `joints` names its model
    /// joints in order (and whether each is prismatic), `home` their home configuration.
    fn build(
        src: &GeometrySource,
        joints: impl FnOnce(&Urdf) -> Result<Vec<(String, bool)>, PlanError>,
        home: &[f64],
        clearance_mm: f64,
        table_z_mm: Option<f64>,
    ) -> Result<Self, PlanError> {
        let urdf = &Urdf::from_file(&src.urdf)?;
        let text = &crate::io::read::read_text_capped(&src.urdf, crate::io::read::CAP_URDF)
            .map_err(|e| geo_err(format!("{}: {e}", src.urdf.display())))?;
        let (names, prismatic): (Vec<String>, Vec<bool>) = joints(urdf)?.into_iter().unzip();
        let movable: Vec<&str> = names.iter().map(String::as_str).collect();
        let movable = &movable[..];
        let base = match &src.base_link {
            Some(b) => b.clone(),
            None => urdf.root_link()?.to_string(),
        };
        let (nodes, chain_nodes) = build_nodes(urdf, &base, movable, &src.tip_link)?;
        let mut notes = Vec::new();
        let bodies = build_bodies(text, src, &nodes, &mut notes)?;
        let mut c = Collider {
            nodes,
            bodies,
            pairs: Vec::new(),
            table_exempt: Vec::new(),
            prismatic,
            chain_nodes,
            clearance_mm,
            notes,
            n_pairs: 0,
            n_bodies: 0,
        };
        let poses = c.link_poses(home);
        let srdf = match &src.srdf {
            Some(p) => {
                let t = crate::io::read::read_text_capped(p, crate::io::read::CAP_URDF)
                    .map_err(|e| geo_err(format!("{}: {e}", p.display())))?;
                Some(srdf_disabled_pairs(&t, &p.display().to_string())?)
            }
            None => None,
        };
        c.choose_pairs(&poses, srdf.as_deref());
        c.table_exempt = c
            .bodies
            .iter()
            .map(|b| {
                let group0 = c.nodes[b.node].group == 0;
                let low = table_z_mm.is_some_and(|z| c.min_z(b, &poses) < z + clearance_mm);
                group0 || low
            })
            .collect();
        for (b, ex) in c.bodies.iter().zip(&c.table_exempt) {
            if *ex && c.nodes[b.node].group != 0 {
                c.notes.push(format!(
                    "link `{}` is within the clearance of the table at the home configuration: its table check is off",
                    c.nodes[b.node].name
                ));
            }
        }
        c.n_pairs = c.pairs.len();
        c.n_bodies = c.bodies.len();
        Ok(c)
    }

    fn choose_pairs(&mut self, home: &[Isometry3<f64>], srdf: Option<&[(String, String)]>) {
        let disabled: HashSet<(String, String)> = srdf
            .unwrap_or_default()
            .iter()
            .flat_map(|(a, b)| [(a.clone(), b.clone()), (b.clone(), a.clone())])
            .collect();
        let body_of: HashMap<usize, usize> = self
            .bodies
            .iter()
            .enumerate()
            .map(|(i, b)| (b.node, i))
            .collect();
        // the geometric parent: the nearest ancestor with shapes
        let geo_parent = |mut n: usize| -> Option<usize> {
            while let Some(p) = self.nodes[n].parent {
                if let Some(&b) = body_of.get(&p) {
                    return Some(b);
                }
                n = p;
            }
            None
        };
        let (mut adjacent, mut at_home) = (0, 0);
        for i in 0..self.bodies.len() {
            for j in i + 1..self.bodies.len() {
                let (ni, nj) = (self.bodies[i].node, self.bodies[j].node);
                if self.nodes[ni].group == self.nodes[nj].group {
                    continue;
                }
                let key = (self.nodes[ni].name.clone(), self.nodes[nj].name.clone());
                if srdf.is_some() {
                    if !disabled.contains(&key) {
                        self.pairs.push((i, j));
                    }
                    continue;
                }
                if geo_parent(ni) == Some(j) || geo_parent(nj) == Some(i) {
                    adjacent += 1;
                } else if self.bodies_close(i, j, home, self.clearance_mm) {
                    at_home += 1;
                } else {
                    self.pairs.push((i, j));
                }
            }
        }
        self.notes.push(match srdf {
            Some(d) => format!(
                "self-collision: {} link pairs checked, the SRDF's {} disabled pairs not",
                self.pairs.len(),
                d.len()
            ),
            None => format!(
                "self-collision: {} link pairs checked; not checked: {adjacent} adjacent pairs and {at_home} pairs within the clearance at the home configuration (no SRDF given)",
                self.pairs.len()
            ),
        });
    }

    /// World placement (mm) of every link for model joints `q` (deg, mm).
    fn link_poses(&self, q: &[f64]) -> Vec<Isometry3<f64>> {
        let mut out: Vec<Isometry3<f64>> = Vec::with_capacity(self.nodes.len());
        for n in &self.nodes {
            let parent = n.parent.map_or_else(Isometry3::identity, |p| out[p]);
            let v = match n.joint {
                Some(j) => {
                    let x = q.get(j).copied().unwrap_or(0.0);
                    if self.prismatic.get(j).copied().unwrap_or(false) {
                        x
                    } else {
                        x.to_radians()
                    }
                }
                None => n.hold,
            };
            let motion = match &n.motion {
                JointMotion::Fixed => Isometry3::identity(),
                JointMotion::Rot(a) => Isometry3::rotation(a * v),
                JointMotion::Trans(a) => Isometry3::translation(a.x * v, a.y * v, a.z * v),
            };
            out.push(parent * n.origin * motion);
        }
        out
    }

    /// The chain's link origins from the base to the tip link (mm, R) at `q`.
    pub fn chain_origins_mm(&self, q: &[f64]) -> Vec<Vector3<f64>> {
        let poses = self.link_poses(q);
        self.chain_nodes
            .iter()
            .map(|&n| poses[n].translation.vector)
            .collect()
    }

    fn min_z(&self, b: &Body, poses: &[Isometry3<f64>]) -> f64 {
        b.shapes
            .iter()
            .map(|(l, s)| s.compute_aabb(&(poses[b.node] * l)).mins.z)
            .fold(f64::INFINITY, f64::min)
    }

    fn bodies_close(&self, i: usize, j: usize, poses: &[Isometry3<f64>], c: f64) -> bool {
        let (a, b) = (&self.bodies[i], &self.bodies[j]);
        a.shapes.iter().any(|(la, sa)| {
            let pa = poses[a.node] * la;
            let aa = sa.compute_aabb(&pa).loosened(c.max(0.0));
            b.shapes.iter().any(|(lb, sb)| {
                let pb = poses[b.node] * lb;
                aa.intersects(&sb.compute_aabb(&pb))
                    && query::distance(&pa, sa.as_ref(), &pb, sb.as_ref()).map_or(true, |d| d < c)
            })
        })
    }

    /// The smallest distance kept with `env`, mm: the clearance, less the slack allowed on the
    /// way between poses, never below half the clearance.
    pub fn kept_distance_mm(&self, env: &Environment<'_>) -> f64 {
        (self.clearance_mm - env.slack_mm.max(0.0)).max(0.5 * self.clearance_mm)
    }

    /// An upper bound of how far any point of any link's collision shapes moves (mm) between
    /// joints `qa` and `qb` (deg, mm), as the chord of each link's motion: `|dt| + angle * r`,
    /// `r` the radius of the link's shapes about its frame origin.
    pub fn motion_bound_mm(&self, qa: &[f64], qb: &[f64]) -> f64 {
        let (pa, pb) = (self.link_poses(qa), self.link_poses(qb));
        self.bodies
            .iter()
            .map(|b| {
                let (a, z) = (pa[b.node], pb[b.node]);
                let angle = (a.rotation.inverse() * z.rotation).angle();
                (z.translation.vector - a.translation.vector).norm() + angle * b.radius_mm
            })
            .fold(0.0, f64::max)
    }

    /// The first collision at model joints `q` (deg, mm) with `env`, described; `None` when
    /// the configuration is free: link origins above the table and outside the boxes, moving
    /// links clear of the table and the boxes, the checked pairs clear of each other.
    pub fn collision(&self, q: &[f64], env: &Environment<'_>) -> Option<String> {
        let poses = self.link_poses(q);
        for (n, p) in self.nodes.iter().zip(&poses) {
            if n.group == 0 {
                continue;
            }
            let o = p.translation.vector;
            if env.table_z_mm.is_some_and(|z| o.z < z) {
                return Some(format!("link `{}` origin below the table", n.name));
            }
            if env.keep_out_mm.iter().any(|b| in_box(&o, b)) {
                return Some(format!("link `{}` origin in a keep-out box", n.name));
            }
        }
        let c = self.kept_distance_mm(env);
        let aabbs: Vec<Aabb> = self
            .bodies
            .iter()
            .map(|b| {
                b.shapes.iter().fold(Aabb::new_invalid(), |acc, (l, s)| {
                    acc.merged(&s.compute_aabb(&(poses[b.node] * l)))
                })
            })
            .collect();
        let boxes: Vec<(Isometry3<f64>, Cuboid, Aabb)> = env
            .keep_out_mm
            .iter()
            .map(|b| {
                let (p, s) = box_shape(b);
                let a = s.aabb(&p);
                (p, s, a)
            })
            .collect();
        for (k, b) in self.bodies.iter().enumerate() {
            let moving = self.nodes[b.node].group != 0;
            if let Some(z) = env.table_z_mm {
                if !self.table_exempt[k] && aabbs[k].mins.z < z + c {
                    // the AABB's lowest point is a convex shape's own: exact
                    return Some(format!(
                        "link `{}` within {c} mm of the table",
                        self.nodes[b.node].name
                    ));
                }
            }
            if !moving {
                continue;
            }
            for (bp, bs, ba) in &boxes {
                if !aabbs[k].loosened(c.max(0.0)).intersects(ba) {
                    continue;
                }
                let hit = b.shapes.iter().any(|(l, s)| {
                    query::distance(&(poses[b.node] * l), s.as_ref(), bp, bs)
                        .map_or(true, |d| d < c)
                });
                if hit {
                    return Some(format!(
                        "link `{}` within {c} mm of a keep-out box",
                        self.nodes[b.node].name
                    ));
                }
            }
        }
        for &(i, j) in &self.pairs {
            if aabbs[i].loosened(c.max(0.0)).intersects(&aabbs[j])
                && self.bodies_close(i, j, &poses, c)
            {
                return Some(format!(
                    "links `{}` and `{}` within {c} mm of each other",
                    self.nodes[self.bodies[i].node].name, self.nodes[self.bodies[j].node].name
                ));
            }
        }
        None
    }
}

/// The home configuration: every joint at 0, moved into its limits.
pub fn home_configuration(model: &Model) -> Vec<f64> {
    home_of(&model.joint_limits())
}

/// Every joint at 0, moved into its `limits`.
fn home_of(limits: &[[f64; 2]]) -> Vec<f64> {
    limits
        .iter()
        .map(|l| 0.0f64.clamp(l[0].min(l[1]), l[1].max(l[0])))
        .collect()
}

/// The model's joint frames' origins (mm, R) at `q`: the frame after every joint's motion, the
/// link frame origins of a model without a URDF.
pub fn model_joint_origins_mm(model: &Model, q: &[f64]) -> Result<Vec<Vector3<f64>>, PlanError> {
    let f = model.frames(q, None)?;
    Ok(model
        .joints()
        .iter()
        .filter_map(|j| f.pos_mm.get(j.elem).copied())
        .collect())
}
