//! A dual-arm URDF as a tree model, checked by a consumer rigctl did not write: TALOS
//! (`talos_reduced.urdf` of `example-robot-data`, read from the package installed in the test
//! venv, never committed). `urdf2model --tip gripper_left_base_link --tip
//! gripper_right_base_link` makes one tree (the two torso joints once, shared by both grippers);
//! `rigctl fk` on 50 random configurations of the whole tree equals pinocchio's forward
//! kinematics of both gripper links in the original URDF within 1e-6 mm; `model2urdf` writes
//! the tree as a new URDF, and pinocchio on that file gives the same points again. One tip's
//! chain of the tree (`urdf2model --tree --tip`) is the chain `urdf2model` imports alone (same
//! elements, parameters, joints and limits; the masses differ where the lone chain carries the
//! other arm as a rigid lump).

use crate::common::spawn::{output_ok as run, path_arg as s};
use std::path::{Path, PathBuf};
use std::process::Command;

use rand::{Rng, SeedableRng};

use crate::common::record::record;
use crate::common::spawn::output;
use crate::common::{py_script, python_env, robots_share};
use rigctl::model::{Model, Tilt, Tree};

const TIPS: [&str; 2] = ["gripper_left_base_link", "gripper_right_base_link"];

/// TALOS's URDF in the installed `example-robot-data` ([`robots_share`]).
fn talos_urdf(test: &str, py: &Path) -> Option<PathBuf> {
    const TALOS: &str = "example-robot-data/robots/talos_data/robots/talos_reduced.urdf";
    robots_share(py, TALOS, test).map(|share| share.join(TALOS))
}

/// `urdf2model` of TALOS's two grippers into `dir`: the tree model file.
fn talos_tree(urdf: &Path, dir: &Path) -> PathBuf {
    let tree_path = dir.join("talos_tree.toml");
    run(&[
        "urdf2model",
        "--urdf",
        s(urdf),
        "--tip",
        TIPS[0],
        "--tip",
        TIPS[1],
        "--out",
        s(&tree_path),
    ]);
    tree_path
}

/// CSV of numbers with a header: (header, rows).
fn read_csv(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header = lines
        .next()
        .expect("a header")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().expect("a number")).collect())
        .collect();
    (header, rows)
}

/// Column `name` of a CSV.
fn column(header: &[String], rows: &[Vec<f64>], name: &str) -> Vec<f64> {
    let c = header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"));
    rows.iter().map(|r| r[c]).collect()
}

