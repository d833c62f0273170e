//! The criteria of `rigctl plan` compared on the Katana, for N poses (default 12) and seeds
//! 1..=S (default 8):
//!
//! * `ratio` (`median_sigma_ratio`, the bar's reading): median over parameters of planned /
//!   random expected sigma, random = the per-parameter median of 400 random designs of N
//!   uniform candidates (never the structured extremes), same noise; its spread against 25
//!   other single random designs (p10 / p50 / p90, pooled over the seeds);
//! * `direct` (the words read literally): the median over parameters of the planned
//!   sigmas over the same median of a random design, the latter averaged (mean) or taken as the
//!   median over the 25 draws (mixed units: degrees and millimetres as plain numbers).
//!
//! `cargo run --release -p rigctl --example plan_criteria -- [N] [SEEDS] [CANDIDATES]
//! [RESTARTS] [REFINE_SWEEPS] [STRUCTURED 0|1] [CRITERIA e.g. agid] [RANDOM_DRAWS]`

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
    let (sweeps, structured) = (arg(5, 3), arg(6, 1) != 0);
    let n_draws = arg(8, rigctl::plan::DEFAULT_RANDOM_DRAWS);
    let kinds: Vec<Criterion> = std::env::args()
        .nth(7)
        .unwrap_or_else(|| "agid".into())
        .chars()
        .filter_map(|c| Criterion::parse(&c.to_string()))
        .collect();
    let declared = katana450(KATANA_TOOL_MM)?;
    println!("N = {n}, seeds 1-{seeds}, {candidates} candidates, {restarts} restarts, {sweeps} refinement sweeps, structured {structured}");
    println!("| criterion | ratio per seed | ratio median | worst | vs single draws p10 / p50 / p90 | direct (mean draw) median / worst | direct (median draw) median / worst | condition number |");
    println!("|---|---|---|---|---|---|---|---|");
    for kind in kinds {
        let (mut ratios, mut draws, mut conds) = (Vec::new(), Vec::new(), Vec::new());
        let (mut dmean, mut dmed) = (Vec::new(), Vec::new());
        let (mut opt_ratio, mut eff) = (Vec::new(), Vec::new());
        for seed in 1..=seeds as u64 {
            let mut cfg = PlanConfig::new(&declared, n);
            cfg.seed = seed;
            cfg.criterion = kind;
            cfg.candidates = candidates;
            cfg.restarts = restarts;
            cfg.refine_sweeps = Some(sweeps);
            cfg.structured = Some(structured);
            cfg.random_draws = n_draws;
            let p = plan(&declared, &cfg, None)?;
            ratios.push(p.median_sigma_ratio);
            draws.extend(p.ratio_per_draw.iter().copied());
            conds.push(p.planned.condition_number);
            dmean.push(p.direct.ratio_to_mean());
            dmed.push(p.direct.ratio_to_median());
            if let Some(o) = &p.optimum {
                opt_ratio.push(o.median_sigma_ratio);
                eff.push(o.efficiency);
            }
        }
        let per: Vec<String> = ratios.iter().map(|r| format!("{r:.4}")).collect();
        let worst = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        println!(
            "| {} | {} | {:.3} | {:.3} | {:.3} / {:.3} / {:.3} | {:.3} / {:.3} | {:.3} / {:.3} | {:.1} |",
            kind.letter(),
            per.join(" "),
            median(&ratios),
            worst(&ratios),
            quantile(&draws, 0.1),
            quantile(&draws, 0.5),
            quantile(&draws, 0.9),
            median(&dmean),
            worst(&dmean),
            median(&dmed),
            worst(&dmed),
            median(&conds)
        );
        let per: Vec<String> = opt_ratio.iter().map(|r| format!("{r:.3}")).collect();
        println!(
            "  best possible on the candidates (approximate optimum): median sigma ratio per seed {} (median {:.3}); plan efficiency median {:.3}, min {:.3}",
            per.join(" "),
            median(&opt_ratio),
            median(&eff),
            eff.iter().copied().fold(f64::INFINITY, f64::min)
        );
    }
    Ok(())
}
