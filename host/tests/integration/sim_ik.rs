//! Inverse kinematics round trips: FK(IK(target)) = target over the workspace, for the nominal
//! Katana, a calibrated (perturbed) one and the tilted chain.

use crate::common;
use crate::common::record::record;

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigctl::model::ik::{solve, tool_target, IkTilt};
use rigctl::model::{katana450, Model, KATANA_GEOMETRIC_PARAMS};

/// Largest FK(IK(p)) - p allowed, mm (and for the tool axis, unit vector).
const ROUND_TRIP_TOL: f64 = 1e-9;

fn random_q(rng: &mut ChaCha8Rng, model: &Model) -> Vec<f64> {
    model
        .joint_limits()
        .iter()
        .map(|l| rng.gen_range(l[0] + 1.0..l[1] - 1.0))
        .collect()
}

/// Random joints whose tool point stays clear of the table (z > 0 in R) and of the joint-1
/// axis, where q1 is undetermined.
fn random_reachable(rng: &mut ChaCha8Rng, model: &Model) -> Vec<f64> {
    loop {
        let q = random_q(rng, model);
        let t = tool_target(model, &q, IkTilt::Off).expect("fk");
        let w = t.position_mm - t.axis * 200.0 - Vector3::new(55.0, 55.0, 201.5);
        if t.position_mm.z > 0.0 && w.x.hypot(w.y) > 20.0 {
            return q;
        }
    }
}

fn round_trip(model: &Model, tilt: IkTilt, n: usize, seed: u64) -> (f64, f64, usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut worst_mm, mut worst_axis, mut same_branch) = (0.0f64, 0.0f64, 0usize);
    for _ in 0..n {
        let q = random_reachable(&mut rng, model);
        let target = tool_target(model, &q, tilt).expect("fk");
        // a seed away from the answer: every joint shifted by up to 20 degrees
        let seed_q: Vec<f64> = q.iter().map(|v| v + rng.gen_range(-20.0..20.0)).collect();
        let sol = solve(model, &target, &seed_q, tilt).expect("reachable by construction");
        let got = tool_target(model, &sol, tilt).expect("fk");
        worst_mm = worst_mm.max((got.position_mm - target.position_mm).norm());
        worst_axis = worst_axis.max((got.axis - target.axis).norm());
        for (v, l) in sol.iter().zip(model.joint_limits()) {
            assert!(
                *v >= l[0] - 1e-9 && *v <= l[1] + 1e-9,
                "joint {v} outside {l:?}"
            );
        }
        if sol.iter().zip(&q).all(|(a, b)| (a - b).abs() < 1e-6) {
            same_branch += 1;
        }
    }
    (worst_mm, worst_axis, same_branch)
}

#[test]
fn nominal_round_trip_is_exact_and_prefers_the_seed_branch() {
    let model = katana450(200.0).unwrap();
    let n = 300;
    let (mm, axis, same) = round_trip(&model, IkTilt::Off, n, 1);
    assert!(mm < ROUND_TRIP_TOL, "worst position error {mm} mm");
    assert!(axis < ROUND_TRIP_TOL, "worst axis error {axis}");
    // the seed is within 20 deg of the generating joints, so the nearest branch is (almost
    // always) that one; singular poses (tool normal to the arm plane) may differ
    assert!(
        same >= n * 95 / 100,
        "only {same}/{n} solutions on the seed's branch"
    );
    record("round_trip_tolerance_mm", ROUND_TRIP_TOL);
}

