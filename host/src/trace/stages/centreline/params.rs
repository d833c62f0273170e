//! The centreline stage's tuned numbers ([`super::centreline`]) in one place, each with its
//! unit and what it trades off; the per-image numbers (scale, step, width, least mass) are
//! [`super::TrackParams`], from the options.

stage_params! {
    /// The numbers of the centreline stage: when faint graphite ends a piece, and how a walk meets
    /// its own track.
    pub struct CentrelineParams {
        /// Faint graphite is a running mass under this many times [`super::TrackParams::min_mass`]:
        /// there a window under half the running mass ends the piece only if the stroke does not go
        /// on (the pencil's pressure drops, the paper's tooth breaks faint graphite up; a skip
        /// leaves none). Higher: more strokes read as faint, followed further through breaks, at
        /// the risk of walking on into noise. Ratio.
        faint_mass: f64 = 2.0,
        /// In faint graphite, at most one window under this share of the stroke's level may lie on
        /// the way of a run that goes on ([`Self::faint_run_steps`]). Lower: fewer breaks crossed.
        /// Ratio.
        faint_share: f64 = 0.2,
        /// The stroke goes on when it is back at half its level within this many more steps. More:
        /// longer breaks crossed, and more chance to step onto another mark. Steps of the tracker.
        back_within_steps: usize = 2,
        /// ... or when the next this many steps (2 mm at the usual step) hold half its level on
        /// average. More: a surer reading of "goes on", at the cost of a later stop. Steps.
        faint_run_steps: usize = 8,
        /// The level a faint window is judged against is the running mass, at most what begins a
        /// piece and at least this share of that (the paper's noise). Lower: faint strokes followed
        /// down into the noise. Ratio.
        faint_floor: f64 = 0.25,
        /// Onto its own track at more than 45 deg (cosine): a crossing, the walk stops at once.
        /// Lower: steeper meetings still read as crossings.
        cross_cos: f64 = 0.707,
        /// Along its own track within 15 deg, either way along it (cosine): the same line again.
        /// Higher: only a closer retrace counts as one.
        aligned_cos: f64 = 0.966,
        /// A piece's flanks are read this far from its centreline on either side (the lightest
        /// of the three offsets is the flank), mm (`illumination.rs`). Nearer: thick strokes
        /// read as their own flanks; farther: a pencil line beside a shadow's edge reads as a
        /// step.
        step_flank_mm: [f64; 3] = [0.7, 1.5, 2.5],
        /// Centre and flanks are averaged along the piece over this half length, mm. More: less
        /// noise, shorter steps missed.
        step_window_mm: f64 = 1.0,
        /// A step of light: one flank's contrast to the centre under this share of the other's.
        /// Higher: more of a line beside a shadow cut out. Ratio.
        step_ratio: f64 = 0.35,
        /// ... with the other flank's contrast at least this darkness. Lower: faint steps cut
        /// too. Darkness (fraction of the paper's light).
        step_min_contrast: f64 = 0.06,
        /// Stretches of steps at least this long are cut out of a piece, mm. Shorter: more of a
        /// pencil line crossing a shadow's edge cut (the link bridges it).
        step_run_mm: f64 = 1.5,
        /// The page's own edge: a straight piece wholly at least this far across from the
        /// sheet's centre (outside the printed ring at 90 mm), mm.
        page_edge_from_mm: f64 = 92.0,
        /// ... along the sheet's y axis within this angle, degrees.
        page_edge_max_deg: f64 = 3.0,
        /// ... straight within this RMS across, mm.
        page_edge_rms_mm: f64 = 0.3,
        /// ... at least this long, mm.
        page_edge_min_mm: f64 = 5.0,
    }
}
