//! Collision geometry of a URDF robot for `rigctl plan` (parry3d-f64): every link below the
//! base link with its `<collision>` shapes (boxes, cylinders, spheres; STL meshes as their
//! convex hulls, a conservative volume), placed by the URDF's own joints (the chain's joints at
//! the pose, every other joint held at 0 within its limits). A configuration collides when two
//! links of different rigid bodies not in the disabled pairs, or a moving link and the table or
//! a keep-out box, come closer than the clearance. Broad phase: world AABBs loosened by the
//! clearance; exact: GJK distances.

use std::collections::{HashMap, HashSet};
use std::path::PathBuf;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::query;
use parry3d_f64::shape::{Cuboid, SharedShape};

use super::meshes::{is_stl, resolve_mesh, stl_vertices_mm};
use super::PlanError;
use crate::model::Model;
use crate::urdf::collision::{link_collisions, srdf_disabled_pairs, CollisionGeometry};
use crate::urdf::{rpy_matrix, JointType, Urdf};

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

#[derive(Debug, Clone)]
enum JointMotion {
    Fixed,
    Rot(Vector3<f64>),
    Trans(Vector3<f64>),
}

#[derive(Debug, Clone)]
struct LinkNode {
    name: String,
    parent: Option<usize>,
    origin: Isometry3<f64>,
    motion: JointMotion,
    /// The model joint driving it, or `None` (held at `hold`: rad or mm).
    joint: Option<usize>,
    hold: f64,
    /// Rigid body: 0 for the base and whatever is fixed to it.
    group: usize,
}

#[derive(Debug, Clone)]
struct Body {
    node: usize,
    shapes: Vec<(Isometry3<f64>, SharedShape)>,
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
}

fn geo_err(m: String) -> PlanError {
    PlanError::Geometry(m)
}

fn iso(xyz_mm: Vector3<f64>, rpy_rad: [f64; 3]) -> Isometry3<f64> {
    let rot = nalgebra::Rotation3::from_matrix_unchecked(rpy_matrix(rpy_rad));
    Isometry3::from_parts(
        Translation3::from(xyz_mm),
        UnitQuaternion::from_rotation_matrix(&rot),
    )
}

/// A keep-out box `[x0, y0, z0, x1, y1, z1]` as a parry cuboid and its placement.
pub fn box_shape(b: &[f64; 6]) -> (Isometry3<f64>, Cuboid) {
    let lo = Vector3::new(b[0].min(b[3]), b[1].min(b[4]), b[2].min(b[5]));
    let hi = Vector3::new(b[0].max(b[3]), b[1].max(b[4]), b[2].max(b[5]));
    (
        Isometry3::translation(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), 0.5 * (lo.z + hi.z)),
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
        let urdf = Urdf::from_file(&src.urdf)?;
        let text = crate::io::read::read_text_capped(&src.urdf, crate::io::read::CAP_URDF)
            .map_err(|e| geo_err(format!("{}: {e}", src.urdf.display())))?;
        let chain = urdf.chain(src.base_link.as_deref(), &src.tip_link)?;
        let movable: Vec<&str> = chain
            .iter()
            .filter(|j| j.joint_type != JointType::Fixed)
            .map(|j| j.name.as_str())
            .collect();
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
        if !names.is_empty() && names.iter().zip(&movable).any(|(a, b)| a != b) {
            return Err(geo_err(format!(
                "{}: the chain's joints ({}) are not the model's ({})",
                src.urdf.display(),
                movable.join(", "),
                names.join(", ")
            )));
        }
        let prismatic: Vec<bool> = chain
            .iter()
            .filter(|j| j.joint_type != JointType::Fixed)
            .map(|j| j.joint_type == JointType::Prismatic)
            .collect();
        let base = match &src.base_link {
            Some(b) => b.clone(),
            None => urdf.root_link()?.to_string(),
        };
        let (nodes, chain_nodes) = build_nodes(&urdf, &base, &movable, &src.tip_link)?;
        let mut notes = Vec::new();
        let bodies = build_bodies(&text, src, &nodes, &mut notes)?;
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
        let home = home_configuration(model);
        let poses = c.link_poses(&home);
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
                } else if self.bodies_close(i, j, home) {
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

    fn bodies_close(&self, i: usize, j: usize, poses: &[Isometry3<f64>]) -> bool {
        let (a, b) = (&self.bodies[i], &self.bodies[j]);
        let c = self.clearance_mm;
        a.shapes.iter().any(|(la, sa)| {
            let pa = poses[a.node] * la;
            let aa = sa.compute_aabb(&pa).loosened(c.max(0.0));
            b.shapes.iter().any(|(lb, sb)| {
                let pb = poses[b.node] * lb;
                aa.intersects(&sb.compute_aabb(&pb))
                    && query::distance(&pa, sa.as_ref(), &pb, sb.as_ref())
                        .map_or(true, |d| d < c)
            })
        })
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
        let c = self.clearance_mm;
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
                    query::distance(&(poses[b.node] * l), s.as_ref(), bp, bs).map_or(true, |d| d < c)
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
                && self.bodies_close(i, j, &poses)
            {
                return Some(format!(
                    "links `{}` and `{}` within {c} mm of each other",
                    self.nodes[self.bodies[i].node].name,
                    self.nodes[self.bodies[j].node].name
                ));
            }
        }
        None
    }
}

/// The home configuration: every joint at 0, moved into its limits.
pub fn home_configuration(model: &Model) -> Vec<f64> {
    model
        .joint_limits()
        .iter()
        .map(|l| 0.0f64.clamp(l[0].min(l[1]), l[1].max(l[0])))
        .collect()
}

