//! The walk through the band of ink: straight and zigzag passes, crossings, gaps and the
//! cloud's queries.

use super::*;

/// Dots along `corners` every 0.25 mm (directions of each segment), of path `path`.
fn dots(corners: &[[f64; 2]], path: usize, zig: f64) -> Vec<Dot> {
    let mut out = Vec::new();
    for w in corners.windows(2) {
        let d = sub(w[1], w[0]);
        let len = d[0].hypot(d[1]);
        let t = [d[0] / len, d[1] / len];
        let k = (len / 0.25).ceil() as usize;
        for j in 0..k {
            let s = j as f64 * len / k as f64;
            let off = zig * ((s / 1.5).fract() - 0.5).abs();
            out.push(Dot {
                p: [
                    w[0][0] + s * t[0] - off * t[1],
                    w[0][1] + s * t[1] + off * t[0],
                ],
                dir: t,
                src: Source::Path(path),
            });
        }
    }
    out
}

#[test]
fn a_band_of_broken_passes_is_walked_end_to_end() {
    // Three passes 2 mm apart, each broken at other places; a line across them.
    let mut v = dots(&[[0.0, 0.0], [40.0, 0.0]], 0, 0.8);
    v.extend(dots(&[[46.0, 0.0], [100.0, 0.0]], 0, 0.8));
    v.extend(dots(&[[-3.0, 2.0], [70.0, 2.0]], 1, 0.6));
    v.extend(dots(&[[75.0, 2.0], [98.0, 2.0]], 1, 0.6));
    v.extend(dots(&[[20.0, -1.0], [102.0, -1.0]], 2, 0.5));
    v.extend(dots(&[[50.0, -40.0], [50.0, 40.0]], 3, 0.5));
    let cloud = Cloud::new(v, &LinesParams::default());
    let w = walk(&cloud, [30.0, 0.5], [1.0, 0.0], 10.0);
    let (a, b) = (w.centres[0], w.centres[w.centres.len() - 1]);
    assert!(!w.closed);
    assert!(
        (a[0] + 3.0).abs() < 1.0 && (b[0] - 102.0).abs() < 1.0,
        "{a:?} {b:?}"
    );
    assert!(w.centres.iter().all(|c| c[1].abs() < 2.5), "left the band");
    assert!(w.gaps.is_empty(), "{:?}", w.gaps);
    // The line across is not taken.
    assert!(w
        .taken
        .iter()
        .all(|&i| cloud.dots[i].src != Source::Path(3)));
}

#[test]
fn gaps_are_bridged_or_missing_and_a_loop_closes() {
    let mut v = dots(&[[0.0, 0.0], [40.0, 0.0]], 0, 0.0);
    v.extend(dots(&[[47.0, 0.2], [80.0, 0.2]], 1, 0.0));
    v.extend(dots(&[[110.0, 0.0], [150.0, 0.0]], 2, 0.0));
    let w = walk(
        &Cloud::new(v, &LinesParams::default()),
        [10.0, 0.0],
        [1.0, 0.0],
        10.0,
    );
    assert_eq!(w.gaps.len(), 2, "{:?}", w.gaps);
    assert!(w.gaps[0].bridged && (w.gaps[0].length_mm - 7.0).abs() < 1.0);
    assert!(!w.gaps[1].bridged && (w.gaps[1].length_mm - 30.0).abs() < 1.0);
    // A square drawn round: a closed walk (the direction filter stops it at corners, so
    // round corners here: a circle).
    let circle: Vec<[f64; 2]> = (0..=360)
        .map(|k| {
            let a = (k as f64).to_radians();
            [30.0 * a.cos(), 30.0 * a.sin()]
        })
        .collect();
    let w = walk(
        &Cloud::new(dots(&circle, 0, 0.0), &LinesParams::default()),
        [30.0, 0.0],
        [0.0, 1.0],
        10.0,
    );
    assert!(w.closed);
    assert!((w.length_mm() - 2.0 * std::f64::consts::PI * 30.0).abs() < 1.5);
}
