//! Error statistics of a set of poses (FORMATS.md "stats" object, thesis table 4.5).

use nalgebra::Vector3;

/// Statistics of the position errors `measured - model` over a set of poses. Field names are the
/// JSON keys of FORMATS.md; lengths in mm.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Stats {
    /// Number of poses.
    pub n: usize,
    /// Mean Euclidean error.
    pub mean_mm: f64,
    /// Root mean square of the Euclidean error.
    pub rms_mm: f64,
    /// Largest Euclidean error.
    pub max_mm: f64,
    /// Smallest Euclidean error.
    pub min_mm: f64,
    /// Mean |dX|.
    pub mean_abs_x_mm: f64,
    /// Mean |dY|.
    pub mean_abs_y_mm: f64,
    /// Mean |dZ|.
    pub mean_abs_z_mm: f64,
}

/// Per-axis extremes of `|dX|, |dY|, |dZ|` (thesis table 4.5 rows "Minimum" and "Maximum").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisExtremes {
    /// Smallest `|dX|, |dY|, |dZ|` (mm).
    pub min_abs_mm: [f64; 3],
    /// Largest `|dX|, |dY|, |dZ|` (mm).
    pub max_abs_mm: [f64; 3],
}

impl Stats {
    /// Statistics of the error vectors `errors_mm` (measured - model, one per pose). An empty set
    /// gives `n = 0` and zeros.
    pub fn from_errors(errors_mm: &[Vector3<f64>]) -> Self {
        let n = errors_mm.len();
        if n == 0 {
            return Self {
                n,
                mean_mm: 0.0,
                rms_mm: 0.0,
                max_mm: 0.0,
                min_mm: 0.0,
                mean_abs_x_mm: 0.0,
                mean_abs_y_mm: 0.0,
                mean_abs_z_mm: 0.0,
            };
        }
        let nf = n as f64;
        let norms: Vec<f64> = errors_mm.iter().map(|e| e.norm()).collect();
        let mean_abs = |k: usize| errors_mm.iter().map(|e| e[k].abs()).sum::<f64>() / nf;
        Self {
            n,
            mean_mm: norms.iter().sum::<f64>() / nf,
            rms_mm: (norms.iter().map(|v| v * v).sum::<f64>() / nf).sqrt(),
            max_mm: norms.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            min_mm: norms.iter().copied().fold(f64::INFINITY, f64::min),
            mean_abs_x_mm: mean_abs(0),
            mean_abs_y_mm: mean_abs(1),
            mean_abs_z_mm: mean_abs(2),
        }
    }
}

impl AxisExtremes {
    /// Per-axis extremes of `errors_mm`; zeros for an empty set.
    pub fn from_errors(errors_mm: &[Vector3<f64>]) -> Self {
        if errors_mm.is_empty() {
            return Self {
                min_abs_mm: [0.0; 3],
                max_abs_mm: [0.0; 3],
            };
        }
        let mut min_abs_mm = [f64::INFINITY; 3];
        let mut max_abs_mm = [0.0_f64; 3];
        for e in errors_mm {
            for k in 0..3 {
                min_abs_mm[k] = min_abs_mm[k].min(e[k].abs());
                max_abs_mm[k] = max_abs_mm[k].max(e[k].abs());
            }
        }
        Self {
            min_abs_mm,
            max_abs_mm,
        }
    }
}

/// Integrated autocorrelation time `1 + 2 sum_k rho_k` of a series (in its order): the number of
/// consecutive values that carry about as much information as one independent value. The sum
/// stops at the first lag whose correlation is below 0.05, or at a tenth of the series; at least
/// 1, and exactly 1 for fewer than 20 values or a constant series. Residuals sampled densely
/// along a path are serially correlated, so statistics that assume independent values (sigmas,
/// F-tests, t statistics) must count `n / tau` of them.
pub fn autocorrelation_time(series: &[f64]) -> f64 {
    let n = series.len();
    if n < 20 {
        return 1.0;
    }
    let mean = series.iter().sum::<f64>() / n as f64;
    let var = series.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
    if var.is_nan() || var <= 0.0 || var.is_infinite() {
        return 1.0;
    }
    let mut tau = 1.0;
    for lag in 1..n / 10 {
        let c = (0..n - lag)
            .map(|i| (series[i] - mean) * (series[i + lag] - mean))
            .sum::<f64>()
            / (n as f64 * var);
        if c < 0.05 {
            break;
        }
        tau += 2.0 * c;
    }
    tau
}

