//! Linking across a skip on a crest whose curvature changes along it.

use super::link;
use crate::trace::chain::PieceMm;

/// The points from arc length `s0` to `s1` (mm, 0.05 mm apart) of the curve whose heading is the
/// integral of `k(s)` from `s = -60`.
fn curve(k: impl Fn(f64) -> f64, s0: f64, s1: f64) -> Vec<[f64; 2]> {
    let ds = 0.05;
    let (mut p, mut h, mut s) = ([0.0f64, 0.0f64], 0.0f64, -60.0f64);
    let mut out = Vec::new();
    while s <= s1 {
        if s >= s0 {
            out.push(p);
        }
        let km = k(s + 0.5 * ds);
        let hm = h + 0.5 * km * ds;
        p = [p[0] + ds * hm.cos(), p[1] + ds * hm.sin()];
        h += km * ds;
        s += ds;
    }
    out
}

/// A crest of radius 7.7 mm (curvature 0.13/mm, 4 mm wide) with a 5 mm skip on its flank: one
/// end reads a nearly straight curve, the other one bending hard. The curve turns across the gap
/// by the mean of the two curvatures (a curvature changing along the gap), not by either end's
/// alone: read from the nearly straight end alone, the turn is too small and the piece beyond
/// the skip is left out as one that "may continue" the path.
#[test]
fn a_skip_where_the_curvature_grows_is_bridged() {
    let k = |s: f64| 0.13 * (-(s - 8.0).powi(2) / (2.0 * 4.0f64.powi(2))).exp();
    let pieces = vec![
        PieceMm {
            pts: curve(k, -40.0, 2.5),
            closed: false,
        },
        PieceMm {
            pts: curve(k, 7.5, 40.0),
            closed: false,
        },
    ];
    let l = link(&pieces, 10.0, None).expect("linked");
    assert_eq!(l.pieces, 2, "{:?}", l.left_out);
    assert!(l.is_whole(), "{:?}", l.left_out);
    assert_eq!(l.gaps.len(), 1);
    assert!((l.gaps[0].length_mm - 5.0).abs() < 0.3, "{:?}", l.gaps);
}
