//! Fixtures shared by the plan module's unit tests.

use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::candidates::{draw_candidates, CandidatePose, Workspace};
use super::setup::Setup;
use crate::model::{katana450, Model, KATANA_TOOL_MM};

/// `n_cand` random 3 x `p` candidate blocks, entries uniform in [-1, 1).
pub(crate) fn random_stack(n_cand: usize, p: usize, seed: u64) -> DMatrix<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    DMatrix::from_fn(3 * n_cand, p, |_, _| rng.gen_range(-1.0..1.0))
}

/// A Katana (default tool) pool of `count` random candidates and its declared setup.
pub(crate) struct KatanaPool {
    pub model: Model,
    pub ws: Workspace,
    pub cands: Vec<CandidatePose>,
    pub setup: Setup,
}

/// The [`KatanaPool`] of `count` candidates drawn with `seed`.
pub(crate) fn katana_pool(count: usize, seed: u64) -> KatanaPool {
    let model = katana450(KATANA_TOOL_MM).expect("the katana preset builds");
    let ws = Workspace::for_model(&model);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let cands = draw_candidates(&model, count, &ws, &mut rng).expect("candidates");
    let setup = Setup::declared(&model, &cands, &[]).expect("setup");
    KatanaPool {
        model,
        ws,
        cands,
        setup,
    }
}
