//! The spike rule of a residual along a traced path ([`super::declared::trim_outliers`]): a
//! sample is a spike in a measured component when its residual departs from the running median
//! over the neighbouring samples (+- [`OUTLIER_HALF_WINDOW`]) by more than [`OUTLIER_SIGMAS`]
//! robust standard deviations of the departures (`1.4826 median |departure|`,
//! [`robust_sigma`]). A missing effect changes the residual smoothly along the path and is no
//! spike.

/// Outlier threshold of the spike rule, in robust standard deviations: the gross-error rule's.
pub use crate::calib::outliers::OUTLIER_SIGMAS;
use crate::calib::stats::robust_sigma;

/// Half width (samples) of the running median of the spike rule.
pub const OUTLIER_HALF_WINDOW: usize = 5;

/// Whether each sample of `components` (the measured components of the residual of every
/// sample, in path order) is a spike in some component: component `c` is the series of the
/// samples that measure it.
pub fn in_components(components: &[Vec<f64>]) -> Vec<bool> {
    let mut spikes = vec![false; components.len()];
    let slots = components.iter().map(Vec::len).max().unwrap_or(0);
    for slot in 0..slots {
        let (samples, series): (Vec<usize>, Vec<f64>) = components
            .iter()
            .enumerate()
            .filter_map(|(k, c)| c.get(slot).map(|v| (k, *v)))
            .unzip();
        for (k, bad) in samples.into_iter().zip(running_median_spikes(&series)) {
            spikes[k] |= bad;
        }
    }
    spikes
}

/// Whether each value of a series departs from the running median of its neighbours by more
/// than [`OUTLIER_SIGMAS`] robust standard deviations of the departures.
fn running_median_spikes(series: &[f64]) -> Vec<bool> {
    let n = series.len();
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    let dep: Vec<f64> = (0..n)
        .map(|i| {
            let lo = i.saturating_sub(OUTLIER_HALF_WINDOW);
            let hi = (i + OUTLIER_HALF_WINDOW + 1).min(n);
            series[i] - median(&mut series[lo..hi].to_vec())
        })
        .collect();
    let sigma = robust_sigma(dep.iter().copied());
    dep.iter()
        .map(|d| sigma > 0.0 && d.abs() > OUTLIER_SIGMAS * sigma)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth residual (a slow sine, as a missing effect leaves) with uniform noise of
    /// +-0.01 and one sample of one component 0.1 off: that sample alone is a spike (its
    /// departure is about 17 robust sigmas, the largest other about 2.7); the component a
    /// sample does not measure (every seventh sample is partial) is passed over, and a series
    /// without departures has none.
    #[test]
    fn one_spike_on_a_smooth_residual() {
        let mut state: u64 = 12345;
        let mut noise = || {
            state = (state * 1_103_515_245 + 12_345) % (1 << 31);
            0.01 * (state as f64 / f64::from(1u32 << 31) * 2.0 - 1.0)
        };
        let n = 80;
        let mut comps: Vec<Vec<f64>> = (0..n)
            .map(|k| {
                let m = if k % 7 == 3 { 1 } else { 2 };
                (0..m)
                    .map(|c| 0.2 * (k as f64 * 0.02 + c as f64).sin() + noise())
                    .collect()
            })
            .collect();
        comps[32][1] += 0.1;
        let spikes = in_components(&comps);
        let found: Vec<usize> = (0..n).filter(|&k| spikes[k]).collect();
        assert_eq!(found, vec![32]);
        assert!(in_components(&vec![vec![1.0, 2.0]; 20]).iter().all(|s| !s));
        assert!(in_components(&[]).is_empty());
    }
}
