//! The second renderer's pencil: a mark as a chain of tip discs stamped every 0.03 mm (each its
//! own radius and pressure, a dome profile), skips left unwritten, and a grid that finds the
//! discs near a point.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::scene::Mark;

pub(super) struct Stamp {
    pub(super) c: [f64; 2],
    pub(super) r: f64,
    a: f64,
}

/// Stamps indexed on a grid of 0.25 mm cells over +-120 mm (compressed rows).
pub(super) struct StampGrid {
    pub(super) stamps: Vec<Stamp>,
    start: Vec<u32>,
    list: Vec<u32>,
    max_r: f64,
}

const SG_CELL: f64 = 0.25;
const SG_N: usize = 960;

fn sg_cell(p: [f64; 2]) -> Option<(usize, usize)> {
    let (i, j) = ((p[0] + 120.0) / SG_CELL, (p[1] + 120.0) / SG_CELL);
    (i >= 0.0 && j >= 0.0 && (i as usize) < SG_N && (j as usize) < SG_N)
        .then_some((i as usize, j as usize))
}

impl StampGrid {
    pub(super) fn new(stamps: Vec<Stamp>) -> Self {
        let mut count = vec![0u32; SG_N * SG_N + 1];
        let mut max_r: f64 = 0.0;
        let cells: Vec<Option<usize>> = stamps
            .iter()
            .map(|s| {
                max_r = max_r.max(s.r);
                sg_cell(s.c).map(|(i, j)| j * SG_N + i)
            })
            .collect();
        for c in cells.iter().flatten() {
            count[c + 1] += 1;
        }
        for k in 1..count.len() {
            count[k] += count[k - 1];
        }
        let mut fill = count.clone();
        let mut list = vec![0u32; stamps.len()];
        for (k, c) in cells.iter().enumerate() {
            if let Some(c) = c {
                list[fill[*c] as usize] = k as u32;
                fill[*c] += 1;
            }
        }
        Self {
            stamps,
            start: count,
            list,
            max_r,
        }
    }

    /// Darkness of the graphite at `p` (max over the discs, dome profile).
    pub(super) fn at(&self, p: [f64; 2]) -> f64 {
        let Some((ci, cj)) = sg_cell(p) else {
            return 0.0;
        };
        let n = (self.max_r / SG_CELL).ceil() as usize;
        let mut best: f64 = 0.0;
        for j in cj.saturating_sub(n)..=(cj + n).min(SG_N - 1) {
            for i in ci.saturating_sub(n)..=(ci + n).min(SG_N - 1) {
                let c = j * SG_N + i;
                for &k in &self.list[self.start[c] as usize..self.start[c + 1] as usize] {
                    let s = &self.stamps[k as usize];
                    let d2 = (p[0] - s.c[0]).powi(2) + (p[1] - s.c[1]).powi(2);
                    if d2 < s.r * s.r {
                        best = best.max(s.a * (1.0 - d2 / (s.r * s.r)).sqrt());
                    }
                }
            }
        }
        best
    }
}

fn arc_lengths(pts: &[[f64; 2]]) -> Vec<f64> {
    let mut s = vec![0.0];
    for w in pts.windows(2) {
        let l = s[s.len() - 1] + (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        s.push(l);
    }
    s
}

pub(super) fn stamps_of(mark: &Mark, seed: u64) -> Vec<Stamp> {
    let s = arc_lengths(&mark.pts);
    let mut out = Vec::new();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Slow pressure: three random sines over the arc length.
    let waves: Vec<(f64, f64, f64)> = (0..3)
        .map(|_| {
            (
                rng.gen_range(0.04..0.12),
                rng.gen_range(5.0..60.0),
                rng.gen_range(0.0..std::f64::consts::TAU),
            )
        })
        .collect();
    let mut next = 0.0;
    for (i, p) in mark.pts.iter().enumerate() {
        if s[i] < next {
            continue;
        }
        next = s[i] + 0.03;
        if mark.skips.iter().any(|k| s[i] >= k[0] && s[i] <= k[1]) {
            continue;
        }
        let pressure: f64 = 1.0
            + waves
                .iter()
                .map(|(a, l, ph)| a * (s[i] / l * std::f64::consts::TAU + ph).sin())
                .sum::<f64>();
        out.push(Stamp {
            c: *p,
            r: 0.5 * mark.width_mm * (1.0 + 0.06 * (rng.gen::<f64>() - 0.5)),
            a: (mark.darkness * pressure * (0.9 + 0.2 * rng.gen::<f64>())).min(0.95),
        });
    }
    out
}
