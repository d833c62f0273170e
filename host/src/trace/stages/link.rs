//! The drawn path from the graphite itself: tracked pieces are linked end to end by continuity
//! (position, direction and curvature carried across each gap), one curve per drawn line, open
//! or closed, any shape; the printed reference is never a mask, only a hint between chains of
//! similar length.
//!
//! Open pieces are first cut where they turn sharply (a corner, or the tracker turning onto a
//! stroke that crosses the path). Every end of an open piece gets its outward tangent and
//! curvature from its last 8 mm (on a plotter's passes, [`Strokes::PASSES`], from the 6.5 mm
//! before its last 1.5 mm); on the rig's one path, where a crest within them bends it harder
//! than the curvature is clamped to, its tangent from its last 3 mm. A link
//! between two ends is admissible when each end's arc, extrapolated over the gap, lands on the
//! other end and the directions agree, turned by the mean of the two ends' curvatures over the
//! gap (tolerances grow with the gap); ends that nearly touch
//! (< 1 mm) need only not double back (a corner). A link those arcs miss (a short end reads no
//! curvature, a long one its span's mean, clamped) is admissible when the path bends one way
//! through the gap and each end bends along itself with it ([`continuity::bends_through`]: a
//! tight crest, not a corner).
//! Links are taken cheapest first, each end once, a cycle only as
//! the closing link of a chain, so a second pencil stroke crossing the path is passed over: its
//! ends meet the path's ends at the wrong angle, and where the crossing cut the path in two the
//! two halves continue each other across it. On the rig's one path a second round reads the
//! free ends of the chains again through the chains themselves ([`relink`]: a short stroke
//! between two skips gets the bend of the stroke it is linked to) and links what it then
//! admits. Gaps up to `max_gap_mm` are bridged: a cubic
//! Hermite curve through both ends' positions and tangents as a first guess, then refitted
//! from the written points on both sides ([`crate::trace::bridge_fit`]).
//!
//! The longest chain is the drawn path. What is left out is listed: specks (shorter than
//! [`LinkParams::min_mark_mm`]), marks, and marks that could be part of the path: a link from one of the
//! path's free ends that would be admissible but longer than `max_gap_mm` (a gap not bridged,
//! including an open path whose ends continue into each other), or a mark of at least
//! [`LinkParams::min_mark_mm`] ahead of a free end within reach, or a separate line nearly as long as the
//! path. Those make the trace incomplete.
//!
//! Files, in the order of the work: `kinks.rs` (pieces cut at sharp turns), `end.rs` (each end's
//! tangent and curvature), `continuity.rs` (which ends continue each other, at what cost),
//! `network.rs` (links taken, chains walked, the drawn path chosen), `relink.rs` (the second
//! round), `bridge.rs` (bridges and each chain's polyline), `crossings.rs` (the path bridged
//! where another mark touches it), `judge.rs` (the chosen chain's free ends, missing gaps and
//! what is left out); here the types the rest of `trace` reads and [`link`] itself.

mod bridge;
mod continuity;
mod crossings;
mod end;
mod judge;
mod kinks;
mod network;
mod params;
mod relink;
mod runs;
mod strokes;
#[cfg(test)]
mod tests;

pub(in crate::trace) use network::Network;
pub(in crate::trace) use strokes::Strokes;

use crate::sheet::ReferencePath;
use crate::trace::chain::{PieceMm, Stroke};
use crate::trace::plane::dist;
pub use params::LinkParams;

/// A gap between two linked pieces of the drawn path.
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// Where the written trace stops and starts again, sheet mm.
    pub from_mm: [f64; 2],
    pub to_mm: [f64; 2],
    /// Length of the bridge curve across it, mm.
    pub length_mm: f64,
    /// Bridged (at most `max_gap_mm`); otherwise missing.
    pub bridged: bool,
}

/// Why a mark was not written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LeftOutKind {
    /// Shorter than [`LinkParams::min_mark_mm`]: dust, a fibre, a flick.
    Speck,
    /// A mark apart from the path (a stroke across it, a stray line).
    Mark,
    /// Long enough and ahead of a free end of the path, within reach: it may continue the path.
    Continues,
    /// A drawn line of its own, comparable in length to the path.
    Separate,
}

/// A mark (chain of pieces) not in the written path.
#[derive(Debug, Clone, PartialEq)]
pub struct LeftOut {
    pub from_mm: [f64; 2],
    pub to_mm: [f64; 2],
    pub length_mm: f64,
    pub kind: LeftOutKind,
}

impl LeftOut {
    /// Whether leaving it out means the written trace may not be the whole drawn path.
    pub fn could_be_path(&self) -> bool {
        matches!(self.kind, LeftOutKind::Continues | LeftOutKind::Separate)
    }
}

/// Where another drawn run crosses (or meets) the path: a second drawing on the sheet, not a
/// gap or a continuation of the path.
#[derive(Debug, Clone, PartialEq)]
pub struct Crossing {
    /// Where the two cross, sheet mm.
    pub at_mm: [f64; 2],
    /// The other run (or a part of it): its index in [`Linking::left_out`].
    pub other: usize,
}

