//! Open pieces cut where they turn sharply (a corner, or the tracker turning onto a stroke that
//! crosses the path), before their ends are read: the linker decides which way the path goes on.

use super::params::LinkParams;
use crate::trace::chain::PieceMm;
use crate::trace::plane::{dist, norm, sub};

/// Open pieces cut where they turn by more than `LinkParams::kink_deg` between the chords of the
/// `LinkParams::kink_chord_mm` before and after a point (a corner, or the tracker turning onto a stroke
/// that crosses the path): the linker decides which way the path goes on.
pub(super) fn split_kinks(pieces: &[PieceMm], lk: &LinkParams) -> Vec<PieceMm> {
    let mut out = Vec::with_capacity(pieces.len());
    for p in pieces {
        let n = p.pts.len();
        if p.closed || n < 5 {
            out.push(p.clone());
            continue;
        }
        // Chord ends by arc length: for each point the indices ~LinkParams::kink_chord_mm back and ahead.
        let mut s = vec![0.0; n];
        for i in 1..n {
            s[i] = s[i - 1] + dist(p.pts[i - 1], p.pts[i]);
        }
        let turn_at = |i: usize| -> f64 {
            let back = s[..i].partition_point(|&v| v < s[i] - lk.kink_chord_mm);
            let ahead = i + s[i..].partition_point(|&v| v < s[i] + lk.kink_chord_mm);
            if back >= i || ahead >= n || s[i] - s[back] < 0.8 * lk.kink_chord_mm {
                return 0.0;
            }
            let (u, v) = (sub(p.pts[i], p.pts[back]), sub(p.pts[ahead], p.pts[i]));
            let (nu, nv) = (norm(u), norm(v));
            if nu < 1e-9 || nv < 1e-9 {
                return 0.0;
            }
            ((u[0] * v[0] + u[1] * v[1]) / (nu * nv))
                .clamp(-1.0, 1.0)
                .acos()
        };
        let turns: Vec<f64> = (0..n).map(turn_at).collect();
        let limit = lk.kink_deg.to_radians();
        let mut cuts = Vec::new();
        let mut i = 0;
        while i < n {
            if turns[i] > limit {
                let mut j = i;
                while j + 1 < n && turns[j + 1] > limit {
                    j += 1;
                }
                let best = (i..=j)
                    .max_by(|&a, &b| turns[a].total_cmp(&turns[b]))
                    .unwrap_or(i);
                cuts.push(best);
                i = j + 1;
            } else {
                i += 1;
            }
        }
        let mut from = 0;
        for c in cuts.into_iter().chain(std::iter::once(n - 1)) {
            if c > from {
                out.push(PieceMm {
                    pts: p.pts[from..=c].to_vec(),
                    closed: false,
                });
            }
            from = c;
        }
    }
    out
}
