//! Drawn lines from synthetic passes: side by side, across each other, round a box, with gaps.

use super::*;
use crate::trace::stages::link::LinkParams;

/// An open path along `corners`, a point every 0.25 mm, with a zigzag of `zig` mm across.
fn pass(corners: &[[f64; 2]], zig: f64) -> DrawnPath {
    let mut pts = Vec::new();
    for w in corners.windows(2) {
        let d = sub(w[1], w[0]);
        let len = d[0].hypot(d[1]);
        let n = (len / 0.25).ceil() as usize;
        let (t, nrm) = (unit(d), [-d[1] / len, d[0] / len]);
        for k in 0..n {
            let s = k as f64 * len / n as f64;
            let off = zig * ((s / 1.5).fract() - 0.5).abs();
            pts.push([
                w[0][0] + s * t[0] + off * nrm[0],
                w[0][1] + s * t[1] + off * nrm[1],
            ]);
        }
    }
    pts.extend(corners.last());
    crate::trace::paths::open_path(pts)
}

fn lines_of(paths: &[DrawnPath]) -> Vec<DrawnLine> {
    let loose = vec![Vec::new(); paths.len()];
    lines(
        paths,
        &[],
        &loose,
        10.0,
        LinkParams::default().min_mark_mm,
        &LinesParams::default(),
    )
}

#[test]
fn passes_side_by_side_are_one_line_and_a_line_across_another() {
    // Three zigzag passes of one line, 1 mm apart, of different extents; a line across
    // them; one pass turning the corner into the line across.
    let paths = vec![
        pass(&[[0.0, 0.0], [100.0, 0.0]], 0.6),
        pass(&[[-2.0, 1.0], [60.0, 1.0]], 0.8),
        pass(&[[40.0, -1.0], [101.0, -1.0]], 0.5),
        pass(&[[50.0, -40.0], [50.0, 40.0]], 0.6),
        pass(&[[30.0, 40.5], [49.0, 40.5], [49.0, -30.0]], 0.6),
    ];
    let l = lines_of(&paths);
    let along = l
        .iter()
        .find(|x| x.passes.len() == 3)
        .expect("the line of three");
    assert_eq!(along.passes, vec![0, 1, 2]);
    assert!((along.length_mm - 103.0).abs() < 1.5, "{}", along.length_mm);
    assert!(along.is_whole() && along.gaps.is_empty(), "{along:#?}");
    // Its centreline runs in the middle of the band.
    assert!(along.points_mm.iter().all(|p| p[1].abs() < 1.5));
    assert!(along
        .points_mm
        .iter()
        .filter(|p| p[0] > 5.0 && p[0] < 95.0)
        .all(|p| p[1].abs() < 0.8));
    // The line across: the straight pass and the one round the corner (longest first).
    let across = l
        .iter()
        .find(|x| x.passes.contains(&3))
        .expect("the line across");
    assert_eq!(across.passes, vec![4, 3]);
    assert!(across.is_whole(), "{across:#?}");
    assert!(
        (across.length_mm - 80.5).abs() < 1.5,
        "{}",
        across.length_mm
    );
    // The stretch before the corner is a line of its own, ending on the line across.
    let top = l
        .iter()
        .find(|x| x.passes == [4] && x.points_mm.iter().all(|p| (p[1] - 40.5).abs() < 1.0))
        .expect("the stretch before the corner");
    assert!(top.is_whole());
    let right = top.from_mm[0].max(top.to_mm[0]);
    assert!((right - 49.5).abs() < 1.0, "{top:#?}");
    assert_eq!(l.len(), 3, "{l:#?}");
}

/// Two passes of one line along x, both broken after `x_mm` (one ends 2 mm short of it) for
/// `gap_mm`: the stretch no pass covers.
fn broken_at(x_mm: f64, gap_mm: f64) -> Vec<DrawnPath> {
    let on = x_mm + gap_mm;
    vec![
        pass(&[[0.0, 0.0], [x_mm, 0.0]], 0.5),
        pass(&[[0.0, 1.0], [x_mm - 2.0, 1.0]], 0.5),
        pass(&[[on, 0.5], [on + 44.0, 0.5]], 0.5),
        pass(&[[on + 1.0, -0.5], [on + 43.0, -0.5]], 0.5),
    ]
}

#[test]
fn a_stretch_no_pass_covers_is_a_gap_of_the_line() {
    // Two passes of one line, both broken at the same place: 6 mm (bridged), then 25 mm
    // (missing).
    let l = lines_of(&broken_at(40.0, 6.0));
    assert_eq!(l.len(), 1, "{l:#?}");
    assert_eq!(l[0].passes.len(), 4);
    assert!(l[0].is_whole());
    assert_eq!(l[0].gaps.len(), 1);
    assert!(
        (l[0].gaps[0].length_mm - 6.0).abs() < 0.6,
        "{:?}",
        l[0].gaps
    );
    let l = lines_of(&broken_at(40.0, 25.0));
    // Farther apart than --max-gap-mm: one line with the stretch between missing.
    assert_eq!(l.len(), 1, "{l:#?}");
    assert!(!l[0].is_whole());
    let missing: Vec<&Gap> = l[0].gaps.iter().filter(|g| !g.bridged).collect();
    assert_eq!(missing.len(), 1, "{:?}", l[0].gaps);
    assert!((missing[0].length_mm - 25.0).abs() < 1.5, "{missing:?}");
}

#[test]
fn a_box_drawn_round_in_one_go_is_one_line() {
    let boxed = vec![pass(
        &[
            [0.0, 0.0],
            [40.0, 0.0],
            [40.0, 30.0],
            [0.0, 30.0],
            [0.0, 2.0],
        ],
        0.0,
    )];
    let l = lines_of(&boxed);
    assert_eq!(l.len(), 1, "{l:#?}");
    assert_eq!(l[0].passes, vec![0]);
    assert!((l[0].length_mm - 138.0).abs() < 0.5, "{}", l[0].length_mm);
}
