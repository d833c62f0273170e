//! Transmission effects on the joint angles (FORMATS.md `joint_scale`, `joint_coupling`,
//! `hysteresis`): what the joint really turns by, given the commanded angles and the direction
//! from which each joint approached the pose (pose order). Used by `simulate` (the truth) and
//! `diagnose` (the candidates).

/// Joint-motion threshold (deg, or mm for a prismatic joint) below which a joint did not move
/// between two poses.
pub const APPROACH_MIN_MOVE: f64 = 1e-9;

/// Direction in which each joint last moved before each pose (FORMATS.md pose order): the
/// poses are visited in the order of `t_s` when given (ties in file order), else in file order;
/// for joint i at pose k the sign of the last non-zero change of `q_i` up to k (+1 up, -1
/// down), 0 for the first pose and while the joint has not moved yet.
pub fn approach_directions(q_deg: &[Vec<f64>], t_s: Option<&[f64]>) -> Vec<Vec<f64>> {
    let n = q_deg.len();
    let mut order: Vec<usize> = (0..n).collect();
    if let Some(t) = t_s.filter(|t| t.len() == n) {
        order.sort_by(|&a, &b| t[a].total_cmp(&t[b]));
    }
    let nj = q_deg.first().map_or(0, Vec::len);
    let mut out = vec![vec![0.0; nj]; n];
    let mut dir = vec![0.0; nj];
    let mut prev: Option<&Vec<f64>> = None;
    for &k in &order {
        if let Some(p) = prev {
            for (j, d) in dir.iter_mut().enumerate() {
                let delta =
                    q_deg[k].get(j).copied().unwrap_or(0.0) - p.get(j).copied().unwrap_or(0.0);
                if delta.abs() > APPROACH_MIN_MOVE {
                    *d = delta.signum();
                }
            }
        }
        out[k] = dir.clone();
        prev = Some(&q_deg[k]);
    }
    out
}

/// The transmission terms of joint angles (FORMATS.md `joint_scale`, `joint_coupling`,
/// `hysteresis`): `q_eff_i = q_i + s_i q_i + sum_k c_ik q_k + b_i d_i`, with `d_i` the
/// direction of approach of joint i (+1, -1, 0). `scale`, `coupling` (rows i, columns k) and
/// `hysteresis_deg` may be empty (no term); returns the increments per joint.
pub fn transmission_increments(
    q_deg: &[f64],
    approach: &[f64],
    scale: &[f64],
    coupling: &[Vec<f64>],
    hysteresis_deg: &[f64],
) -> Vec<f64> {
    (0..q_deg.len())
        .map(|i| {
            let s = scale.get(i).copied().unwrap_or(0.0) * q_deg[i];
            let c: f64 = coupling
                .get(i)
                .map(|row| row.iter().zip(q_deg).map(|(c, q)| c * q).sum())
                .unwrap_or(0.0);
            let h = hysteresis_deg.get(i).copied().unwrap_or(0.0)
                * approach.get(i).copied().unwrap_or(0.0);
            s + c + h
        })
        .collect()
}
