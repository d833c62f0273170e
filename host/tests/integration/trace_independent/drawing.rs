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
