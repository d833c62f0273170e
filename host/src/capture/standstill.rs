//! Standstills of a continuous joint log: the stretches where every joint's speed stays below
//! a threshold for at least a minimum duration.

/// Half-width of the time span a joint speed is taken over (s): speeds are differences over
/// about 0.1 s, so that encoder quantisation and a fast log's jitter do not look like motion.
pub const SPEED_HALF_SPAN_S: f64 = 0.05;

/// One standstill: joint-log sample indices `first..=last` and their times (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Standstill {
    pub first: usize,
    pub last: usize,
    pub start_s: f64,
    pub end_s: f64,
}

/// The largest joint speed at each sample (deg/s; mm/s for prismatic joints), a difference
/// over the samples about [`SPEED_HALF_SPAN_S`] before and after it.
pub fn joint_speeds(t_s: &[f64], q: &[Vec<f64>]) -> Vec<f64> {
    let n = t_s.len();
    let (mut a, mut b) = (0usize, 0usize);
    (0..n)
        .map(|k| {
            while a < k && t_s[a + 1] <= t_s[k] - SPEED_HALF_SPAN_S {
                a += 1;
            }
            if b < k {
                b = k;
            }
            while b + 1 < n && t_s[b] < t_s[k] + SPEED_HALF_SPAN_S {
                b += 1;
            }
            let (i, j) = (a.min(k), b.max(k));
            let dt = t_s[j] - t_s[i];
            if j == i || dt <= 0.0 {
                return 0.0;
            }
            q[i].iter()
                .zip(&q[j])
                .map(|(u, v)| (v - u).abs() / dt)
                .fold(0.0, f64::max)
        })
        .collect()
}

/// The standstills of a joint log (times increasing): runs of samples whose speed
/// ([`joint_speeds`]) is below `still_speed` lasting at least `min_duration_s`.
pub fn find_standstills(
    t_s: &[f64],
    q: &[Vec<f64>],
    still_speed: f64,
    min_duration_s: f64,
) -> Vec<Standstill> {
    let speed = joint_speeds(t_s, q);
    let mut out = Vec::new();
    let mut k = 0;
    while k < speed.len() {
        if speed[k] >= still_speed {
            k += 1;
            continue;
        }
        let first = k;
        while k + 1 < speed.len() && speed[k + 1] < still_speed {
            k += 1;
        }
        let last = k;
        if t_s[last] - t_s[first] >= min_duration_s {
            out.push(Standstill {
                first,
                last,
                start_s: t_s[first],
                end_s: t_s[last],
            });
        }
        k += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_dwells_joined_by_a_move_are_found() {
        // 100 Hz: still 0..2 s, a 1 s move of 30 deg, still 3..5 s
        let t: Vec<f64> = (0..=500).map(|k| f64::from(k) * 0.01).collect();
        let q: Vec<Vec<f64>> = t
            .iter()
            .map(|&t| {
                let s = ((t - 2.0).clamp(0.0, 1.0) * std::f64::consts::PI).cos();
                vec![15.0 * (1.0 - s), 1.0]
            })
            .collect();
        let s = find_standstills(&t, &q, 0.5, 1.0);
        assert_eq!(s.len(), 2, "{s:?}");
        assert!(
            s[0].start_s == 0.0 && (s[0].end_s - 2.0).abs() < 0.1,
            "{s:?}"
        );
        assert!(
            (s[1].start_s - 3.0).abs() < 0.1 && s[1].end_s == 5.0,
            "{s:?}"
        );
    }
}
