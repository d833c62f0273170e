//! Gross errors in measured poses (a broken tracker beam, the wrong marker, a typo), found the
//! same way by `calibrate` and `diagnose`: fit, take the error of every pose under the fit, and
//! flag the poses whose error is inconsistent with the others; refit without them and look
//! again, until the flagged set no longer changes ([`trim`]).
//!
//! The rule: a pose is flagged when its error exceeds [`OUTLIER_SIGMAS`] times the robust
//! per-coordinate scale of the errors (the median error norm over the median of the chi
//! distribution with as many degrees of freedom as the pose measures coordinates), or of the
//! known floor when that is larger. For Gaussian errors at the scale, a 3-D pose passes 5 sigma
//! with probability 1.5e-5, so a clean set of 1000 poses has a flag about once in 70 sets. A
//! gross error also stands apart from the other errors: only the poses above a jump of at least
//! [`GAP_RATIO`] in the sorted errors, beyond the threshold, are flagged, so that the continuous
//! tail of a missing effect (whose poses carry the evidence `diagnose` needs) stays in. When
//! more than [`MAX_OUTLIER_SHARE`] of the poses would be flagged, the errors are not a few
//! gross ones but heavy tails (a missing effect, or the wrong model): nothing is flagged and
//! [`Trimmed::note`] says so.

use serde::Serialize;

/// Flag threshold in robust standard deviations per coordinate.
pub const OUTLIER_SIGMAS: f64 = 5.0;
/// Largest share of the poses that may be flagged as gross errors.
pub const MAX_OUTLIER_SHARE: f64 = 0.1;
/// A gross error stands apart: the flagged poses are those above the first jump of at least
/// this factor between consecutive sorted errors beyond the threshold (a missing effect or a
/// step of the declared law leaves a continuous tail of errors, not a jump).
pub const GAP_RATIO: f64 = 2.0;
/// Most fit-and-flag rounds of [`trim`].
pub const MAX_ROUNDS: usize = 6;

/// A pose a report names, with its error: the first keys of the `outliers` and `extrapolated`
/// entries of the `calibrate` and `diagnose` JSON (FORMATS.md).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PoseError {
    /// `"cal"` or `"val"`.
    pub file: String,
    /// Line of the pose in its file (as in error messages), when read from a file.
    pub line: Option<usize>,
    /// The pose's `id`, when the file has them.
    pub id: Option<String>,
    /// The pose's error under the final model, mm.
    pub error_mm: f64,
    /// Index of the pose in its set.
    #[serde(skip)]
    pub index: usize,
}

impl PoseError {
    /// Pose `index` of set `file` with its error; its line and id are filled by who read the
    /// file.
    pub fn new(file: &str, index: usize, error_mm: f64) -> Self {
        Self {
            file: file.to_string(),
            line: None,
            id: None,
            error_mm,
            index,
        }
    }

    /// Names the pose by its line and id in `data`, the set its index is into.
    pub fn label(&mut self, data: &super::measured::MeasuredSet) {
        self.line = data.lines.as_ref().and_then(|l| l.get(self.index).copied());
        self.id = data.ids.as_ref().and_then(|i| i.get(self.index).cloned());
    }

    /// The pose's line in its file (`?` when not read from one), then its id when it has one:
    /// `6 (id D4_2_1)`, as the text outputs name it.
    pub fn line_and_id(&self) -> String {
        let line = self.line.map_or_else(|| "?".to_string(), |l| l.to_string());
        match &self.id {
            Some(id) => format!("{line} (id {id})"),
            None => line,
        }
    }
}

/// A pose left out as a gross error (the `outliers` entries of the `calibrate` and `diagnose`
/// JSON, FORMATS.md).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutlierReport {
    /// The pose and its error.
    #[serde(flatten)]
    pub pose: PoseError,
    /// Why it was flagged.
    pub note: String,
}

