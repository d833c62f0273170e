//! Exact pose files of a model for the tests: random joint values within its limits and the
//! model's own tool point (no noise).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigctl::model::{Model, Tilt};

/// Writes `n` poses `q1..qN,x,y,z` (deg, mm; 9 decimals) of `truth` at joint values drawn
/// uniformly within its limits (seed `seed`), the point by `truth` with `tilt`; `header` lines
/// (e.g. a `# comment`) come first.
pub fn write_exact_poses(
    truth: &Model,
    tilt: Tilt<'_>,
    path: &std::path::Path,
    n: usize,
    seed: u64,
    header: &str,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let cols: Vec<String> = (1..=truth.n_joints()).map(|j| format!("q{j}")).collect();
    let mut text = format!("{header}{},x,y,z\n", cols.join(","));
    for _ in 0..n {
        let q: Vec<f64> = truth
            .joint_limits()
            .iter()
            .map(|l| rng.gen_range(l[0]..l[1]))
            .collect();
        let p = truth.position_mm(&q, tilt).unwrap();
        let qs: Vec<String> = q.iter().map(|v| format!("{v:.9}")).collect();
        text.push_str(&format!(
            "{},{:.9},{:.9},{:.9}\n",
            qs.join(","),
            p.x,
            p.y,
            p.z
        ));
    }
    std::fs::write(path, text).unwrap();
}
