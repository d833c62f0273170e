//! `rigctl plan` on the Katana: 10 000 uniform candidates (plus the 210 structured ones), N = 30:
//! candidates, Jacobians, the random baseline (400 draws) and its spread, the approximate
//! optimum with its certificate and the sensitivity climbs that extend the pool, weighted-A
//! greedy + exchange (from the rounded optimum, the greedy start and 1 random restart), the
//! continuous refinement (3 sweeps) (the defaults); and with the greedy start only.

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
