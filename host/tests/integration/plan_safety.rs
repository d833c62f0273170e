//! Safe plans on a public URDF robot: the Franka Panda of `example-robot-data` (installed in the
//! test venv, read from the package, not committed) through `urdf2model` and `plan --urdf
//! --srdf` for 60 and 150 poses. An independent checker (`host/tests/py/check_plan_safety.py`:
//! pinocchio + coal on the URDF's own meshes, the SRDF's pairs, a half-space table) finds no
//! pose and no point of the driven path (the trajectory's segments, via points included, every 0.5 deg,
//! finer than the planner's 1 deg) in collision or
//! below the table; every joint is >= 2 deg inside its limits; the order's joint travel is
//! shorter than random orders'. The checker is shown to find collisions on random
//! configurations (it can fail). On the Katana without a URDF: keep-out boxes are kept and the
//! output says that no collision check was made.

use std::path::Path;
use std::process::Command;

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};

use super::common::record::record;
use super::common::spawn::rigctl;
use super::common::{py_script, python_env, robots_share};

const JOINTS: &str =
    "panda_joint1,panda_joint2,panda_joint3,panda_joint4,panda_joint5,panda_joint6,panda_joint7";

fn rows(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect()
}

fn travel(q: &[Vec<f64>]) -> f64 {
    q.windows(2)
        .map(|p| {
            p[0][..7]
                .iter()
                .zip(&p[1][..7])
                .map(|(a, b)| (a - b).abs())
                .sum::<f64>()
        })
        .sum()
}

