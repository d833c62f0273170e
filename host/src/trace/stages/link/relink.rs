//! A second linking round, between chains: a chain's free end is read again from the chain's
//! own polyline (its pieces with their bridges), so an end piece too short to read a tangent
//! and a curvature of its own (a stroke between two skips) gets them from the stroke it is
//! already linked to. Ends the first round could not link across a gap are tried again with
//! those readings, cheapest first, each end once.

use super::bridge::build;
use super::continuity::{candidates, continuity};
use super::end::{ends, End};
use super::network::Chain;
use super::params::LinkParams;
use super::strokes::Strokes;
use crate::trace::chain::{polyline_length, PieceMm};
use crate::trace::plane::dist;

/// The end indices (2 * piece + side) by which open `chain` leaves its first and last piece.
fn free_ends(chain: &Chain) -> [usize; 2] {
    let (p0, rev0) = chain.order[0];
    let (p1, rev1) = chain.order[chain.order.len() - 1];
    [2 * p0 + usize::from(rev0), (2 * p1 + usize::from(rev1)) ^ 1]
}

/// Links free chain ends the first round left apart, where the chains' own readings of their
/// ends admit it (see the module note); sets `partner` for the links made. Only chains of two
/// pieces or more read their ends again (a lone piece's ends read the same as before).
pub(super) fn relink(
    chains: &[Chain],
    pieces: &[PieceMm],
    piece_ends: &[Option<[End; 2]>],
    partner: &mut [Option<usize>],
    max_gap_mm: f64,
    strokes: Strokes,
    lk: &LinkParams,
) {
    // Per piece: the re-read ends of the chain it ends, at its free end indices; `None` where
    // the piece ends no open chain of two pieces or more.
    let mut reread: Vec<Option<[End; 2]>> = vec![None; pieces.len()];
    let mut chain_of = vec![usize::MAX; 2 * pieces.len()];
    let mut chain_len = vec![0.0; chains.len()];
    let mut any = false;
    for (ci, c) in chains.iter().enumerate() {
        if c.closed || c.order.iter().any(|(p, _)| piece_ends[*p].is_none()) {
            continue;
        }
        let [head, tail] = free_ends(c);
        chain_of[head] = ci;
        chain_of[tail] = ci;
        let piece_end = |k: usize| piece_ends[k / 2].map(|e| e[k % 2]);
        let mut read = [piece_end(head), piece_end(tail)];
        if c.order.len() >= 2 {
            let (stroke, ..) = build(c, pieces, piece_ends, strokes, lk);
            chain_len[ci] = stroke.length_mm();
            let whole = PieceMm {
                pts: stroke.points_mm,
                closed: false,
            };
            if let Some([h, t]) = ends(&whole, strokes, lk) {
                read = [Some(h), Some(t)];
                any = true;
            }
        } else {
            chain_len[ci] = polyline_length(&pieces[head / 2].pts, false);
        }
        // Only the free ends are read; the pieces' linked ends stay out of the candidates.
        for (k, e) in [(head, read[0]), (tail, read[1])] {
            if let (Some(e), Some(pe)) = (e, piece_ends[k / 2]) {
                reread[k / 2].get_or_insert(pe)[k % 2] = e;
            }
        }
    }
    if !any {
        return;
    }
    let reach = max_gap_mm.max(1.0);
    let mut cands = candidates(&reread, reach, |ea, eb, a, b| {
        let (ca, cb) = (chain_of[ea], chain_of[eb]);
        // Free chain ends only (their partners are unset by construction).
        if ca == usize::MAX || cb == usize::MAX {
            return None;
        }
        // Something new to try: one of the two chains has read its end again.
        if chains[ca].order.len() < 2 && chains[cb].order.len() < 2 {
            return None;
        }
        let g = dist(a.p, b.p);
        // A chain closes on itself only across a gap short against its length.
        if ca == cb && chain_len[ca] < 3.0 * g + 10.0 {
            return None;
        }
        // Ends that nearly touch were judged in the first round on their turn alone.
        if g < lk.relink_near_mm || g > max_gap_mm {
            return None;
        }
        continuity(a, b, reach, lk)
    });
    cands.sort_by(|x, y| x.cost.total_cmp(&y.cost));
    for c in &cands {
        if partner[c.a].is_some() || partner[c.b].is_some() {
            continue;
        }
        partner[c.a] = Some(c.b);
        partner[c.b] = Some(c.a);
    }
}
