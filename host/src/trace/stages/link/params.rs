//! The link stage's tuned numbers ([`super::link`]), in one place: each with its unit and what
//! it trades off. The two kinds of drawing differ only by [`super::Strokes`]' presets.

stage_params! {
    /// The numbers of the link stage: how ends are read, which links are admissible, how bridges
    /// and crossings are built and what left out is judged.
    pub struct LinkParams {
        /// Marks shorter than this are specks (dust, grain), mm. Longer: more dust ignored, and a
        /// short piece of the path between two skips listed as a speck, not a part.
        min_mark_mm: f64 = 5.0,
        /// Length of an end used for its tangent and curvature, mm. Longer: steadier against the
        /// centres' scatter, blinder to a bend near the end.
        end_span_mm: f64 = 8.0,
        /// The part of an end left out of its reading and bridged over where it may be pulled
        /// aside: next to a crossing the path is cut at, and on a plotter's passes
        /// ([`super::Strokes::PASSES`]), mm. Longer: a pulled end's hook kept out of its tangent,
        /// at the cost of that much graphite bridged over.
        pulled_end_mm: f64 = 1.5,
        /// An end's curvature is read only from a span of at least this (shorter ones cannot tell
        /// it from the centreline's noise), mm, and is at most this, 1/mm. A shorter span or a
        /// higher clamp carries tighter bends across a gap, and noise with them.
        k_span_mm: f64 = 5.0,
        /// The clamp on an end's curvature (see `k_span_mm`), 1/mm.
        max_k_per_mm: f64 = 0.1,
        /// Length of an end a crest's tangent is read over, mm: short against a crest of 3 mm
        /// radius, long enough that the centres' scatter turns it by a few degrees at most.
        /// Shorter: tighter crests followed, a noisier tangent.
        tangent_span_mm: f64 = 3.0,
        /// A short end's last chord, mm, over which a hook is looked for before the span's own
        /// tangent is taken (see `hook_deg`). Longer: longer hooks seen, short spans refused.
        hook_chord_mm: f64 = 1.0,
        /// How far a short end's last chord may turn off its span's circle (see `hook_chord_mm`),
        /// degrees. Wider: more short ends keep their own tangent, hooks included.
        hook_deg: f64 = 8.0,
        /// Scatter of a centre about the stroke's true centreline, mm, read into a short span's
        /// sag. Larger: a short span must bend more before its own bend is believed.
        sag_noise_mm: f64 = 0.03,
        /// A piece turning by more than this between its chords of `kink_chord_mm` is cut there,
        /// degrees. Lower: gentler corners cut (more links to make), fewer strokes crossing the
        /// path followed onto.
        kink_deg: f64 = 25.0,
        /// The chord length a kink's turn is measured between (see `kink_deg`), mm.
        kink_chord_mm: f64 = 1.0,
        /// Where the ends' arcs miss each other, the mean curvature a link may bend by from the
        /// middle of one end's span to the other's (a pencil crest of 3 mm radius), 1/mm, and the
        /// least share of the turn each end takes from the chord between them
        /// ([`super::continuity::bends_through`]). Higher: tighter crests bridged, and corners
        /// between two strokes taken for crests.
        max_joint_k_per_mm: f64 = 0.35,
        /// The least share of the turn each end takes from the chord (see `max_joint_k_per_mm`),
        /// ratio. Lower: links where one end does not bend with the path admitted.
        joint_share: f64 = 0.25,
        /// Ends nearer than this were linked or not in the first round on their turn alone (see
        /// [`super::continuity`]), mm: the second round leaves them as they are.
        relink_near_mm: f64 = 1.0,
        /// Spacing of bridge points (the first guess and the refitted bridge), mm. Finer: more
        /// points written, no better bridge.
        bridge_step_mm: f64 = 0.2,
        /// A mark ending this close to the path touches it (its centroids there are pulled), mm.
        /// Larger: more nearby marks make the path cut and bridged around them.
        cross_touch_mm: f64 = 1.5,
        /// The radius the path is bridged over around a touching mark (see `cross_touch_mm`), mm.
        /// Larger: the other mark's graphite kept off the path, at the cost of more bridged length.
        cross_cut_mm: f64 = 3.0,
        /// A cut stretch longer than this along the path is kept (a mark running along the path,
        /// not across it), mm. Longer: marks along the path cut out too, as long bridges.
        cross_max_mm: f64 = 15.0,
        /// Another run's end this close to the path (the tracker stopped it where it met the path's
        /// graphite) meets the path there, mm. Larger: more runs read as meeting the path (a second
        /// run named), fewer as apart.
        run_meet_mm: f64 = 3.0,
        /// A mark's centre this close to the path touches it, mm (see `run_meet_mm`).
        run_touch_mm: f64 = 0.75,
        /// Crossings closer than this along the sheet are one, mm. Larger: two nearby crossings of
        /// a second run counted once.
        run_same_mm: f64 = 3.0,
        /// A mark meeting the path at two places at least this far apart runs from one to the other
        /// (a second run's arc between two crossings, or a branch the path might have taken), mm.
        /// Shorter: more short marks named as runs between crossings.
        run_apart_mm: f64 = 10.0,
        /// A left-out line at least this share of the path's length is a drawn line of its own.
        /// Lower: more left-out lines make the trace incomplete (exit 1).
        separate_share: f64 = 0.3,
        /// The graphite collected on each side of a gap for its refitted bridge
        /// ([`crate::trace::bridge_fit`]), mm of written path: candidates, smallest first, the
        /// largest one whose fit stays within `bridge_wider_ok` of the smallest's taken. Longer:
        /// smoother bridges over gentle curves, more chance to take in a corner.
        bridge_side_mm: [f64; 3] = [3.5, 6.0, 9.0],
        /// Bridges longer than this keep their first guess (a gap bridged on purpose with a large
        /// `--max-gap-mm`): what the sides say about the middle of a long gap is no better than
        /// the first guess, mm. Longer: longer bridges refitted.
        bridge_max_refit_mm: f64 = 16.0,
        /// The walk outwards for a side's data stops after this much path (bridges included)
        /// beyond the side's data length, mm. Longer: sides read across more earlier bridges.
        bridge_walk_extra_mm: f64 = 12.0,
        /// Highest polynomial degree of a refitted bridge (at most 5 is tried, the solver's room).
        /// Higher: tighter curves followed, and noise with them. Count.
        bridge_max_degree: usize = 5,
        /// A larger side is taken while its leave-one-out residual stays within this factor of
        /// the smallest side's (no sign of the curve outgrowing the polynomial). Ratio. Larger:
        /// wider sides taken, over curves the polynomial follows worse.
        bridge_wider_ok: f64 = 1.25,
        /// Floor of a bridge fit's residual scale (centroid noise is never below this), mm.
        /// Larger: fewer points down-weighted as dust on a clean stroke.
        bridge_min_scale_mm: f64 = 0.002,
        /// A fit whose leave-one-out residual exceeds this (a corner, not a smooth curve) leaves
        /// the first guess in place, mm. Larger: more bridges refitted, over corners too.
        bridge_max_residual_mm: f64 = 0.05,
    }
}
