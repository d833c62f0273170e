//! `plan` on a tree model, checked with the independent humanoid generator of `tree_body.rs`:
//! every planned pose is safe by the generator's own kinematics (joints inside the limits less
//! the margin, every joint frame origin and both hands above the table, the hands apart), and
//! the planned poses calibrate the elastic tree (truth of `tree_lateral.rs`) better held out
//! than every one of three random designs of safe poses of the same (near-minimal) number. Chain-only options are refused on a tree.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};

use super::tree_body::{calibrate, tree_csv, Body};
use super::tree_compliance::NOISE_MM;
use super::tree_lateral::data;
use crate::common::record::record;
use crate::common::spawn::{output, path_arg, text};

const TABLE_Z_MM: f64 = 150.0;
const BRANCH_CLEARANCE_MM: f64 = 100.0;
/// The model file's joint limits (+-170 deg) less the default margin (2 deg).
const USABLE_DEG: f64 = 168.0;
const N: usize = 20;

/// Whether the generator finds `q` safe as the plan must: frame origins and hands above the
/// table, the hands apart.
fn safe(body: &Body, q: &[f64]) -> bool {
    let hands = body.rigid_hands_mm(q);
    body.origins_mm(q).iter().all(|o| o.z >= TABLE_Z_MM - 1e-6)
        && hands.iter().all(|h| h.z >= TABLE_Z_MM - 1e-6)
        && (hands[0] - hands[1]).norm() >= BRANCH_CLEARANCE_MM - 1e-6
}

/// `n` random safe configurations (uniform within the usable limits).
fn random_safe(body: &Body, n: usize, rng: &mut rand::rngs::StdRng) -> Vec<Vec<f64>> {
    let mut out = Vec::new();
    while out.len() < n {
        let q: Vec<f64> = body
            .segs
            .iter()
            .map(|_| rng.gen_range(-USABLE_DEG..USABLE_DEG))
            .collect();
        if safe(body, &q) {
            out.push(q);
        }
    }
    out
}

type Poses = Vec<(Vec<f64>, Vec<Vector3<f64>>)>;

/// The hands of `truth` at every configuration of `qs`, with the motion-capture noise.
fn measured(truth: &Body, qs: &[Vec<f64>], rng: &mut rand::rngs::StdRng) -> Poses {
    let noise = rand_distr::Normal::new(0.0, NOISE_MM).unwrap();
    qs.iter()
        .map(|q| {
            let hands = truth
                .hands_mm(q)
                .into_iter()
                .map(|p| p.map(|v| v + rand_distr::Distribution::sample(&noise, rng)))
                .collect();
            (q.clone(), hands)
        })
        .collect()
}

