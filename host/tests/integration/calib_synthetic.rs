//! Calibration on synthetic Katana data made here from the model's own FK: a known perturbation
//! of the 12 geometric parameters, the declared joint tilting, and seeded Gaussian noise.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rigctl::calib::measured::PosePoints;
use rigctl::calib::{calibrate, position_errors, CalibrateOptions, MeasuredSet, Method, Stats};
use rigctl::model::{katana450, Model, Tilt};

use crate::common::record::record;

/// Measurement noise per axis (mm), about the Optotrack's resolution.
const NOISE_MM: f64 = 0.01;

/// Perturbation of the true robot (deg), the size of thesis table 3.2.
const TRUTH_DEG: [(&str, f64); 11] = [
    ("dth1", -0.061),
    ("dth2", 0.0232),
    ("dth3", -0.057),
    ("dth4", 0.0641),
    ("dth5", -0.121),
    ("al2", 89.92),
    ("al3", 0.003),
    ("al4", -90.01),
    ("al5", 90.03),
    ("be3", 0.0021),
    ("be4", 0.0013),
];

fn truth() -> Model {
    let mut m = katana450(200.0).unwrap();
    for (n, v) in TRUTH_DEG {
        m.set_param(n, v).unwrap();
    }
    m
}

fn poses_with(model: &Model, n: usize, seed: u64, tilt: Tilt<'static>) -> PosePoints {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, NOISE_MM).unwrap();
    let limits = model.joint_limits();
    let mut p = PosePoints::default();
    for _ in 0..n {
        let q: Vec<f64> = limits.iter().map(|l| rng.gen_range(l[0]..l[1])).collect();
        let x = model.position_mm(&q, tilt).unwrap();
        let e = Vector3::new(
            noise.sample(&mut rng),
            noise.sample(&mut rng),
            noise.sample(&mut rng),
        );
        p.q_deg.push(q);
        p.xyz_mm.push(x + e);
    }
    p
}

fn poses(model: &Model, n: usize, seed: u64) -> PosePoints {
    poses_with(model, n, seed, Tilt::Static)
}

fn run(method: Method, cal: &PosePoints, val: &PosePoints) -> rigctl::calib::Outcome {
    let opts = CalibrateOptions {
        method,
        ..CalibrateOptions::default()
    };
    let (cal, val) = (
        MeasuredSet::from_poses(cal.clone()),
        MeasuredSet::from_poses(val.clone()),
    );
    calibrate(&katana450(200.0).unwrap(), &cal, Some(&val), &opts).unwrap()
}

#[test]
fn tilting_reaches_the_noise_floor_and_standard_does_not() {
    let t = truth();
    let cal = poses(&t, 118, 1);
    let val = poses(&t, 60, 2);
    let floor = Stats::from_errors(&position_errors(&t, &val, true).unwrap()).mean_mm;
    let tilting = run(Method::Tilting, &cal, &val);
    let v = tilting.report.validation.unwrap();
    let std_val = tilting.report.standard.validation.unwrap();
    eprintln!(
        "floor {floor:.4} tilting {:.4} standard {:.4} before {:.4}",
        v.after.mean_mm, std_val.mean_mm, v.before.mean_mm
    );
    record("floor_mm", floor);
    record("tilting_mm", v.after.mean_mm);
    record("standard_mm", std_val.mean_mm);
    record("before_mm", v.before.mean_mm);
    assert!(
        v.after.mean_mm <= 1.25 * floor,
        "tilting {} vs floor {floor}",
        v.after.mean_mm
    );
    assert!(
        std_val.mean_mm >= 3.0 * v.after.mean_mm,
        "standard {} vs tilting {}",
        std_val.mean_mm,
        v.after.mean_mm
    );
    assert!(v.before.mean_mm > 10.0 * v.after.mean_mm);
}

#[test]
fn identifiable_parameters_within_three_sigma_and_unidentifiable_named() {
    let t = truth();
    let cal = poses(&t, 118, 3);
    let val = poses(&t, 20, 4);
    let out = run(Method::Tilting, &cal, &val);
    let r = &out.report;
    // be5 turns the tool about its own length; dth5 and be4 turn the wrist about one axis.
    assert!(
        r.unidentifiable.iter().any(|u| u == "be5"),
        "{:?}",
        r.unidentifiable
    );
    assert!(
        r.unidentifiable
            .iter()
            .any(|u| u == "dth5+be4" || u == "be4+dth5"),
        "{:?}",
        r.unidentifiable
    );
    assert_eq!(r.fixed, ["be4", "be5"]);
    assert_eq!(r.rank, 10);
    assert!(r.condition_number.is_finite() && r.condition_number > 1.0);
    for (name, sigma) in r.sigma.0.iter().filter(|(n, _)| !r.fixed.contains(n)) {
        let est = r.parameters.get(name).unwrap();
        let truth_v = if name == "dth5" {
            // Only dth5 + be4 is seen; be4 stays nominal (0), so dth5 takes the sum.
            t.param("dth5").unwrap() + t.param("be4").unwrap()
        } else {
            t.param(name).unwrap()
        };
        assert!(sigma.is_finite() && *sigma > 0.0, "{name}: sigma {sigma}");
        assert!(
            (est - truth_v).abs() <= 3.0 * sigma,
            "{name}: {est} vs {truth_v} (sigma {sigma})"
        );
    }
}

#[test]
fn influence_improves_on_nominal_for_a_rigid_robot() {
    // Without tilting in the data the standard fit reaches the noise floor; the influence-based
    // iteration (per-pose minimum-norm steps, combined) must improve on the nominal model.
    let t = truth();
    let cal = poses_with(&t, 118, 5, Tilt::Off);
    let val = poses_with(&t, 30, 6, Tilt::Off);
    let floor = Stats::from_errors(&position_errors(&t, &val, false).unwrap()).mean_mm;
    let inf = run(Method::Influence, &cal, &val);
    let r = &inf.report;
    let v = r.validation.unwrap();
    let std_val = r.standard.validation.unwrap().mean_mm;
    eprintln!(
        "rigid: floor {floor:.4} before {:.4} influence {:.4} standard {std_val:.4}",
        v.before.mean_mm, v.after.mean_mm
    );
    assert_eq!(r.method, "influence");
    assert!(!r.tilting_applied);
    assert!(
        std_val <= 1.25 * floor,
        "standard {std_val} vs floor {floor}"
    );
    // Measured: 0.633 -> 0.466 mm (standard: 0.015). The per-pose minimum-norm sets, averaged,
    // are far from the least-squares optimum; see calib::influence's doc.
    assert!(
        v.after.mean_mm < 0.85 * v.before.mean_mm,
        "influence {} vs before {}",
        v.after.mean_mm,
        v.before.mean_mm
    );
    assert!(
        v.after.mean_mm > std_val,
        "influence is not expected to beat least squares here"
    );
}

#[test]
fn standard_method_reports_the_standard_fit() {
    let t = truth();
    let cal = poses(&t, 118, 7);
    let std = run(Method::Standard, &cal, &poses(&t, 10, 8));
    assert!(!std.report.tilting_applied);
    assert_eq!(std.report.method, "standard");
    assert_eq!(
        std.report.calibration.after,
        std.report.standard.calibration
    );
}
