//! Calibration speed: the 118-pose Katana identification (target < 5 ms) and the 1000-pose UR5
//! laser-tracker fit (target < 100 ms; skipped when the shared data is absent).

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigctl::calib::accumulate::PositionNormalProblem;
use rigctl::calib::default_selection;
use rigctl::calib::identifiability::DEFAULT_RTOL;
use rigctl::calib::lm::LmConfig;
use rigctl::calib::measured::PosePoints;
use rigctl::calib::normal::{Normal, NormalProblem};
use rigctl::calib::position_fit::fit_parameters;
use rigctl::calib::MeasuredSet;
use rigctl::model::{katana450, ur5, Tilt, UR5_SMR_TOOL_MM};

fn katana_poses() -> PosePoints {
    let mut truth = katana450(200.0).unwrap();
    for (n, v) in [
        ("dth2", 0.03),
        ("al3", 0.02),
        ("dth4", -0.05),
        ("be3", 0.01),
    ] {
        truth.set_param(n, v).unwrap();
    }
    let mut rng = ChaCha8Rng::seed_from_u64(118);
    let mut p = PosePoints::default();
    for _ in 0..118 {
        let q: Vec<f64> = truth
            .joint_limits()
            .iter()
            .map(|l| rng.gen_range(l[0]..l[1]))
            .collect();
        let x = truth.position_mm(&q, Tilt::Static).unwrap();
        p.xyz_mm
            .push(x + Vector3::new(rng.gen_range(-0.01..0.01), rng.gen_range(-0.01..0.01), 0.0));
        p.q_deg.push(q);
    }
    p
}

fn bench(c: &mut Criterion) {
    let lm = LmConfig::default();
    let nominal = katana450(200.0).unwrap();
    let cal = katana_poses();
    let sel = default_selection(&nominal, false);
    c.bench_function("katana_118_tilting", |b| {
        b.iter(|| fit_parameters(&nominal, &cal, &sel, true, &lm, DEFAULT_RTOL, None).unwrap())
    });
    c.bench_function("katana_118_standard", |b| {
        b.iter(|| fit_parameters(&nominal, &cal, &sel, false, &lm, DEFAULT_RTOL, None).unwrap())
    });
    // One LM linearisation (normal equations of 118 poses with tilting, 12 parameters).
    let x =
        nalgebra::DVector::from_iterator(sel.len(), sel.iter().map(|&c| nominal.params()[c].value));
    let mut problem = PositionNormalProblem::new(&nominal, &cal, sel.clone(), true);
    let mut eq = Normal::zeros(sel.len());
    c.bench_function("katana_118_lm_iteration_normal_equations", |b| {
        b.iter(|| problem.normal(&x, &mut eq).unwrap())
    });
    let Some(dir) = rigctl::shared_dir()
        .map(|d| d.join("data/real/ur5_laser_tracker"))
        .filter(|d| d.is_dir())
    else {
        eprintln!("SKIP ur5_1000: shared data absent");
        return;
    };
    let mut model = ur5().unwrap();
    for (name, v) in ["tool_dx", "tool_dy", "tool_dz"]
        .iter()
        .zip(UR5_SMR_TOOL_MM)
    {
        model.set_param(name, v).unwrap();
    }
    let grid = MeasuredSet::read(&dir.join("grid.csv"), &model)
        .unwrap()
        .poses;
    let sel = default_selection(&model, true);
    let mut g = c.benchmark_group("ur5");
    g.sample_size(20);
    g.bench_function("ur5_1000_standard", |b| {
        b.iter(|| fit_parameters(&model, &grid, &sel, false, &lm, DEFAULT_RTOL, None).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
