//! `trace_paths` on a rendered sheet with several separate drawn lines (independent renderer):
//! one path per line, each covering its truth, the closed one closed.

use super::cases::measure;
use super::render2::{self, scan_view, Mark, Printed, Scene};
use indicatif::ProgressBar;
use rigctl::trace::{trace_paths, PathChoice, Prepared, TraceOptions};

/// A dense polyline (0.02 mm steps) of `f` over `[0, 1]`.
fn dense(f: impl Fn(f64) -> [f64; 2], closed: bool) -> Vec<[f64; 2]> {
    let n = 400_000;
    let raw: Vec<[f64; 2]> = (0..=n).map(|i| f(i as f64 / n as f64)).collect();
    let mut out = vec![raw[0]];
    for p in &raw[1..] {
        let q = out[out.len() - 1];
        if (p[0] - q[0]).hypot(p[1] - q[1]) >= 0.02 {
            out.push(*p);
        }
    }
    if closed {
        out.pop();
    }
    out
}

/// A drawn line: its dense centreline, whether it closes, its pencil skips (arc-length
/// intervals, mm).
struct Line {
    pts: Vec<[f64; 2]>,
    closed: bool,
    skips: Vec<[f64; 2]>,
}

/// The drawn lines: a wavy line, a closed ellipse, a half circle, a straight slanted line.
fn lines() -> Vec<Line> {
    use std::f64::consts::TAU;
    vec![
        Line {
            pts: dense(
                |u| {
                    let x = -70.0 + 130.0 * u;
                    [x, 55.0 + 4.0 * (x / 9.0).sin()]
                },
                false,
            ),
            closed: false,
            skips: vec![[30.0, 32.5], [90.0, 93.5]],
        },
        Line {
            pts: dense(
                |u| {
                    let a = TAU * u;
                    [-40.0 + 22.0 * a.cos(), -30.0 + 14.0 * a.sin()]
                },
                true,
            ),
            closed: true,
            skips: vec![[20.0, 22.0], [70.0, 73.0]],
        },
        Line {
            pts: dense(
                |u| {
                    let a = (-60.0 + 180.0 * u).to_radians();
                    [45.0 + 25.0 * a.cos(), -35.0 + 25.0 * a.sin()]
                },
                false,
            ),
            closed: false,
            skips: vec![[40.0, 42.5]],
        },
        Line {
            pts: dense(|u| [-75.0 + 45.0 * u, 10.0 + 10.0 * u], false),
            closed: false,
            skips: vec![[18.0, 19.5]],
        },
    ]
}

#[test]
fn a_sheet_of_several_lines_gives_one_path_per_line() {
    let truths = lines();
    let marks = truths
        .iter()
        .map(|l| Mark {
            pts: l.pts.clone(),
            width_mm: 0.45,
            darkness: 0.4,
            skips: l.skips.clone(),
        })
        .collect();
    let img = render2::render(&Scene {
        printed: Printed::Circle,
        marks,
        dust: vec![[10.0, -70.0, 0.12, 0.8], [-60.0, 30.0, 0.08, 0.7]],
        fibres: Vec::new(),
        view: scan_view(300.0, 1.3),
        light: [0.95, 0.02, -0.02, 0.0],
        noise: 2.0,
        jpeg: None,
        seed: 24,
        tone: None,
        sag: None,
        hand: None,
        page: render2::Page::default(),
    });
    let opts = TraceOptions {
        path: PathChoice::Free,
        ..TraceOptions::default()
    };
    let d =
        trace_paths(&img, &Prepared::build(&img), &opts, &ProgressBar::hidden()).expect("paths");
    assert_eq!(
        d.paths.len(),
        truths.len(),
        "paths: {:?}",
        d.paths
            .iter()
            .map(|p| p.stroke.length_mm())
            .collect::<Vec<_>>()
    );
    for (
        k,
        Line {
            pts: truth, closed, ..
        },
    ) in truths.iter().enumerate()
    {
        // The path that covers this line best; no other path covers any of it.
        let cov: Vec<f64> = d
            .paths
            .iter()
            .map(|p| measure(truth, *closed, &p.stroke.points_mm, p.stroke.closed).0)
            .collect();
        let best = (0..cov.len())
            .max_by(|&a, &b| cov[a].total_cmp(&cov[b]))
            .expect("a path");
        let p = &d.paths[best];
        eprintln!(
            "line {k}: coverage {:.3}, {:.1} mm, closed {}, whole {}",
            cov[best],
            p.stroke.length_mm(),
            p.stroke.closed,
            p.is_whole()
        );
        assert!(cov[best] >= 0.95, "line {k}: coverage {:.3}", cov[best]);
        assert_eq!(p.stroke.closed, *closed, "line {k}");
        assert!(p.is_whole(), "line {k}: {:?}", p.gaps);
        for (i, c) in cov.iter().enumerate() {
            assert!(i == best || *c < 0.05, "line {k} also in path {i}: {c:.3}");
        }
    }
    assert!(d.is_whole());
}

