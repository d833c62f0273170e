//! The probe of the final residual (`rigctl::diagnose::probe`): pure noise gives nothing, an
//! additive function of one joint and a two-joint interaction are named, on full positions and
//! on partial (traced) measurements; in a whole diagnosis of a simulated Katana session, a
//! smooth error that no library effect describes makes the residual `structured` with the
//! right `depends_on`, clean data do not, and `--residual-model` lowers the held-out error.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rigctl::calib::Poses;
use rigctl::diagnose::data::Dataset;
use rigctl::diagnose::probe::{hybrid_report, jacobians, probe_dataset, ProbeConfig, ProbeResult};
use rigctl::diagnose::{diagnose, DiagnoseOptions, Diagnosis};
use rigctl::model::katana450;
use rigctl::sim::simulate::{simulate, SimConfig, SimPose};

const NOISE_MM: f64 = 0.01;

/// `n` random poses of 6 joints in [-120, 120] deg (no measured point: the probe reads only
/// the joints and the residual).
fn random_q(n: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| (0..6).map(|_| rng.gen_range(-120.0..120.0)).collect())
        .collect()
}

fn noise(n: usize, seed: u64) -> Vec<Vector3<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let d = Normal::new(0.0, NOISE_MM).unwrap();
    (0..n)
        .map(|_| Vector3::new(d.sample(&mut rng), d.sample(&mut rng), d.sample(&mut rng)))
        .collect()
}

fn run_probe(q: Vec<Vec<f64>>, residual: &[Vector3<f64>]) -> ProbeResult {
    let n = q.len();
    let data = Dataset::from_poses(Poses {
        q_deg: q,
        xyz_mm: vec![Vector3::zeros(); n],
    });
    probe_dataset(&data, residual, &[], &ProbeConfig::default())
}

fn rad(d: f64) -> f64 {
    d.to_radians()
}

#[test]
fn pure_noise_gives_nothing() {
    for seed in 1..=6 {
        let q = random_q(300, seed);
        let r = noise(300, seed);
        let p = run_probe(q, &r);
        assert!(
            !p.structured && p.depends_on.is_empty(),
            "seed {seed}: {:?} {:?}",
            p.depends_on,
            p.terms
        );
        assert!(p.explainable_share < 0.01, "{}", p.explainable_share);
        assert!(p.sentence().contains("explains none"));
    }
}

#[test]
fn an_additive_function_of_q2_is_named_q2() {
    let q = random_q(300, 11);
    let mut r = noise(300, 11);
    for (e, q) in r.iter_mut().zip(&q) {
        let s = 0.03 * (1.5 * rad(q[1])).sin();
        *e += Vector3::new(s, -0.5 * s, 0.2 * s);
    }
    let p = run_probe(q, &r);
    assert_eq!(p.depends_on, vec!["q2".to_string()], "{:?}", p.terms);
    assert!(p.structured);
    assert!(p.explainable_share > 0.3, "{}", p.explainable_share);
    assert!(
        p.sentence().starts_with("it depends on q2:"),
        "{}",
        p.sentence()
    );
}

#[test]
fn a_q1_q3_interaction_is_named_q1_q3() {
    let q = random_q(400, 12);
    let mut r = noise(400, 12);
    for (e, q) in r.iter_mut().zip(&q) {
        e.z += 0.04 * rad(q[0]).sin() * rad(q[2]).sin();
    }
    let p = run_probe(q, &r);
    assert_eq!(p.depends_on, vec!["q1:q3".to_string()], "{:?}", p.terms);
    assert!(p.sentence().contains("depends on q1 with q3"));
}

#[test]
fn two_sources_read_as_a_sentence() {
    let q = random_q(500, 13);
    let mut r = noise(500, 13);
    for (e, q) in r.iter_mut().zip(&q) {
        e.x += 0.04 * (rad(q[1]) * 1.2).cos();
        e.y += 0.04 * rad(q[0]).sin() * rad(q[2]).sin();
    }
    let p = run_probe(q, &r);
    let mut got = p.depends_on.clone();
    got.sort();
    assert_eq!(
        got,
        vec!["q1:q3".to_string(), "q2".to_string()],
        "{:?}",
        p.terms
    );
    let s = p.sentence();
    assert!(
        s.contains("depends on q2 and on q1 with q3")
            || s.contains("depends on q1 with q3 and on q2"),
        "{s}"
    );
}

