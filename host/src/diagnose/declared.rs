//! The start of every diagnosis: the declared model fitted as `calibrate --method tilting`
//! ([`declared_fit`]), and on a traced path the samples whose declared-fit residual is a spike
//! left out first ([`trim_outliers`]).

use super::decide::DecideConfig;
use super::extended::{self, ExtModel, ExtendedFit, Unknown};
use super::spikes;
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

/// The declared fit ([`declared_fit`]) of the calibration set, after leaving out the samples
/// along a traced path whose declared-fit residual is a **spike** in some measured component
/// ([`spikes::in_components`]; at most 3 passes, each refitting). Such spikes are expected with the
/// declared tilting law: where a joint moment is near zero its sign, hence the side of the
/// clearance, can differ between the arm and the model for a sample or two. A missing effect
/// changes the residual smoothly along the path and is kept. Full positions (independent poses)
/// are never left out, nor is the validation set.
pub fn trim_outliers(
    model: &Model,
    cal: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<Declared, DiagnoseError> {
    if !cal.is_serial() {
        return Declared::on(model, cal.clone(), 0, cfg);
    }
    let mut kept: Vec<usize> = (0..cal.len()).collect();
    let mut sub = cal.clone();
    let (mut fit, mut requested) = declared_fit(model, &sub, cfg)?;
    for _ in 0..3 {
        let comps: Vec<Vec<f64>> = (0..sub.len())
            .map(|k| {
                let p = fit.model.predict_pose(&sub, k)?;
                Ok(sub.components(k, &(sub.poses.xyz_mm[k] - p)))
            })
            .collect::<Result<_, ModelError>>()?;
        let spikes = spikes::in_components(&comps);
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
    Ok(Declared {
        spikes_left_out: cal.len() - kept.len(),
        cal: sub,
        fit,
        requested,
    })
}

/// The declared fit every selection starts from, on the calibration poses it keeps
/// ([`trim_outliers`]).
#[derive(Debug, Clone)]
pub struct Declared {
    /// The calibration poses kept.
    pub cal: MeasuredSet,
    /// Samples left out as spikes along a traced path.
    pub spikes_left_out: usize,
    /// The declared fit ([`declared_fit`]) on `cal`.
    pub fit: ExtendedFit,
    /// Its requested unknowns.
    pub requested: Vec<Unknown>,
}

impl Declared {
    /// The declared fit on `cal`, after `spikes_left_out` samples were left out.
    pub fn on(
        model: &Model,
        cal: MeasuredSet,
        spikes_left_out: usize,
        cfg: &DecideConfig,
    ) -> Result<Self, DiagnoseError> {
        let (fit, requested) = declared_fit(model, &cal, cfg)?;
        Ok(Self {
            cal,
            spikes_left_out,
            fit,
            requested,
        })
    }
}
