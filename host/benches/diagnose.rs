//! Runtime of `diagnose` on a simulated session of 118 calibration + 60 validation poses (the
//! ISO 9283 sequence), clean and with one undeclared encoder harmonic; and on the partial
//! measurements of the low-cost rig (ideal fused samples of the circle sheet, held out on the
//! line sheet, about 600 samples each) with the same harmonic. The UR5 with the whole library:
//! the laser-tracker data (1000 poses) and simulated sessions of 1000 and 20 000 poses. The
//! repeatability floor's grouping of repeated poses on 1e4 to 1e6 poses.

use criterion::{criterion_group, criterion_main, Criterion};
use rigctl::calib::measured::PosePoints;
use rigctl::calib::MeasuredSet;
use rigctl::diagnose::{diagnose, DiagnoseOptions};
use rigctl::model::{katana450, KATANA_PENCIL_TOOL_MM};
use rigctl::sim::effects::parse_effect;
use rigctl::sim::session::{simulate_session, SessionConfig, SessionPath};
use rigctl::sim::simulate::{simulate, SimConfig};

fn bench(c: &mut Criterion) {
    let declared = katana450(200.0).expect("preset");
    let mut g = c.benchmark_group("diagnose_118_60");
    g.sample_size(10);
    for (name, effects) in [
        ("clean", vec![]),
        ("harmonic_j2_h1", vec!["encoder_harmonic:j2:h1=0.03,40"]),
    ] {
        let cfg = SimConfig {
            effects: effects
                .iter()
                .map(|e| parse_effect(e).expect("effect"))
                .collect(),
            ..SimConfig::default()
        };
        let out = simulate(&declared, &cfg).expect("simulate");
        let (cal, val) = (
            MeasuredSet::from_sim_poses(&out.cal),
            MeasuredSet::from_sim_poses(&out.val),
        );
        g.bench_function(name, |b| {
            b.iter(|| {
                diagnose(&declared, &cal, &val, &DiagnoseOptions::default()).expect("diagnose")
            })
        });
    }
    g.finish();

    let pencil = katana450(KATANA_PENCIL_TOOL_MM).expect("preset");
    let sheet = |path| {
        let cfg = SessionConfig {
            path,
            effects: vec![parse_effect("encoder_harmonic:j2:h1=0.05,30").expect("effect")],
            ..SessionConfig::default()
        };
        let s = simulate_session(&pencil, &cfg).expect("session");
        let f = s.ideal_fused_samples(&pencil, 0.003, 1).expect("samples");
        MeasuredSet::from_fused(&f)
            .and_then(|d| d.with_inertial_moments(&pencil))
            .expect("dataset")
    };
    let (cal, val) = (sheet(SessionPath::Circle), sheet(SessionPath::Line));
    let mut g = c.benchmark_group("diagnose_samples_circle_line");
    g.sample_size(10);
    g.bench_function("harmonic_j2_h1", |b| {
        b.iter(|| diagnose(&pencil, &cal, &val, &DiagnoseOptions::default()).expect("diagnose"))
    });
    g.finish();
}

/// The probe alone on 1000 and 20 000 random 6-joint poses: noise plus a q2 function, with a
/// 12-parameter physical Jacobian to annihilate (random, as only its cost matters here).
fn bench_probe(c: &mut Criterion) {
    use nalgebra::{DMatrix, Vector3};
    use rand::{Rng, SeedableRng};
    use rigctl::diagnose::probe::{probe_dataset, ProbeConfig};
    let mut g = c.benchmark_group("diagnose_probe");
    g.sample_size(10);
    for n in [1000usize, 20_000] {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let q: Vec<Vec<f64>> = (0..n)
            .map(|_| (0..6).map(|_| rng.gen_range(-120.0..120.0)).collect())
            .collect();
        let r: Vec<Vector3<f64>> = q
            .iter()
            .map(|q| {
                Vector3::new(
                    rng.gen_range(-0.02..0.02) + 0.03 * q[1].to_radians().sin(),
                    rng.gen_range(-0.02..0.02),
                    rng.gen_range(-0.02..0.02),
                )
            })
            .collect();
        let jac: Vec<DMatrix<f64>> = (0..n)
            .map(|_| DMatrix::from_fn(3, 12, |_, _| rng.gen_range(-1.0..1.0)))
            .collect();
        let data = MeasuredSet::from_poses(PosePoints {
            q_deg: q,
            xyz_mm: vec![Vector3::zeros(); n],
        });
        g.bench_function(format!("poses_{n}"), |b| {
            b.iter(|| probe_dataset(&data, &r, &jac, &ProbeConfig::default()))
        });
    }
    g.finish();
}

