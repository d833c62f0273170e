//! The fiducial stage's tuned numbers ([`super::fiducials`]) in one place, each with its unit and
//! what it trades off.

stage_params! {
    /// The numbers of the fiducial search: what is black print, how many corners are tried, how
    /// close a mark must match.
    pub struct FiducialParams {
        /// A block is "black" when its darkest red value is below this fraction of the paper level
        /// (black print reflects < 10 %; graphite 30-60 %). Higher: grey print and heavy graphite
        /// taken for discs; lower: a dim or toned scan's discs missed. Ratio.
        black_fraction: f32 = 0.22,
        /// A block under this fraction of the paper level is dark enough to be print through any
        /// tone curve the tracer undoes (black at 0.03-0.08 of the paper is 0.2-0.35 through sRGB
        /// or a gamma of 1/2.2); used only to find the marks whose black measures the curve. Ratio.
        encoded_black_fraction: f32 = 0.5,
        /// How many of the largest discs are tried as corners. More: a sheet with many dark blots
        /// still found, at a cost growing with the fourth power.
        max_corner_candidates: usize = 16,
        /// A mark matches its printed place when the corner homography puts it this close, mm (at
        /// the nominal print scale; generous: the lens may bend the sheet's edges by a millimetre
        /// or two). Smaller: a strong lens's edge marks unmatched; larger: neighbouring marks
        /// confused.
        match_tol_mm: f64 = 3.0,
    }
}