/// The links below `base` in parent-first order, and the chain's links base..tip among them.
fn build_nodes(
    urdf: &Urdf,
    base: &str,
    movable: &[&str],
    tip: &str,
) -> Result<(Vec<LinkNode>, Vec<usize>), PlanError> {
    let mut nodes = vec![LinkNode {
        name: base.to_string(),
        parent: None,
        origin: Isometry3::identity(),
        motion: JointMotion::Fixed,
        joint: None,
        hold: 0.0,
        group: 0,
    }];
    let mut groups = 1;
    let mut k = 0;
    while k < nodes.len() {
        let parent_name = nodes[k].name.clone();
        for j in urdf.joints.iter().filter(|j| j.parent == parent_name) {
            let o = j.origin_xyz_m;
            let origin = iso(Vector3::new(o[0], o[1], o[2]) * 1e3, j.origin_rpy_rad);
            let a = Vector3::new(j.axis[0], j.axis[1], j.axis[2]);
            let unit = || {
                a.try_normalize(1e-12)
                    .ok_or_else(|| geo_err(format!("joint `{}`: a zero axis", j.name)))
            };
            let motion = match j.joint_type {
                JointType::Fixed => JointMotion::Fixed,
                JointType::Revolute | JointType::Continuous => JointMotion::Rot(unit()?),
                JointType::Prismatic => JointMotion::Trans(unit()?),
                // a floating or planar joint outside the chain: held at its origin
                JointType::Floating | JointType::Planar => JointMotion::Fixed,
            };
            let joint = movable.iter().position(|m| *m == j.name);
            let hold_si = j
                .limits
                .map_or(0.0, |l| 0.0f64.clamp(l[0].min(l[1]), l[1].max(l[0])));
            let hold = if j.joint_type == JointType::Prismatic {
                hold_si * 1e3
            } else {
                hold_si
            };
            let group = if joint.is_some() {
                groups += 1;
                groups - 1
            } else {
                nodes[k].group
            };
            nodes.push(LinkNode {
                name: j.child.clone(),
                parent: Some(k),
                origin,
                motion,
                joint,
                hold,
                group,
            });
        }
        k += 1;
    }
    let index: HashMap<&str, usize> = nodes
        .iter()
        .enumerate()
        .map(|(i, n)| (n.name.as_str(), i))
        .collect();
    let mut chain = Vec::new();
    let mut at = index.get(tip).copied();
    while let Some(i) = at {
        chain.push(i);
        at = nodes[i].parent;
    }
    chain.reverse();
    Ok((nodes, chain))
}

/// The shapes of every link of `nodes` (mm, link frame); notes for links without shapes.
fn build_bodies(
    text: &str,
    src: &GeometrySource,
    nodes: &[LinkNode],
    notes: &mut Vec<String>,
) -> Result<Vec<Body>, PlanError> {
    let cols = link_collisions(text, &src.urdf.display().to_string())?;
    let mut bodies = Vec::new();
    let mut bare = Vec::new();
    let mut hull_cache: HashMap<(PathBuf, [u64; 3]), SharedShape> = HashMap::new();
    for (k, n) in nodes.iter().enumerate() {
        let mut shapes = Vec::new();
        for c in cols.iter().filter(|c| c.link == n.name) {
            let o = c.origin_xyz_m;
            let place = iso(Vector3::new(o[0], o[1], o[2]) * 1e3, c.origin_rpy_rad);
            let shape = match &c.geometry {
                CollisionGeometry::Box { size_m } => {
                    SharedShape::cuboid(size_m[0] * 500.0, size_m[1] * 500.0, size_m[2] * 500.0)
                }
                CollisionGeometry::Sphere { radius_m } => SharedShape::ball(radius_m * 1e3),
                CollisionGeometry::Cylinder { radius_m, length_m } => {
                    // parry's cylinder is along y, the URDF's along z
                    let turn = Isometry3::rotation(Vector3::x() * std::f64::consts::FRAC_PI_2);
                    shapes.push((
                        place * turn,
                        SharedShape::cylinder(length_m * 500.0, radius_m * 1e3),
                    ));
                    continue;
                }
                CollisionGeometry::Mesh { filename, scale } => {
                    let path = resolve_mesh(filename, &src.urdf, &src.package_paths)?;
                    if !is_stl(&path) {
                        notes.push(format!(
                            "link `{}`: collision mesh {} not read (STL only): not checked",
                            n.name,
                            path.display()
                        ));
                        continue;
                    }
                    let key = (path.clone(), scale.map(f64::to_bits));
                    if let Some(s) = hull_cache.get(&key) {
                        s.clone()
                    } else {
                        let pts: Vec<Point3<f64>> =
                            stl_vertices_mm(&path, scale.map(|s| s * 1e3))?;
                        let s = SharedShape::convex_hull(&pts).ok_or_else(|| {
                            geo_err(format!(
                                "collision mesh {}: no convex hull (flat or degenerate)",
                                path.display()
                            ))
                        })?;
                        hull_cache.insert(key, s.clone());
                        s
                    }
                }
            };
            shapes.push((place, shape));
        }
        if shapes.is_empty() {
            bare.push(n.name.clone());
        } else {
            bodies.push(Body { node: k, shapes });
        }
    }
    if !bare.is_empty() {
        notes.push(format!(
            "links without collision geometry (their origins are checked, not their volume): {}",
            bare.join(", ")
        ));
    }
    Ok(bodies)
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
