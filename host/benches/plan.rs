//! `rigctl plan` on the Katana: 10 000 candidates, N = 30 (candidates, Jacobians, A-optimal
//! greedy + exchange with 1 random restart (the default), random baseline and its spread), and with
//! the greedy start only.

use criterion::{criterion_group, criterion_main, Criterion};
use rigctl::model::{katana450, KATANA_TOOL_MM};
use rigctl::plan::{plan, PlanConfig};

fn bench(c: &mut Criterion) {
    let model = katana450(KATANA_TOOL_MM).expect("katana preset");
    let mut cfg = PlanConfig::new(&model, 30);
    cfg.candidates = 10_000;
    let mut g = c.benchmark_group("plan");
    g.sample_size(10);
    g.bench_function("katana_10000_candidates_n30", |b| {
        b.iter(|| plan(&model, &cfg, None).expect("plan"))
    });
    cfg.restarts = 0;
    g.bench_function("katana_10000_candidates_n30_greedy_start_only", |b| {
        b.iter(|| plan(&model, &cfg, None).expect("plan"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
