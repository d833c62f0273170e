//! Input size: the CSV header check on 1e5 and 1e6 columns, and the URDF import of a chain of
//! 1e4 and 1e5 revolute joints with a link mass each (parse, chain, model with masses): both
//! linear in their input.

use criterion::{criterion_group, criterion_main, Criterion};
use rigctl::io::table::Table;
use rigctl::urdf::{import_chain_with_masses, ImportOptions, Urdf};

#[path = "../tests/integration/common/long_urdf.rs"]
mod long_urdf;
use long_urdf::long_urdf;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("csv_header");
    g.sample_size(10);
    for n in [100_000usize, 1_000_000] {
        let header: Vec<String> = (0..n).map(|k| format!("c{k}")).collect();
        let text = format!("{}\n{}\n", header.join(","), vec!["1"; n].join(","));
        g.bench_function(format!("columns_{n}"), |b| {
            b.iter(|| Table::parse(&text, "wide.csv").expect("table"))
        });
    }
    g.finish();
    let mut g = c.benchmark_group("urdf_import");
    g.sample_size(10);
    for n in [10_000usize, 100_000] {
        let text = long_urdf(n);
        let tip = format!("l{n}");
        g.bench_function(format!("joints_{n}"), |b| {
            b.iter(|| {
                let urdf = Urdf::parse(&text, "long.urdf").expect("urdf");
                import_chain_with_masses(
                    &urdf,
                    &ImportOptions {
                        base_link: None,
                        tip_link: &tip,
                        tool_mm: [0.0; 3],
                    },
                )
                .expect("import")
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
