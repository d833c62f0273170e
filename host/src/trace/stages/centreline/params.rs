//! The centreline stage's tuned numbers ([`super::centreline`]) in one place, each with its
//! unit and what it trades off; the per-image numbers (scale, step, width, least mass) are
//! [`super::TrackParams`], from the options.

/// The numbers of the centreline stage: when faint graphite ends a piece, and how a walk meets its
/// own track.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::trace) struct CentrelineParams {
    /// Faint graphite is a running mass under this many times [`super::TrackParams::min_mass`]:
    /// there a window under half the running mass ends the piece only if the stroke does not go
    /// on (the pencil's pressure drops, the paper's tooth breaks faint graphite up; a skip leaves
    /// none). Higher: more strokes read as faint, followed further through breaks, at the risk of
    /// walking on into noise. Ratio.
    pub(in crate::trace) faint_mass: f64,
    /// In faint graphite, at most one window under this share of the stroke's level may lie on
    /// the way of a run that goes on ([`Self::faint_run_steps`]). Lower: fewer breaks crossed.
    /// Ratio.
    pub(in crate::trace) faint_share: f64,
    /// The stroke goes on when it is back at half its level within this many more steps. More:
    /// longer breaks crossed, and more chance to step onto another mark. Steps of the tracker.
    pub(in crate::trace) back_within_steps: usize,
    /// ... or when the next this many steps (2 mm at the usual step) hold half its level on
    /// average. More: a surer reading of "goes on", at the cost of a later stop. Steps.
    pub(in crate::trace) faint_run_steps: usize,
    /// The level a faint window is judged against is the running mass, at most what begins a
    /// piece and at least this share of that (the paper's noise). Lower: faint strokes followed
    /// down into the noise. Ratio.
    pub(in crate::trace) faint_floor: f64,
    /// Onto its own track at more than 45 deg (cosine): a crossing, the walk stops at once.
    /// Lower: steeper meetings still read as crossings.
    pub(in crate::trace) cross_cos: f64,
    /// Along its own track within 15 deg, either way along it (cosine): the same line again.
    /// Higher: only a closer retrace counts as one.
    pub(in crate::trace) aligned_cos: f64,
}

/// The tuned values.
pub(in crate::trace) const CENTRELINE: CentrelineParams = CentrelineParams {
    faint_mass: 2.0,
    faint_share: 0.2,
    back_within_steps: 2,
    faint_run_steps: 8,
    faint_floor: 0.25,
    cross_cos: 0.707,
    aligned_cos: 0.966,
};
