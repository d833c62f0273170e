//! `diagnose --plots DIR`: one SVG per term the probe selected, `probe_<term>.svg` (`:` replaced
//! by `_`): the residual against the (first) variable of the term with the probe's fit of that
//! term.
//!
//! Both are signed along the term's main direction `d` (the unit vector along which its
//! contribution varies most over the poses): the **partial residual**
//! `d . (r_k - P_k (f(q_k) - c(q_k)))` (the residual without the other terms) and the term's
//! fit `d . P_k c(q_k)` (`P_k` the projector on the measured directions). For a pair term the
//! fit scatters as a band: its value also follows the second joint.

use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Vector3};

use super::basis::{Term, Var};
use super::ProbeResult;
use crate::plot::{write, PlotError, Scatter};

/// The unit vector along which `c` varies most (largest eigenvector of `sum c c^T`).
fn main_direction(c: &[Vector3<f64>]) -> Vector3<f64> {
    let m: Matrix3<f64> = c.iter().map(|v| v * v.transpose()).sum();
    let e = m.symmetric_eigen();
    let i = e.eigenvalues.imax();
    let d: Vector3<f64> = e.eigenvectors.column(i).into();
    if d.iter().all(|v| v.is_finite()) && d.norm() > 0.0 {
        d.normalize()
    } else {
        Vector3::z()
    }
}

/// The scatter of term `index` of the probe's model.
pub fn term_scatter(probe: &ProbeResult, index: usize) -> Option<Scatter> {
    let term = *probe.model.terms.get(index)?;
    let vars = term.vars();
    let v = *vars.first()?;
    let j = match v {
        Var::Joint(j) => j,
        Var::Time => probe.model.domain.n_joints,
    };
    let contributions: Vec<Vec<Vector3<f64>>> = probe
        .points
        .iter()
        .map(|q| probe.model.term_contributions_mm(q))
        .collect();
    let own: Vec<Vector3<f64>> = contributions.iter().map(|c| c[index]).collect();
    let d = main_direction(&own);
    let project = |k: usize, v: Vector3<f64>| match probe.projectors.get(k).copied().flatten() {
        Some(p) => p * v,
        None => v,
    };
    let mut x = Vec::new();
    let mut residual = Vec::new();
    let mut fit = Vec::new();
    for (k, q) in probe.points.iter().enumerate() {
        let total: Vector3<f64> = contributions[k].iter().sum();
        let r = probe.residual_mm[k] - project(k, total - own[k]);
        x.push(q.get(j).copied().unwrap_or(f64::NAN));
        residual.push(d.dot(&r));
        fit.push(d.dot(&project(k, own[k])));
    }
    let with = match term {
        Term::Pair(_, b) => format!(" (interaction with {})", b.name()),
        _ => String::new(),
    };
    Some(Scatter {
        title: format!(
            "probe: residual vs {}{with}, along ({:.2}, {:.2}, {:.2})",
            v.name(),
            d.x,
            d.y,
            d.z
        ),
        x_label: format!(
            "{} ({})",
            v.name(),
            if v == Var::Time { "s" } else { "deg" }
        ),
        y_label: "residual without the other terms (mm)".to_string(),
        x,
        before: residual,
        after: fit,
        labels: ["residual".to_string(), format!("probe fit {}", term.name())],
    })
}

/// Writes one SVG per selected joint term into `dir` (which must exist); returns the paths.
pub fn write_probe_plots(dir: &Path, probe: &ProbeResult) -> Result<Vec<PathBuf>, PlotError> {
    let mut out = Vec::new();
    for (i, t) in probe.model.terms.iter().enumerate() {
        let Some(chart) = term_scatter(probe, i) else {
            continue;
        };
        let path = dir.join(format!("probe_{}.svg", t.name().replace(':', "_")));
        write(&path, &chart)?;
        out.push(path);
    }
    Ok(out)
}