/// Samples along a path measure two directions only; the serial folds and the autocorrelation
/// of the paired differences keep smooth noise from being called structure, while a function
/// of q4 is found through the measured components.
#[test]
fn partial_measurements_along_a_path() {
    let n = 1200;
    let q: Vec<Vec<f64>> = (0..n)
        .map(|k| {
            let s = k as f64 / n as f64;
            vec![
                -60.0 + 120.0 * s,
                40.0 * (7.0 * s).sin(),
                30.0 * (3.0 * s).cos(),
                90.0 * (40.0 * s).sin(),
                10.0 * s,
            ]
        })
        .collect();
    let dirs: Vec<Vec<Vector3<f64>>> = (0..n)
        .map(|k| {
            let a = k as f64 * 0.01;
            vec![Vector3::new(a.cos(), a.sin(), 0.0), Vector3::z()]
        })
        .collect();
    let white = noise(n, 21);
    // serially correlated noise (AR(1), a = 0.9)
    let mut red = vec![Vector3::zeros(); n];
    for k in 1..n {
        red[k] = red[k - 1] * 0.9 + white[k] * 0.44;
    }
    let data = Dataset {
        poses: Poses {
            q_deg: q.clone(),
            xyz_mm: vec![Vector3::zeros(); n],
        },
        directions: Some(dirs),
        ..Dataset::default()
    };
    let clean = probe_dataset(&data, &red, &[], &ProbeConfig::default());
    assert!(!clean.structured, "{:?}", clean.terms);
    let with: Vec<Vector3<f64>> = red
        .iter()
        .zip(&q)
        .map(|(e, q)| e + Vector3::new(0.0, 0.0, 0.03 * (rad(q[3]) * 2.0).sin()))
        .collect();
    let p = probe_dataset(&data, &with, &[], &ProbeConfig::default());
    assert_eq!(p.depends_on, vec!["q4".to_string()], "{:?}", p.terms);
}

fn dataset(poses: &[SimPose], extra: &dyn Fn(&[f64]) -> Vector3<f64>) -> Dataset {
    Dataset {
        poses: Poses {
            q_deg: poses.iter().map(|p| p.q_deg.clone()).collect(),
            xyz_mm: poses
                .iter()
                .map(|p| p.measured_mm + extra(&p.q_deg))
                .collect(),
        },
        t_s: Some(poses.iter().map(|p| p.t_s).collect()),
        ..Dataset::default()
    }
}

fn diagnose_sim(seed: u64, extra: &dyn Fn(&[f64]) -> Vector3<f64>) -> (Diagnosis, Dataset) {
    let declared = katana450(200.0).unwrap();
    let cfg = SimConfig {
        seed,
        ..SimConfig::default()
    };
    let out = simulate(&declared, &cfg).unwrap();
    let val = dataset(&out.val, extra);
    let diag = diagnose(
        &declared,
        &dataset(&out.cal, extra),
        &val,
        &DiagnoseOptions::default(),
    )
    .unwrap();
    (diag, val)
}

/// A smooth error of the measured point that is no library effect (a fixed-direction error
/// `0.06 sin(1.5 q3)` mm along z, as a cable pulling the tool): structured, depends on q3, and
/// the hybrid model removes most of it on the held-out poses.
#[test]
fn katana_smooth_non_physical_error_is_structured_with_the_right_joint() {
    let bump = |q: &[f64]| Vector3::new(0.0, 0.0, 0.06 * (1.5 * q[2].to_radians()).sin());
    let (diag, val) = diagnose_sim(1, &bump);

    let r = &diag.report;
    assert!(r.unexplained.structured, "{}", r.table());
    assert_eq!(
        r.unexplained.depends_on,
        vec!["q3".to_string()],
        "{}",
        r.table()
    );
    assert!(r.unexplained.explainable_share > 0.2, "{}", r.table());
    let physical = diag.model.errors(&val).unwrap();
    let fitted = &diag.selection.last.fitted;
    let jac = jacobians(&diag.model, &val, fitted).unwrap();
    let h = hybrid_report(&diag.probe.model, &val, &physical, &jac, &[]);
    assert!(
        h.validation_hybrid.mean_mm < 0.8 * h.validation_physical.mean_mm,
        "hybrid {:.4} vs physical {:.4}",
        h.validation_hybrid.mean_mm,
        h.validation_physical.mean_mm
    );
}

#[test]
fn katana_clean_data_is_not_structured() {
    for seed in [1, 2, 3] {
        let (diag, _) = diagnose_sim(seed, &|_| Vector3::zeros());
        let u = &diag.report.unexplained;
        assert!(!u.structured, "seed {seed}: {}", diag.report.table());
        assert!(u.depends_on.is_empty() && u.explainable_share < 0.05);
    }
}
