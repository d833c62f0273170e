use nalgebra::Vector3;

use super::*;
use crate::model::tree::test_support::{dh_joint, elem};
use crate::model::{Axis, Motion, Tip, TreeJoint};

fn joint(name: &str, parent: Option<usize>, row: [f64; 3], kg: f64, com_mm: [f64; 3]) -> TreeJoint {
    dh_joint(name, parent, row, 2.0, kg, com_mm)
}

/// A torso of two joints (yaw, then a horizontal pitch) and one 3-joint arm per side in
/// `sides`.
fn tree(sides: &[(&str, f64)]) -> Tree {
    let mut joints = vec![
        joint("t1", None, [0.0, 0.0, 400.0], 8.0, [10.0, 20.0, 150.0]),
        joint("t2", Some(0), [-90.0, 50.0, 0.0], 6.0, [30.0, -40.0, 20.0]),
    ];
    let mut tips = Vec::new();
    for &(side, sign) in sides {
        let base = joints.len();
        let rows = [
            [90.0, 300.0, sign * 200.0],
            [-90.0, 0.0, 80.0],
            [90.0, 280.0, 0.0],
        ];
        for (k, row) in rows.iter().enumerate() {
            let parent = if k == 0 { 1 } else { base + k - 1 };
            let com = [20.0 * k as f64, sign * 15.0, 90.0 - 30.0 * k as f64];
            joints.push(joint(
                &format!("{side}{}", k + 1),
                Some(parent),
                *row,
                3.0 - 0.5 * k as f64,
                com,
            ));
        }
        tips.push(Tip {
            name: format!("{side}_hand"),
            joint: joints.len() - 1,
            after: vec![elem(Motion::Trans, Axis::X, "hand_x", 120.0)],
            tool_mm: [0.0, 0.0, 40.0],
        });
    }
    Tree {
        name: "upper_body".into(),
        root: Vec::new(),
        joints,
        tips,
        params: [("base_rx".to_string(), 2.0)].into_iter().collect(),
        masses_assumed: false,
    }
}

fn q_of(n: usize, k: usize) -> Vec<f64> {
    (0..n)
        .map(|j| 70.0 * ((j * 7 + k * 13) as f64 * 0.37).sin())
        .collect()
}

/// A tree that is one chain, with axial and lateral compliances, puts its tip where the chain
/// with the same terms does (the chain's joint map, then its lateral bend under its own
/// moments).
#[test]
fn a_single_chain_tree_bends_as_the_chain() {
    let mut t = tree(&[("l", 1.0)]);
    let axial = [0.0, 0.04, 0.06, 0.0, 0.03];
    let lateral = [0.05, 0.08, 0.0, 0.07, 0.02];
    for j in 0..t.n_joints() {
        t.joints[j].compliance_deg_per_kgfm = axial[j];
        t.joints[j].lateral_compliance_deg_per_kgfm = lateral[j];
    }
    let mut chain = t.chain(0).unwrap();
    chain.transmission_mut().compliance_deg_per_kgfm = axial.to_vec();
    for (j, c) in lateral.iter().enumerate() {
        chain.set_lateral_compliance(j, *c).unwrap();
    }
    let rigid = t.chain(0).unwrap();
    for k in 0..5 {
        let q = q_of(t.n_joints(), k);
        let q_eff = chain
            .transmission()
            .effective_joints(&chain, &q, &[])
            .unwrap();
        let want = chain.fk(&q_eff, Tilt::Off).unwrap().position_mm;
        let got = t.tip_points_mm(&q).unwrap()[0];
        assert!((got - want).norm() < 1e-9, "tree {got:?} chain {want:?}");
        // and the terms matter here
        let stiff = rigid.fk(&q, Tilt::Off).unwrap().position_mm;
        assert!((got - stiff).norm() > 0.1, "{}", (got - stiff).norm());
    }
}

/// A torso joint's lateral bend is driven by both arms: the left hand moves when the right
/// arm's masses change, only through the torso's (vertical yaw joint's) lateral compliance.
#[test]
fn the_torso_bends_under_both_arms() {
    let mut t = tree(&[("l", 1.0), ("r", -1.0)]);
    let light = |t: &Tree| {
        let mut u = t.clone();
        for j in &mut u.joints[5..] {
            j.masses.clear();
        }
        u
    };
    for k in 0..4 {
        let q = q_of(t.n_joints(), k);
        t.joints[0].lateral_compliance_deg_per_kgfm = 0.0;
        let (a, b) = (
            t.tip_points_mm(&q).unwrap(),
            light(&t).tip_points_mm(&q).unwrap(),
        );
        assert!(
            (a[0] - b[0]).norm() < 1e-12,
            "rigid: the right arm is invisible"
        );
        t.joints[0].lateral_compliance_deg_per_kgfm = 0.1;
        let (a, b) = (
            t.tip_points_mm(&q).unwrap(),
            light(&t).tip_points_mm(&q).unwrap(),
        );
        // the bend's change is the tilt of the torso frame times the change of its moment:
        // c * (delta eta_x, delta eta_y) deg about the frame's x and y axes, at the hand's arm
        let d_eta = t.moments_kgfm(&q).unwrap()[0] - light(&t).moments_kgfm(&q).unwrap()[0];
        assert!(
            d_eta.xy().norm() > 0.05,
            "the right arm loads the torso: {d_eta:?}"
        );
        let small = (0.1 * d_eta.xy().norm()).to_radians();
        let moved = (a[0] - b[0]).norm();
        assert!(
            moved > 0.2 * small * 100.0,
            "the left hand moves: {moved} mm"
        );
        assert!(moved < small * 2000.0, "by a small bend: {moved} mm");
    }
}

/// The bend needs the moments: a chain with lateral compliance evaluated with `bend` and no
/// moments is rigid, and a wrong number of moments is an error.
#[test]
fn bend_without_moments_is_off() {
    let t = tree(&[("l", 1.0)]);
    let chain = t.chain(0).unwrap();
    assert!(matches!(bend(&[]), Tilt::Off));
    let m = vec![Vector3::new(1.0, 2.0, 3.0); 2];
    let mut bent = chain.clone();
    bent.set_lateral_compliance(0, 0.1).unwrap();
    let e = bent
        .fk(&q_of(t.n_joints(), 0), bend(&m))
        .unwrap_err()
        .to_string();
    assert!(e.contains("expected 5"), "{e}");
}
