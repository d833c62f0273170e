//! Aliasing (FORMATS.md `aliased`): effects or parameters that these poses cannot tell apart, so
//! that a value is never reported as found when it is only a stand-in.
//!
//! At the final fit, the stacked Jacobian (measured part, one row per measured component) of
//! every fitted unknown and of every candidate's unknowns is column-scaled to unit norm. Then:
//!
//! * **pairs**: an accepted effect's column and a declared parameter's, another accepted
//!   effect's or a candidate's with `|correlation| >=` [`ALIAS_MIN`] (the cosine of the two
//!   scaled columns: the residuals are absolute errors, not centred);
//! * **reproduced**: a candidate not accepted whose columns' parts that the declared parameters
//!   cannot reproduce (projected off their span) lie in the span of the accepted effects' (also
//!   projected off it) with cosine `>=` [`ALIAS_MIN`]: the accepted effects stand in for it.
//!   It is paired with the accepted effect that carries the largest share of the reproduction.
//!
//! Candidates that the declared parameters alone reproduce are not listed: they could never be
//! found on these poses and are already reported as adding no identifiable direction.

use crate::calib::fit::Fit;
use nalgebra::{DMatrix, DVector};

use super::candidates::Candidate;
use super::compress::stacked_or_compressed;
use super::extended::{ExtModel, Unknown};
use crate::calib::CalibError;
use crate::calib::MeasuredSet;

/// Smallest |correlation| (or cosine to a span) of two columns that the poses cannot separate.
pub const ALIAS_MIN: f64 = 0.9;

/// One aliased pair.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AliasReport {
    /// An accepted effect id or a declared parameter name.
    pub a: String,
    /// Another effect id or parameter name.
    pub b: String,
    /// |correlation| of their columns, or the cosine of `b`'s column to the span of the fitted
    /// columns.
    pub correlation: f64,
    /// What it means.
    pub note: String,
    /// The kind of pair (extra key): `stand_in` (an accepted effect and a candidate it may stand
    /// in for), `reproduced` (a candidate the accepted effects reproduce together),
    /// `both_effects` (two accepted effects) or `declared` (an accepted effect and a fitted
    /// declared parameter: both fitted, their values trade off).
    pub kind: String,
    /// Whether `b` is a candidate that was refitted and rejected (extra key).
    pub tested: bool,
}

/// Most pairs listed in the text report; the JSON keeps them all, in the same order.
pub const ALIAS_TEXT_MAX: usize = 8;

/// Orders the pairs by what matters to a user: a candidate that was tested and rejected while an
/// accepted effect may stand in for it first, then other candidates the accepted effects stand
/// in for or reproduce, then pairs of accepted effects, then accepted effects against declared
/// parameters (both fitted; their sigmas already carry the trade-off); by |correlation| within
/// each. `tested` are the ids of the candidates refitted and rejected.
pub fn rank_pairs(pairs: &mut [AliasReport], tested: &[String]) {
    for p in pairs.iter_mut() {
        p.tested = tested.contains(&p.b);
    }
    let class = |p: &AliasReport| match (p.kind.as_str(), p.tested) {
        ("stand_in" | "reproduced", true) => 0,
        ("stand_in" | "reproduced", false) => 1,
        ("both_effects", _) => 2,
        _ => 3,
    };
    pairs.sort_by(|x, y| {
        class(x)
            .cmp(&class(y))
            .then(y.correlation.total_cmp(&x.correlation))
    });
}

/// A group of columns: a name and the unknowns it covers.
struct Group {
    name: String,
    unknowns: Vec<Unknown>,
    accepted: bool,
}

