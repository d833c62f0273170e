//! The criteria of `rigctl plan` compared on the Katana: for N poses (default 12) and seeds
//! 1..=S (default 8), the median over parameters of planned / random expected sigma (random =
//! the per-parameter median of 25 random designs of N candidates from the same pool, same
//! noise), and its spread against 25 other single random designs (p10 / p50 / p90).
//!
//! `cargo run --release -p rigctl --example plan_criteria -- [N] [SEEDS] [CANDIDATES] [RESTARTS]`

use rigctl::model::{katana450, KATANA_TOOL_MM};
use rigctl::plan::metrics::median;
use rigctl::plan::{plan, quantile, Criterion, PlanConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |k: usize, d: usize| -> usize {
        std::env::args()
            .nth(k)
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let (n, seeds, candidates, restarts) = (arg(1, 12), arg(2, 8), arg(3, 5000), arg(4, 1));
    let declared = katana450(KATANA_TOOL_MM)?;
    println!("| criterion | median ratio per seed | median | worst | per-draw p10 / p50 / p90 (pooled) | condition number (median) |");
    println!("|---|---|---|---|---|---|");
    for kind in [Criterion::D, Criterion::A, Criterion::G, Criterion::I] {
        let (mut ratios, mut draws, mut conds) = (Vec::new(), Vec::new(), Vec::new());
        for seed in 1..=seeds as u64 {
            let mut cfg = PlanConfig::new(&declared, n);
            cfg.seed = seed;
            cfg.criterion = kind;
            cfg.candidates = candidates;
            cfg.restarts = restarts;
            let p = plan(&declared, &cfg, None)?;
            ratios.push(p.median_sigma_ratio);
            draws.extend(p.ratio_per_draw.iter().copied());
            conds.push(p.planned.condition_number);
        }
        let per: Vec<String> = ratios.iter().map(|r| format!("{r:.3}")).collect();
        println!(
            "| {} | {} | {:.3} | {:.3} | {:.3} / {:.3} / {:.3} | {:.1} |",
            kind.letter(),
            per.join(" "),
            median(&ratios),
            ratios.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            quantile(&draws, 0.1),
            quantile(&draws, 0.5),
            quantile(&draws, 0.9),
            median(&conds)
        );
    }
    Ok(())
}