/// Median of the chi distribution with `dims` degrees of freedom (a pose's measured
/// coordinates: 3 per point, 6 for a tree's two tips): the values of 1-3 coordinates
/// tabulated, beyond the root of the chi-square median found by bisection on its distribution
/// function ([`chi2_cdf`]).
fn chi_median(dims: usize) -> f64 {
    match dims {
        0 | 1 => 0.674_489_75,
        2 => 1.177_410_02,
        3 => 1.538_172_7,
        k => {
            let k = k as f64;
            let (mut lo, mut hi) = (0.0, 2.0 * k + 20.0);
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if chi2_cdf(mid, k) < 0.5 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            (0.5 * (lo + hi)).sqrt()
        }
    }
}

/// `P(X <= x)` of a chi-square variable with `k` (a whole number) degrees of freedom: the
/// regularised lower incomplete gamma `P(k/2, x/2)` by its power series, `Gamma(k/2)` by
/// recursion from `Gamma(1) = 1` or `Gamma(1/2) = sqrt(pi)`.
fn chi2_cdf(x: f64, k: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let (a, y) = (0.5 * k, 0.5 * x);
    let mut gamma_a = if k.round() as i64 % 2 == 0 {
        1.0
    } else {
        std::f64::consts::PI.sqrt()
    };
    let mut z = if k.round() as i64 % 2 == 0 { 1.0 } else { 0.5 };
    while z < a - 0.25 {
        gamma_a *= z;
        z += 1.0;
    }
    // P(a, y) = y^a e^-y / Gamma(a + 1) * sum_n y^n / ((a + 1) ... (a + n))
    let (mut term, mut sum) = (1.0, 1.0);
    for n in 1..1000 {
        term *= y / (a + n as f64);
        sum += term;
        if term < 1e-17 * sum {
            break;
        }
    }
    (a * y.ln() - y).exp() / (a * gamma_a) * sum
}

/// Robust per-coordinate scale of per-pose error norms (`dims` coordinates each).
pub fn robust_sigma_mm(norms_mm: &[f64], dims: usize) -> f64 {
    let mut v: Vec<f64> = norms_mm.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    median / chi_median(dims)
}

/// The threshold (mm, on the error norm) of the rule at robust scale `sigma_mm` and floor
/// `floor_mm`.
pub fn threshold_mm(sigma_mm: f64, floor_mm: Option<f64>) -> f64 {
    OUTLIER_SIGMAS * sigma_mm.max(floor_mm.unwrap_or(0.0))
}

/// Whether `e` is beyond `threshold` (a NaN error is).
fn beyond(e: f64, threshold: f64) -> bool {
    !matches!(
        e.partial_cmp(&threshold),
        Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
    )
}

/// The poses whose error is beyond `threshold_mm` and above a jump of [`GAP_RATIO`] between
/// consecutive sorted errors (the jump itself beyond the threshold), ascending.
pub fn beyond_gap(errors_mm: &[f64], threshold_mm: f64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..errors_mm.len()).collect();
    // non-finite errors sort last: they are flagged whenever anything is
    order.sort_by(|&a, &b| {
        let (x, y) = (errors_mm[a], errors_mm[b]);
        match (x.is_finite(), y.is_finite()) {
            (true, true) => x.total_cmp(&y),
            (a_f, b_f) => b_f.cmp(&a_f),
        }
    });
    let start = order
        .iter()
        .position(|&k| beyond(errors_mm[k], threshold_mm))
        .unwrap_or(order.len());
    for i in start..order.len() {
        let e = errors_mm[order[i]];
        let below = if i == 0 { 0.0 } else { errors_mm[order[i - 1]] };
        if !e.is_finite() || e >= GAP_RATIO * below {
            let mut out: Vec<usize> = order[i..].to_vec();
            out.sort_unstable();
            return out;
        }
    }
    Vec::new()
}

