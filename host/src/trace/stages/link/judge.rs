//! One chain judged as the drawn line: bridged across the marks that touch it, its bridges
//! refitted and its centres smoothed, its free ends and the gaps beyond them too long to bridge
//! ([`Network::judge`]); what it leaves out, and why ([`Network::left_out`]).

use super::bridge::bridge;
use super::continuity::continuity;
use super::crossings::cut_crossings;
use super::end::End;
use super::network::Network;
use super::params::LinkParams;
use super::{orient, Gap, LeftOut, LeftOutKind};
use crate::trace::chain::Stroke;
use crate::trace::plane::{dist, norm, sub};
use crate::trace::{bridge_fit, smooth};

/// One chain judged as a drawn line: its refined polyline, its gaps (bridged in order along
/// it, then the missing ones), its free ends, and which other chains may continue it.
pub(in crate::trace) struct Judged {
    pub(in crate::trace) path: Stroke,
    pub(in crate::trace) gaps: Vec<Gap>,
    free: Vec<End>,
    continues: Vec<bool>,
    /// For each missing gap in `gaps` (in order), the chain it leads to (`None`: the path's
    /// own other end).
    pub(in crate::trace) missing_to: Vec<Option<usize>>,
}

impl Judged {
    /// The free ends of the path: position and outward unit tangent.
    pub(in crate::trace) fn free_ends(&self) -> Vec<([f64; 2], [f64; 2])> {
        self.free.iter().map(|e| (e.p, e.t)).collect()
    }
}

impl Network {
    /// Chain `main` as a drawn line: bridged across the marks that touch it, its bridges
    /// refitted, its written centres smoothed along it on one path ([`super::Strokes::smooth_centres`]; the
    /// lines of `--paths` are smoothed across the band of their passes instead), its free ends
    /// and the gaps beyond them that are too long to bridge.
    pub(in crate::trace) fn judge(&self, main: usize, lk: &LinkParams) -> Judged {
        let max_gap_mm = self.max_gap_mm;
        let (path, mut gaps, mask) = self.built[main].clone();
        // The points of other chains that touch this one (the rest cannot cut it).
        let mut touching: Vec<(usize, usize)> = path
            .points_mm
            .iter()
            .flat_map(|p| self.points.within(*p, lk.cross_touch_mm))
            .map(|(_, ck)| *ck)
            .filter(|(ci, _)| *ci != main)
            .collect();
        touching.sort_unstable();
        touching.dedup();
        let touching: Vec<[f64; 2]> = touching
            .into_iter()
            .map(|(ci, k)| self.built[ci].0.points_mm[k])
            .collect();
        let (path, mask) = cut_crossings(
            path,
            mask,
            &[touching.as_slice()],
            &mut gaps,
            self.strokes,
            lk,
        );
        let (points_mm, mask, bridged_mm) =
            bridge_fit::refine(&path.points_mm, &mask, path.closed, lk);
        let points_mm = if self.strokes.smooth_centres {
            smooth::smooth_written(&points_mm, &mask, path.closed)
        } else {
            points_mm
        };
        let path = Stroke {
            points_mm,
            bridged_mm,
            ..path
        };
        let main_chain = &self.chains[main];
        // Free ends of the path and what lies beyond them.
        let mut free: Vec<End> = Vec::new();
        if !main_chain.closed {
            let (first, last) = (
                main_chain.order[0],
                main_chain.order[main_chain.order.len() - 1],
            );
            let first_entry = 2 * first.0 + usize::from(first.1);
            let last_exit = (2 * last.0 + usize::from(last.1)) ^ 1;
            for e in [first_entry, last_exit] {
                if let Some(x) = self.end(e) {
                    free.push(x);
                }
            }
        }
        let far = (5.0 * max_gap_mm).max(50.0);
        let mut continues: Vec<bool> = vec![false; self.chains.len()];
        let mut missing_to: Vec<Option<usize>> = Vec::new();
        if free.len() == 2 {
            // The path's ends continuing into each other across a gap too long to bridge.
            if dist(free[0].p, free[1].p) > max_gap_mm {
                if let Some(_c) = continuity(&free[0], &free[1], far, lk)
                    .filter(|_| path.length_mm() > 2.0 * dist(free[0].p, free[1].p))
                {
                    let (_, len) = bridge(&free[0], &free[1], lk);
                    gaps.push(Gap {
                        from_mm: free[1].p,
                        to_mm: free[0].p,
                        length_mm: len,
                        bridged: false,
                    });
                    missing_to.push(None);
                }
            }
        }
        let mut main_pieces = vec![false; self.pieces.len()];
        for (p, _) in &main_chain.order {
            main_pieces[*p] = true;
        }
        for f in &free {
            let mut best: Option<(f64, usize, End)> = None;
            for (ci, ch) in self.chains.iter().enumerate() {
                if ci == main || self.lengths[ci] < 2.0 || ch.closed {
                    continue;
                }
                let (first, last) = (ch.order[0], ch.order[ch.order.len() - 1]);
                for e in [
                    2 * first.0 + usize::from(first.1),
                    (2 * last.0 + usize::from(last.1)) ^ 1,
                ] {
                    if main_pieces[e / 2] {
                        continue;
                    }
                    let Some(x) = self.end(e) else { continue };
                    if dist(f.p, x.p) <= max_gap_mm {
                        continue; // was admissible and not taken: not a continuation
                    }
                    if let Some(c) = continuity(f, &x, far, lk) {
                        if best.is_none_or(|(bc, ..)| c < bc) {
                            best = Some((c, ci, x));
                        }
                    }
                }
            }
            if let Some((_, ci, x)) = best {
                let (_, len) = bridge(f, &x, lk);
                gaps.push(Gap {
                    from_mm: f.p,
                    to_mm: x.p,
                    length_mm: len,
                    bridged: false,
                });
                missing_to.push(Some(ci));
                continues[ci] = true;
            }
        }
        Judged {
            path: orient(path),
            gaps,
            free,
            continues,
            missing_to,
        }
    }

