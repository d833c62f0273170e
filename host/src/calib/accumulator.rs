//! The per-pose accumulation of the geometric identification: per pose, FK and the parameter
//! Jacobian in a reusable [`Data`] workspace, accumulated into `J^T J`, `J^T r`, `r^T r`
//! (bounded memory), over fixed chunks of [`CHUNK_POSES`] poses spread on up to [`THREADS`]
//! threads. Each chunk is summed from zero and the chunks are added in order, so the result
//! does not depend on the number of threads (deterministic). The position errors of a set are
//! computed the same way.

use std::ops::Range;

use nalgebra::{DMatrix, DMatrixView, Vector3};

use super::measured::PosePoints;
use super::normal::Normal;
use super::problem::{norms_mm, tilt_mode};
use crate::model::{Data, Model, ModelError, Tilt, Wrt};

/// What an evaluation computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Work {
    /// Normal equations per chunk.
    Normal,
    /// `r^T r` per chunk.
    SumSq,
}

/// Poses per chunk of the accumulation (the unit of work and of summation order).
pub const CHUNK_POSES: usize = 256;

/// Threads used when there is more than one chunk.
pub const THREADS: usize = 2;

pub(super) fn n_chunks(poses: usize) -> usize {
    poses.div_ceil(CHUNK_POSES).max(1)
}

fn chunk(c: usize, poses: usize) -> Range<usize> {
    (c * CHUNK_POSES).min(poses)..((c + 1) * CHUNK_POSES).min(poses)
}

/// Runs `f(chunk index, workspace, output)` on every chunk, on two threads when there are
/// several chunks and two workspaces (first half of the chunks here, second half on a scoped
/// thread); the first error in chunk order is returned.
fn run_chunks<W, T, F>(workers: &mut [W], out: &mut [T], f: F) -> Result<(), ModelError>
where
    W: Send,
    T: Send,
    F: Fn(usize, &mut W, &mut T) -> Result<(), ModelError> + Sync,
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

/// `(sin, cos)` of every joint reading of a pose set (radians of the degrees read), computed
/// once for the many evaluations of an identification ([`Data::give_joint_sin_cos`]).
#[derive(Debug, Clone, Default)]
pub struct JointTrig {
    joints: usize,
    sin_cos: Vec<(f64, f64)>,
}

impl JointTrig {
    /// The table of `poses` (empty, i.e. unused, when the poses differ in their joint count).
    pub fn new(poses: &PosePoints) -> Self {
        let joints = poses.q_deg.first().map_or(0, Vec::len);
        if poses.q_deg.iter().any(|q| q.len() != joints) {
            return Self::default();
        }
        Self {
            joints,
            sin_cos: poses
                .q_deg
                .iter()
                .flatten()
                .map(|q| q.to_radians().sin_cos())
                .collect(),
        }
    }

    /// The pairs of pose `i` (`None` outside the table).
    fn pose(&self, i: usize) -> Option<&[(f64, f64)]> {
        self.sin_cos
            .get(i * self.joints..(i + 1) * self.joints)
            .filter(|_| self.joints > 0)
    }

    /// Gives pose `i`'s pairs to `d` for its next evaluation (nothing without a table).
    fn give(trig: Option<&Self>, i: usize, d: &mut Data) {
        if let Some(sc) = trig.and_then(|t| t.pose(i)) {
            d.give_joint_sin_cos(sc);
        }
    }
}

/// One thread's workspace for the normal equations: the model workspace, the residual rows
/// `[J_k, r_k]` of a chunk (`n + 1` values per row, one column per row) and their product
/// `[J r]^T [J r]` (`J^T J` and `J^T r` in one matrix product, SIMD through `matrixmultiply`;
/// its packing buffer is the one allocation per chunk, none per pose).
#[derive(Debug, Clone)]
struct Worker {
    data: Data,
    rows: Vec<f64>,
    aug: DMatrix<f64>,
}

