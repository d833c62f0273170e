//! The start of every diagnosis: the declared model fitted as `calibrate --method tilting`
//! ([`declared_fit`]), and on a traced path the samples whose declared-fit residual is a spike
//! left out first ([`trim_outliers`]).

use super::decide::DecideConfig;
use super::extended::{self, ExtModel, ExtendedFit, Unknown};
use super::DiagnoseError;
use crate::calib::fit::{Fit, Split};
use crate::calib::position_fit::fit_parameters;
use crate::calib::{default_selection, MeasuredSet};
use crate::model::{Model, ModelError};

/// The declared fit (as `calibrate --method tilting`) as an extended fit, and the requested
/// unknowns.
pub fn declared_fit(
    model: &Model,
    cal: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<(Fit<ExtModel, Unknown>, Vec<Unknown>), DiagnoseError> {
    let selection = default_selection(model, false);
    let tilt = model.has_tilt();
    let requested: Vec<Unknown> = selection.iter().copied().map(Unknown::Param).collect();
    if cal.directions.is_some() || cal.moments_kgfm.is_some() {
        // partial measurements (or moments in motion): the same identification on the extended
        // problem, which projects on the measured directions
        let fit = extended::fit(
            &ExtModel::new(model.clone()),
            cal,
            &requested,
            &cfg.lm,
            cfg.rtol,
            false,
        )?;
        return Ok((fit, requested));
    }
    let f = fit_parameters(model, &cal.poses, &selection, tilt, &cfg.lm, cfg.rtol, None)?;
    let mut ext = ExtModel::new(f.model.clone());
    ext.tilt = tilt;
    // the residual of the extended model (its own evaluation of every pose)
    let rss_mm2 = ext.errors(cal)?.iter().map(|e| e.norm_squared()).sum();
    // never worse than the model as given: the geometric fit does not see every term of a model
    // file (its compliance, say), so it can end above where the input already is; the input is
    // then the declared fit, unchanged
    let mut start = ExtModel::new(model.clone());
    start.tilt = tilt;
    let start_rss: f64 = start.errors(cal)?.iter().map(|e| e.norm_squared()).sum();
    if start_rss < rss_mm2 {
        // nothing is requested beyond the model as given: a candidate is then tested with its
        // own unknowns only (not with every geometric parameter freed again beside it, which
        // the input already beats)
        let split = Split {
            fitted: Vec::new(),
            fixed: requested,
            unidentifiable: f.unidentifiable.clone(),
            rank: f.rank,
        };
        return Ok((
            Fit::unfitted(start, split, start_rss, cal.n_residuals()),
            Vec::new(),
        ));
    }
    let fit = Fit {
        rss_mm2,
        n_residuals: cal.n_residuals(),
        ..f.map(|_| ext, Unknown::Param)
    };
    Ok((fit, requested))
}

/// Outlier threshold of [`trim_outliers`], in robust standard deviations.
pub const OUTLIER_SIGMAS: f64 = 5.0;
/// Half width (samples) of the running median of [`trim_outliers`].
pub const OUTLIER_HALF_WINDOW: usize = 5;

/// The declared fit ([`declared_fit`]) of the calibration set, after leaving out the samples
/// along a traced path whose declared-fit residual is a **spike** (at most 3 passes, each
/// refitting): in some measured component the residual departs from its running median over
/// the neighbouring samples (+- [`OUTLIER_HALF_WINDOW`]) by more than [`OUTLIER_SIGMAS`] robust
/// standard deviations (`1.4826 median |departure|`). Such spikes are expected with the
/// declared tilting law: where a joint moment is near zero its sign, hence the side of the
/// clearance, can differ between the arm and the model for a sample or two. A missing effect
/// changes the residual smoothly along the path and is kept. Full positions (independent poses)
/// are never left out, nor is the validation set. Returns the kept set, the number left out,
/// and the declared fit on the kept set with its requested unknowns.
pub fn trim_outliers(
    model: &Model,
    cal: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<(MeasuredSet, usize, ExtendedFit, Vec<Unknown>), DiagnoseError> {
    if !cal.is_serial() {
        let (fit, requested) = declared_fit(model, cal, cfg)?;
        return Ok((cal.clone(), 0, fit, requested));
    }
    let mut kept: Vec<usize> = (0..cal.len()).collect();
    let mut sub = cal.clone();
    let (mut fit, mut requested) = declared_fit(model, &sub, cfg)?;
    for _ in 0..3 {
        let mut spikes = vec![false; kept.len()];
        let comps: Vec<Vec<f64>> = (0..sub.len())
            .map(|k| {
                let p = fit.model.predict_pose(&sub, k)?;
                Ok(sub.components(k, &(sub.poses.xyz_mm[k] - p)))
            })
            .collect::<Result<_, ModelError>>()?;
        let slots = comps.iter().map(Vec::len).max().unwrap_or(0);
        for slot in 0..slots {
            let series: Vec<(usize, f64)> = comps
                .iter()
                .enumerate()
                .filter_map(|(k, c)| c.get(slot).map(|v| (k, *v)))
                .collect();
            for (k, bad) in running_median_spikes(&series) {
                if bad {
                    spikes[k] = true;
                }
            }
        }
        let next: Vec<usize> = kept
            .iter()
            .zip(&spikes)
            .filter(|(_, s)| !**s)
            .map(|(k, _)| *k)
            .collect();
        if next.len() == kept.len() || next.len() < 2 * cfg.folds.max(2) {
            break;
        }
        kept = next;
        sub = cal.subset(&kept);
        (fit, requested) = declared_fit(model, &sub, cfg)?;
    }
    Ok((sub, cal.len() - kept.len(), fit, requested))
}

/// For each `(index, value)` of a series: whether it departs from the running median of its
/// neighbours by more than [`OUTLIER_SIGMAS`] robust standard deviations of the departures.
fn running_median_spikes(series: &[(usize, f64)]) -> Vec<(usize, bool)> {
    let n = series.len();
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    let dep: Vec<f64> = (0..n)
        .map(|i| {
            let lo = i.saturating_sub(OUTLIER_HALF_WINDOW);
            let hi = (i + OUTLIER_HALF_WINDOW + 1).min(n);
            let mut w: Vec<f64> = series[lo..hi].iter().map(|x| x.1).collect();
            series[i].1 - median(&mut w)
        })
        .collect();
    let sigma = 1.4826 * median(&mut dep.iter().map(|d| d.abs()).collect());
    series
        .iter()
        .zip(&dep)
        .map(|((k, _), d)| (*k, sigma > 0.0 && d.abs() > OUTLIER_SIGMAS * sigma))
        .collect()
}