/// The distance from `p` to the polyline `pts`.
fn to_polyline(p: [f64; 2], pts: &[[f64; 2]]) -> f64 {
    pts.windows(2)
        .map(|w| {
            let d = [w[1][0] - w[0][0], w[1][1] - w[0][1]];
            let l2 = (d[0] * d[0] + d[1] * d[1]).max(1e-12);
            let t = (((p[0] - w[0][0]) * d[0] + (p[1] - w[0][1]) * d[1]) / l2).clamp(0.0, 1.0);
            (p[0] - w[0][0] - t * d[0]).hypot(p[1] - w[0][1] - t * d[1])
        })
        .fold(f64::INFINITY, f64::min)
}

/// A grid (3 lines across, 3 down: a box with a cross) whose every line a plotter with backlash
/// drew three times: each pass offset across by up to 1.2 mm, with a sawtooth of 0.5-1.1 mm
/// and a period of 2.5-4.5 mm, starting and stopping up to 1 mm off the line's ends, some
/// passes with skips. Another stroke model than the tracer's tests: a line is a band of passes,
/// crossing each other and the lines across.
#[test]
fn a_grid_drawn_several_times_gives_one_line_per_grid_line() {
    let grid: Vec<[[f64; 2]; 2]> = vec![
        [[-60.0, -30.0], [60.0, -30.0]],
        [[-60.0, 0.0], [60.0, 0.0]],
        [[-60.0, 30.0], [60.0, 30.0]],
        [[-60.0, -30.0], [-60.0, 30.0]],
        [[0.0, -30.0], [0.0, 30.0]],
        [[60.0, -30.0], [60.0, 30.0]],
    ];
    // A small deterministic generator (not the renderer's).
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut uniform = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut marks = Vec::new();
    for g in &grid {
        let d = [g[1][0] - g[0][0], g[1][1] - g[0][1]];
        let len = d[0].hypot(d[1]);
        let (t, n) = ([d[0] / len, d[1] / len], [-d[1] / len, d[0] / len]);
        for pass in 0..3 {
            let off = 1.2 * (2.0 * uniform() - 1.0);
            let amp = 0.5 + 0.6 * uniform();
            let period = 2.5 + 2.0 * uniform();
            let (s0, s1) = (-1.0 + 2.0 * uniform(), len + 1.0 - 2.0 * uniform());
            let tooth = |s: f64| amp * ((s / period).fract() - 0.5);
            let pts = dense(
                |u| {
                    let s = s0 + u * (s1 - s0);
                    let a = off + tooth(s);
                    [g[0][0] + s * t[0] + a * n[0], g[0][1] + s * t[1] + a * n[1]]
                },
                false,
            );
            let skips = if pass == 1 {
                let at = 20.0 + 60.0 * uniform();
                vec![[at, at + 1.5 + 2.0 * uniform()]]
            } else {
                Vec::new()
            };
            marks.push(Mark {
                pts,
                width_mm: 0.4,
                darkness: 0.35 + 0.1 * uniform(),
                skips,
            });
        }
    }
    let img = render2::render(&Scene {
        printed: Printed::Circle,
        marks,
        dust: vec![[25.0, -15.0, 0.1, 0.8]],
        fibres: Vec::new(),
        view: scan_view(300.0, 0.7),
        light: [0.95, 0.02, -0.02, 0.0],
        noise: 2.0,
        jpeg: None,
        seed: 31,
        tone: None,
        sag: None,
        hand: None,
        page: render2::Page::default(),
    });
    let opts = TraceOptions {
        path: PathChoice::Free,
        ..TraceOptions::default()
    };
    let d =
        trace_paths(&img, &Prepared::build(&img), &opts, &ProgressBar::hidden()).expect("paths");
    eprintln!(
        "{} paths, {} drawn lines ({} whole): {:?}",
        d.paths.len(),
        d.lines.len(),
        d.lines.iter().filter(|l| l.is_whole()).count(),
        d.lines
            .iter()
            .map(|l| (l.length_mm.round(), l.passes.len(), l.is_whole()))
            .collect::<Vec<_>>()
    );
    let mut traced = 0;
    for (k, g) in grid.iter().enumerate() {
        // The drawn line along it: its centreline within 1 mm of the grid line along 98 % of
        // the grid line, its ends within 2 mm of the grid line's.
        let truth = dense(
            |u| {
                [
                    g[0][0] + u * (g[1][0] - g[0][0]),
                    g[0][1] + u * (g[1][1] - g[0][1]),
                ]
            },
            false,
        );
        let share = |l: &rigctl::trace::DrawnLine| {
            let near = truth
                .iter()
                .step_by(25)
                .filter(|p| to_polyline(**p, &l.points_mm) <= 1.0)
                .count();
            near as f64 / truth.iter().step_by(25).count() as f64
        };
        let along: Vec<(usize, f64)> = d
            .lines
            .iter()
            .enumerate()
            .map(|(i, l)| (i, share(l)))
            .filter(|x| x.1 > 0.2)
            .collect();
        assert_eq!(along.len(), 1, "grid line {k}: lines along it {along:?}");
        let l = &d.lines[along[0].0];
        let end_err = [l.from_mm, l.to_mm]
            .iter()
            .map(|e| {
                let (a, b) = (
                    (e[0] - g[0][0]).hypot(e[1] - g[0][1]),
                    (e[0] - g[1][0]).hypot(e[1] - g[1][1]),
                );
                a.min(b)
            })
            .fold(0.0, f64::max);
        let worst = l
            .points_mm
            .iter()
            .map(|p| to_polyline(*p, &truth))
            .fold(0.0, f64::max);
        eprintln!(
            "grid line {k}: {:.1} mm, {} passes, share {:.3}, ends off by {end_err:.2} mm, centreline at most {worst:.2} mm off, whole {}",
            l.length_mm,
            l.passes.len(),
            along[0].1,
            l.is_whole()
        );
        assert!(worst <= 1.5, "grid line {k}: centreline {worst:.2} mm off");
        let end_to_end = along[0].1 >= 0.98 && end_err <= 2.0;
        if end_to_end {
            assert!(
                l.is_whole(),
                "grid line {k}: {:?} {:?}",
                l.gaps,
                l.continued_by
            );
            traced += 1;
        } else {
            // Never whole on a part: here the tracker leaves the top 15 mm of the middle
            // line (its passes broken into short dashes) untraced, and the ink past the
            // line's end says so.
            assert!(!l.is_whole(), "grid line {k}: a part reported whole");
        }
    }
    // Measured: 5 of the 6 end to end and whole, the sixth named as not whole (exit 1).
    assert!(traced >= 5, "{traced} grid lines end to end");
    assert_eq!(d.is_whole(), traced == grid.len());
    // Nothing else but the grid lines.
    assert_eq!(d.lines.len(), grid.len());
}
