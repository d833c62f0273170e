//! Six sheets drawn as a new user would try the tracer, each rendered by the independent
//! renderer with its camera set as stated: an off-centre circle in a tilted photo with lens
//! distortion and skips, a line turned against the printed one in a steep photo, a scan with a
//! second pencil stroke across the line, a wiggly free curve in a photo, a faint wiggly scan
//! with skips, a rotated scan of a circle. Each must be traced whole (exit 0) with coverage
//! >= 0.95 and RMS within its bar.

use super::cases::{densify, length, segment, Case};
use super::render2::Printed;
use super::{render_independent_shot, trace_outcome, Kind, Shot};
use std::f64::consts::{PI, TAU};

/// A case of `truth` with `skips` (arc-length intervals, mm), a few specks of dust and fibres
/// away from it.
fn sheet(
    shape: &'static str,
    printed: Printed,
    truth: Vec<[f64; 2]>,
    closed: bool,
    skips: Vec<[f64; 2]>,
    darkness: f64,
) -> Case {
    Case {
        shape,
        printed,
        truth,
        closed,
        skips,
        width_mm: 0.45,
        darkness,
        crossing: None,
        strays: vec![segment([70.0, -75.0], [72.5, -73.0])],
        dust: vec![
            [-60.0, 70.0, 0.1, 0.8],
            [55.0, 60.0, 0.14, 0.7],
            [-20.0, -80.0, 0.08, 0.9],
        ],
        fibres: vec![[80.0, 20.0, 83.0, 24.0]],
        second_run: None,
    }
}

fn photo(ppi: f64, tilt_deg: f64, k1: f64, seed: u64) -> Shot {
    Shot {
        ppm: ppi / 25.4,
        tilt: tilt_deg.to_radians(),
        azimuth: 0.7 + seed as f64,
        roll: 0.3 * seed as f64,
        k1,
        rot_deg: 0.0,
        jpeg: 90,
        centre_off_px: 0.0,
    }
}

fn scan(dpi: f64, rot_deg: f64) -> Shot {
    Shot {
        ppm: dpi / 25.4,
        tilt: 0.0,
        azimuth: 0.0,
        roll: 0.0,
        k1: 0.0,
        rot_deg,
        jpeg: 95,
        centre_off_px: 0.0,
    }
}

/// A wiggly open curve through the sheet centre region.
fn wiggly(turn: f64, half: f64) -> Vec<[f64; 2]> {
    let (s, c) = turn.sin_cos();
    densify(
        move |t| {
            let u = (2.0 * t - 1.0) * half;
            let v = 8.0 * (1.1 * PI * (2.0 * t - 1.0) + 0.4).sin()
                + 3.0 * (2.9 * PI * (2.0 * t - 1.0) + 1.3).sin();
            [6.0 + c * u - s * v, -4.0 + s * u + c * v]
        },
        false,
    )
}

#[test]
fn the_six_reported_sheets_are_traced_whole() {
    let mut results = Vec::new();
    // 1: a 60 mm radius circle centred 22 mm off the printed one, photo at 25 deg, k1 -0.05,
    // four skips of 1-6 mm.
    let circle = densify(
        |t| {
            let a = t * TAU;
            [18.0 + 60.0 * a.cos(), -12.5 + 60.0 * a.sin()]
        },
        true,
    );
    let c1 = sheet(
        "off-centre circle",
        Printed::Circle,
        circle,
        true,
        vec![[30.0, 31.2], [110.0, 116.0], [205.0, 208.5], [300.0, 302.0]],
        0.45,
    );
    results.push((c1, Kind::Photo, photo(250.0, 25.0, -0.05, 1), 0.03));
    // 2: a 150 mm line at 28 deg to the printed line, offset, photo at 35 deg.
    let (s, c) = 28f64.to_radians().sin_cos();
    let line = densify(
        move |t| {
            let u = (2.0 * t - 1.0) * 75.0;
            [-4.0 + c * u, 9.0 + s * u]
        },
        false,
    );
    let c2 = sheet(
        "turned line",
        Printed::Line,
        line,
        false,
        vec![[35.0, 37.0], [90.0, 94.0]],
        0.4,
    );
    results.push((c2, Kind::Photo, photo(230.0, 35.0, 0.03, 2), 0.03));
    // 3: a 600 dpi scan of a line with a second, shorter pencil stroke crossing it at 55 deg.
    let (s, c) = 8f64.to_radians().sin_cos();
    let line = densify(
        move |t| {
            let u = (2.0 * t - 1.0) * 80.0;
            [c * u, 14.0 + s * u]
        },
        false,
    );
    let mid = [c * 10.0, 14.0 + s * 10.0];
    let (s2, c2a) = 63f64.to_radians().sin_cos();
    let mut c3 = sheet(
        "line + crossing stroke",
        Printed::Line,
        line,
        false,
        vec![[40.0, 42.0], [120.0, 123.0], [140.0, 141.5]],
        0.3,
    );
    c3.crossing = Some(segment(
        [mid[0] - 14.0 * c2a, mid[1] - 14.0 * s2],
        [mid[0] + 18.0 * c2a, mid[1] + 18.0 * s2],
    ));
    results.push((c3, Kind::Scan600, scan(600.0, 1.5), 0.015));
    // 4: a wiggly free curve, photo at 20 deg.
    let c4 = sheet(
        "wiggly curve",
        Printed::Line,
        wiggly(0.35, 70.0),
        false,
        vec![[25.0, 28.0], [80.0, 82.0], [130.0, 135.0]],
        0.42,
    );
    results.push((c4, Kind::Photo, photo(220.0, 20.0, -0.03, 4), 0.03));
    // 5: a faint wiggly curve in a 600 dpi scan, five skips.
    let c5 = sheet(
        "faint wiggly",
        Printed::Circle,
        wiggly(-0.6, 65.0),
        false,
        vec![
            [20.0, 22.0],
            [45.0, 50.0],
            [80.0, 81.5],
            [110.0, 114.0],
            [140.0, 145.5],
        ],
        0.24,
    );
    results.push((c5, Kind::Scan600, scan(600.0, -2.0), 0.015));
    // 6: a rotated 300 dpi scan of a circle.
    let circle = densify(
        |t| {
            let a = t * TAU;
            [-6.0 + 44.0 * a.cos(), 8.0 + 44.0 * a.sin()]
        },
        true,
    );
    let c6 = sheet(
        "circle, rotated scan",
        Printed::Circle,
        circle,
        true,
        vec![[50.0, 53.0], [150.0, 151.5], [230.0, 234.0]],
        0.3,
    );
    results.push((c6, Kind::Scan300, scan(300.0, 3.5), 0.02));

    let mut failed = Vec::new();
    for (i, (case, kind, shot, rms_bar)) in results.into_iter().enumerate() {
        let img = render_independent_shot(&case, kind, &shot, 900 + i as u64);
        let o = trace_outcome(&img, &case);
        eprintln!(
            "{} ({:?}, {:.0} mm, {} skips): coverage {:.4}, rms {:.4} mm, exit {} ({})",
            case.shape,
            kind,
            length(&case.truth),
            case.skips.len(),
            o.coverage,
            o.rms,
            if o.exit0 { 0 } else { 1 },
            o.note
        );
        assert!(
            !(o.exit0 && o.coverage < 0.95),
            "{}: exit 0 below 0.95 coverage",
            case.shape
        );
        if !(o.exit0 && o.coverage >= 0.95 && o.rms <= rms_bar) {
            failed.push(case.shape);
        }
    }
    assert!(failed.is_empty(), "not traced whole: {failed:?}");
}