#[test]
fn tree_plan_is_safe_and_beats_random_poses_held_out() {
    let nominal = Body::nominal();
    let (truth, _, _) = data(&nominal);
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (model, plan_csv, plan_json) =
        (d.join("body.toml"), d.join("plan.csv"), d.join("plan.json"));
    std::fs::write(&model, nominal.model_toml()).unwrap();
    let n = N.to_string();
    let table = TABLE_Z_MM.to_string();
    let run = output(&[
        "plan",
        "--model",
        path_arg(&model),
        "--n",
        &n,
        "--out",
        path_arg(&plan_csv),
        "--json",
        path_arg(&plan_json),
        "--table-z-mm",
        &table,
        "--seed",
        "7",
    ]);
    let stdout = text(&run.stdout);
    assert!(run.status.success(), "{stdout}\n{}", text(&run.stderr));
    eprintln!("{stdout}");
    assert!(stdout.contains("NO COLLISION CHECK"), "{stdout}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&plan_json).unwrap()).unwrap();
    assert_eq!(doc["collisions_verified"], false);
    assert_eq!(doc["order"]["moves_verified"], false);
    assert!(doc["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .any(|p| p.as_str().unwrap().starts_with("lateral_compliance_j")));

    // the plan file: q1..q14, nom_x1..nom_z2; every pose safe by the generator's kinematics
    let csv = std::fs::read_to_string(&plan_csv).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let joints = nominal.segs.len();
    assert_eq!(header.len(), joints + 6, "{header:?}");
    assert_eq!(header[joints], "nom_x1");
    assert_eq!(header[joints + 5], "nom_z2");
    let mut planned: Vec<Vec<f64>> = Vec::new();
    for line in lines {
        let v: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        let q = v[..joints].to_vec();
        assert!(q.iter().all(|x| x.abs() <= USABLE_DEG + 1e-6), "{q:?}");
        assert!(safe(&nominal, &q), "unsafe planned pose {q:?}");
        let hands = nominal.rigid_hands_mm(&q);
        for (t, h) in hands.iter().enumerate() {
            let nom = Vector3::new(
                v[joints + 3 * t],
                v[joints + 3 * t + 1],
                v[joints + 3 * t + 2],
            );
            assert!((nom - h).norm() < 1e-3, "tip {t}: {nom} vs {h}");
        }
        planned.push(q);
    }
    assert_eq!(planned.len(), N);

    // measured on the elastic truth: the planned poses against random safe ones, held out on
    // random safe poses, the tree calibrated with its compliances
    let mut rng = rand::rngs::StdRng::seed_from_u64(4711);
    let val = measured(&truth, &random_safe(&nominal, 150, &mut rng), &mut rng);
    let val_csv = d.join("val.csv");
    std::fs::write(&val_csv, tree_csv(&nominal, &val, 1.0)).unwrap();
    let held_out = |poses: &Poses, name: &str| {
        let cal = d.join(name);
        std::fs::write(&cal, tree_csv(&nominal, poses, 1.0)).unwrap();
        calibrate(&[
            "--model",
            path_arg(&model),
            "--poses",
            path_arg(&cal),
            "--validate",
            path_arg(&val_csv),
            "--compliance",
        ])
        .0
    };
    let planned_rms = held_out(&measured(&truth, &planned, &mut rng), "planned.csv");
    let mut random: Vec<f64> = (0..3)
        .map(|k| {
            let qs = random_safe(&nominal, N, &mut rng);
            held_out(&measured(&truth, &qs, &mut rng), &format!("random{k}.csv"))
        })
        .collect();
    random.sort_by(f64::total_cmp);
    eprintln!(
        "held-out rms per coordinate, {N} poses (noise {NOISE_MM} mm): planned {planned_rms:.4} mm, random {random:.4?} mm"
    );
    record("poses", N as f64);
    record("noise_mm", NOISE_MM);
    record("planned_mm", planned_rms);
    record("random_best_mm", random[0]);
    record("random_median_mm", random[1]);
    record(
        "median_sigma_ratio",
        doc["median_sigma_ratio"].as_f64().unwrap(),
    );
    assert!(
        planned_rms < random[0],
        "planned {planned_rms} mm not better than every random design {random:?}"
    );
}

/// `rigctl plan --model BODY --n 20 --out plan.csv EXTRA` on the nominal body: exit code,
/// stderr, and whether plan.csv was written.
fn plan_body(extra: &[&str]) -> (Option<i32>, String, bool) {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("body.toml");
    std::fs::write(&model, Body::nominal().model_toml()).unwrap();
    let out = dir.path().join("plan.csv");
    let mut args = vec![
        "plan",
        "--model",
        path_arg(&model),
        "--n",
        "20",
        "--out",
        path_arg(&out),
    ];
    args.extend(extra);
    let run = output(&args);
    (run.status.code(), text(&run.stderr), out.exists())
}

#[test]
fn chain_only_plan_options_are_refused_on_a_tree() {
    let (code, err, written) = plan_body(&["--plot", "p.svg", "--sheets"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--plot") && err.contains("--sheets"), "{err}");
    assert!(!written, "nothing written");
}

#[test]
fn a_table_above_every_pose_is_a_failure_naming_the_tree_options() {
    // the table 5 m up: no pose of the body has its hands above it
    let (code, err, written) = plan_body(&["--candidates", "200", "--table-z-mm", "5000"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("--table-z-mm") && err.contains("--branch-clearance-mm"),
        "{err}"
    );
    assert!(
        !err.contains("--visible-from"),
        "a chain's option named: {err}"
    );
    assert!(!written, "nothing written");
}
