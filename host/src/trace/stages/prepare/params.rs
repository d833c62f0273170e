//! The prepare stage's numbers ([`super::prepare`]) in one place, each with its unit and what it
//! trades off. None of them changes a map: every band's result depends on its rows alone.

stage_params! {
    /// How the whole-image passes are cut into bands and shared among threads.
    pub struct PrepareParams {
        /// At most this many threads share the bands of a decoded image. More: faster on a large
        /// machine, with that many bands' buffers held at once.
        max_threads: usize = 8,
        /// A band holds at least this many image rows (rounded up to whole blocks of both maps),
        /// rows. More: fewer hand-overs between threads and the PNG decoder, later first results.
        min_band_rows: usize = 128,
        /// The paper map's blocks are at least this wide, pixels (a tiny image still gets blocks
        /// with a percentile to read).
        min_paper_block_px: usize = 4,
    }
}