/// Result of [`trim`].
#[derive(Debug, Clone, PartialEq)]
pub struct Trimmed {
    /// Indices of the flagged poses, ascending.
    pub flagged: Vec<usize>,
    /// Error norm of every pose under the last fit, mm.
    pub errors_mm: Vec<f64>,
    /// The threshold in force at the end, mm.
    pub threshold_mm: f64,
    /// Robust per-coordinate scale of the kept poses' errors, mm.
    pub sigma_mm: f64,
    /// Set when the rule was not applied (heavy tails, see the module doc) or did not settle.
    pub note: Option<String>,
}

/// The poses to keep: those not in `flagged` (ascending) among `n`.
pub fn kept(n: usize, flagged: &[usize]) -> Vec<usize> {
    (0..n)
        .filter(|k| flagged.binary_search(k).is_err())
        .collect()
}

/// Iterative trimming of `n` poses of `dims` coordinates: `errors_after_fit(kept)` fits on the
/// poses `kept` and returns the error norm (mm) of **every** pose under that fit. Starts from
/// all poses; stops when the flagged set repeats (at most [`MAX_ROUNDS`] rounds).
pub fn trim<E>(
    n: usize,
    dims: usize,
    floor_mm: Option<f64>,
    mut errors_after_fit: impl FnMut(&[usize]) -> Result<Vec<f64>, E>,
) -> Result<Trimmed, E> {
    let mut flagged: Vec<usize> = Vec::new();
    let mut seen: Vec<Vec<usize>> = Vec::new();
    let max_flagged = ((MAX_OUTLIER_SHARE * n as f64).floor() as usize).max(1);
    for _ in 0..MAX_ROUNDS {
        let keep = kept(n, &flagged);
        let errors = errors_after_fit(&keep)?;
        let kept_errors: Vec<f64> = keep.iter().map(|&k| errors[k]).collect();
        let sigma = robust_sigma_mm(&kept_errors, dims);
        let threshold = threshold_mm(sigma, floor_mm);
        let next = beyond_gap(&errors, threshold);
        if next.len() > max_flagged {
            let note = format!(
                "{} of {n} poses lie beyond {OUTLIER_SIGMAS} robust sigmas ({threshold:.4} mm): \
                 heavy tails rather than a few gross errors (the model may lack an effect), so \
                 none is left out",
                next.len()
            );
            let all = errors_after_fit(&(0..n).collect::<Vec<_>>())?;
            let sigma = robust_sigma_mm(&all, dims);
            return Ok(Trimmed {
                flagged: Vec::new(),
                threshold_mm: threshold_mm(sigma, floor_mm),
                errors_mm: all,
                sigma_mm: sigma,
                note: Some(note),
            });
        }
        if next == flagged {
            return Ok(Trimmed {
                flagged,
                errors_mm: errors,
                threshold_mm: threshold,
                sigma_mm: sigma,
                note: None,
            });
        }
        if seen.contains(&next) {
            // a cycle between sets: keep the union's complement fitted once more
            let mut union = next.clone();
            union.extend(flagged.iter().copied());
            union.sort_unstable();
            union.dedup();
            let errors = errors_after_fit(&kept(n, &union))?;
            return Ok(Trimmed {
                flagged: union,
                errors_mm: errors,
                threshold_mm: threshold,
                sigma_mm: sigma,
                note: Some(
                    "the flagged set alternated between rounds; the union is left out".into(),
                ),
            });
        }
        seen.push(flagged);
        flagged = next;
    }
    let errors = errors_after_fit(&kept(n, &flagged))?;
    let keep = kept(n, &flagged);
    let sigma = robust_sigma_mm(&keep.iter().map(|&k| errors[k]).collect::<Vec<_>>(), dims);
    Ok(Trimmed {
        flagged,
        errors_mm: errors,
        threshold_mm: threshold_mm(sigma, floor_mm),
        sigma_mm: sigma,
        note: Some(format!(
            "the flagged set did not settle in {MAX_ROUNDS} rounds"
        )),
    })
}

