//! A two-link arm on a box base with every shape kind (box, cylinder, sphere, an ASCII STL
//! mesh): free upright and level, the table, a keep-out box, self-collision with the base,
//! adjacent links not checked.

use super::*;
use crate::urdf::{import_chain, ImportOptions};

const MESH: &str = "solid m
facet normal 0 0 1
 outer loop
  vertex -0.02 -0.02 0
  vertex 0.02 -0.02 0
  vertex 0 0.02 0.04
 endloop
endfacet
facet normal 0 0 1
 outer loop
  vertex -0.02 -0.02 0
  vertex 0 0.02 0.04
  vertex 0 0.02 0
 endloop
endfacet
endsolid m
";

const URDF: &str = r#"<robot name="arm">
  <link name="b"><collision><origin xyz="0 0 0.15"/><geometry><box size="0.2 0.2 0.3"/></geometry></collision></link>
  <link name="l1"><collision><origin xyz="0 0 0.25"/><geometry><cylinder radius="0.03" length="0.5"/></geometry></collision></link>
  <link name="l2"><collision><origin xyz="0 0 0.275"/><geometry><box size="0.05 0.05 0.55"/></geometry></collision>
    <collision><origin xyz="0 0 0.55"/><geometry><sphere radius="0.03"/></geometry></collision></link>
  <link name="tip"><collision><geometry><mesh filename="package://armpkg/tip.stl"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="b"/><child link="l1"/><origin xyz="0 0 0.3"/><axis xyz="0 1 0"/><limit lower="-3" upper="3"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.5"/><axis xyz="0 1 0"/><limit lower="-3" upper="3"/></joint>
  <joint name="jt" type="fixed"><parent link="l2"/><child link="tip"/><origin xyz="0 0 0.6"/></joint>
</robot>"#;

fn arm() -> (tempfile::TempDir, GeometrySource, Model) {
    let dir = tempfile::tempdir().unwrap();
    let pkg = dir.path().join("armpkg");
    std::fs::create_dir_all(&pkg).unwrap();
    std::fs::write(pkg.join("tip.stl"), MESH).unwrap();
    let urdf = pkg.join("arm.urdf");
    std::fs::write(&urdf, URDF).unwrap();
    let parsed = Urdf::parse(URDF, "arm.urdf").unwrap();
    let model = import_chain(
        &parsed,
        &ImportOptions {
            base_link: None,
            tip_link: "tip",
            tool_mm: [0.0; 3],
        },
    )
    .unwrap()
    .model;
    let src = GeometrySource {
        urdf,
        base_link: None,
        tip_link: "tip".into(),
        package_paths: Vec::new(),
        srdf: None,
    };
    (dir, src, model)
}

#[test]
fn free_table_box_and_self_collision() {
    let (_dir, src, model) = arm();
    let c = Collider::from_urdf(&src, &model, 10.0, Some(0.0)).unwrap();
    assert_eq!(c.n_bodies, 4);
    // pairs of different bodies: b-l1 and l1-l2 and l2-tip adjacent (tip is fixed to l2: same
    // body), b-l2 and b-tip and l1-tip checked
    assert_eq!(c.n_pairs, 3, "{:?}", c.notes);
    let env = Environment {
        table_z_mm: Some(0.0),
        keep_out_mm: &[],
        slack_mm: 0.0,
    };
    assert_eq!(c.collision(&[0.0, 0.0], &env), None, "upright");
    assert_eq!(c.collision(&[90.0, 0.0], &env), None, "level");
    let low = c.collision(&[150.0, 0.0], &env).expect("below the level");
    assert!(low.contains("table"), "{low}");
    let folded = c
        .collision(&[0.0, 170.0], &env)
        .expect("folded onto the base");
    assert!(
        folded.contains("`b`") && folded.contains("`l2`"),
        "{folded}"
    );
    // a keep-out box around the upright arm's second link
    let boxes = [[-100.0, -100.0, 800.0, 100.0, 100.0, 900.0]];
    let env_box = Environment {
        table_z_mm: Some(0.0),
        keep_out_mm: &boxes,
        slack_mm: 0.0,
    };
    assert!(c.collision(&[0.0, 0.0], &env_box).is_some());
    assert_eq!(c.collision(&[90.0, 0.0], &env_box), None);
    // no table: the low pose is free
    let no_table = Environment {
        table_z_mm: None,
        keep_out_mm: &[],
        slack_mm: 0.0,
    };
    assert_eq!(c.collision(&[150.0, 0.0], &no_table), None);
    // the stick figure: base, l1, l2, tip
    let o = c.chain_origins_mm(&[0.0, 0.0]);
    assert_eq!(o.len(), 4);
    assert!((o[3].z - 1400.0).abs() < 1e-9);
    // an SRDF disabling b-l1, b-l2 and b-tip: the folded pose no longer collides with the base (its
    // pairs are exactly the SRDF's: l1-l2, adjacent, is checked then)
    let srdf = src.urdf.with_file_name("arm.srdf");
    std::fs::write(
        &srdf,
        r#"<robot name="arm"><disable_collisions link1="l2" link2="b" reason="x"/>
<disable_collisions link1="b" link2="tip" reason="x"/>
<disable_collisions link1="b" link2="l1" reason="Adjacent"/></robot>"#,
    )
    .unwrap();
    let with = GeometrySource {
        srdf: Some(srdf),
        ..src.clone()
    };
    let c2 = Collider::from_urdf(&with, &model, 10.0, Some(0.0)).unwrap();
    assert!(c2
        .collision(&[0.0, 170.0], &env)
        .is_none_or(|w| !w.contains("`b`")));
    // a model with other joints is refused
    let mut other = model.clone();
    other
        .set_joint_names(vec!["x1".into(), "x2".into()])
        .unwrap();
    assert!(Collider::from_urdf(&src, &other, 10.0, Some(0.0)).is_err());
}

/// The motion bound holds for the corners of every shape's local box (they hold the shape),
/// and is not loose by more than the shapes' extent: on small and large joint moves.
#[test]
fn motion_bound_covers_every_shape_point() {
    let (_dir, src, model) = arm();
    let c = Collider::from_urdf(&src, &model, 10.0, Some(0.0)).unwrap();
    for (qa, qb) in [
        ([0.0, 0.0], [1.0, 0.0]),
        ([10.0, -20.0], [10.5, -19.0]),
        ([-30.0, 40.0], [60.0, -90.0]),
    ] {
        let bound = c.motion_bound_mm(&qa, &qb);
        let (pa, pb) = (c.link_poses(&qa), c.link_poses(&qb));
        let mut moved = 0.0f64;
        for b in &c.bodies {
            for (l, s) in &b.shapes {
                let box_local = s.compute_local_aabb();
                for v in box_local.vertices() {
                    let x = l * v;
                    moved = moved.max(((pb[b.node] * x) - (pa[b.node] * x)).norm());
                }
            }
        }
        assert!(moved <= bound + 1e-9, "{qa:?}->{qb:?}: {moved} > {bound}");
        // the tip sphere at 1.15 m from joint 1: one degree moves it about 20 mm
        assert!(
            bound < 2.0 * moved + 50.0,
            "{qa:?}->{qb:?}: bound {bound}, moved {moved}"
        );
    }
}