/// The linked path and what was left out.
#[derive(Debug, Clone)]
pub struct Linking {
    /// The drawn path (bridges included), ordered along it.
    pub path: Stroke,
    /// The other chains, longest first (not resampled).
    pub others: Vec<Stroke>,
    /// Gaps of the path: bridged ones in order along it, then the missing ones.
    pub gaps: Vec<Gap>,
    pub left_out: Vec<LeftOut>,
    /// Where another drawn run crosses or meets the path (two drawn paths), along x.
    pub crossings: Vec<Crossing>,
    /// The missing gaps (indices into `gaps`) that lead to such a run: its part across the
    /// path, not a pencil skip.
    pub gaps_to_crossing: Vec<usize>,
    /// Number of tracked pieces linked into the path.
    pub pieces: usize,
    /// The printed path used as a hint, and the mean distance of the path from it, mm.
    pub hint: Option<(ReferencePath, f64)>,
}

impl Linking {
    /// The gaps too long to bridge.
    pub fn missing(&self) -> impl Iterator<Item = &Gap> {
        self.gaps.iter().filter(|g| !g.bridged)
    }

    /// Whether the written path is the whole drawn path: nothing missing, nothing left out that
    /// could be part of it.
    pub fn is_whole(&self) -> bool {
        self.missing().next().is_none() && !self.left_out.iter().any(LeftOut::could_be_path)
    }
}

/// Links `pieces` into chains; returns the drawn path and what was left out. `hint`: the printed
/// path, to choose between chains of similar length. `None` without pieces.
pub(crate) fn link(
    pieces: &[PieceMm],
    max_gap_mm: f64,
    hint: Option<ReferencePath>,
    lk: &LinkParams,
) -> Option<Linking> {
    let net = Network::build(pieces, max_gap_mm, Strokes::ONE_PATH, lk)?;
    let main = net.choose_main(hint)?;
    let judged = net.judge(main, lk);
    // Another run crossing the path is named as such, whatever its length.
    let indexed = net.left_out_indexed(main, &judged, lk);
    let chain_of: Vec<usize> = indexed.iter().map(|(ci, _)| *ci).collect();
    let mut marks: Vec<(&Stroke, LeftOut)> = indexed
        .into_iter()
        .map(|(ci, o)| (net.chain_stroke(ci), o))
        .collect();
    let crossings = runs::crossings(&judged.path, &mut marks, lk);
    let left_out: Vec<LeftOut> = marks.into_iter().map(|(_, o)| o).collect();
    let crossing_chains: Vec<usize> = crossings.iter().map(|c| chain_of[c.other]).collect();
    let gaps_to_crossing: Vec<usize> = (0..judged.gaps.len())
        .filter(|&g| !judged.gaps[g].bridged)
        .zip(&judged.missing_to)
        .filter(|(_, to)| to.is_some_and(|ci| crossing_chains.contains(&ci)))
        .map(|(g, _)| g)
        .collect();
    let mut others: Vec<Stroke> = (0..net.built.len())
        .filter(|&ci| ci != main)
        .map(|ci| net.chain_stroke(ci).clone())
        .collect();
    others.sort_by(|a, b| b.length_mm().total_cmp(&a.length_mm()));
    let path = judged.path;
    let hint = hint.map(|h| (h, mean_from(&path.points_mm, h)));
    Some(Linking {
        path,
        others,
        gaps: judged.gaps,
        left_out,
        crossings,
        gaps_to_crossing,
        pieces: net.chains[main].order.len(),
        hint,
    })
}

/// Total length of piece segments within `band_mm` of the printed `path` (to pick the hint).
pub(crate) fn length_near(pieces: &[PieceMm], path: ReferencePath, band_mm: f64) -> f64 {
    pieces
        .iter()
        .flat_map(|p| p.pts.windows(2))
        .filter(|w| path.distance_mm(w[0]) <= band_mm && path.distance_mm(w[1]) <= band_mm)
        .map(|w| dist(w[0], w[1]))
        .sum()
}

/// Mean distance of `pts` from the printed path.
fn mean_from(pts: &[[f64; 2]], h: ReferencePath) -> f64 {
    if pts.is_empty() {
        return f64::INFINITY;
    }
    pts.iter().map(|p| h.distance_mm(*p)).sum::<f64>() / pts.len() as f64
}

/// A fixed order: a closed path counter-clockwise from its point at the smallest polar angle
/// about its centroid; an open path from its end with the smaller x (then y).
pub(in crate::trace) fn orient(mut s: Stroke) -> Stroke {
    let pts = &mut s.points_mm;
    if pts.len() < 2 {
        return s;
    }
    if s.closed {
        let area: f64 = (0..pts.len())
            .map(|i| {
                let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
                a[0] * b[1] - a[1] * b[0]
            })
            .sum();
        if area < 0.0 {
            pts.reverse();
        }
        let n = pts.len() as f64;
        let c = [
            pts.iter().map(|p| p[0]).sum::<f64>() / n,
            pts.iter().map(|p| p[1]).sum::<f64>() / n,
        ];
        let start = (0..pts.len())
            .min_by(|&i, &j| {
                let a = |k: usize| {
                    (pts[k][1] - c[1])
                        .atan2(pts[k][0] - c[0])
                        .rem_euclid(std::f64::consts::TAU)
                };
                a(i).total_cmp(&a(j))
            })
            .unwrap_or(0);
        pts.rotate_left(start);
    } else {
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        if (b[0], b[1]) < (a[0], a[1]) {
            pts.reverse();
        }
    }
    s
}