impl Worker {
    fn new(model: &Model, n: usize) -> Self {
        Self {
            data: Data::new(model),
            rows: vec![0.0; (n + 1) * 3 * CHUNK_POSES],
            aug: DMatrix::zeros(n + 1, n + 1),
        }
    }
}

/// One evaluation over the poses: the model, the poses, their [`JointTrig`] and the tilting;
/// what every chunk of it needs.
#[derive(Clone, Copy)]
struct Pass<'a> {
    model: &'a Model,
    poses: &'a PosePoints,
    trig: Option<&'a JointTrig>,
    tilt: Tilt<'a>,
}

impl<'a> Pass<'a> {
    fn new(
        model: &'a Model,
        poses: &'a PosePoints,
        trig: Option<&'a JointTrig>,
        tilt: bool,
    ) -> Self {
        Self {
            model,
            poses,
            trig,
            tilt: tilt_mode(tilt),
        }
    }

    /// Normal equations of the poses `range` (at most [`CHUNK_POSES`]) wrt `wrt` into `eq`.
    fn normal(
        &self,
        range: Range<usize>,
        wrt: &[Wrt],
        w: &mut Worker,
        eq: &mut Normal,
    ) -> Result<(), ModelError> {
        let (model, poses) = (self.model, self.poses);
        let (n, k) = (wrt.len(), 3 * range.len());
        let width = n + 1;
        let rows = w.rows.get_mut(..width * k).ok_or_else(|| {
            ModelError::Invalid("accumulation chunk larger than its buffer".into())
        })?;
        w.data.sync(model);
        // `r^T r` summed pose by pose as in `Pass::sum_sq` (bitwise the same cost both ways).
        let mut rtr = 0.0;
        for (p, i) in range.enumerate() {
            JointTrig::give(self.trig, i, &mut w.data);
            model.jacobian_synced(&mut w.data, &poses.q_deg[i], self.tilt, wrt)?;
            let r = w.data.position_mm() - poses.xyz_mm[i];
            rtr += r.norm_squared();
            for (row, &res) in r.iter().enumerate() {
                let dst = &mut rows[(3 * p + row) * width..(3 * p + row + 1) * width];
                for (slot, c) in dst.iter_mut().zip(w.data.jacobian()) {
                    *slot = c[row];
                }
                dst[n] = res;
            }
        }
        let rows: &[f64] = rows;
        let r = DMatrixView::from_slice(rows, width, k);
        let rt = DMatrixView::from_slice_with_strides(rows, k, width, width, 1);
        w.aug.gemm(1.0, &r, &rt, 0.0);
        eq.jtj.copy_from(&w.aug.view((0, 0), (n, n)));
        eq.jtr.copy_from(&w.aug.view((0, n), (n, 1)));
        eq.rtr = rtr;
        eq.m = k;
        Ok(())
    }

    /// Sum of squared residuals of the poses `range`.
    fn sum_sq(&self, range: Range<usize>, d: &mut Data) -> Result<f64, ModelError> {
        let mut s = 0.0;
        d.sync(self.model);
        for i in range {
            JointTrig::give(self.trig, i, d);
            self.model.fk_synced(d, &self.poses.q_deg[i], self.tilt)?;
            s += (d.position_mm() - self.poses.xyz_mm[i]).norm_squared();
        }
        Ok(s)
    }
}

