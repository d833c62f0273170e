//! The geometric identification on normal equations: per pose, FK and the parameter Jacobian in
//! a reusable [`Data`] workspace, accumulated into `J^T J`, `J^T r`, `r^T r` (bounded memory),
//! over fixed chunks of [`CHUNK_POSES`] poses spread on up to [`THREADS`] threads. Each chunk is
//! summed from zero and the chunks are added in order, so the result does not depend on the
//! number of threads (deterministic).

use std::ops::Range;

use nalgebra::{DVector, Vector3};

use super::normal::{Normal, NormalProblem};
use super::problem::{tilt_mode, Poses, Unknowns};
use crate::model::{Data, Model, ModelError, Tilt, Wrt};

/// Poses per chunk of the accumulation (the unit of work and of summation order).
pub const CHUNK_POSES: usize = 256;

/// Threads used when there is more than one chunk.
pub const THREADS: usize = 2;

fn n_chunks(poses: usize) -> usize {
    poses.div_ceil(CHUNK_POSES).max(1)
}

fn chunk(c: usize, poses: usize) -> Range<usize> {
    (c * CHUNK_POSES).min(poses)..((c + 1) * CHUNK_POSES).min(poses)
}

/// Runs `f(chunk index, workspace, output)` on every chunk, on two threads when there are
/// several chunks and two workspaces (first half of the chunks here, second half on a scoped
/// thread); the first error in chunk order is returned.
fn run_chunks<T, F>(workers: &mut [Data], out: &mut [T], f: F) -> Result<(), ModelError>
where
    T: Send,
    F: Fn(usize, &mut Data, &mut T) -> Result<(), ModelError> + Sync,
{
    let n = out.len();
    let (w0, rest) = workers
        .split_first_mut()
        .ok_or_else(|| ModelError::Invalid("no workspace".into()))?;
    if n < 2 || rest.is_empty() {
        for (c, o) in out.iter_mut().enumerate() {
            f(c, w0, o)?;
        }
        return Ok(());
    }
    let half = n.div_ceil(2);
    let (a, b) = out.split_at_mut(half);
    let w1 = &mut rest[0];
    let f = &f;
    std::thread::scope(|s| {
        let h = s.spawn(move || -> Result<(), ModelError> {
            for (k, o) in b.iter_mut().enumerate() {
                f(half + k, w1, o)?;
            }
            Ok(())
        });
        let mut r0 = Ok(());
        for (c, o) in a.iter_mut().enumerate() {
            if let Err(e) = f(c, w0, o) {
                r0 = Err(e);
                break;
            }
        }
        let r1 = h
            .join()
            .unwrap_or_else(|_| Err(ModelError::Invalid("accumulation thread panicked".into())));
        r0.and(r1)
    })
}

/// Adds one pose's residual `r` (3 rows) and Jacobian columns `cols` to `eq` (upper triangle).
#[inline]
fn add_pose(eq: &mut Normal, cols: &[Vector3<f64>], r: &Vector3<f64>) {
    let n = cols.len();
    let jtj = eq.jtj.as_mut_slice();
    for (b, cb) in cols.iter().enumerate() {
        let col = &mut jtj[b * n..b * n + b + 1];
        for (slot, ca) in col.iter_mut().zip(cols) {
            *slot += ca.dot(cb);
        }
        eq.jtr[b] += cb.dot(r);
    }
    eq.rtr += r.norm_squared();
    eq.m += 3;
}

/// Normal equations of the poses `range` into `eq` (cleared first).
fn chunk_normal(
    model: &Model,
    poses: &Poses,
    range: Range<usize>,
    tilt: Tilt<'_>,
    wrt: &[Wrt],
    d: &mut Data,
    eq: &mut Normal,
) -> Result<(), ModelError> {
    eq.clear();
    d.sync(model);
    for i in range {
        model.jacobian_synced(d, &poses.q_deg[i], tilt, wrt)?;
        let r = d.position_mm() - poses.xyz_mm[i];
        add_pose(eq, d.jacobian(), &r);
    }
    Ok(())
}

/// Sum of squared residuals of the poses `range`.
fn chunk_sum_sq(
    model: &Model,
    poses: &Poses,
    range: Range<usize>,
    tilt: Tilt<'_>,
    d: &mut Data,
) -> Result<f64, ModelError> {
    let mut s = 0.0;
    d.sync(model);
    for i in range {
        model.fk_synced(d, &poses.q_deg[i], tilt)?;
        s += (d.position_mm() - poses.xyz_mm[i]).norm_squared();
    }
    Ok(s)
}

/// Workspaces and per-chunk partial sums for one model and pose set, allocated once.
#[derive(Debug, Clone)]
pub struct Accumulator {
    workers: Vec<Data>,
    partial: Vec<Normal>,
    sums: Vec<f64>,
    wrt: Vec<Wrt>,
}

impl Accumulator {
    /// Buffers for `poses` poses and the parameters `cols` of `model`.
    pub fn new(model: &Model, poses: usize, cols: &[usize]) -> Self {
        Self::with_threads(model, poses, cols, THREADS)
    }