fn check(py: &Path, share: &Path, csv: &Path, traj: Option<&Path>) -> serde_json::Value {
    let panda = share.join("example-robot-data/robots/panda_description");
    let o = Command::new(py)
        .arg(py_script("check_plan_safety.py"))
        .arg(panda.join("urdf/panda.urdf"))
        .arg(panda.join("srdf/panda.srdf"))
        .arg(share)
        .arg(csv)
        .args([JOINTS, "0", "0.5"])
        .args(traj)
        .output()
        .expect("python runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("checker JSON")
}

#[test]
fn panda_plans_have_no_collision_and_keep_the_margins() {
    let Some(py) = python_env("plan_safety") else {
        return;
    };
    let Some(share) = robots_share(
        &py,
        "example-robot-data/robots/panda_description/urdf/panda.urdf",
        "plan_safety",
    ) else {
        return;
    };
    let panda = share.join("example-robot-data/robots/panda_description");
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("panda.toml");
    let o = rigctl()
        .args(["urdf2model", "--tip", "panda_link8", "--urdf"])
        .arg(panda.join("urdf/panda.urdf"))
        .arg("--out")
        .arg(&model)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // the checker can fail: random configurations within the limits collide or go below
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let limits = rigctl::model::Model::from_file(&model)
        .unwrap()
        .joint_limits();
    let mut text = String::from("q1,q2,q3,q4,q5,q6,q7\n");
    for _ in 0..40 {
        let r: Vec<String> = limits
            .iter()
            .map(|l| format!("{:.6}", rng.gen_range(l[0]..l[1])))
            .collect();
        text += &(r.join(",") + "\n");
    }
    let random_csv = dir.path().join("random.csv");
    std::fs::write(&random_csv, text).unwrap();
    let r = check(&py, &share, &random_csv, None);
    let bad =
        r["pose_collisions"].as_array().unwrap().len() + r["below_table"].as_array().unwrap().len();
    assert!(bad > 0, "the checker finds unsafe random poses: {r}");
    for n in [60usize, 150] {
        let csv = dir.path().join(format!("plan{n}.csv"));
        let traj = dir.path().join(format!("plan{n}.yaml"));
        let svg = dir.path().join(format!("plan{n}.svg"));
        let o = rigctl()
            .args(["plan", "--base", "--n", &n.to_string(), "--model"])
            .arg(&model)
            .arg("--urdf")
            .arg(panda.join("urdf/panda.urdf"))
            .args(["--tip-link", "panda_link8", "--srdf"])
            .arg(panda.join("srdf/panda.srdf"))
            .arg("--out")
            .arg(&csv)
            .arg("--trajectory")
            .arg(&traj)
            .arg("--plot")
            .arg(&svg)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(
            stdout.contains("collision check: 11 links with shapes"),
            "{stdout}"
        );
        assert!(!stdout.contains("NO COLLISION CHECK"));
        let q = rows(&csv);
        assert_eq!(q.len(), n);
        // the segments a robot drives: the trajectory's, through the via configuration where
        // the straight way between two poses is not safe
        let r = check(&py, &share, &csv, Some(&traj));
        record(&format!("plan_safety_panda_{n}"), r.clone());
        assert_eq!(r["poses"], n);
        assert!(r["segment_points"].as_u64().unwrap() > 10 * n as u64);
        assert_eq!(r["pose_collisions"].as_array().unwrap().len(), 0, "{r}");
        assert_eq!(r["segment_collisions"].as_array().unwrap().len(), 0, "{r}");
        assert_eq!(r["below_table"].as_array().unwrap().len(), 0, "{r}");
        assert!(r["min_margin_deg"].as_f64().unwrap() >= 2.0 - 1e-6, "{r}");
        // every tool point above the table too
        assert!(q.iter().all(|p| p[9] >= 0.0));
        // shorter than random orders of the same poses
        let planned = travel(&q);
        let mut shuffled = q.clone();
        let random: Vec<f64> = (0..50)
            .map(|_| {
                shuffled.shuffle(&mut rng);
                travel(&shuffled)
            })
            .collect();
        let shortest_random = random.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(
            planned < shortest_random,
            "travel {planned} against random orders >= {shortest_random}"
        );
        // the trajectory: the joint names, an arrival and a departure point per pose, in rad
        let y = std::fs::read_to_string(&traj).unwrap();
        assert!(y.contains("  - \"panda_joint7\""));
        assert_eq!(r["stops_match_poses"], true, "{r}");
        let via = r["via_points"].as_u64().unwrap() as usize;
        assert_eq!(y.matches("positions:").count(), 2 * n + via, "{r}");
        let first = format!("{:.9}", q[0][0].to_radians());
        assert!(y.contains(&first), "{first}");
        let s = std::fs::read_to_string(&svg).unwrap();
        assert!(s.contains("robot at a few poses"));
    }
}

#[test]
fn keep_out_boxes_and_no_geometry_said_on_the_katana() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.csv");
    let boxes = ["-1000,-1000,-10,-50,1000,2000", "50,50,-10,1000,1000,150"];
    let o = rigctl()
        .args([
            "plan",
            "--robot",
            "katana450",
            "--n",
            "12",
            "--candidates",
            "1500",
        ])
        .args(["--keep-out", boxes[0], "--keep-out", boxes[1]])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("NO COLLISION CHECK MADE"), "{stdout}");
    assert!(stdout.contains("2 keep-out box(es)"), "{stdout}");
    for p in rows(&out) {
        let t = &p[5..8];
        assert!(t[0] > -50.0, "{t:?} in the first box");
        assert!(
            !(t[0] >= 50.0 && t[1] >= 50.0 && t[2] <= 150.0),
            "{t:?} in the second box"
        );
    }
    // boxes that leave no room: exit 1, saying how many were found, nothing written
    std::fs::remove_file(&out).unwrap();
    let o = rigctl()
        .args([
            "plan",
            "--robot",
            "katana450",
            "--n",
            "12",
            "--candidates",
            "200",
        ])
        .args(["--keep-out", "-2000,-2000,-10,2000,2000,2000"])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("only 0 of"));
    assert!(!out.exists());
    let o = rigctl()
        .args([
            "plan",
            "--robot",
            "katana450",
            "--n",
            "12",
            "--keep-out",
            "1,2,3",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--keep-out"));
}