/// Workspaces and per-chunk partial sums for one model and pose set, allocated once.
#[derive(Debug, Clone)]
pub struct Accumulator {
    workers: Vec<Worker>,
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
            workers: (0..threads)
                .map(|_| Worker::new(model, cols.len()))
                .collect(),
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
        poses: &PosePoints,
        tilt: bool,
        eq: &mut Normal,
    ) -> Result<(), ModelError> {
        self.normal_with(model, poses, None, tilt, eq)
    }

    /// [`Accumulator::normal`] with the poses' joint sines and cosines computed once
    /// ([`JointTrig`]; the same sums to round-off).
    pub fn normal_with(
        &mut self,
        model: &Model,
        poses: &PosePoints,
        trig: Option<&JointTrig>,
        tilt: bool,
        eq: &mut Normal,
    ) -> Result<(), ModelError> {
        self.normal_chunks_threaded(model, poses, trig, tilt)?;
        self.total(eq);
        Ok(())
    }

    /// The per-chunk normal equations of every chunk, on this accumulator's threads.
    pub(super) fn normal_chunks_threaded(
        &mut self,
        model: &Model,
        poses: &PosePoints,
        trig: Option<&JointTrig>,
        tilt: bool,
    ) -> Result<(), ModelError> {
        let (len, wrt) = (poses.len(), &self.wrt[..]);
        let pass = Pass::new(model, poses, trig, tilt);
        run_chunks(&mut self.workers, &mut self.partial, |c, d, out| {
            pass.normal(chunk(c, len), wrt, d, out)
        })
    }

    /// `work` (normal equations or `r^T r`) on the chunks `chunks`, on this thread (first
    /// workspace), into the per-chunk sums ([`Accumulator::partial_mut`]).
    pub(super) fn run_here(
        &mut self,
        model: &Model,
        poses: &PosePoints,
        trig: Option<&JointTrig>,
        tilt: bool,
        work: Work,
        chunks: Range<usize>,
    ) -> Result<(), ModelError> {
        let (len, wrt) = (poses.len(), &self.wrt[..]);
        let pass = Pass::new(model, poses, trig, tilt);
        let w = self
            .workers
            .first_mut()
            .ok_or_else(|| ModelError::Invalid("no workspace".into()))?;
        for c in chunks {
            let (Some(normal), Some(sum)) = (self.partial.get_mut(c), self.sums.get_mut(c)) else {
                return Err(ModelError::Invalid(format!("no chunk {c}")));
            };
            match work {
                Work::Normal => pass.normal(chunk(c, len), wrt, w, normal)?,
                Work::SumSq => *sum = pass.sum_sq(chunk(c, len), &mut w.data)?,
            }
        }
        Ok(())
    }

    /// The per-chunk normal equations and residual sums (chunk order).
    pub(super) fn partial_mut(&mut self) -> (&mut [Normal], &mut [f64]) {
        (&mut self.partial, &mut self.sums)
    }

    /// `eq` = the sum of the per-chunk equations, in chunk order.
    pub(super) fn total(&self, eq: &mut Normal) {
        eq.clear();
        for p in &self.partial {
            eq.add(p);
        }
    }

    /// `r^T r` of `model - measured`.
    pub fn sum_sq(
        &mut self,
        model: &Model,
        poses: &PosePoints,
        tilt: bool,
    ) -> Result<f64, ModelError> {
        self.sum_sq_with(model, poses, None, tilt)
    }

    /// [`Accumulator::sum_sq`] with the poses' [`JointTrig`] (bitwise the `r^T r` of
    /// [`Accumulator::normal_with`] with the same table).
    pub fn sum_sq_with(
        &mut self,
        model: &Model,
        poses: &PosePoints,
        trig: Option<&JointTrig>,
        tilt: bool,
    ) -> Result<f64, ModelError> {
        let (len, pass) = (poses.len(), Pass::new(model, poses, trig, tilt));
        run_chunks(&mut self.workers, &mut self.sums, |c, d, out| {
            *out = pass.sum_sq(chunk(c, len), &mut d.data)?;
            Ok(())
        })?;
        Ok(self.sums.iter().sum())
    }
}

/// Position errors `measured - model` of every pose (mm), chunked on [`THREADS`] threads when
/// there are several chunks (same values as one pose after the other).
pub fn position_errors(
    model: &Model,
    poses: &PosePoints,
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

/// Norms of the position errors of every pose (mm).
pub fn error_norms_mm(
    model: &Model,
    poses: &PosePoints,
    tilt: bool,
) -> Result<Vec<f64>, ModelError> {
    Ok(norms_mm(&position_errors(model, poses, tilt)?))
}