/// pinocchio's positions (mm) of `frame` in `urdf` for the configurations of `q_rad` (a CSV of
/// URDF joint names, rad).
fn pinocchio(py: &Path, dir: &Path, urdf: &Path, q_rad: &Path, frame: &str) -> Vec<[f64; 3]> {
    let out = dir.join(format!("pin_{frame}.csv"));
    let run = Command::new(py)
        .arg(py_script("pin_fk.py"))
        .args([s(urdf), s(q_rad), s(&out), frame])
        .output()
        .expect("python runs");
    assert!(
        run.status.success(),
        "pin_fk.py {frame}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (h, rows) = read_csv(&std::fs::read_to_string(&out).unwrap());
    let (x, y, z) = (
        column(&h, &rows, "x"),
        column(&h, &rows, "y"),
        column(&h, &rows, "z"),
    );
    (0..rows.len()).map(|i| [x[i], y[i], z[i]]).collect()
}

/// Largest coordinate difference (mm) between pinocchio and `rigctl fk`'s tip `k` (1-based).
fn worst(pin: &[[f64; 3]], fk_header: &[String], fk_rows: &[Vec<f64>], k: usize) -> f64 {
    assert_eq!(pin.len(), fk_rows.len());
    let cols: Vec<Vec<f64>> = ["x", "y", "z"]
        .iter()
        .map(|c| column(fk_header, fk_rows, &format!("{c}{k}")))
        .collect();
    let mut w = 0.0f64;
    for (i, p) in pin.iter().enumerate() {
        for c in 0..3 {
            w = w.max((p[c] - cols[c][i]).abs());
        }
    }
    w
}

#[test]
fn talos_dual_arm_tree_round_trips_through_pinocchio() {
    let test = "talos_dual_arm_tree_round_trips_through_pinocchio";
    let Some(py) = python_env(test) else {
        return;
    };
    let Some(urdf) = talos_urdf(test, &py) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tree_path = talos_tree(&urdf, d);
    let tree = Tree::from_file(&tree_path).unwrap();
    // every joint once; the torso's two joints on both tips' paths, the arms' on one each
    assert_eq!(tree.n_joints(), 16, "{:?}", tree.joint_names());
    assert_eq!(tree.tips.len(), 2);
    let paths = [tree.path(0), tree.path(1)];
    let shared: Vec<&str> = paths[0]
        .iter()
        .filter(|j| paths[1].contains(j))
        .map(|&j| tree.joints[j].name.as_str())
        .collect();
    assert_eq!(shared, ["torso_1_joint", "torso_2_joint"]);
    assert_eq!(paths[0].len() + paths[1].len() - 2, 16);

    // 50 random configurations of the whole tree within its limits
    let mut rng = rand::rngs::StdRng::seed_from_u64(52);
    let q: Vec<Vec<f64>> = (0..50)
        .map(|_| {
            tree.joints
                .iter()
                .map(|j| rng.gen_range(j.limits[0]..=j.limits[1]))
                .collect()
        })
        .collect();
    let names = tree.joint_names().join(",");
    let csv = |f: &dyn Fn(f64) -> f64| {
        let mut t = names.clone() + "\n";
        for row in &q {
            let cells: Vec<String> = row.iter().map(|v| format!("{:e}", f(*v))).collect();
            t += &(cells.join(",") + "\n");
        }
        t
    };
    let (q_deg, q_rad) = (d.join("q.csv"), d.join("q_rad.csv"));
    std::fs::write(&q_deg, csv(&|v| v)).unwrap();
    std::fs::write(&q_rad, csv(&|v: f64| v.to_radians())).unwrap();
    let fk = run(&["fk", "--model", s(&tree_path), "--joints", s(&q_deg)]);
    let (fk_h, fk_rows) = read_csv(&String::from_utf8_lossy(&fk.stdout));
    assert_eq!(fk_h.len(), 12, "{fk_h:?}");
    assert_eq!(fk_rows.len(), 50);

    // the original URDF, then the tree written back as a URDF
    let written = d.join("talos_tree.urdf");
    run(&["model2urdf", "--model", s(&tree_path), "--out", s(&written)]);
    for (label, file) in [("original", &urdf), ("written", &written)] {
        for (k, tip) in TIPS.iter().enumerate() {
            let pin = pinocchio(&py, d, file, &q_rad, tip);
            let w = worst(&pin, &fk_h, &fk_rows, k + 1);
            eprintln!("{label} URDF, {tip}: pinocchio vs rigctl fk max {w:.3e} mm");
            assert!(w <= 1e-6, "{label} URDF, {tip}: {w} mm");
            record(&format!("talos_tree_{label}_{tip}_vs_fk_mm"), w);
        }
    }
    // the arms move their own tip only, the torso both
    let moved = |k: usize, joint: usize| {
        let chain = tree.chain(k).unwrap();
        let qc = |dq: f64| -> Vec<f64> {
            tree.path(k)
                .iter()
                .map(|&j| if j == joint { 10.0 + dq } else { 10.0 })
                .collect()
        };
        let p = |dq| chain.fk(&qc(dq), Tilt::Off).unwrap().position_mm;
        (p(5.0) - p(0.0)).norm()
    };
    let torso = paths[0][0];
    let left_arm = paths[0][3];
    assert!(moved(0, torso) > 1.0 && moved(1, torso) > 1.0);
    assert!(moved(0, left_arm) > 1.0 && moved(1, left_arm) == 0.0);
}

#[test]
fn one_tip_of_the_tree_is_the_chain_imported_alone() {
    let test = "one_tip_of_the_tree_is_the_chain_imported_alone";
    let Some(py) = python_env(test) else {
        return;
    };
    let Some(urdf) = talos_urdf(test, &py) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tree_path = d.join("tree.toml");
    let tool = "12.5,-3,40";
    run(&[
        "urdf2model",
        "--urdf",
        s(&urdf),
        "--tip",
        TIPS[0],
        "--tip",
        TIPS[1],
        "--tool-mm",
        tool,
        "--out",
        s(&tree_path),
    ]);
    for tip in TIPS {
        let (from_tree, alone) = (d.join("from_tree.toml"), d.join("alone.toml"));
        run(&[
            "urdf2model",
            "--tree",
            s(&tree_path),
            "--tip",
            tip,
            "--out",
            s(&from_tree),
        ]);
        run(&[
            "urdf2model",
            "--urdf",
            s(&urdf),
            "--tip",
            tip,
            "--tool-mm",
            tool,
            "--out",
            s(&alone),
        ]);
        let (a, b) = (
            Model::from_file(&from_tree).unwrap(),
            Model::from_file(&alone).unwrap(),
        );
        assert_eq!(a.elems(), b.elems(), "{tip}: elements");
        assert_eq!(a.params(), b.params(), "{tip}: parameters and values");
        assert_eq!(a.joint_names(), b.joint_names(), "{tip}");
        assert_eq!(a.joint_limits(), b.joint_limits(), "{tip}");
        assert_eq!(a.param("tool_dz"), Some(40.0));
        // the lone chain's torso carries the other arm rigidly; the tree's does not
        let kg = |m: &Model| m.masses().iter().map(|p| p.mass_kg).collect::<Vec<_>>();
        let (ka, kb) = (kg(&a), kg(&b));
        assert_eq!(ka.len(), kb.len());
        assert!(ka[1] < kb[1], "{tip}: torso_2 {} vs {}", ka[1], kb[1]);
        assert_eq!(ka[2..], kb[2..], "{tip}: the arm's own masses");
    }
    // a chain-only option given with a tree is named as such
    let plan = d.join("plan.csv");
    let plot = d.join("plan.svg");
    let out = output(&[
        "plan",
        "--model",
        s(&tree_path),
        "--n",
        "5",
        "--out",
        s(&plan),
        "--plot",
        s(&plot),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("tree model"), "{err}");
}

/// `plan` on the TALOS tree with its URDF and SRDF: every planned pose is free of
/// self-collision by pinocchio + coal on the URDF's own meshes (`check_plan_safety.py`, every
/// pair but the SRDF's disabled ones), where the plan without the URDF keeps only frame origins
/// and tips apart; the plan says what it checked (`collisions_verified`) and what it did not
/// (the moves).
#[test]
fn talos_tree_plan_with_its_urdf_is_collision_free_by_pinocchio() {
    let test = "talos_tree_plan_with_its_urdf_is_collision_free_by_pinocchio";
    let Some(py) = python_env(test) else {
        return;
    };
    let Some(urdf) = talos_urdf(test, &py) else {
        return;
    };
    let share = urdf.ancestors().nth(5).unwrap().to_path_buf();
    let srdf = urdf
        .parent()
        .unwrap()
        .parent()
        .unwrap()
        .join("srdf/talos.srdf");
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tree_path = talos_tree(&urdf, d);
    let names = Tree::from_file(&tree_path).unwrap().joint_names().join(",");
    let plan = |extra: &[&str], csv: &Path, json: &Path| -> String {
        let mut args = vec![
            "plan",
            "--model",
            s(&tree_path),
            "--n",
            "20",
            "--candidates",
            "400",
            "--no-table",
            "--out",
            s(csv),
            "--json",
            s(json),
        ];
        args.extend(extra);
        String::from_utf8_lossy(&run(&args).stdout).into_owned()
    };
    let collisions = |csv: &Path| -> usize {
        let o = Command::new(&py)
            .arg(py_script("check_plan_safety.py"))
            .args([
                s(&urdf),
                s(&srdf),
                s(&share),
                s(csv),
                &names,
                "-100000",
                "5",
            ])
            .output()
            .expect("python runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let doc: serde_json::Value = serde_json::from_slice(&o.stdout).expect("checker JSON");
        assert_eq!(doc["poses"], 20);
        doc["pose_collisions"].as_array().unwrap().len()
    };
    let (checked_csv, checked_json) = (d.join("checked.csv"), d.join("checked.json"));
    let said = plan(
        &[
            "--urdf",
            s(&urdf),
            "--srdf",
            s(&srdf),
            "--package-path",
            s(&share),
        ],
        &checked_csv,
        &checked_json,
    );
    assert!(said.contains("NO CHECK OF THE MOVES"), "{said}");
    assert!(!said.contains("NO COLLISION CHECK"), "{said}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&checked_json).unwrap()).unwrap();
    assert_eq!(doc["collisions_verified"], true);
    assert_eq!(doc["order"]["moves_verified"], false);
    assert_eq!(
        collisions(&checked_csv),
        0,
        "planned poses in self-collision"
    );
    // the same plan without the URDF: nothing but frame origins and tips kept apart, and said
    let (bare_csv, bare_json) = (d.join("bare.csv"), d.join("bare.json"));
    let said = plan(&[], &bare_csv, &bare_json);
    assert!(said.contains("NO COLLISION CHECK OF THE LINKS"), "{said}");
    eprintln!(
        "TALOS tree plan, 20 poses: {} in self-collision without the URDF, 0 with it",
        collisions(&bare_csv)
    );
}
