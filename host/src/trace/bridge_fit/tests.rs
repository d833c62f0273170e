//! Bridges refitted across gaps of known curves (arcs, wiggles, dust beside the gap), and the
//! least-squares pieces.

use super::*;
use crate::trace::plane::farthest_from;

/// Written points of `f` at 0.25 mm steps of `u` outside the gap, a straight first guess
/// inside it.
fn with_gap(f: impl Fn(f64) -> [f64; 2], len: f64, gap: [f64; 2]) -> (Vec<[f64; 2]>, Vec<bool>) {
    let mut pts = Vec::new();
    let mut mask = Vec::new();
    let mut guessed = false;
    let n = (len / 0.25) as usize;
    for k in 0..=n {
        let u = k as f64 * 0.25;
        if u > gap[0] && u < gap[1] {
            continue;
        }
        if u >= gap[1] && !guessed {
            guessed = true;
            let (a, b) = (f(gap[0]), f(gap[1]));
            for q in 1..10 {
                let g = q as f64 / 10.0;
                pts.push([a[0] + g * (b[0] - a[0]), a[1] + g * (b[1] - a[1])]);
                mask.push(true);
            }
        }
        pts.push(f(u));
        mask.push(false);
    }
    (pts, mask)
}

fn worst_off(pts: &[[f64; 2]], f: impl Fn(f64) -> [f64; 2], len: f64) -> f64 {
    let truth: Vec<[f64; 2]> = (0..=(len * 100.0) as usize)
        .map(|k| f(k as f64 * 0.01))
        .collect();
    farthest_from(pts, &truth)
}

#[test]
fn a_skip_on_an_arc_is_bridged_on_the_arc() {
    let r = 35.0;
    let f = |u: f64| [r * (u / r).cos(), r * (u / r).sin()];
    let (pts, mask) = with_gap(f, 40.0, [15.0, 24.0]);
    assert!(
        worst_off(&pts, f, 40.0) > 0.2,
        "the straight guess is off the arc"
    );
    let (out, m, len) = refine(&pts, &mask, false, &LinkParams::default());
    assert_eq!(out.len(), m.len());
    assert!(
        worst_off(&out, f, 40.0) < 0.002,
        "{}",
        worst_off(&out, f, 40.0)
    );
    assert!((len - 9.0).abs() < 0.05, "{len}");
}

#[test]
fn a_speck_beside_the_line_does_not_bend_the_bridge() {
    let f = |u: f64| [u, 0.2 * u];
    let (mut pts, mask) = with_gap(f, 30.0, [12.0, 18.0]);
    // A centroid pulled 0.12 mm aside 4 mm after the gap (dust on the line).
    let k = pts
        .iter()
        .position(|p| (p[0] - 22.0).abs() < 0.13)
        .expect("a point");
    pts[k][1] += 0.12;
    pts[k + 1][1] += 0.08;
    let (out, _, _) = refine(&pts, &mask, false, &LinkParams::default());
    let bridge_off = out
        .iter()
        .filter(|p| p[0] > 12.0 && p[0] < 18.0)
        .map(|p| (p[1] - 0.2 * p[0]).abs() / 1.04f64.sqrt())
        .fold(0.0, f64::max);
    assert!(bridge_off < 0.003, "{bridge_off}");
}

#[test]
fn a_wiggle_is_followed_across_the_gap() {
    let f = |u: f64| [u, 4.0 * (0.23 * u).sin()];
    let (pts, mask) = with_gap(f, 45.0, [20.0, 27.0]);
    assert!(
        worst_off(&pts, f, 45.0) > 0.2,
        "the straight guess is off the wave"
    );
    let (out, _, _) = refine(&pts, &mask, false, &LinkParams::default());
    // A wave of 27 mm wavelength and 4 mm amplitude, 9.5 mm of it missing.
    let off = worst_off(&out, f, 45.0);
    assert!(off < 0.05, "{off}");
}
