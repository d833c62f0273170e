//! The drawn-lines stage's tuned numbers ([`super::lines`], `rigctl trace --paths`), in one
//! place: each with its unit and what it trades off.

use crate::trace::band::BAND_HALF_MM;

/// The numbers of the drawn-lines stage: which paths are passes of a line, how a line's ends are
/// read, carried on and met.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::trace) struct LinesParams {
    /// Passes of one line lie within this of its centre, mm. Wider: passes drawn further apart
    /// are one line, and two close parallel lines become one.
    pub(in crate::trace) alongside_mm: f64,
    /// A path is a pass of a line with this much of it in the line's band (or half of it), mm.
    pub(in crate::trace) pass_mm: f64,
    /// Direction of a path at a point: the chord over this arc length either side of it, mm.
    pub(in crate::trace) dir_half_mm: f64,
    /// A mark meeting a pass's end at more than this to it runs across the line, degrees. Lower:
    /// more marks read as across (ending a line) rather than continuing it.
    pub(in crate::trace) across_deg: f64,
    /// Direction of a line's end (to carry it on past the end, and to tell whether another line
    /// continues it): the chord over this length, mm (a zigzag pass turns often within a few mm).
    pub(in crate::trace) end_chord_mm: f64,
    /// A walk starts the way its seed path runs over this either side of the seed, mm.
    pub(in crate::trace) seed_half_mm: f64,
    /// Spacing of a line's centreline, mm.
    pub(in crate::trace) line_spacing_mm: f64,
    /// Marks shorter than this are not followed (dust), mm.
    pub(in crate::trace) min_dot_mark_mm: f64,
    /// A path turning by more than this between the chords of `dir_half_mm` before and after a
    /// point turns a corner there, degrees.
    pub(in crate::trace) corner_deg: f64,
    /// Direction of a path's point for following a band: the chord over this either side, mm.
    pub(in crate::trace) band_dir_half_mm: f64,
    /// A walk whose centres lie within this of another line's (running its way) for half its
    /// length is that line, mm.
    pub(in crate::trace) duplicate_mm: f64,
    /// A walk whose end lies within this of another's centres may be continued by it, mm (the
    /// band's width: passes drawn apart).
    pub(in crate::trace) join_mm: f64,
    /// Walks continue each other only where their directions (over `end_chord_mm`) agree within
    /// this, degrees. Wider: lines joined round sharper corners.
    pub(in crate::trace) join_deg: f64,
    /// A line ends on a line across it whose centreline lies within this ahead of its end, mm.
    pub(in crate::trace) meet_mm: f64,
    /// ... or within this, where the stretch beyond the other's band is drawn (no stretch longer
    /// than `inkless_ok_mm` without a written point within 1 mm) or else a skip (bridged), mm.
    pub(in crate::trace) meet_inked_mm: f64,
    /// The longest stretch without a written point within 1 mm that still counts as drawn
    /// (for `meet_inked_mm`), mm. Longer: a skip just before the line across reads as drawn.
    pub(in crate::trace) inkless_ok_mm: f64,
    /// ... within this of the end's direction, mm.
    pub(in crate::trace) step_off_mm: f64,
    /// At most this much of a line's end is another line's, mm.
    pub(in crate::trace) overrun_max_mm: f64,
    /// The line's own direction at an end: the chord over this much before the stretch that may
    /// be another line's, mm.
    pub(in crate::trace) own_dir_mm: f64,
    /// The end ran along the other line, inside its band, at least this far, mm.
    pub(in crate::trace) along_other_mm: f64,
    /// A centre whose direction is off the line's own by more than this has left the line,
    /// degrees.
    pub(in crate::trace) turned_deg: f64,
    /// Less than this is not cut (a centre wobbling in the other line's band), mm.
    pub(in crate::trace) overrun_min_mm: f64,
}

/// The tuned values.
pub(in crate::trace) const LINES: LinesParams = LinesParams {
    alongside_mm: BAND_HALF_MM,
    pass_mm: 5.0,
    dir_half_mm: 4.0,
    across_deg: 45.0,
    end_chord_mm: 12.0,
    seed_half_mm: 8.0,
    line_spacing_mm: 0.25,
    min_dot_mark_mm: 1.0,
    corner_deg: 50.0,
    band_dir_half_mm: 4.0,
    duplicate_mm: 1.5 * BAND_HALF_MM,
    join_mm: 2.0 * BAND_HALF_MM,
    join_deg: 40.0,
    meet_mm: BAND_HALF_MM + 1.5,
    meet_inked_mm: 2.0 * BAND_HALF_MM,
    inkless_ok_mm: 1.0,
    step_off_mm: 1.0,
    overrun_max_mm: 20.0,
    own_dir_mm: 15.0,
    along_other_mm: 2.0,
    turned_deg: 20.0,
    overrun_min_mm: 1.0,
};
