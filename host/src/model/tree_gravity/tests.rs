use nalgebra::Vector3;

use super::*;
use crate::model::tree::test_support::{dh_joint, elem as c};
use crate::model::{Axis, Motion, Tip, TreeJoint};

/// Joint `name`: `Rx(al) Tx(a) Tz(d) Rz(q + off)` from its parent's frame, with `kg` at
/// `com_mm` in its frame.
fn joint(name: &str, parent: Option<usize>, row: [f64; 3], kg: f64, com_mm: [f64; 3]) -> TreeJoint {
    dh_joint(name, parent, row, 1.5, kg, com_mm)
}

/// A torso of two joints and two 3-joint arms (`two_arms`), or the torso and the left arm only.
fn tree(two_arms: bool) -> Tree {
    let mut joints = vec![
        joint("t1", None, [0.0, 0.0, 400.0], 8.0, [10.0, 20.0, 150.0]),
        joint("t2", Some(0), [-90.0, 50.0, 0.0], 6.0, [30.0, -40.0, 20.0]),
    ];
    let sides: &[(&str, f64)] = if two_arms {
        &[("l", 1.0), ("r", -1.0)]
    } else {
        &[("l", 1.0)]
    };
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
            after: vec![c(Motion::Trans, Axis::X, "hand_x", 120.0)],
            tool_mm: [0.0, 0.0, 40.0],
        });
    }
    Tree {
        name: "upper_body".into(),
        root: Vec::new(),
        joints,
        tips,
        params: [("base_rx".to_string(), 2.0), ("base_z".to_string(), 300.0)]
            .into_iter()
            .collect(),
        masses_assumed: false,
    }
}

fn q_of(n: usize, k: usize) -> Vec<f64> {
    (0..n)
        .map(|j| 70.0 * ((j * 7 + k * 13) as f64 * 0.37).sin())
        .collect()
}

/// A tree that is one chain has the chain's moments (axis and perpendicular components).
#[test]
fn a_single_chain_tree_has_the_chains_moments() {
    let t = tree(false);
    t.validate().unwrap();
    let chain = t.chain(0).unwrap();
    for k in 0..5 {
        let q = q_of(t.n_joints(), k);
        let tree_m = t.moments_kgfm(&q).unwrap();
        let chain_m = chain.moments_kgfm(&q).unwrap();
        assert_eq!(tree_m.len(), chain_m.len());
        for (a, b) in tree_m.iter().zip(&chain_m) {
            assert!((a - b).norm() < 1e-9, "tree {a:?} chain {b:?}");
        }
        assert!(tree_m[1].norm() > 1.0, "a loaded torso: {:?}", tree_m[1]);
    }
}

/// The whole tree's moment at every joint is the sum, over the joints that carry masses, of the
/// moment their masses alone put on it: a chain's statics (through any tip whose path holds
/// both) on a copy of the tree with only those masses.
#[test]
fn every_branch_loads_the_shared_joints() {
    let t = tree(true);
    t.validate().unwrap();
    for k in 0..5 {
        let q = q_of(t.n_joints(), k);
        let mut expected = vec![Vector3::zeros(); t.n_joints()];
        for j in 0..t.n_joints() {
            let mut only = t.clone();
            for (i, joint) in only.joints.iter_mut().enumerate() {
                if i != j {
                    joint.masses.clear();
                }
            }
            let tip = (0..t.tips.len())
                .find(|&tip| t.path(tip).contains(&j))
                .unwrap();
            let path = t.path(tip);
            let chain = only.chain(tip).unwrap();
            let qc: Vec<f64> = path.iter().map(|&i| q[i]).collect();
            for (m, &i) in chain.moments_kgfm(&qc).unwrap().iter().zip(&path) {
                expected[i] += m;
            }
        }
        let got = t.moments_kgfm(&q).unwrap();
        for (a, b) in got.iter().zip(&expected) {
            assert!((a - b).norm() < 1e-9, "tree {a:?} expected {b:?}");
        }
        // the torso carries both arms: more than either arm's chain alone says
        let left = t
            .chain(0)
            .unwrap()
            .moments_kgfm(&q_chain(&t, 0, &q))
            .unwrap();
        let right = t
            .chain(1)
            .unwrap()
            .moments_kgfm(&q_chain(&t, 1, &q))
            .unwrap();
        assert!((got[0] - left[0]).norm() > 0.1 && (got[0] - right[0]).norm() > 0.1);
        let torques = t.axis_torques_kgfm(&q).unwrap();
        assert!(torques.iter().zip(&got).all(|(a, m)| *a == m.z));
    }
}

fn q_chain(t: &Tree, tip: usize, q: &[f64]) -> Vec<f64> {
    t.path(tip).iter().map(|&i| q[i]).collect()
}

#[test]
fn wrong_joint_count_is_an_error() {
    let t = tree(true);
    assert!(t.moments_kgfm(&[0.0; 3]).is_err());
}