/// A simulated UR5 session of `n` random poses within +-170 deg (joint 2 in -170..-10) plus 20
/// held out: the truth has a base tilt, a joint-2 first harmonic and a joint-3 gear-ratio error,
/// the tracker noise is 0.015 mm per coordinate.
fn ur5_session(n: usize, seed: u64) -> (rigctl::model::Model, MeasuredSet, MeasuredSet) {
    use nalgebra::Vector3;
    use rand::{Rng, SeedableRng};
    use rand_distr::{Distribution, Normal};
    use rigctl::model::{transmission::JointTerms, ur5, Tilt};
    let declared = ur5().expect("preset");
    let mut truth = declared.clone();
    for (name, v) in [
        ("base_rx", 0.02),
        ("base_ry", -0.015),
        ("enc_j2_h1_sin", 0.03),
        ("enc_j2_h1_cos", -0.01),
    ] {
        truth.set_param(name, v).expect("param");
    }
    let mut t = JointTerms::zeros(6);
    t.scale[2] = 2e-4;
    truth.set_transmission(t);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 0.015).expect("sigma");
    let mut set = |m: usize| {
        let q: Vec<Vec<f64>> = (0..m)
            .map(|_| {
                (0..6)
                    .map(|j| {
                        if j == 1 {
                            rng.gen_range(-170.0..-10.0)
                        } else {
                            rng.gen_range(-170.0..170.0)
                        }
                    })
                    .collect()
            })
            .collect();
        let q_eff = truth.effective_pose_joints(&q, None).expect("joints");
        let xyz: Vec<Vector3<f64>> = q_eff
            .iter()
            .map(|q| {
                truth.fk(q, Tilt::Off).expect("fk").position_mm
                    + Vector3::from_fn(|_, _| noise.sample(&mut rng))
            })
            .collect();
        MeasuredSet::from_poses(PosePoints {
            q_deg: q,
            xyz_mm: xyz,
        })
    };
    let cal = set(n);
    let val = set(20);
    (declared, cal, val)
}

/// The whole library on the UR5: the laser-tracker data (1000 grid poses, 20 held out; skipped
/// without the shared data) and simulated sessions of 1000 and 20 000 poses.
fn bench_ur5(c: &mut Criterion) {
    let mut g = c.benchmark_group("diagnose_ur5");
    g.sample_size(10);
    let opts = DiagnoseOptions {
        instrument_mm: Some(0.015),
        ..DiagnoseOptions::default()
    };
    if let Some(dir) = rigctl::shared_dir().map(|d| d.join("data/real/ur5_laser_tracker")) {
        if dir.is_dir() {
            let mut model = rigctl::model::ur5().expect("preset");
            for (name, v) in ["tool_dx", "tool_dy", "tool_dz"]
                .iter()
                .zip(rigctl::model::UR5_SMR_TOOL_MM)
            {
                model.set_param(name, v).expect("tool");
            }
            let cal = MeasuredSet::read(&dir.join("grid.csv"), &model).expect("grid.csv");
            let val = MeasuredSet::read(&dir.join("random.csv"), &model).expect("random.csv");
            g.bench_function("tracker_1000", |b| {
                b.iter(|| diagnose(&model, &cal, &val, &opts).expect("diagnose"))
            });
        }
    }
    for n in [1000usize, 20_000] {
        let (model, cal, val) = ur5_session(n, 3);
        g.bench_function(format!("sim_{n}"), |b| {
            b.iter(|| diagnose(&model, &cal, &val, &opts).expect("diagnose"))
        });
    }
    g.finish();
}

/// The repeatability floor's grouping of repeated poses on 1e4, 1e5 and 1e6 poses, each pose
/// measured twice (random Katana joints): `O(n log n)`.
fn bench_repeatability(c: &mut Criterion) {
    use nalgebra::Vector3;
    use rand::{Rng, SeedableRng};
    use rigctl::diagnose::floor::repeatability_mm;
    let mut g = c.benchmark_group("diagnose_repeatability");
    g.sample_size(10);
    for n in [10_000usize, 100_000, 1_000_000] {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut q: Vec<Vec<f64>> = (0..n / 2)
            .map(|_| (0..5).map(|_| rng.gen_range(-170.0..170.0)).collect())
            .collect();
        q.extend(q.clone());
        let data = MeasuredSet::from_poses(PosePoints {
            q_deg: q,
            xyz_mm: vec![Vector3::zeros(); n],
        });
        g.bench_function(format!("poses_{n}"), |b| b.iter(|| repeatability_mm(&data)));
    }
    g.finish();
}

criterion_group!(benches, bench, bench_probe, bench_ur5, bench_repeatability);
criterion_main!(benches);
