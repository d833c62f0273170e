//! `rigctl plan --candidates-from`: the plan is a subset of the configurations given (no
//! random or structured candidates, no refinement, no climbs), with `--base`; on the real UR5
//! laser-tracker grid too; and bad input.

use crate::common;
use crate::common::spawn::output;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigctl::model::katana450;
use rigctl::plan::{plan, PlanConfig};

/// `rigctl plan --robot katana450 --n 12 --candidates-from POOL --out OUT` and `extra`.
fn plan_from(
    pool: &std::path::Path,
    out: &std::path::Path,
    extra: &[&str],
) -> std::process::Output {
    let (pool, out) = (pool.to_str().unwrap(), out.to_str().unwrap());
    let mut args = vec![
        "plan",
        "--robot",
        "katana450",
        "--n",
        "12",
        "--candidates-from",
        pool,
        "--out",
        out,
    ];
    args.extend_from_slice(extra);
    output(&args)
}

fn joints(csv: &str) -> Vec<Vec<f64>> {
    csv.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').take(5).map(|v| v.parse().unwrap()).collect())
        .collect()
}

#[test]
fn the_plan_is_a_subset_of_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let pool = dir.path().join("pool.csv");
    let model = katana450(200.0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut text = String::from("q1,q2,q3,q4,q5\n");
    for _ in 0..400 {
        let q: Vec<String> = model
            .joint_limits()
            .iter()
            .map(|[lo, hi]| format!("{:.6}", rng.gen_range(lo + 2.0..hi - 2.0)))
            .collect();
        text.push_str(&q.join(","));
        text.push('\n');
    }
    std::fs::write(&pool, &text).unwrap();
    let (out, json) = (dir.path().join("p.csv"), dir.path().join("p.json"));
    let o = plan_from(&pool, &out, &["--json", json.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let given = joints(&text);
    let planned = joints(&std::fs::read_to_string(&out).unwrap());
    assert_eq!(planned.len(), 12);
    for q in &planned {
        assert!(
            given
                .iter()
                .any(|g| g.iter().zip(q).all(|(a, b)| (a - b).abs() < 1e-6)),
            "{q:?} is not in the file"
        );
    }
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // the table keeps some of the 400 out; no structured ones, no refinement, no climbs
    let kept = doc["candidates"].as_u64().unwrap();
    assert!(kept > 12 && kept <= 400, "{kept}");
    assert_eq!(doc["structured_candidates"], 0);
    assert_eq!(doc["refinement"]["moves"], 0);
    assert_eq!(doc["optimum"]["added_configurations"], 0);
    assert!(doc["optimum"]["efficiency"].as_f64().unwrap() <= 1.0 + 1e-9);
    assert!(doc["median_sigma_ratio"].as_f64().unwrap() < 0.8);
}

#[test]
fn bad_pool_input_is_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let pool = dir.path().join("pool.csv");
    std::fs::write(&pool, "q1,q2,q3,q4,q5\n0,10,20,30,40\n0,10,x,30,40\n").unwrap();
    let out = dir.path().join("p.csv");
    let o = plan_from(&pool, &out, &[]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("pool.csv:3") && err.contains("q3"), "{err}");
    assert!(!out.exists(), "nothing half-written");
    // fewer usable configurations than poses asked
    std::fs::write(&pool, "q1,q2,q3,q4,q5\n0,10,20,30,40\n").unwrap();
    let o = plan_from(&pool, &out, &[]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!out.exists());
    // refinement would leave the file's configurations
    let o = plan_from(&pool, &out, &["--refine-sweeps", "2"]);
    assert_eq!(o.status.code(), Some(2));
}

/// The real UR5 grid (1000 measured poses) as the pool, with the base frame as `calibrate
/// --base` identifies it: 20 distinct measured poses whose expected sigmas are well below those
/// of 20 random grid poses.
#[test]
fn ur5_grid_as_the_pool() {
    let Some((model, cal, _)) = common::ur5_tracker("ur5_grid_as_the_pool") else {
        return;
    };
    let mut cfg = PlanConfig::new(&model, 20);
    cfg.pool_q = Some(cal.poses.q_deg.clone());
    cfg.base = true;
    let p = plan(&model, &cfg, None).unwrap();
    let idx = p.pool_index.clone().unwrap();
    let mut sorted = idx.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(sorted.len(), 20, "distinct poses");
    for (k, &i) in idx.iter().enumerate() {
        assert_eq!(p.poses[k].q_deg, cal.poses.q_deg[i]);
    }
    assert!(
        p.parameters.iter().any(|n| n == "base_x"),
        "{:?}",
        p.parameters
    );
    eprintln!(
        "UR5 grid pool: median sigma ratio {:.3}",
        p.median_sigma_ratio
    );
    assert!(p.median_sigma_ratio < 0.75, "{}", p.median_sigma_ratio);
}
