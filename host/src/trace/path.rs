//! Assembling tracked pieces into the one pencil path along the printed reference path: the
//! pencil follows the printed circle or line within a few millimetres, so every piece is given
//! its position `s` along that path (mm of arc). Pieces that do not run along the path (dust,
//! fibres across it, the page edge, a stray mark) are left out; pieces that repeat a stretch
//! already covered are trimmed; what remains is concatenated in order of `s`, bridging pencil
//! skips up to `max_gap_mm`. Longer gaps are reported as missing.

use super::chain::{polyline_length, PieceMm, Stroke};
use crate::sheet::{ReferencePath, CIRCLE_RADIUS_MM, LINE_HALF_LENGTH_MM};

/// A stretch of the reference path between two written pieces.
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// Where the written trace stops and starts again, sheet mm.
    pub from_mm: [f64; 2],
    pub to_mm: [f64; 2],
    /// Length along the reference path, mm.
    pub length_mm: f64,
    /// Bridged by a straight segment (at most `max_gap_mm`); otherwise missing.
    pub bridged: bool,
}

/// The assembled path.
#[derive(Debug, Clone)]
pub struct Assembly {
    pub stroke: Stroke,
    /// Length of the reference path, mm.
    pub reference_mm: f64,
    /// Length of the reference path covered by written pencil, mm.
    pub covered_mm: f64,
    pub gaps: Vec<Gap>,
    /// Length of tracked marks that were not used (not along the path or repeating), mm.
    pub unused_mm: f64,
}

impl Assembly {
    /// The gaps that were too long to bridge.
    pub fn missing(&self) -> impl Iterator<Item = &Gap> {
        self.gaps.iter().filter(|g| !g.bridged)
    }
}

/// A run of points along the path, oriented so that `s` grows.
#[derive(Debug, Clone)]
struct Run {
    pts: Vec<[f64; 2]>,
    /// Unwrapped `s` of each point.
    s: Vec<f64>,
}

impl Run {
    fn extent(&self) -> f64 {
        self.s.last().copied().unwrap_or(0.0) - self.s.first().copied().unwrap_or(0.0)
    }
}

/// Position along the path (mm, in `[0, period)` for the circle) and distance from it.
fn locate(path: ReferencePath, p: [f64; 2]) -> (f64, f64) {
    match path {
        ReferencePath::Circle => {
            let a = p[1].atan2(p[0]).rem_euclid(std::f64::consts::TAU);
            (
                a * CIRCLE_RADIUS_MM,
                (p[0].hypot(p[1]) - CIRCLE_RADIUS_MM).abs(),
            )
        }
        ReferencePath::Line => {
            let beyond = (p[0].abs() - LINE_HALF_LENGTH_MM).max(0.0);
            (p[0] + LINE_HALF_LENGTH_MM, beyond.hypot(p[1]))
        }
    }
}

/// Length of the reference path, mm.
pub fn reference_length_mm(path: ReferencePath) -> f64 {
    match path {
        ReferencePath::Circle => std::f64::consts::TAU * CIRCLE_RADIUS_MM,
        ReferencePath::Line => 2.0 * LINE_HALF_LENGTH_MM,
    }
}

