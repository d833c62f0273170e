//! What drew the strokes a [`super::Network`] links, as the rules and numbers that differ
//! between the two kinds: two presets of one struct, [`Strokes::ONE_PATH`] (the rig's pencil,
//! `rigctl trace`) and [`Strokes::PASSES`] (a plotter's passes, `rigctl trace --paths`). The
//! code reads the fields; nowhere does it ask which preset it runs.

use super::params::LinkParams;

/// How the ends of pieces are read, chains are linked and a path is written, for one kind of
/// drawing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::trace) struct Strokes {
    /// The last [`LinkParams::pulled_end_mm`] of every end left out of its reading (tangent,
    /// curvature) and bridged over ([`Self::end_skip_mm`]). Off reads an end to its last point,
    /// so a bridge starts there and its refit gets the graphite next to the skip; on keeps a
    /// pass's backlash saw and the crossings near a plotter's line ends out of the tangent, at
    /// the cost of that much of the end.
    pub(in crate::trace) skip_pulled_end: bool,
    /// Where an end's span holds a crest (its curvature over the clamp), read the tangent again
    /// from the last few millimetres before the anchor. Right for one smooth pencil path; on a
    /// plotter's passes the sawn last millimetres would turn it.
    pub(in crate::trace) crest_tangent: bool,
    /// A span too short to read a curvature keeps its own circle's tangent where its last
    /// millimetre holds no hook (a short stroke between two skips). Off for passes, whose
    /// short pieces are pieces of saw.
    pub(in crate::trace) own_short_tangent: bool,
    /// A second round reads each chain's free ends through the chain and links what it then
    /// admits ([`super::relink`]). Off for passes: a plotter's lines meet at corners and
    /// crossings, where an end read through its bridges would turn onto the crossing line.
    pub(in crate::trace) relink: bool,
    /// The written centres are smoothed along the path between bridges (`smooth.rs`). Off for
    /// passes: their lines are smoothed across the band of their passes instead (`lines`).
    pub(in crate::trace) smooth_centres: bool,
}

impl Strokes {
    /// The rig's pencil: one path, read to its ends.
    pub(in crate::trace) const ONE_PATH: Self = Self {
        skip_pulled_end: false,
        crest_tangent: true,
        own_short_tangent: true,
        relink: true,
        smooth_centres: true,
    };
    /// A plotter's passes (`--paths`): ends read from [`LinkParams::pulled_end_mm`] back,
    /// centres as tracked.
    pub(in crate::trace) const PASSES: Self = Self {
        skip_pulled_end: true,
        crest_tangent: false,
        own_short_tangent: false,
        relink: false,
        smooth_centres: false,
    };

    /// The part of every end left out of its reading, mm: [`LinkParams::pulled_end_mm`] or 0.
    pub(in crate::trace) fn end_skip_mm(&self, lk: &LinkParams) -> f64 {
        if self.skip_pulled_end {
            lk.pulled_end_mm
        } else {
            0.0
        }
    }
}
