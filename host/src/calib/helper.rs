//! The second core of an identification on normal equations: a thread that lives as long as
//! the problem ([`super::accumulate::PositionNormalProblem`]) and accumulates the second half
//! of the chunks of every evaluation, while the calling thread does the first half.
//!
//! Starting a thread per evaluation cost 50-100 us each (a fresh stack, the scheduler), about
//! a tenth of a 1000-pose evaluation; this one blocks on a channel between evaluations (it does
//! not spin). It owns copies of what it needs (the unknowns' model, the poses of its half of the
//! chunks and their joint sines and cosines), receives the unknowns' values, and sends back its
//! per-chunk sums; the buffers travel back and forth, so an evaluation allocates nothing. The
//! chunks and their order of summation are those of [`super::accumulate::Accumulator`], so the
//! results are bitwise the same as on one thread.

use std::ops::Range;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::thread::JoinHandle;

use nalgebra::DVector;

use super::accumulator::{Accumulator, JointTrig, Work, CHUNK_POSES};
use super::measured::PosePoints;
use super::normal::Normal;
use super::problem::{SetUnknowns, Unknowns};
use crate::model::ModelError;

/// The buffers that travel between the threads.
struct Buffers {
    x: DVector<f64>,
    normals: Vec<Normal>,
    sums: Vec<f64>,
}

struct Request {
    work: Work,
    chunks: Range<usize>,
    buffers: Buffers,
}

struct Reply {
    result: Result<(), ModelError>,
    buffers: Buffers,
}

/// The helper thread and its channels (see the module doc); joined when dropped.
pub(super) struct Helper {
    tx: Option<SyncSender<Request>>,
    rx: Receiver<Reply>,
    handle: Option<JoinHandle<()>>,
    /// The buffers while they are on this side; `None` while the helper works.
    buffers: Option<Buffers>,
    /// The chunks of the evaluation under way.
    chunks: Range<usize>,
}

impl Helper {
    /// A helper for the unknowns `unknowns` of an identification on `poses` in `chunks` chunks:
    /// it takes the chunks `first..chunks` (a copy of their poses); `None` when the thread
    /// cannot be started (the caller then works alone).
    pub(super) fn spawn(
        unknowns: &Unknowns,
        poses: &PosePoints,
        tilt: bool,
        first: usize,
        chunks: usize,
    ) -> Option<Self> {
        let n = unknowns.cols().len();
        let start = (first * CHUNK_POSES).min(poses.len());
        let tail = PosePoints {
            q_deg: poses.q_deg[start..].to_vec(),
            xyz_mm: poses.xyz_mm[start..].to_vec(),
        };
        let (tx, requests) = sync_channel::<Request>(1);
        let (replies, rx) = sync_channel::<Reply>(1);
        let mut unknowns = unknowns.clone();
        let handle = std::thread::Builder::new()
            .name("rigctl-accumulate".into())
            .spawn(move || {
                let trig = JointTrig::new(&tail);
                let mut acc =
                    Accumulator::with_threads(unknowns.model(), tail.len(), unknowns.cols(), 1);
                while let Ok(Request {
                    work,
                    chunks,
                    mut buffers,
                }) = requests.recv()
                {
                    let here = chunks.start.saturating_sub(first)..chunks.end.saturating_sub(first);
                    let result = serve(
                        &mut unknowns,
                        &mut acc,
                        &tail,
                        &trig,
                        tilt,
                        work,
                        &here,
                        &mut buffers,
                    );
                    if replies.send(Reply { result, buffers }).is_err() {
                        break;
                    }
                }
            })
            .ok()?;
        let back = chunks.saturating_sub(first);
        Some(Self {
            tx: Some(tx),
            rx,
            handle: Some(handle),
            buffers: Some(Buffers {
                x: DVector::zeros(n),
                normals: vec![Normal::zeros(n); back],
                sums: vec![0.0; back],
            }),
            chunks: 0..0,
        })
    }

    /// Starts `work` at the unknowns' values `x` on the chunks `chunks` (within the ones given
    /// at [`Helper::spawn`]); [`Helper::finish`] waits for it.
    pub(super) fn start(
        &mut self,
        x: &DVector<f64>,
        work: Work,
        chunks: Range<usize>,
    ) -> Result<(), ModelError> {
        let stopped = || ModelError::Invalid("the accumulation thread stopped".into());
        let mut buffers = self.buffers.take().ok_or_else(stopped)?;
        if buffers.normals.len() < chunks.len() || buffers.x.len() != x.len() {
            self.buffers = Some(buffers);
            return Err(ModelError::Invalid(
                "accumulation thread buffers do not match the evaluation".into(),
            ));
        }
        buffers.x.copy_from(x);
        self.chunks = chunks.clone();
        let tx = self.tx.as_ref().ok_or_else(stopped)?;
        tx.send(Request {
            work,
            chunks,
            buffers,
        })
        .map_err(|_| stopped())
    }

    /// Waits for the evaluation started last and copies its per-chunk results into
    /// `normals` / `sums` (indexed by chunk, as in the caller's accumulator).
    pub(super) fn finish(
        &mut self,
        work: Work,
        normals: &mut [Normal],
        sums: &mut [f64],
    ) -> Result<(), ModelError> {
        let Reply { result, buffers } = self
            .rx
            .recv()
            .map_err(|_| ModelError::Invalid("the accumulation thread stopped".into()))?;
        let first = self.chunks.start;
        copy_results(
            work,
            (&buffers.normals, &buffers.sums),
            0,
            (normals, sums),
            first,
            self.chunks.len(),
        );
        self.buffers = Some(buffers);
        result
    }
}

/// One request on the helper's side: its unknowns set to `x`, the chunks `chunks` of its poses
/// (numbered from its first) accumulated with its own accumulator, the per-chunk results copied
/// into the buffers.
#[allow(clippy::too_many_arguments)]
fn serve(
    unknowns: &mut Unknowns,
    acc: &mut Accumulator,
    poses: &PosePoints,
    trig: &JointTrig,
    tilt: bool,
    work: Work,
    chunks: &Range<usize>,
    buffers: &mut Buffers,
) -> Result<(), ModelError> {
    unknowns.set(&buffers.x)?;
    let model = unknowns.model();
    acc.run_here(model, poses, Some(trig), tilt, work, chunks.clone())?;
    let (normals, sums) = acc.partial_mut();
    copy_results(
        work,
        (normals, sums),
        chunks.start,
        (&mut buffers.normals, &mut buffers.sums),
        0,
        chunks.len(),
    );
    Ok(())
}

/// Copies the `count` per-chunk results of `work` from `src` (from index `src_at`) to `dst`
/// (from `dst_at`): between the accumulator's per-chunk sums and the buffers that travel.
fn copy_results(
    work: Work,
    src: (&[Normal], &[f64]),
    src_at: usize,
    dst: (&mut [Normal], &mut [f64]),
    dst_at: usize,
    count: usize,
) {
    for k in 0..count {
        match work {
            Work::Normal => {
                if let (Some(d), Some(s)) = (dst.0.get_mut(dst_at + k), src.0.get(src_at + k)) {
                    d.assign(s);
                }
            }
            Work::SumSq => {
                if let (Some(d), Some(s)) = (dst.1.get_mut(dst_at + k), src.1.get(src_at + k)) {
                    *d = *s;
                }
            }
        }
    }
}

impl Drop for Helper {
    fn drop(&mut self) {
        // Closing the request channel ends the thread's loop.
        self.tx.take();
        if let Some(h) = self.handle.take() {
            // A panic on the helper was already reported as a stopped thread.
            let _ = h.join();
        }
    }
}