/// The aliased pairs at the final fit `last` (declared unknowns `declared`, accepted effects
/// `accepted`, other candidates `others`) on `data`.
pub fn aliased(
    last: &Fit<ExtModel, Unknown>,
    declared: &[Unknown],
    accepted: &[Candidate],
    others: &[Candidate],
    data: &MeasuredSet,
) -> Result<Vec<AliasReport>, CalibError> {
    let model = &last.model.model;
    let mut groups: Vec<Group> = Vec::new();
    for u in declared.iter().filter(|u| last.fitted.contains(u)) {
        groups.push(Group {
            name: u.name(model),
            unknowns: vec![*u],
            accepted: false,
        });
    }
    for c in accepted {
        groups.push(Group {
            name: c.id.clone(),
            unknowns: c.unknowns.clone(),
            accepted: true,
        });
    }
    let n_fitted_groups = groups.len();
    for c in others {
        groups.push(Group {
            name: c.id.clone(),
            unknowns: c.unknowns.clone(),
            accepted: false,
        });
    }
    let mut all: Vec<Unknown> = Vec::new();
    for g in &groups {
        for u in &g.unknowns {
            if !all.contains(u) {
                all.push(*u);
            }
        }
    }
    let (mut jac, _) = stacked_or_compressed(&last.model, data, &all)?;
    let norms: Vec<f64> = (0..jac.ncols()).map(|k| jac.column(k).norm()).collect();
    let top = norms.iter().copied().fold(0.0, f64::max);
    for (k, n) in norms.iter().enumerate() {
        if *n > 1e-12 * top && *n > 0.0 {
            jac.column_mut(k).unscale_mut(*n);
        }
    }
    let live = |u: &Unknown| -> Option<usize> {
        all.iter()
            .position(|a| a == u)
            .filter(|&k| norms[k] > 1e-12 * top && norms[k] > 0.0)
    };
    let cols = |g: &Group| -> Vec<usize> { g.unknowns.iter().filter_map(live).collect() };
    let mut out: Vec<AliasReport> = Vec::new();
    // pairs involving an accepted effect
    for (ai, a) in groups.iter().enumerate().filter(|(_, g)| g.accepted) {
        for (bi, b) in groups.iter().enumerate() {
            if bi == ai || (b.accepted && bi < ai) {
                continue;
            }
            let mut best = 0.0f64;
            for &ka in &cols(a) {
                for &kb in &cols(b) {
                    if ka != kb {
                        best = best.max(jac.column(ka).dot(&jac.column(kb)).abs());
                    }
                }
            }
            if best >= ALIAS_MIN {
                let (what, kind) = if bi >= n_fitted_groups {
                    ("the poses cannot tell them apart: the accepted effect may stand in for the other", "stand_in")
                } else if b.accepted {
                    (
                        "both fitted; their values trade off and each is uncertain",
                        "both_effects",
                    )
                } else {
                    (
                        "both fitted; their values trade off and each is uncertain",
                        "declared",
                    )
                };
                out.push(AliasReport {
                    a: a.name.clone(),
                    b: b.name.clone(),
                    correlation: best,
                    note: format!("|correlation| {best:.3} of their columns: {what}"),
                    kind: kind.to_string(),
                    tested: false,
                });
            }
        }
    }
    // candidates reproduced by the fitted columns, thanks to the accepted effects
    let declared_cols: Vec<usize> = groups[..n_fitted_groups]
        .iter()
        .filter(|g| !g.accepted)
        .flat_map(&cols)
        .collect();
    let basis_decl = Span::new(sub(&jac, &declared_cols));
    // the accepted effects' columns with the declared span projected out
    let acc_groups: Vec<&Group> = groups[..n_fitted_groups]
        .iter()
        .filter(|g| g.accepted)
        .collect();
    let mut acc_cols: Vec<(usize, DVector<f64>)> = Vec::new();
    for (gi, g) in acc_groups.iter().enumerate() {
        for k in cols(g) {
            let v = jac.column(k).into_owned();
            let r = &v - basis_decl.project(&v);
            if r.norm() > 1e-6 {
                acc_cols.push((gi, r));
            }
        }
    }
    if acc_cols.is_empty() {
        return Ok(out);
    }
    let mut acc_basis = DMatrix::zeros(jac.nrows(), acc_cols.len());
    for (i, (_, c)) in acc_cols.iter().enumerate() {
        acc_basis.set_column(i, c);
    }
    let basis_acc = Span::new(acc_basis);
    for b in &groups[n_fitted_groups..] {
        let bc = cols(b);
        if bc.is_empty() || out.iter().any(|r| r.b == b.name) {
            continue;
        }
        // every column of the candidate: its part the declared parameters cannot reproduce
        // must be reproduced by the accepted effects
        let mut cos_min = f64::INFINITY;
        let mut share = vec![0.0; acc_groups.len()];
        let mut decl_only = true;
        for &k in &bc {
            let v = jac.column(k).into_owned();
            let r = &v - basis_decl.project(&v);
            if r.norm() < (1.0 - ALIAS_MIN * ALIAS_MIN).sqrt() {
                continue; // the declared parameters reproduce this column already
            }
            decl_only = false;
            let (c, coef) = basis_acc.reproduce(&r);
            cos_min = cos_min.min(c);
            for ((gi, col), x) in acc_cols.iter().zip(coef.iter()) {
                share[*gi] += (x * col.norm()).abs();
            }
        }
        if decl_only || cos_min < ALIAS_MIN {
            continue;
        }
        let Some(gi) = (0..share.len()).max_by(|&a, &c| share[a].total_cmp(&share[c])) else {
            continue;
        };
        let a = &acc_groups[gi].name;
        out.push(AliasReport {
            a: a.clone(),
            b: b.name.clone(),
            correlation: cos_min,
            note: format!(
                "what the declared parameters cannot reproduce of {} the accepted effects do (cosine {cos_min:.3}): {a} may be a stand-in for it",
                b.name
            ),
            kind: "reproduced".to_string(),
            tested: false,
        });
    }
    Ok(out)
}

fn sub(jac: &DMatrix<f64>, cols: &[usize]) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(jac.nrows(), cols.len());
    for (i, &k) in cols.iter().enumerate() {
        m.set_column(i, &jac.column(k));
    }
    m
}

/// A column space with its pseudo-inverse.
struct Span {
    basis: DMatrix<f64>,
    pinv: Option<DMatrix<f64>>,
}

impl Span {
    fn new(basis: DMatrix<f64>) -> Self {
        let pinv = if basis.ncols() == 0 {
            None
        } else {
            let svd = basis.clone().svd(true, true);
            let top = svd.singular_values.iter().copied().fold(0.0, f64::max);
            svd.pseudo_inverse(1e-9 * top).ok()
        };
        Self { basis, pinv }
    }

    /// The projection of `v` on the span.
    fn project(&self, v: &DVector<f64>) -> DVector<f64> {
        match &self.pinv {
            Some(p) => &self.basis * (p * v),
            None => DVector::zeros(v.len()),
        }
    }

    /// Cosine of `v` to the span, and the least-squares coefficients.
    fn reproduce(&self, v: &DVector<f64>) -> (f64, DVector<f64>) {
        let Some(pinv) = &self.pinv else {
            return (0.0, DVector::zeros(self.basis.ncols()));
        };
        let c = pinv * v;
        let p = &self.basis * &c;
        let n = v.norm();
        ((if n > 0.0 { p.norm() / n } else { 0.0 }).min(1.0), c)
    }
}
