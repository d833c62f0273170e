//! Tracked pieces linked into chains ([`Network::build`]): kinks cut, ends read, candidate links
//! taken cheapest first, each end once, a second round between chains on the rig's one path
//! ([`super::relink`]), each chain walked and built with its bridges; the drawn path chosen
//! among the longest.

use super::bridge::build;
use super::continuity::{candidates, continuity};
use super::end::{ends, End};
use super::kinks::split_kinks;
use super::params::LinkParams;
use super::strokes::Strokes;
use super::{mean_from, relink, Gap};
use crate::sheet::ReferencePath;
use crate::trace::chain::{polyline_length, PieceMm, Stroke};
use crate::trace::plane::{dist, Grid};

/// A chain of pieces: piece indices in order, each reversed or not, and whether it closes.
#[derive(Debug, Clone)]
pub(super) struct Chain {
    pub(super) order: Vec<(usize, bool)>,
    pub(super) closed: bool,
}

/// Tracked pieces linked into chains (one per drawn line), each built with its bridges.
pub(in crate::trace) struct Network {
    pub(super) pieces: Vec<PieceMm>,
    pub(super) piece_ends: Vec<Option<[End; 2]>>,
    pub(super) chains: Vec<Chain>,
    /// Each chain's polyline, gaps and bridge mask ([`build`]).
    pub(super) built: Vec<(Stroke, Vec<Gap>, Vec<bool>)>,
    /// Each chain's length, mm.
    pub(in crate::trace) lengths: Vec<f64>,
    /// Every point of every chain of two points or more: (chain, index).
    pub(super) points: Grid<(usize, usize)>,
    pub(super) max_gap_mm: f64,
    pub(super) strokes: Strokes,
}

impl Network {
    /// Links `pieces` end to end by continuity. `None` without pieces.
    pub(in crate::trace) fn build(
        pieces: &[PieceMm],
        max_gap_mm: f64,
        strokes: Strokes,
        lk: &LinkParams,
    ) -> Option<Self> {
        let pieces: Vec<PieceMm> = split_kinks(pieces, lk)
            .into_iter()
            .filter(|p| p.pts.len() >= 2)
            .collect();
        if pieces.is_empty() {
            return None;
        }
        let piece_ends: Vec<Option<[End; 2]>> =
            pieces.iter().map(|p| ends(p, strokes, lk)).collect();
        let n_ends = 2 * pieces.len();
        // Candidate links within the bridging reach, over a coarse grid of end positions.
        let reach = max_gap_mm.max(1.0);
        let piece_len: Vec<f64> = pieces
            .iter()
            .map(|p| polyline_length(&p.pts, p.closed))
            .collect();
        let mut cands = candidates(&piece_ends, reach, |ea, eb, a, b| {
            let g = dist(a.p, b.p);
            // A piece closes on itself only across a gap short against its length.
            if ea / 2 == eb / 2 && piece_len[ea / 2] < 3.0 * g + 10.0 {
                return None;
            }
            continuity(a, b, reach, lk).filter(|_| g <= max_gap_mm || g < 1.0)
        });
        cands.sort_by(|x, y| x.cost.total_cmp(&y.cost));
        // Greedy: cheapest first, each end once. Every chain has exactly two free ends, so a
        // link between two ends of one chain closes it.
        let mut partner: Vec<Option<usize>> = vec![None; n_ends];
        for c in &cands {
            if partner[c.a].is_some() || partner[c.b].is_some() {
                continue;
            }
            partner[c.a] = Some(c.b);
            partner[c.b] = Some(c.a);
        }
        let first = walk_chains(&pieces, &piece_ends, &partner);
        // The rig's one path only ([`Strokes::relink`]).
        if strokes.relink {
            relink::relink(
                &first,
                &pieces,
                &piece_ends,
                &mut partner,
                max_gap_mm,
                strokes,
                lk,
            );
        }
        let chains = walk_chains(&pieces, &piece_ends, &partner);
        let built: Vec<(Stroke, Vec<Gap>, Vec<bool>)> = chains
            .iter()
            .map(|c| build(c, &pieces, &piece_ends, strokes, lk))
            .collect();
        let lengths: Vec<f64> = built.iter().map(|(s, ..)| s.length_mm()).collect();
        let mut points = Grid::new(lk.cross_touch_mm);
        for (ci, (s, ..)) in built.iter().enumerate() {
            if s.points_mm.len() >= 2 {
                for (k, p) in s.points_mm.iter().enumerate() {
                    points.insert(*p, (ci, k));
                }
            }
        }
        Some(Self {
            pieces,
            piece_ends,
            chains,
            built,
            lengths,
            points,
            max_gap_mm,
            strokes,
        })
    }

    pub(super) fn end(&self, e: usize) -> Option<End> {
        self.piece_ends[e / 2].map(|pe| pe[e % 2])
    }

    /// The drawn path: the longest chain; among chains within 80 % of it, the one nearest the
    /// printed path.
    pub(super) fn choose_main(&self, hint: Option<ReferencePath>) -> Option<usize> {
        let longest = self.lengths.iter().copied().fold(0.0, f64::max);
        (0..self.built.len())
            .filter(|&i| self.lengths[i] >= 0.8 * longest)
            .min_by(|&i, &j| {
                let near =
                    |k: usize| hint.map_or(0.0, |h| mean_from(&self.built[k].0.points_mm, h));
                near(i)
                    .total_cmp(&near(j))
                    .then(self.lengths[j].total_cmp(&self.lengths[i]))
            })
    }

    /// The chain of index `ci` as built (bridges as first guesses, not refitted).
    pub(in crate::trace) fn chain_stroke(&self, ci: usize) -> &Stroke {
        &self.built[ci].0
    }
}

/// The chains of linked pieces: each from a free end (or around a cycle).
fn walk_chains(
    pieces: &[PieceMm],
    piece_ends: &[Option<[End; 2]>],
    partner: &[Option<usize>],
) -> Vec<Chain> {
    let mut seen = vec![false; pieces.len()];
    let mut chains = Vec::new();
    for start in 0..pieces.len() {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        if piece_ends[start].is_none() {
            chains.push(Chain {
                order: vec![(start, false)],
                closed: pieces[start].closed,
            });
            continue;
        }
        // Backwards from the head of `start` to a free end, or around a cycle.
        let mut e = 2 * start;
        let mut cycle = false;
        for _ in 0..=pieces.len() {
            match partner[e] {
                Some(q) if q / 2 == start => {
                    cycle = true;
                    break;
                }
                Some(q) => e = q ^ 1,
                None => break,
            }
        }
        let mut entry = if cycle { 2 * start } else { e };
        let mut order = Vec::new();
        loop {
            let p = entry / 2;
            order.push((p, entry % 2 == 1));
            seen[p] = true;
            match partner[entry ^ 1] {
                Some(q) if q / 2 != order[0].0 && !order.iter().any(|(o, _)| *o == q / 2) => {
                    entry = q;
                }
                _ => break,
            }
        }
        chains.push(Chain {
            order,
            closed: cycle,
        });
    }
    chains
}
