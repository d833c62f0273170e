//! The mean of one marker's samples at a standstill, moving and outlying samples left out: a
//! sample farther from the coordinate-wise median than `k` times the samples' own scatter is
//! rejected (the scatter from the median distance: for a normal scatter of sigma per coordinate
//! the distance is chi-distributed with 3 degrees of freedom, median 1.5382 sigma).

/// Median of the chi distribution with 3 degrees of freedom (units of sigma).
pub const CHI3_MEDIAN: f64 = 1.538_2;
/// Smallest scatter the rejection assumes (mm): an instrument's rounding can make the median
/// distance zero.
pub const MIN_SCATTER_MM: f64 = 1e-4;

/// One marker's robust mean.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobustMean {
    pub mean_mm: [f64; 3],
    /// One-sigma scatter per coordinate of the kept samples about their mean (mm).
    pub spread_mm: f64,
    pub used: usize,
    pub rejected: usize,
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The robust mean of `points` (at least one); `k` the rejection threshold in sigmas.
pub fn robust_mean(points: &[[f64; 3]], k: f64) -> Option<RobustMean> {
    if points.is_empty() {
        return None;
    }
    let centre = [0, 1, 2].map(|c| median(&mut points.iter().map(|p| p[c]).collect::<Vec<_>>()));
    let dist = |p: &[f64; 3]| {
        (0..3)
            .map(|c| (p[c] - centre[c]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let mut d: Vec<f64> = points.iter().map(dist).collect();
    let sigma = (median(&mut d) / CHI3_MEDIAN).max(MIN_SCATTER_MM);
    let kept: Vec<&[f64; 3]> = points.iter().filter(|p| dist(p) <= k * sigma).collect();
    let n = kept.len();
    if n == 0 {
        return None;
    }
    let mean_mm = [0, 1, 2].map(|c| kept.iter().map(|p| p[c]).sum::<f64>() / n as f64);
    let ss: f64 = kept
        .iter()
        .map(|p| (0..3).map(|c| (p[c] - mean_mm[c]).powi(2)).sum::<f64>())
        .sum();
    let spread_mm = if n > 1 {
        (ss / (3.0 * (n - 1) as f64)).sqrt()
    } else {
        0.0
    };
    Some(RobustMean {
        mean_mm,
        spread_mm,
        used: n,
        rejected: points.len() - n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outliers_are_left_out_and_the_spread_is_the_noise() {
        let mut pts: Vec<[f64; 3]> = (0..200)
            .map(|k| {
                let f = f64::from(k);
                // deterministic noise of about 0.05 mm per coordinate
                [
                    0.07 * (f * 1.3).sin(),
                    0.07 * (f * 2.7).cos(),
                    0.07 * (f * 0.9).sin(),
                ]
            })
            .map(|e| [100.0 + e[0], 200.0 + e[1], 300.0 + e[2]])
            .collect();
        pts.push([150.0, 200.0, 300.0]);
        pts.push([100.0, 200.0, 312.0]);
        let m = robust_mean(&pts, 4.0).unwrap();
        assert_eq!((m.used, m.rejected), (200, 2));
        assert!((m.mean_mm[0] - 100.0).abs() < 0.01, "{m:?}");
        assert!(m.spread_mm > 0.03 && m.spread_mm < 0.07, "{m:?}");
        assert!(robust_mean(&[], 4.0).is_none());
    }
}