/// Total length of piece points within `band_mm` of `path` (to pick the printed path).
pub(crate) fn length_near(pieces: &[PieceMm], path: ReferencePath, band_mm: f64) -> f64 {
    pieces
        .iter()
        .flat_map(|p| p.pts.windows(2))
        .filter(|w| locate(path, w[0]).1 <= band_mm && locate(path, w[1]).1 <= band_mm)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

/// Assembles `pieces` along `path`. `None` when no piece runs along it.
pub(crate) fn assemble(
    pieces: &[PieceMm],
    path: ReferencePath,
    band_mm: f64,
    max_gap_mm: f64,
) -> Option<Assembly> {
    let period = match path {
        ReferencePath::Circle => Some(reference_length_mm(path)),
        ReferencePath::Line => None,
    };
    let total: f64 = pieces
        .iter()
        .map(|p| polyline_length(&p.pts, p.closed))
        .sum();
    let mut runs: Vec<Run> = pieces
        .iter()
        .flat_map(|p| split_runs(p, path, band_mm, period))
        .filter(|r| r.extent() >= 0.5 && r.extent() >= 0.6 * polyline_length(&r.pts, false))
        .collect();
    runs.sort_by(|a, b| b.extent().total_cmp(&a.extent()));
    // Greedy: longest first; what repeats an accepted stretch is cut away.
    let mut accepted: Vec<Run> = Vec::new();
    for run in runs {
        for part in cut_covered(&run, &accepted, period) {
            if part.extent() >= 0.5 {
                accepted.push(part);
            }
        }
    }
    if accepted.is_empty() {
        return None;
    }
    // Normalise to s0 in [0, period) and order.
    for r in accepted.iter_mut() {
        if let Some(p) = period {
            let shift = (r.s[0] / p).floor() * p;
            r.s.iter_mut().for_each(|s| *s -= shift);
        }
    }
    accepted.sort_by(|a, b| a.s[0].total_cmp(&b.s[0]));
    let covered_mm: f64 = accepted.iter().map(Run::extent).sum();
    let used: f64 = accepted
        .iter()
        .map(|r| polyline_length(&r.pts, false))
        .sum();
    let mut gaps = Vec::new();
    let mut pts: Vec<[f64; 2]> = Vec::new();
    for (i, r) in accepted.iter().enumerate() {
        if i > 0 {
            let prev = &accepted[i - 1];
            gaps.push(gap(prev, r, 0.0, max_gap_mm));
        }
        pts.extend_from_slice(&r.pts);
    }
    let mut closed = false;
    if let (Some(p), Some(first), Some(last)) = (period, accepted.first(), accepted.last()) {
        gaps.push(gap(last, first, p, max_gap_mm));
        // Closed only when every gap, the wrap-around included, is bridged.
        closed = gaps.iter().all(|g| g.bridged);
    }
    let bridged_mm = gaps
        .iter()
        .filter(|g| g.bridged)
        .map(|g| (g.to_mm[0] - g.from_mm[0]).hypot(g.to_mm[1] - g.from_mm[1]))
        .sum();
    let gaps: Vec<Gap> = gaps.into_iter().filter(|g| g.length_mm > 1e-9).collect();
    Some(Assembly {
        stroke: Stroke {
            points_mm: pts,
            closed,
            bridged_mm,
        },
        reference_mm: reference_length_mm(path),
        covered_mm,
        gaps,
        unused_mm: (total - used).max(0.0),
    })
}

fn gap(a: &Run, b: &Run, wrap: f64, max_gap_mm: f64) -> Gap {
    let (Some(&from_mm), Some(&to_mm)) = (a.pts.last(), b.pts.first()) else {
        return Gap {
            from_mm: [0.0; 2],
            to_mm: [0.0; 2],
            length_mm: 0.0,
            bridged: true,
        };
    };
    let length_mm = (b.s[0] + wrap - a.s[a.s.len() - 1]).max(0.0);
    Gap {
        from_mm,
        to_mm,
        length_mm,
        bridged: length_mm <= max_gap_mm,
    }
}

/// Splits a piece into runs of points within the band, each oriented along increasing `s` and
/// with `s` unwrapped along the run.
fn split_runs(p: &PieceMm, path: ReferencePath, band_mm: f64, period: Option<f64>) -> Vec<Run> {
    let mut pts = p.pts.clone();
    if p.closed {
        if let Some(&first) = p.pts.first() {
            pts.push(first);
        }
    }
    let mut runs = Vec::new();
    let mut cur = Run {
        pts: Vec::new(),
        s: Vec::new(),
    };
    for q in pts {
        let (s, d) = locate(path, q);
        if d > band_mm {
            if cur.pts.len() >= 2 {
                runs.push(std::mem::replace(
                    &mut cur,
                    Run {
                        pts: Vec::new(),
                        s: Vec::new(),
                    },
                ));
            } else {
                cur.pts.clear();
                cur.s.clear();
            }
            continue;
        }
        let s = match (period, cur.s.last()) {
            (Some(per), Some(&last)) => last + (s - last + per / 2.0).rem_euclid(per) - per / 2.0,
            _ => s,
        };
        cur.pts.push(q);
        cur.s.push(s);
    }
    if cur.pts.len() >= 2 {
        runs.push(cur);
    }
    for r in runs.iter_mut() {
        if r.s[r.s.len() - 1] < r.s[0] {
            r.pts.reverse();
            r.s.reverse();
        }
        // A run whose s goes back and forth is kept only over its monotone hull.
        let mut keep_pts = vec![r.pts[0]];
        let mut keep_s = vec![r.s[0]];
        for (q, &s) in r.pts.iter().zip(&r.s).skip(1) {
            if s > keep_s[keep_s.len() - 1] {
                keep_pts.push(*q);
                keep_s.push(s);
            }
        }
        r.pts = keep_pts;
        r.s = keep_s;
    }
    runs
}

/// The parts of `run` not inside any accepted run's `[s0, s1]` (modulo the period).
fn cut_covered(run: &Run, accepted: &[Run], period: Option<f64>) -> Vec<Run> {
    let inside = |s: f64| {
        accepted.iter().any(|a| {
            let (a0, a1) = (a.s[0], a.s[a.s.len() - 1]);
            match period {
                Some(p) => {
                    let x = a0 + (s - a0).rem_euclid(p);
                    x <= a1
                }
                None => s >= a0 && s <= a1,
            }
        })
    };
    let mut out = Vec::new();
    let mut cur = Run {
        pts: Vec::new(),
        s: Vec::new(),
    };
    for (q, &s) in run.pts.iter().zip(&run.s) {
        if inside(s) {
            if cur.pts.len() >= 2 {
                out.push(cur.clone());
            }
            cur.pts.clear();
            cur.s.clear();
        } else {
            cur.pts.push(*q);
            cur.s.push(s);
        }
    }
    if cur.pts.len() >= 2 {
        out.push(cur);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arc(a0: f64, a1: f64, r: f64) -> PieceMm {
        let n = 200;
        PieceMm {
            pts: (0..=n)
                .map(|i| {
                    let a = (a0 + (a1 - a0) * i as f64 / n as f64).to_radians();
                    [r * a.cos(), r * a.sin()]
                })
                .collect(),
            closed: false,
        }
    }

    #[test]
    fn skips_are_bridged_and_long_gaps_reported() {
        // Three arcs with two short skips and, reversed, one piece; a fibre across the path.
        let mut rev = arc(181.0, 300.0, 100.3);
        rev.pts.reverse();
        let fibre = PieceMm {
            pts: vec![[0.0, 97.0], [0.5, 103.0]],
            closed: false,
        };
        let pieces = vec![arc(0.5, 180.0, 100.2), rev, arc(301.0, 359.8, 100.1), fibre];
        let a = assemble(&pieces, ReferencePath::Circle, 5.0, 3.0).expect("assembled");
        assert!(a.stroke.closed);
        assert_eq!(a.missing().count(), 0);
        assert!(
            a.covered_mm > 0.99 * a.reference_mm - 6.0,
            "{}",
            a.covered_mm
        );
        assert!(a.unused_mm > 5.0);
        // A 60-degree hole is missing.
        let pieces = vec![arc(0.0, 200.0, 100.0), arc(260.0, 359.0, 100.0)];
        let a = assemble(&pieces, ReferencePath::Circle, 5.0, 3.0).expect("assembled");
        let missing: Vec<_> = a.missing().collect();
        assert_eq!(missing.len(), 1);
        assert!((missing[0].length_mm - 60f64.to_radians() * 100.0).abs() < 0.5);
        assert!(!a.stroke.closed);
    }
}