/// Poses of a set judged against a threshold from elsewhere (the held-out poses, or the
/// calibration poses re-checked after a change of model, against the calibration's
/// `threshold_mm`): flagged when their error norm exceeds that threshold **and**
/// [`OUTLIER_SIGMAS`] robust sigmas of this set's own errors (inconsistent with the floor and
/// with the other poses: held-out poses lie farther from the fit than the fitted ones, so the
/// calibration's scale alone would flag the tail of a clean set); none when more than
/// [`MAX_OUTLIER_SHARE`] of them would be (the set differs as a whole). Returns the flagged
/// indices and the threshold applied.
pub fn flag_set_against(errors_mm: &[f64], threshold_mm: f64) -> (Vec<usize>, f64) {
    let own = threshold_mm_of(errors_mm);
    let thr = threshold_mm.max(own);
    let flagged = beyond_gap(errors_mm, thr);
    let max_flagged = ((MAX_OUTLIER_SHARE * errors_mm.len() as f64).floor() as usize).max(1);
    if flagged.len() > max_flagged {
        (Vec::new(), thr)
    } else {
        (flagged, thr)
    }
}

/// [`OUTLIER_SIGMAS`] robust sigmas of 3-D error norms.
fn threshold_mm_of(errors_mm: &[f64]) -> f64 {
    threshold_mm(robust_sigma_mm(errors_mm, 3), None)
}

/// A held-out pose the model extrapolates to (the `extrapolated` entries of the `calibrate`
/// JSON): its prediction uncertainty is larger than the calibration residual. Reported, never
/// left out.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Extrapolated {
    /// The pose (of `"val"`) and its error.
    #[serde(flatten)]
    pub pose: PoseError,
    /// One standard deviation (per coordinate) of the model's prediction at the pose, from the
    /// fit's covariance, mm.
    pub prediction_sd_mm: f64,
    /// The joints (`q6`) whose reading lies outside the calibration poses' range (by more than
    /// [`RANGE_MARGIN`] of it): what the fit never saw, whatever its covariance says.
    pub outside_joints: Vec<String>,
}

/// Share of a joint's calibration range by which a held-out reading may lie outside it before
/// the pose counts as extrapolated: well outside (a quarter of the range), where the covariance
/// of a fit says nothing about the model's own errors; a pose just past the range of random
/// calibration poses is still judged by its prediction uncertainty.
pub const RANGE_MARGIN: f64 = 0.25;

/// The joints (`q<i>`, 1-based) of every pose of `at` whose reading lies outside the range of
/// the readings `cal` by more than [`RANGE_MARGIN`] of that range.
pub fn outside_range(cal: &[Vec<f64>], at: &[Vec<f64>]) -> Vec<Vec<String>> {
    let nj = cal.first().map_or(0, Vec::len);
    let range: Vec<(f64, f64)> = (0..nj)
        .map(|j| {
            let (lo, hi) = cal
                .iter()
                .filter_map(|q| q.get(j))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
            let m = RANGE_MARGIN * (hi - lo).max(0.0);
            (lo - m, hi + m)
        })
        .collect();
    at.iter()
        .map(|q| {
            q.iter()
                .zip(&range)
                .enumerate()
                .filter(|(_, (v, (lo, hi)))| *v < lo || *v > hi)
                .map(|(j, _)| format!("q{}", j + 1))
                .collect()
        })
        .collect()
}