    /// [`Accumulator::new`] on `threads` threads (1 or 2; the sums do not depend on it).
    pub fn with_threads(model: &Model, poses: usize, cols: &[usize], threads: usize) -> Self {
        let chunks = n_chunks(poses);
        let threads = if chunks > 1 { threads.clamp(1, 2) } else { 1 };
        Self {
            workers: (0..threads).map(|_| Data::new(model)).collect(),
            partial: vec![Normal::zeros(cols.len()); chunks],
            sums: vec![0.0; chunks],
            wrt: cols.iter().map(|&c| Wrt::Param(c)).collect(),
        }
    }

    /// Normal equations of `model - measured` wrt the parameters given at construction, into
    /// `eq` (upper triangle; call [`Normal::symmetrise`] for both).
    pub fn normal(
        &mut self,
        model: &Model,
        poses: &Poses,
        tilt: bool,
        eq: &mut Normal,
    ) -> Result<(), ModelError> {
        let (len, wrt, t) = (poses.len(), &self.wrt[..], tilt_mode(tilt));
        run_chunks(&mut self.workers, &mut self.partial, |c, d, out| {
            chunk_normal(model, poses, chunk(c, len), t, wrt, d, out)
        })?;
        eq.clear();
        for p in &self.partial {
            eq.add(p);
        }
        Ok(())
    }

    /// `r^T r` of `model - measured`.
    pub fn sum_sq(&mut self, model: &Model, poses: &Poses, tilt: bool) -> Result<f64, ModelError> {
        let (len, t) = (poses.len(), tilt_mode(tilt));
        run_chunks(&mut self.workers, &mut self.sums, |c, d, out| {
            *out = chunk_sum_sq(model, poses, chunk(c, len), t, d)?;
            Ok(())
        })?;
        Ok(self.sums.iter().sum())
    }
}

/// Position errors `measured - model` of every pose (mm), chunked on [`THREADS`] threads when
/// there are several chunks (same values as one pose after the other).
pub fn position_errors(
    model: &Model,
    poses: &Poses,
    tilt: bool,
) -> Result<Vec<Vector3<f64>>, ModelError> {
    let (len, t) = (poses.len(), tilt_mode(tilt));
    let chunks = n_chunks(len);
    let threads = if chunks > 1 { THREADS } else { 1 };
    let mut workers: Vec<Data> = (0..threads).map(|_| Data::new(model)).collect();
    let mut out: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); chunks];
    run_chunks(&mut workers, &mut out, |c, d, errs| {
        let range = chunk(c, len);
        errs.reserve_exact(range.len());
        d.sync(model);
        for i in range {
            model.fk_synced(d, &poses.q_deg[i], t)?;
            errs.push(poses.xyz_mm[i] - d.position_mm());
        }
        Ok(())
    })?;
    Ok(out.concat())
}

/// The normal equations (symmetric) of `model - measured` over `poses` wrt the parameters `cols`.
pub fn normal_equations(
    model: &Model,
    poses: &Poses,
    cols: &[usize],
    tilt: bool,
) -> Result<Normal, ModelError> {
    let mut acc = Accumulator::new(model, poses.len(), cols);
    let mut eq = Normal::zeros(cols.len());
    acc.normal(model, poses, tilt, &mut eq)?;
    eq.symmetrise();
    Ok(eq)
}

/// The geometric identification ([`super::problem::PositionProblem`]) as a [`NormalProblem`].
pub struct PositionNormalProblem<'a> {
    unknowns: Unknowns,
    poses: &'a Poses,
    tilt: bool,
    acc: Accumulator,
}

impl<'a> PositionNormalProblem<'a> {
    /// A problem on a copy of `model` with the parameters `cols` as unknowns.
    pub fn new(model: &Model, poses: &'a Poses, cols: Vec<usize>, tilt: bool) -> Self {
        let acc = Accumulator::new(model, poses.len(), &cols);
        Self {
            unknowns: Unknowns::new(model, cols),
            poses,
            tilt,
            acc,
        }
    }

    /// The model and its unknowns.
    pub fn into_unknowns(self) -> Unknowns {
        self.unknowns
    }
}

impl NormalProblem for PositionNormalProblem<'_> {
    type Error = ModelError;

    fn n_params(&self) -> usize {
        self.unknowns.cols().len()
    }

    fn n_residuals(&self) -> usize {
        3 * self.poses.len()
    }

    fn sum_sq(&mut self, x: &DVector<f64>) -> Result<f64, ModelError> {
        self.unknowns.set(x)?;
        self.acc
            .sum_sq(self.unknowns.model(), self.poses, self.tilt)
    }

    fn normal(&mut self, x: &DVector<f64>, eq: &mut Normal) -> Result<(), ModelError> {
        self.unknowns.set(x)?;
        self.acc
            .normal(self.unknowns.model(), self.poses, self.tilt, eq)
    }
}
