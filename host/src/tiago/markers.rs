//! Identification from all 4 hand points of every posture: one model (its selected
//! parameters) and one point per marker in the tip link frame (the model's `tool_d*` set to
//! that point), fitted together. Four points of a rigid body carry the hand's orientation too,
//! so a posture gives 12 coordinates instead of 3.

use nalgebra::{DMatrix, DVector, Vector3};

use super::mocap::{PostureSet, N_MARKERS};
use crate::calib::identifiability::analyse;
use crate::calib::lm::{solve, LmConfig, Problem};
use crate::calib::CalibError;
use crate::model::{Model, ModelError, Tilt};

/// Result of [`fit_markers`].
#[derive(Debug, Clone)]
pub struct MarkerFit {
    /// The fitted model, its tool point set to marker 0 (BL).
    pub model: Model,
    /// Every marker's point in the tip link frame (mm).
    pub markers_mm: [Vector3<f64>; N_MARKERS],
    /// Fitted model parameters (model indices).
    pub fitted: Vec<usize>,
    /// Names of the unidentifiable combinations (their first-fixed member kept at its value).
    pub unidentifiable: Vec<String>,
    /// Solver iterations.
    pub iterations: usize,
}

impl MarkerFit {
    /// The model with its tool point at marker `k`.
    pub fn model_for(&self, k: usize) -> Result<Model, ModelError> {
        let mut m = self.model.clone();
        set_tool(&mut m, &self.markers_mm[k.min(N_MARKERS - 1)])?;
        Ok(m)
    }
}

fn tool_indices(model: &Model) -> Result<[usize; 3], ModelError> {
    Ok([
        model.require_param("tool_dx")?,
        model.require_param("tool_dy")?,
        model.require_param("tool_dz")?,
    ])
}

fn set_tool(model: &mut Model, t: &Vector3<f64>) -> Result<(), ModelError> {
    for (i, v) in tool_indices(model)?.into_iter().zip(t.iter()) {
        model.set_param_at(i, *v)?;
    }
    Ok(())
}

/// Unknowns: the model parameters `cols`, then 3 coordinates per marker.
struct MarkerProblem<'a> {
    model: Model,
    set: &'a PostureSet,
    cols: Vec<usize>,
    tool: [usize; 3],
}

impl MarkerProblem<'_> {
    fn set(&mut self, x: &DVector<f64>) -> Result<[Vector3<f64>; N_MARKERS], ModelError> {
        for (&c, &v) in self.cols.iter().zip(x.iter()) {
            self.model.set_param_at(c, v)?;
        }
        let n = self.cols.len();
        Ok(std::array::from_fn(|k| {
            Vector3::new(x[n + 3 * k], x[n + 3 * k + 1], x[n + 3 * k + 2])
        }))
    }
}

impl Problem for MarkerProblem<'_> {
    type Error = ModelError;

    fn n_params(&self) -> usize {
        self.cols.len() + 3 * N_MARKERS
    }

    fn n_residuals(&self) -> usize {
        3 * N_MARKERS * self.set.len()
    }

    fn evaluate(
        &mut self,
        x: &DVector<f64>,
        r: &mut DVector<f64>,
        mut jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), ModelError> {
        let points = self.set(x)?;
        let n = self.cols.len();
        let mut cols = self.cols.clone();
        cols.extend(self.tool);
        for (k, t) in points.iter().enumerate() {
            set_tool(&mut self.model, t)?;
            for (i, p) in self.set.postures.iter().enumerate() {
                let row = 3 * (N_MARKERS * i + k);
                let measured = p.markers_mm[k];
                match jac.as_deref_mut() {
                    Some(jac) => {
                        let (fk, j) = self.model.param_jacobian(&p.q, Tilt::Off, &cols)?;
                        r.fixed_rows_mut::<3>(row)
                            .copy_from(&(fk.position_mm - measured));
                        jac.view_mut((row, 0), (3, n)).copy_from(&j.columns(0, n));
                        jac.view_mut((row, n), (3, 3 * N_MARKERS)).fill(0.0);
                        jac.view_mut((row, n + 3 * k), (3, 3))
                            .copy_from(&j.columns(n, 3));
                    }
                    None => {
                        let pos = self.model.position_mm(&p.q, Tilt::Off)?;
                        r.fixed_rows_mut::<3>(row).copy_from(&(pos - measured));
                    }
                }
            }
        }
        Ok(())
    }
}

