//! Model throughput: FK with static tilting plus the joint and parameter Jacobians for one pose,
//! and a batch of 118 poses (the size of the thesis's calibration + validation sets).

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigctl::model::{katana450, Data, Model, Tilt, Wrt, KATANA_GEOMETRIC_PARAMS};

fn poses(model: &Model, n: usize) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    (0..n)
        .map(|_| {
            model
                .joint_limits()
                .iter()
                .map(|[lo, hi]| rng.gen_range(*lo..*hi))
                .collect()
        })
        .collect()
}

fn bench_model(c: &mut Criterion) {
    let model = katana450(200.0).unwrap();
    let geometric: Vec<usize> = KATANA_GEOMETRIC_PARAMS
        .iter()
        .map(|n| model.param_index(n).unwrap())
        .collect();
    let batch = poses(&model, 118);
    let q = batch[0].clone();
    c.bench_function("fk_tilt_one_pose", |b| {
        b.iter(|| model.fk(black_box(&q), Tilt::Static).unwrap())
    });
    c.bench_function("fk_tilt_joint_jacobian_one_pose", |b| {
        b.iter(|| model.joint_jacobian(black_box(&q), Tilt::Static).unwrap())
    });
    c.bench_function("fk_tilt_param_jacobian_12_one_pose", |b| {
        b.iter(|| {
            model
                .param_jacobian(black_box(&q), Tilt::Static, &geometric)
                .unwrap()
        })
    });
    c.bench_function("fk_tilt_param_jacobian_12_batch_118", |b| {
        b.iter(|| {
            for q in &batch {
                black_box(model.param_jacobian(q, Tilt::Static, &geometric).unwrap());
            }
        })
    });
    // The reusable workspace (no allocation per pose).
    let wrt: Vec<Wrt> = geometric.iter().map(|&i| Wrt::Param(i)).collect();
    let mut d = Data::new(&model);
    c.bench_function("workspace_fk_tilt_one_pose", |b| {
        b.iter(|| model.fk_with(&mut d, black_box(&q), Tilt::Static).unwrap())
    });
    c.bench_function("workspace_fk_no_tilt_one_pose", |b| {
        b.iter(|| model.fk_with(&mut d, black_box(&q), Tilt::Off).unwrap())
    });
    c.bench_function("workspace_fk_tilt_param_jacobian_12_one_pose", |b| {
        b.iter(|| {
            model
                .jacobian_with(&mut d, black_box(&q), Tilt::Static, &wrt)
                .unwrap()
        })
    });
    c.bench_function("fk_no_tilt_batch_118", |b| {
        b.iter(|| {
            for q in &batch {
                black_box(model.fk(q, Tilt::Off).unwrap());
            }
        })
    });
}

criterion_group!(benches, bench_model);
criterion_main!(benches);
