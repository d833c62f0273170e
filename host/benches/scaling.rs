//! Input size: the CSV header check on 1e5 and 1e6 columns, and the URDF import of a chain of
//! 1e4 and 1e5 revolute joints with a link mass each (parse, chain, model with masses): both
//! linear in their input.

use criterion::{criterion_group, criterion_main, Criterion};
use rigctl::io::table::Table;
use rigctl::urdf::{import_chain_with_masses, ImportOptions, Urdf};

/// A chain of `n` revolute joints, each link with a mass.
fn long_urdf(n: usize) -> String {
    let mut s = String::from("<robot name=\"long\">\n<link name=\"l0\"/>\n");
    for k in 1..=n {
        s.push_str(&format!(
            "<link name=\"l{k}\"><inertial><mass value=\"0.1\"/><origin xyz=\"0.01 0 0\"/></inertial></link>\n\
             <joint name=\"j{k}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{k}\"/>\
             <origin xyz=\"0.001 0 0.001\" rpy=\"0 0.1 0\"/><axis xyz=\"0 0 1\"/>\
             <limit lower=\"-1\" upper=\"1\"/></joint>\n",
            k - 1
        ));
    }
    s.push_str("</robot>\n");
    s
}

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