#[test]
fn calibrated_model_round_trip_is_exact() {
    let mut model = katana450(200.0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for name in KATANA_GEOMETRIC_PARAMS {
        let v = model.param(name).unwrap() + rng.gen_range(-0.3..0.3);
        model.set_param(name, v).unwrap();
    }
    for name in ["a2", "a3", "d4", "d5"] {
        let v = model.param(name).unwrap() + rng.gen_range(-2.0..2.0);
        model.set_param(name, v).unwrap();
    }
    model.set_param("tool_dx", 1.5).unwrap();
    model.set_param("enc_j2_h1_sin", 0.05).unwrap();
    let (mm, axis, _) = round_trip(&model, IkTilt::Off, 150, 2);
    assert!(mm < ROUND_TRIP_TOL, "worst position error {mm} mm");
    assert!(axis < ROUND_TRIP_TOL, "worst axis error {axis}");
}

#[test]
fn tilted_model_round_trip_is_exact() {
    let model = katana450(200.0).unwrap();
    let (mm, axis, _) = round_trip(&model, IkTilt::Static, 100, 3);
    assert!(mm < ROUND_TRIP_TOL, "worst position error {mm} mm");
    assert!(axis < ROUND_TRIP_TOL, "worst axis error {axis}");
}

#[test]
fn unreachable_target_is_an_error_not_a_panic() {
    let model = katana450(200.0).unwrap();
    let target = rigctl::model::ik::ToolTarget {
        position_mm: Vector3::new(2000.0, 0.0, 200.0),
        axis: -Vector3::z(),
    };
    assert!(solve(&model, &target, &[0.0; 5], IkTilt::Off).is_err());
    // degenerate targets: no tool axis, a NaN coordinate
    let zero_axis = rigctl::model::ik::ToolTarget {
        position_mm: Vector3::new(300.0, 0.0, 300.0),
        axis: Vector3::zeros(),
    };
    assert!(solve(&model, &zero_axis, &[0.0; 5], IkTilt::Off).is_err());
    let nan = rigctl::model::ik::ToolTarget {
        position_mm: Vector3::new(f64::NAN, 0.0, 300.0),
        axis: -Vector3::z(),
    };
    assert!(solve(&model, &nan, &[0.0; 5], IkTilt::Off).is_err());
    // a wrong seed length is a model error, not a panic
    assert!(solve(&model, &target, &[0.0; 4], IkTilt::Off).is_err());
}

/// Golden poses from the independent reference implementation
/// (shared/data/reference/katana_fk.csv, nominal rigid rows): the IK of each reference position
/// and tool axis (from its ZXZ angles), seeded 15 deg away, returns the reference joints, and
/// its tool point is the reference position.
#[test]
fn ik_recovers_the_reference_joints() {
    let Some(path) = common::shared_file(
        "ik_recovers_the_reference_joints",
        "data/reference/katana_fk.csv",
    ) else {
        return;
    };
    let text = std::fs::read_to_string(&path).expect("read katana_fk.csv");
    let model = katana450(200.0).unwrap();
    let mut checked = 0;
    for line in text.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if !f[5].is_empty() || f[6] != "0" || f[7].parse::<f64>().unwrap() != 200.0 {
            continue;
        }
        let v: Vec<f64> = f
            .iter()
            .enumerate()
            .filter(|(i, _)| ![5, 6].contains(i))
            .map(|(_, s)| s.parse().unwrap())
            .collect();
        let q = &v[..5];
        let p = Vector3::new(v[6], v[7], v[8]);
        let (phi, theta) = (v[9].to_radians(), v[10].to_radians());
        let axis = Vector3::new(
            phi.sin() * theta.sin(),
            -phi.cos() * theta.sin(),
            theta.cos(),
        );
        let seed: Vec<f64> = q.iter().map(|x| x + 15.0).collect();
        let target = rigctl::model::ik::ToolTarget {
            position_mm: p,
            axis,
        };
        let sol = solve(&model, &target, &seed, IkTilt::Off).unwrap();
        let got = tool_target(&model, &sol, IkTilt::Off).unwrap();
        // the reference prints 9 decimals
        assert!((got.position_mm - p).norm() < 1e-8, "{line}");
        // q = 0 is the singular pose (tool normal to the arm plane): the seed picks the pitch
        if q.iter().any(|x| *x != 0.0) {
            for (a, b) in sol.iter().zip(q) {
                assert!((a - b).abs() < 1e-5, "{line}: {sol:?}");
            }
        }
        checked += 1;
    }
    assert!(checked >= 5, "only {checked} reference rows");
}