/// Held-out poses judged with the model's own prediction uncertainty: pose `k` is flagged when
/// its error norm exceeds [`OUTLIER_SIGMAS`] times `sqrt(s^2 + p_k^2)` (per coordinate), `s` the
/// larger of the calibration's robust scale `sigma_mm` and this set's own, `p_k` the prediction
/// standard deviation at the pose (`prediction_sd_mm`), and stands apart from the other poses
/// (the gap rule on the normalised errors); none when more than [`MAX_OUTLIER_SHARE`] would be.
/// A pose the fit extrapolates to badly has a large `p_k` and is not a gross error. Returns the
/// flagged indices and every pose's threshold (mm).
pub fn flag_held_out(
    errors_mm: &[f64],
    prediction_sd_mm: &[f64],
    sigma_mm: f64,
) -> (Vec<usize>, Vec<f64>) {
    flag_held_out_dims(errors_mm, prediction_sd_mm, sigma_mm, 3)
}

/// [`flag_held_out`] on poses that measure `dims` coordinates each (a tree's pose: 3 per tip),
/// the robust scale of the held-out errors read with as many degrees of freedom.
pub fn flag_held_out_dims(
    errors_mm: &[f64],
    prediction_sd_mm: &[f64],
    sigma_mm: f64,
    dims: usize,
) -> (Vec<usize>, Vec<f64>) {
    let s = sigma_mm.max(robust_sigma_mm(errors_mm, dims));
    let scale: Vec<f64> = (0..errors_mm.len())
        .map(|k| {
            let p = prediction_sd_mm.get(k).copied().unwrap_or(0.0);
            (s * s + if p.is_finite() { p * p } else { f64::INFINITY }).sqrt()
        })
        .collect();
    let z: Vec<f64> = errors_mm
        .iter()
        .zip(&scale)
        .map(|(e, sc)| if *sc > 0.0 { e / sc } else { *e })
        .collect();
    let flagged = beyond_gap(&z, OUTLIER_SIGMAS);
    let max_flagged = ((MAX_OUTLIER_SHARE * errors_mm.len() as f64).floor() as usize).max(1);
    let thresholds = scale.iter().map(|sc| OUTLIER_SIGMAS * sc).collect();
    if flagged.len() > max_flagged {
        (Vec::new(), thresholds)
    } else {
        (flagged, thresholds)
    }
}

/// The report entries of held-out poses flagged by [`flag_held_out`].
pub fn held_out_reports(
    flagged: &[usize],
    errors_mm: &[f64],
    judged_mm: &[f64],
    thresholds_mm: &[f64],
    prediction_sd_mm: &[f64],
) -> Vec<OutlierReport> {
    flagged
        .iter()
        .map(|&k| OutlierReport {
            pose: PoseError::new("val", k, errors_mm[k]),
            note: format!(
                "error {:.4} mm > {:.4} mm ({OUTLIER_SIGMAS} sigmas of the calibration residual and \
                 of the model's prediction uncertainty at this pose, {:.4} mm) and apart from the \
                 other held-out poses' errors: a gross error",
                judged_mm[k], thresholds_mm[k], prediction_sd_mm[k]
            ),
        })
        .collect()
}

