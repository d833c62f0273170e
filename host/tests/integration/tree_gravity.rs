//! The whole tree's gravity torques (`Tree::axis_torques_kgfm`) against pinocchio's
//! `computeGeneralizedGravity` on a URDF this test writes of the same body (the humanoid upper
//! body of [`super::tree_body`], with its link masses as `<inertial>`s): pinocchio's
//! torque is what the joint must exert, `g = -9.81 tau` (N.m, `tau` in kgf.m), and the test's own
//! brute-force statics agree too.

use std::path::Path;

use rand::{Rng, SeedableRng};

use super::tree_body::Body;
use crate::common::{py_script, python_env};
use rigctl::model::Tree;

const G_M_S2: f64 = 9.81;

/// The body as a URDF: link `base` (frame R), link `link_<joint>` per joint with its mass.
fn urdf(body: &Body) -> String {
    let mut s = String::from("<?xml version=\"1.0\"?>\n<robot name=\"upper_body\">\n");
    s += "  <link name=\"base\"/>\n";
    for g in &body.segs {
        let (al, a, d) = (g.al_deg.to_radians(), g.a_mm * 1e-3, g.d_mm * 1e-3);
        // Rx(al) Tx(a) Tz(d) = Trans(Rx(al) (a, 0, d)) Rx(al)
        let xyz = [a, -d * al.sin(), d * al.cos()];
        let parent = g.parent.map_or("base".to_string(), |p| {
            format!("link_{}", body.segs[p].name)
        });
        let [cx, cy, cz] = g.mass.1.map(|v| v * 1e-3);
        s += &format!(
            "  <link name=\"link_{n}\">\n    <inertial>\n      <origin xyz=\"{cx:e} {cy:e} {cz:e}\" \
             rpy=\"0 0 0\"/>\n      <mass value=\"{m:e}\"/>\n      <inertia ixx=\"1e-4\" ixy=\"0\" \
             ixz=\"0\" iyy=\"1e-4\" iyz=\"0\" izz=\"1e-4\"/>\n    </inertial>\n  </link>\n  \
             <joint name=\"{n}\" type=\"revolute\">\n    <parent link=\"{parent}\"/>\n    \
             <child link=\"link_{n}\"/>\n    <origin xyz=\"{:e} {:e} {:e}\" rpy=\"{al:e} 0 0\"/>\n    \
             <axis xyz=\"0 0 1\"/>\n    <limit lower=\"-3\" upper=\"3\" effort=\"100\" \
             velocity=\"1\"/>\n  </joint>\n",
            xyz[0],
            xyz[1],
            xyz[2],
            n = g.name,
            m = g.mass.0,
        );
    }
    s + "</robot>\n"
}

fn read_rows(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect()
}

#[test]
fn tree_gravity_equals_pinocchio_generalized_gravity() {
    let test = "tree_gravity_equals_pinocchio_generalized_gravity";
    let body = Body::nominal();
    let tree = Tree::from_toml_str(&body.model_toml(), "body.toml").unwrap();
    let mut rng = rand::rngs::StdRng::seed_from_u64(5262);
    let q_deg: Vec<Vec<f64>> = (0..30)
        .map(|_| {
            body.segs
                .iter()
                .map(|_| rng.gen_range(-150.0..150.0))
                .collect()
        })
        .collect();
    // the test's own statics first (no Python needed)
    let mut worst_own = 0.0f64;
    for q in &q_deg {
        let ours = tree.axis_torques_kgfm(q).unwrap();
        for (a, b) in ours.iter().zip(body.torques_kgfm(q)) {
            worst_own = worst_own.max((a - b).abs());
        }
    }
    assert!(worst_own < 1e-9, "tree vs brute force: {worst_own:e} kgf.m");
    let Some(py) = python_env(test) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (urdf_path, q_csv, out) = (d.join("body.urdf"), d.join("q.csv"), d.join("g.csv"));
    std::fs::write(&urdf_path, urdf(&body)).unwrap();
    let names: Vec<String> = body.segs.iter().map(|g| g.name.clone()).collect();
    let mut text = names.join(",") + "\n";
    for q in &q_deg {
        let cells: Vec<String> = q.iter().map(|v| format!("{:e}", v.to_radians())).collect();
        text += &(cells.join(",") + "\n");
    }
    std::fs::write(&q_csv, text).unwrap();
    let run = std::process::Command::new(&py)
        .arg(py_script("pin_gravity.py"))
        .args([&urdf_path, &q_csv, &out])
        .output()
        .expect("python runs");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let g = read_rows(&out);
    assert_eq!(g.len(), q_deg.len());
    let (mut worst, mut largest, mut largest_pin) = (0.0f64, 0.0f64, 0.0f64);
    for (q, g) in q_deg.iter().zip(&g) {
        let ours = tree.axis_torques_kgfm(q).unwrap();
        assert_eq!(ours.len(), g.len());
        for (tau, g) in ours.iter().zip(g) {
            worst = worst.max((tau + g / G_M_S2).abs());
            largest = largest.max(tau.abs());
            largest_pin = largest_pin.max(g.abs() / G_M_S2);
        }
    }
    eprintln!(
        "tree gravity vs pinocchio computeGeneralizedGravity: max |tau + g/9.81| {worst:.3e} kgf.m \
         (torques up to {largest:.2} kgf.m); vs the test's brute force {worst_own:.3e}"
    );
    assert!(
        largest > 5.0 && largest_pin > 5.0,
        "the torso carries both arms: {largest}, pinocchio {largest_pin}"
    );
    assert!(worst < 1e-9, "{worst:e} kgf.m");
}
