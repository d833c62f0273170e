//! The links of a URDF below the base link (parent first, with the joint that moves each) and
//! their collision shapes (mm, in the link frame).

use std::collections::HashMap;
use std::path::PathBuf;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use parry3d_f64::shape::SharedShape;

use super::GeometrySource;
use crate::plan::meshes::{is_stl, resolve_mesh, stl_vertices_mm};
use crate::plan::PlanError;
use crate::urdf::collision::{link_collisions, CollisionGeometry};
use crate::urdf::{rpy_matrix, JointType, Urdf};

fn geo_err(m: String) -> PlanError {
    PlanError::Geometry(m)
}

#[derive(Debug, Clone)]
pub(super) enum JointMotion {
    Fixed,
    Rot(Vector3<f64>),
    Trans(Vector3<f64>),
}

#[derive(Debug, Clone)]
pub(super) struct LinkNode {
    pub(super) name: String,
    pub(super) parent: Option<usize>,
    pub(super) origin: Isometry3<f64>,
    pub(super) motion: JointMotion,
    /// The model joint driving it, or `None` (held at `hold`: rad or mm).
    pub(super) joint: Option<usize>,
    pub(super) hold: f64,
    /// Rigid body: 0 for the base and whatever is fixed to it.
    pub(super) group: usize,
}

#[derive(Debug, Clone)]
pub(super) struct Body {
    pub(super) node: usize,
    pub(super) shapes: Vec<(Isometry3<f64>, SharedShape)>,
    /// Radius of the shapes about the link frame's origin, mm (their bounding spheres'): how far
    /// a point of them moves per radian the link turns.
    pub(super) radius_mm: f64,
}

fn iso(xyz_mm: Vector3<f64>, rpy_rad: [f64; 3]) -> Isometry3<f64> {
    let rot = nalgebra::Rotation3::from_matrix_unchecked(rpy_matrix(rpy_rad));
    Isometry3::from_parts(
        Translation3::from(xyz_mm),
        UnitQuaternion::from_rotation_matrix(&rot),
    )
}

/// The links below `base` in parent-first order, and the chain's links base..tip among them.
pub(super) fn build_nodes(
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
pub(super) fn build_bodies(
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
                        let pts: Vec<Point3<f64>> = stl_vertices_mm(&path, scale.map(|s| s * 1e3))?;
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
            let radius_mm = shapes
                .iter()
                .map(|(l, s)| {
                    let bs = s.compute_local_bounding_sphere();
                    (l * bs.center).coords.norm() + bs.radius
                })
                .fold(0.0, f64::max);
            bodies.push(Body {
                node: k,
                shapes,
                radius_mm,
            });
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