/// Fits the parameters `selection` of `start` (the `tool_d*` entries of `selection`, if any,
/// are ignored: the marker points replace them) and the 4 marker points to every hand point of
/// `set`. Unidentifiable parameters (threshold `rtol`, see
/// [`crate::calib::identifiability`]) keep their start values.
pub fn fit_markers(
    start: &Model,
    set: &PostureSet,
    selection: &[usize],
    lm: &LmConfig,
    rtol: f64,
) -> Result<MarkerFit, CalibError> {
    if set.is_empty() {
        return Err(CalibError::NoPoses);
    }
    let tool = tool_indices(start)?;
    let cols: Vec<usize> = selection
        .iter()
        .copied()
        .filter(|c| !tool.contains(c))
        .collect();
    // Start points: the start model's tool point for every marker.
    let t0 = Vector3::new(
        start.params()[tool[0]].value,
        start.params()[tool[1]].value,
        start.params()[tool[2]].value,
    );
    let x_of = |cols: &[usize], m: &Model| {
        let v = m.param_values();
        let mut x: Vec<f64> = cols.iter().map(|&c| v[c]).collect();
        for _ in 0..N_MARKERS {
            x.extend(t0.iter());
        }
        DVector::from_vec(x)
    };
    // Identifiability at the start point, over the model columns and the marker points.
    let mut probe = MarkerProblem {
        model: start.clone(),
        set,
        cols: cols.clone(),
        tool,
    };
    let x0 = x_of(&cols, start);
    let mut r = DVector::zeros(probe.n_residuals());
    let mut jac = DMatrix::zeros(probe.n_residuals(), probe.n_params());
    probe.evaluate(&x0, &mut r, Some(&mut jac))?;
    let id = analyse(&jac, rtol);
    let mut names: Vec<String> = cols
        .iter()
        .map(|&c| start.params()[c].name.clone())
        .collect();
    for k in 0..N_MARKERS {
        for a in ["x", "y", "z"] {
            names.push(format!("marker{}_{a}", k + 1));
        }
    }
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let unidentifiable = id.combinations.iter().map(|c| c.name(&name_refs)).collect();
    let fitted: Vec<usize> = id
        .kept
        .iter()
        .filter(|&&k| k < cols.len())
        .map(|&k| cols[k])
        .collect();
    let mut problem = MarkerProblem {
        model: start.clone(),
        set,
        cols: fitted.clone(),
        tool,
    };
    let rep = solve(&mut problem, x_of(&fitted, start), lm).map_err(CalibError::from_lm)?;
    let markers_mm = problem.set(&rep.x)?;
    let mut model = problem.model;
    set_tool(&mut model, &markers_mm[0])?;
    Ok(MarkerFit {
        model,
        markers_mm,
        fitted,
        unidentifiable,
        iterations: rep.iterations,
    })
}

/// Residuals (model - measured, mm) and Jacobian of `model` with marker points `markers_mm`
/// over all hand points of `set`: columns `cols` (model indices), then 3 per marker; rows in
/// blocks of `3 N_MARKERS` per posture.
pub fn marker_jacobian(
    model: &Model,
    set: &PostureSet,
    cols: &[usize],
    markers_mm: &[Vector3<f64>; N_MARKERS],
) -> Result<(DMatrix<f64>, DVector<f64>), ModelError> {
    let mut problem = MarkerProblem {
        model: model.clone(),
        set,
        cols: cols.to_vec(),
        tool: tool_indices(model)?,
    };
    let v = model.param_values();
    let mut x: Vec<f64> = cols.iter().map(|&c| v[c]).collect();
    for m in markers_mm {
        x.extend(m.iter());
    }
    let mut r = DVector::zeros(problem.n_residuals());
    let mut jac = DMatrix::zeros(problem.n_residuals(), problem.n_params());
    problem.evaluate(&DVector::from_vec(x), &mut r, Some(&mut jac))?;
    Ok((jac, r))
}