/// The median absolute deviation's normal-consistent scale of values about 0: `1.4826` times the
/// median of `|x|` (the upper one of an even count; 0 for none). For Gaussian values it is their
/// standard deviation; a few gross ones barely move it.
pub fn robust_sigma(values: impl IntoIterator<Item = f64>) -> f64 {
    let mut abs: Vec<f64> = values.into_iter().map(f64::abs).collect();
    abs.sort_by(f64::total_cmp);
    1.4826 * abs.get(abs.len() / 2).copied().unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The robust sigma is the upper median of |x| times 1.4826, 0 for no values, and a gross
    /// value does not move it much.
    #[test]
    fn robust_sigma_is_the_scaled_median_of_absolute_values() {
        assert_eq!(robust_sigma(Vec::new()), 0.0);
        // |x| sorted: 1, 2, 3, 4 -> upper median 3
        assert!((robust_sigma([-4.0, 1.0, -2.0, 3.0]) - 1.4826 * 3.0).abs() < 1e-12);
        let clean = robust_sigma([1.0, -1.0, 2.0, -2.0, 1.5]);
        let gross = robust_sigma([1.0, -1.0, 2.0, -2.0, 1000.0]);
        assert!((clean - 1.4826 * 1.5).abs() < 1e-12, "{clean}");
        assert!((gross - 1.4826 * 2.0).abs() < 1e-12, "{gross}");
    }

    /// White noise has tau about 1; an AR(1) series with coefficient a has
    /// tau = (1 + a) / (1 - a) (here 3 for a = 0.5), to the estimator's truncation.
    #[test]
    fn autocorrelation_time_of_white_and_ar1_series() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let normal = Normal::new(0.0, 1.0).unwrap();
        let white: Vec<f64> = (0..20_000).map(|_| normal.sample(&mut rng)).collect();
        let t = autocorrelation_time(&white);
        assert!((1.0..1.1).contains(&t), "white: {t}");
        let mut x = 0.0;
        let ar: Vec<f64> = (0..20_000)
            .map(|_| {
                x = 0.5 * x + normal.sample(&mut rng);
                x
            })
            .collect();
        let t = autocorrelation_time(&ar);
        assert!((2.6..3.2).contains(&t), "AR(1) 0.5: {t}");
        assert_eq!(autocorrelation_time(&[1.0; 50]), 1.0);
        assert_eq!(autocorrelation_time(&white[..10]), 1.0);
    }

    #[test]
    fn hand_computed_values() {
        // Errors (3,4,0) |5|, (0,0,-1) |1|, (-2,0,0) |2|.
        let e = [
            Vector3::new(3.0, 4.0, 0.0),
            Vector3::new(0.0, 0.0, -1.0),
            Vector3::new(-2.0, 0.0, 0.0),
        ];
        let s = Stats::from_errors(&e);
        assert_eq!(s.n, 3);
        assert!((s.mean_mm - 8.0 / 3.0).abs() < 1e-12);
        assert!((s.rms_mm - (30.0_f64 / 3.0).sqrt()).abs() < 1e-12);
        assert_eq!(s.max_mm, 5.0);
        assert_eq!(s.min_mm, 1.0);
        assert!((s.mean_abs_x_mm - 5.0 / 3.0).abs() < 1e-12);
        assert!((s.mean_abs_y_mm - 4.0 / 3.0).abs() < 1e-12);
        assert!((s.mean_abs_z_mm - 1.0 / 3.0).abs() < 1e-12);
        let x = AxisExtremes::from_errors(&e);
        assert_eq!(x.min_abs_mm, [0.0, 0.0, 0.0]);
        assert_eq!(x.max_abs_mm, [3.0, 4.0, 1.0]);
    }

    #[test]
    fn json_keys_are_the_contract() {
        let s = Stats::from_errors(&[Vector3::new(1.0, 0.0, 0.0)]);
        let v = serde_json::to_value(s).unwrap();
        let mut keys: Vec<_> = v.as_object().unwrap().keys().cloned().collect();
        keys.sort();
        assert_eq!(
            keys,
            [
                "max_mm",
                "mean_abs_x_mm",
                "mean_abs_y_mm",
                "mean_abs_z_mm",
                "mean_mm",
                "min_mm",
                "n",
                "rms_mm"
            ]
        );
    }

    #[test]
    fn empty_set_is_zero() {
        assert_eq!(Stats::from_errors(&[]).n, 0);
        assert_eq!(Stats::from_errors(&[]).mean_mm, 0.0);
    }
}
