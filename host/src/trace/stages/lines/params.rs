//! The drawn-lines stage's tuned numbers ([`super::lines`], `rigctl trace --paths`), in one
//! place: each with its unit and what it trades off.

/// The band's tuned half width ([`LinesParams::band_half_mm`]), and the unit of the widths of
/// this stage derived from it, mm.
const BAND_HALF_MM: f64 = 3.0;

stage_params! {
    /// The numbers of the drawn-lines stage: which paths are passes of a line, how a line's ends
    /// are read, carried on and met.
    pub struct LinesParams {
        /// Passes of one line lie within this of its centre, mm. Wider: passes drawn further apart
        /// are one line, and two close parallel lines become one.
        alongside_mm: f64 = BAND_HALF_MM,
        /// A path is a pass of a line with this much of it in the line's band (or half of it), mm.
        pass_mm: f64 = 5.0,
        /// Direction of a path at a point: the chord over this arc length either side of it, mm.
        dir_half_mm: f64 = 4.0,
        /// A mark meeting a pass's end at more than this to it runs across the line, degrees.
        /// Lower: more marks read as across (ending a line) rather than continuing it.
        across_deg: f64 = 45.0,
        /// Direction of a line's end (to carry it on past the end, and to tell whether another line
        /// continues it): the chord over this length, mm (a zigzag pass turns often within a few
        /// mm).
        end_chord_mm: f64 = 12.0,
        /// A walk starts the way its seed path runs over this either side of the seed, mm.
        seed_half_mm: f64 = 8.0,
        /// Spacing of a line's centreline, mm.
        line_spacing_mm: f64 = 0.25,
        /// Marks shorter than this are not followed (dust), mm.
        min_dot_mark_mm: f64 = 1.0,
        /// A path turning by more than this between the chords of `dir_half_mm` before and after a
        /// point turns a corner there, degrees.
        corner_deg: f64 = 50.0,
        /// Direction of a path's point for following a band: the chord over this either side, mm.
        band_dir_half_mm: f64 = 4.0,
        /// A walk whose centres lie within this of another line's (running its way) for half its
        /// length is that line, mm.
        duplicate_mm: f64 = 1.5 * BAND_HALF_MM,
        /// A walk whose end lies within this of another's centres may be continued by it, mm (the
        /// band's width: passes drawn apart).
        join_mm: f64 = 2.0 * BAND_HALF_MM,
        /// Walks continue each other only where their directions (over `end_chord_mm`) agree within
        /// this, degrees. Wider: lines joined round sharper corners.
        join_deg: f64 = 40.0,
        /// A line ends on a line across it whose centreline lies within this ahead of its end, mm.
        meet_mm: f64 = BAND_HALF_MM + 1.5,
        /// ... or within this, where the stretch beyond the other's band is drawn (no stretch
        /// longer than `inkless_ok_mm` without a written point within 1 mm) or else a skip
        /// (bridged), mm.
        meet_inked_mm: f64 = 2.0 * BAND_HALF_MM,
        /// The longest stretch without a written point within 1 mm that still counts as drawn (for
        /// `meet_inked_mm`), mm. Longer: a skip just before the line across reads as drawn.
        inkless_ok_mm: f64 = 1.0,
        /// ... within this of the end's direction, mm.
        step_off_mm: f64 = 1.0,
        /// At most this much of a line's end is another line's, mm.
        overrun_max_mm: f64 = 20.0,
        /// The line's own direction at an end: the chord over this much before the stretch that may
        /// be another line's, mm.
        own_dir_mm: f64 = 15.0,
        /// The end ran along the other line, inside its band, at least this far, mm.
        along_other_mm: f64 = 2.0,
        /// A centre whose direction is off the line's own by more than this has left the line,
        /// degrees.
        turned_deg: f64 = 20.0,
        /// Less than this is not cut (a centre wobbling in the other line's band), mm.
        overrun_min_mm: f64 = 1.0,
        /// A line's band ([`crate::trace::band`]) reaches this far either side of its centre, mm.
        /// Wider: passes drawn further apart followed as one line, and a close parallel line
        /// pulled in.
        band_half_mm: f64 = BAND_HALF_MM,
        /// Points running within this angle of the line belong to its band, degrees. Wider: a
        /// band followed through tighter bends, and onto lines crossing it at a shallow angle.
        band_deg: f64 = 40.0,
        /// A band's centre is placed among the points running within this angle of the line,
        /// degrees. Wider: more points steer the centre, a pass leaving the line among them.
        band_centre_deg: f64 = 25.0,
        /// ... moving at most this across the line from one centre to the next, mm. More: the
        /// centre follows a bend sooner, and a pass leaving the line drags it further.
        band_max_shift_mm: f64 = 0.15,
        /// Distance between a band's centres, mm. Shorter: a finer centreline, more steps.
        band_step_mm: f64 = 0.5,
        /// A band's window reaches this far along the line either side of a centre, mm. Longer:
        /// steadier centres, later to follow a bend.
        band_half_along_mm: f64 = 1.5,
        /// A band walk's direction is the chord back over this arc, mm. Longer: steadier against
        /// the passes' scatter, later to turn with the line.
        band_dir_back_mm: f64 = 4.0,
        /// A walk coming back within this of its own start (after `band_close_after_mm`) closes,
        /// mm. Larger: a loop closed across a wider miss.
        band_close_mm: f64 = 1.5,
        /// A walk closes only after this much arc, mm. Shorter: small loops closed, and a walk
        /// turning back early taken for one.
        band_close_after_mm: f64 = 20.0,
        /// A walk turning by more than these angles (degrees) over the arcs of
        /// `band_turn_over_mm` ends there (a corner). Lower: gentler corners end a line.
        band_turn_deg: [f64; 2] = [45.0, 60.0],
        /// The arcs the turns of `band_turn_deg` are measured over, mm (the corner is cut half
        /// of it back). Shorter: only sharp corners seen.
        band_turn_over_mm: [f64; 2] = [8.0, 16.0],
        /// A gap longer than `--max-gap-mm` leads only to a path running the line's way (within
        /// `band_centre_deg`) with this many points within `band_far_mark_mm` of each other along
        /// it. More: fewer far gaps crossed onto specks; a short far stretch missed.
        band_far_min_dots: usize = 12,
        /// The length the points of `band_far_min_dots` lie within, mm.
        band_far_mark_mm: f64 = 5.0,
        /// ... and only from a line drawn straight for this long before the gap, mm. Longer:
        /// fewer far gaps crossed from a bend.
        band_settled_mm: f64 = 10.0,
        /// A point of a gap within this of a written point is inked, mm. Larger: gaps read as
        /// shorter where stray ink lies beside them.
        band_ink_near_mm: f64 = 1.0,
        /// Ink past a line's end ([`crate::trace::probe`]): a pixel is ink when its darkness (1 -
        /// the lightest of its channels relative to the paper's) is at least this. Ratio. Lower:
        /// fainter marks (and paper texture) read as ink past an end.
        probe_ink_darkness: f32 = 0.15,
        /// The probe past an end reaches this far across the end's direction, mm. Wider: ink of a
        /// line turning just after its end found, and ink beside it too.
        probe_half_mm: f64 = 2.0,
        /// A written point within this covers the ink the probe finds, mm. Larger: more ink next
        /// to the written paths taken as traced.
        probe_traced_mm: f64 = 1.2,
        /// Untraced ink this long along the end's direction may continue the line, mm. Longer:
        /// fewer specks past an end make a line not whole.
        probe_run_mm: f64 = 2.0,
        /// ... counted over holes up to this long, mm. Longer: a dashed or looping line's ink
        /// summed over wider holes.
        probe_hole_mm: f64 = 3.0,
        /// The band of a line across (the line an end ends on) reaches this far from its
        /// centreline, and its ink is not probed, mm. Wider: more ink beside a crossing ignored.
        probe_across_band_mm: f64 = 4.0,
        /// The probe's grid spacing, along and across the end, mm. Finer: thinner ink found, more
        /// pixels read.
        probe_step_mm: f64 = 0.25,
    }
}
