use super::test_support::elem as c;
use super::*;
use crate::model::Tilt;

fn joint(name: &str, parent: Option<usize>, before: Vec<TreeElem>) -> TreeJoint {
    TreeJoint {
        name: name.into(),
        parent,
        before,
        prismatic: false,
        offset_name: format!("{name}_offset"),
        offset: 0.5,
        limits: [-170.0, 170.0],
        masses: vec![TreeMass {
            mass_kg: 2.0,
            com_mm: [10.0, 0.0, 50.0],
        }],
        compliance_deg_per_kgfm: 0.0,
        lateral_compliance_deg_per_kgfm: 0.0,
    }
}

/// A torso joint and two 2-joint arms.
fn tree() -> Tree {
    use Axis::{X, Y, Z};
    use Motion::{Rot, Trans};
    Tree {
        name: "dual".into(),
        root: vec![c(Rot, Z, "base_rz", 3.0)],
        joints: vec![
            joint("torso", None, vec![c(Trans, Z, "torso_z", 300.0)]),
            joint(
                "l1",
                Some(0),
                vec![c(Trans, Y, "l1_y", 200.0), c(Rot, X, "l1_rx", -90.0)],
            ),
            joint(
                "r1",
                Some(0),
                vec![c(Trans, Y, "r1_y", -200.0), c(Rot, X, "r1_rx", 90.0)],
            ),
            joint("l2", Some(1), vec![c(Trans, X, "l2_x", 250.0)]),
            joint("r2", Some(2), vec![c(Trans, X, "r2_x", 250.0)]),
        ],
        tips: vec![
            Tip {
                name: "left".into(),
                joint: 3,
                after: vec![c(Trans, X, "tip_x", 100.0), c(Rot, Y, "tip_ry", 5.0)],
                tool_mm: [1.0, 2.0, 3.0],
            },
            Tip {
                name: "right".into(),
                joint: 4,
                after: vec![c(Trans, X, "tip_x", 110.0)],
                tool_mm: [0.0, 0.0, 30.0],
            },
        ],
        params: [("base_z".to_string(), 700.0)].into_iter().collect(),
        masses_assumed: false,
    }
}

#[test]
fn paths_and_chains() {
    let t = tree();
    t.validate().unwrap();
    assert_eq!(t.path(0), vec![0, 1, 3]);
    assert_eq!(t.path(1), vec![0, 2, 4]);
    let left = t.chain(0).unwrap();
    assert_eq!(left.joint_names(), ["torso", "l1", "l2"]);
    assert_eq!(left.masses().len(), 3);
    assert_eq!(left.param("base_z"), Some(700.0));
    assert_eq!(left.param("tool_dz"), Some(3.0));
    assert_eq!(left.param("tip_ry"), Some(5.0));
    let right = t.chain(1).unwrap();
    assert_eq!(right.param("tip_x"), Some(110.0));
    assert!(right.param("l1_y").is_none());
    // the torso moves both tips; l1 only the left one
    let p = |m: &Model, q: [f64; 3]| m.fk(&q, Tilt::Off).unwrap().position_mm;
    let (l0, r0) = (p(&left, [0.0; 3]), p(&right, [0.0; 3]));
    assert!((p(&left, [10.0, 0.0, 0.0]) - l0).norm() > 1.0);
    assert!((p(&right, [10.0, 0.0, 0.0]) - r0).norm() > 1.0);
    assert!((p(&left, [0.0, 10.0, 0.0]) - l0).norm() > 1.0);
}

#[test]
fn chains_join_back_into_the_tree() {
    let t = tree();
    let chains: Vec<(String, Model)> = t
        .tips
        .iter()
        .enumerate()
        .map(|(k, tip)| (tip.name.clone(), t.chain(k).unwrap()))
        .collect();
    let back = Tree::from_chains("dual", &chains).unwrap();
    // the joined tree keeps base_rz and torso_z where they act the same: compare chains
    for k in 0..2 {
        assert_eq!(back.chain(k).unwrap(), t.chain(k).unwrap());
    }
    assert_eq!(back.joints.len(), 5);
    assert_eq!(back.path(1).len(), 3);
    // a shared joint that differs between the chains is refused
    let mut bent = chains.clone();
    bent[1].1.set_param("torso_z", 301.0).unwrap();
    let e = Tree::from_chains("dual", &bent).unwrap_err().to_string();
    assert!(e.contains("torso"), "{e}");
}

#[test]
fn file_round_trip() {
    let t = tree();
    let text = t.to_toml_string();
    assert!(super::super::tree_file::is_tree_text(&text));
    let back = Tree::from_toml_str(&text, "t.toml").unwrap();
    assert_eq!(back, t);
    assert_eq!(back.to_toml_string(), text);
    // a chain reader names the tree
    let e = Model::from_toml_str(&text, "t.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("tree model"), "{e}");
}

#[test]
fn bad_tree_files_are_refused() {
    let text = tree().to_toml_string();
    for (from, to, expect) in [
        ("parent = 2\n", "parent = 5\n", "parent"),
        ("name = \"l2\"", "name = \"l1\"", "twice"),
        ("joint = 4\ntool_mm", "joint = 9\ntool_mm", "does not exist"),
        ("name = \"r2_x\"", "name = \"l2_x\"", "twice"),
        (
            "[params]\nbase_z",
            "[params]\npayload_kg = 1.0\nbase_z",
            "payload_kg",
        ),
    ] {
        assert!(text.contains(from), "{from}");
        let bad = text.replacen(from, to, 1);
        let e = Tree::from_toml_str(&bad, "t.toml").unwrap_err().to_string();
        assert!(e.contains(expect), "{from} -> {to}: {e}");
    }
}

/// Every file with one line removed or one number made huge reads to a tree or an error, never
/// a panic, and a tree read has a valid chain per tip.
#[test]
fn damaged_tree_files_never_panic() {
    let text = tree().to_toml_string();
    let lines: Vec<&str> = text.lines().collect();
    let check = |t: String| {
        if let Ok(tree) = Tree::from_toml_str(&t, "t.toml") {
            assert!(tree.chains().is_ok());
            for k in 0..tree.tips.len() {
                assert!(tree.path(k).len() <= tree.n_joints());
            }
        }
    };
    for skip in 0..lines.len() {
        let mut t: Vec<&str> = lines.clone();
        t.remove(skip);
        check(t.join("\n"));
        let mut t: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        if let Some((key, _)) = lines[skip].split_once(" = ") {
            t[skip] = format!("{key} = 1e308");
            check(t.join("\n"));
            t[skip] = format!("{key} = 0");
            check(t.join("\n"));
        }
    }
}