    /// What the judged chain `main` leaves out: every other chain with its index, longest
    /// first, with why.
    pub(in crate::trace) fn left_out_indexed(
        &self,
        main: usize,
        judged: &Judged,
        lk: &LinkParams,
    ) -> Vec<(usize, LeftOut)> {
        let reach_ahead = (2.0 * self.max_gap_mm).max(15.0);
        let main_len = self.lengths[main];
        let mut left_out: Vec<(usize, LeftOut)> = Vec::new();
        for (ci, (s, ..)) in self.built.iter().enumerate() {
            if ci == main {
                continue;
            }
            let len = self.lengths[ci];
            let pts = &s.points_mm;
            let ahead = len >= lk.min_mark_mm
                && judged.free.iter().any(|f| {
                    pts.iter().any(|q| {
                        let d = sub(*q, f.p);
                        let dn = norm(d);
                        dn <= reach_ahead
                            && (dn < 1e-9 || (d[0] * f.t[0] + d[1] * f.t[1]) / dn >= 0.7)
                    })
                });
            let kind = if judged.continues[ci] || ahead {
                LeftOutKind::Continues
            } else if len >= lk.min_mark_mm.max(lk.separate_share * main_len) {
                LeftOutKind::Separate
            } else if len < lk.min_mark_mm {
                LeftOutKind::Speck
            } else {
                LeftOutKind::Mark
            };
            left_out.push((
                ci,
                LeftOut {
                    from_mm: pts[0],
                    to_mm: pts[pts.len() - 1],
                    length_mm: len,
                    kind,
                },
            ));
        }
        left_out.sort_by(|a, b| b.1.length_mm.total_cmp(&a.1.length_mm));
        left_out
    }
}
