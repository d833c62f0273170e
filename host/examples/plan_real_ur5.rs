//! `rigctl plan --candidates-from` on real data: the UR5 laser-tracker set
//! (shared/data/real/ur5_laser_tracker). From the 1000 measured grid poses, N are chosen by the
//! planner (criteria given, default `ai`) or drawn at random (25 draws); each subset is
//! calibrated (`standard` with the base, as for the full set) and judged on the 20 random test
//! poses, which no subset contains. Prints a Markdown table: held-out mean error (mm), planned
//! and the median / p10-p90 of the random subsets, and the full 1000-pose calibration.
//!
//! `cargo run --release -p rigctl --example plan_real_ur5 -- [CRITERIA] [DRAWS]`

use rand::seq::index::sample;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rigctl::calib::{calibrate, CalibrateOptions, MeasuredSet, Method};
use rigctl::model::{ur5, Model, UR5_SMR_TOOL_MM};
use rigctl::plan::metrics::median;
use rigctl::plan::{plan, quantile, Criterion, PlanConfig};

fn held_out(
    model: &Model,
    cal: &MeasuredSet,
    val: &MeasuredSet,
) -> Result<f64, Box<dyn std::error::Error>> {
    let opts = CalibrateOptions {
        method: Method::Standard,
        base: true,
        ..Default::default()
    };
    let out = calibrate(model, cal, Some(val), &opts)?;
    Ok(out
        .report
        .validation
        .ok_or("no validation statistics")?
        .after
        .mean_mm)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let kinds: Vec<Criterion> = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "ai".into())
        .chars()
        .filter_map(|c| Criterion::parse(&c.to_string()))
        .collect();
    let draws: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(25);
    let dir = rigctl::shared_dir()
        .ok_or("../shared is absent: no real data")?
        .join("data/real/ur5_laser_tracker");
    let mut model = ur5()?;
    for (name, v) in ["tool_dx", "tool_dy", "tool_dz"]
        .iter()
        .zip(UR5_SMR_TOOL_MM)
    {
        model.set_param(name, v)?;
    }
    let cal = MeasuredSet::read(&dir.join("grid.csv"), &model)?;
    let val = MeasuredSet::read(&dir.join("random.csv"), &model)?;
    println!(
        "full {} grid poses: held-out mean {:.4} mm",
        cal.len(),
        held_out(&model, &cal, &val)?
    );
    let heads: Vec<String> = kinds
        .iter()
        .map(|k| format!("planned {} (mm)", k.letter()))
        .collect();
    println!(
        "| N | {} | random median (mm) | random p10 / p90 (mm) |",
        heads.join(" | ")
    );
    println!("|---|{}---|---|", "---|".repeat(kinds.len()));
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for n in [12usize, 16, 20, 30, 40, 60] {
        let mut cells = Vec::new();
        for &kind in &kinds {
            let mut cfg = PlanConfig::new(&model, n);
            cfg.criterion = kind;
            cfg.pool_q = Some(cal.poses.q_deg.clone());
            cfg.base = true;
            let p = plan(&model, &cfg, None)?;
            let idx = p.pool_index.ok_or("no pool index")?;
            cells.push(format!("{:.4}", held_out(&model, &cal.subset(&idx), &val)?));
        }
        let mut random = Vec::new();
        for _ in 0..draws {
            let idx = sample(&mut rng, cal.len(), n).into_vec();
            random.push(held_out(&model, &cal.subset(&idx), &val)?);
        }
        println!(
            "| {n} | {} | {:.4} | {:.4} / {:.4} |",
            cells.join(" | "),
            median(&random),
            quantile(&random, 0.1),
            quantile(&random, 0.9)
        );
    }
    Ok(())
}
