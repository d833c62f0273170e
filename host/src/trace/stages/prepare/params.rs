//! The prepare stage's numbers ([`super::prepare`]) in one place, each with its unit and what it
//! trades off. None of them changes a map: every band's result depends on its rows alone.

/// How the whole-image passes are cut into bands and shared among threads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::trace) struct PrepareParams {
    /// At most this many threads share the bands of a decoded image. More: faster on a large
    /// machine, with that many bands' buffers held at once.
    pub(in crate::trace) max_threads: usize,
    /// A band holds at least this many image rows (rounded up to whole blocks of both maps),
    /// rows. More: fewer hand-overs between threads and the PNG decoder, later first results.
    pub(in crate::trace) min_band_rows: usize,
    /// The paper map's blocks are at least this wide, pixels (a tiny image still gets blocks
    /// with a percentile to read).
    pub(in crate::trace) min_paper_block_px: usize,
}

/// The values.
pub(in crate::trace) const PREPARE: PrepareParams = PrepareParams {
    max_threads: 8,
    min_band_rows: 128,
    min_paper_block_px: 4,
};