/// The report entries of `flagged` poses of set `file` (`"cal"`, `"val"`): `errors_mm` under the
/// final model, `judged_mm` under the model that judged them against `threshold_mm`.
pub fn reports(
    file: &str,
    flagged: &[usize],
    errors_mm: &[f64],
    judged_mm: &[f64],
    threshold_mm: f64,
) -> Vec<OutlierReport> {
    flagged
        .iter()
        .map(|&k| OutlierReport {
            pose: PoseError::new(file, k, errors_mm[k]),
            note: format!(
                "error {:.4} mm > {threshold_mm:.4} mm ({OUTLIER_SIGMAS} robust sigmas) and apart from the \
                 other poses' errors: a gross error, left out of every fit",
                judged_mm[k]
            ),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn robust_sigma_of_chi3_norms_is_the_coordinate_sigma() {
        // norms of 3-D Gaussian vectors with sigma 2: the median norm is 2 * 1.5382
        let norms = vec![2.0 * 1.538_172_7; 11];
        assert!((robust_sigma_mm(&norms, 3) - 2.0).abs() < 1e-9);
    }

    #[test]
    fn trim_flags_gross_errors_and_settles() {
        // 100 poses at 0.01 mm, three off by 1-3 mm; the "fit" does not move
        let mut e: Vec<f64> = (0..100)
            .map(|k| 0.01 * (1.0 + 0.5 * ((k as f64) * 0.7).sin()))
            .collect();
        e[5] = 1.0;
        e[50] = 2.0;
        e[77] = 3.0;
        let t = trim(100, 3, None, |_| Ok::<_, ()>(e.clone())).unwrap();
        assert_eq!(t.flagged, vec![5, 50, 77]);
        assert!(t.note.is_none());
    }

    #[test]
    fn a_continuous_tail_is_not_flagged() {
        // errors rising smoothly to 10 x the typical one: no jump, nothing flagged
        let e: Vec<f64> = (0..100)
            .map(|k| 0.01 * (1.0 + 9.0 * (k as f64 / 99.0).powi(8)))
            .collect();
        assert!(beyond_gap(&e, 0.05).is_empty());
        let mut g = e.clone();
        g[10] = 0.5;
        assert_eq!(beyond_gap(&g, 0.05), vec![10]);
    }

    /// The chi medians: the 1-3 coordinate values as before, a tree's 6, and the
    /// approximation continuous with the table.
    #[test]
    fn chi_medians_of_several_points() {
        assert!((chi_median(1) - 0.674_489_75).abs() < 1e-7);
        assert!((chi_median(3) - 1.538_172_7).abs() < 1e-6);
        // chi-square medians (bisection of the regularised gamma, 1e-10 elsewhere)
        for (k, m) in [
            (3, 2.365_973_884_4),
            (4, 3.356_693_980_0),
            (6, 5.348_120_627_4),
            (9, 8.342_832_692_3),
            (10, 9.341_817_765_6),
        ] {
            if k > 3 {
                assert!((chi_median(k).powi(2) - m).abs() < 1e-8, "{k}");
            }
            assert!((chi2_cdf(m, k as f64) - 0.5).abs() < 1e-9, "{k}");
        }
    }

    #[test]
    fn heavy_tails_are_not_gross_errors() {
        let e: Vec<f64> = (0..100)
            .map(|k| if k % 4 == 0 { 1.0 } else { 0.01 })
            .collect();
        let t = trim(100, 3, None, |_| Ok::<_, ()>(e.clone())).unwrap();
        assert!(t.flagged.is_empty());
        assert!(t.note.is_some());
    }

    #[test]
    fn held_out_flags_only_a_few() {
        let mut e = vec![0.01; 60];
        e[3] = 2.0;
        assert_eq!(flag_set_against(&e, 0.1).0, vec![3]);
        let all_worse = vec![0.5; 60];
        assert!(flag_set_against(&all_worse, 0.1).0.is_empty());
    }

    /// A held-out pose far off is a gross error where the model predicts well, and not where
    /// its prediction is uncertain (extrapolation); joints outside the calibration range are
    /// named.
    #[test]
    fn held_out_extrapolation_is_not_a_gross_error() {
        let mut e = vec![0.015; 60];
        e[3] = 2.0;
        e[7] = 2.0;
        let mut sd = vec![0.001; 60];
        sd[7] = 1.0;
        let (flagged, thr) = flag_held_out(&e, &sd, 0.01);
        assert_eq!(flagged, vec![3]);
        assert!(thr[7] > 2.0 && thr[3] < 0.1, "{thr:?}");
        let cal = vec![vec![0.0, 10.0], vec![100.0, 20.0]];
        let at = vec![vec![50.0, 15.0], vec![120.0, 25.0], vec![-30.0, 30.0]];
        let out = outside_range(&cal, &at);
        assert!(out[0].is_empty());
        assert_eq!(out[1], ["q2"]);
        assert_eq!(out[2], ["q1", "q2"]);
    }
}
