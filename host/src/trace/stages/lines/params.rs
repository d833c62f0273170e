//! The drawn-lines stage's tuned numbers ([`super::lines`], `rigctl trace --paths`), in one
//! place: each with its unit and what it trades off.

use crate::trace::band::BAND_HALF_MM;

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
    }
}
