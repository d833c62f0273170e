//! `trace` on rendered scans with known truth: sub-pixel accuracy, full coverage, orientation
//! handling and the typed errors.

use crate::common::record::record;

use indicatif::ProgressBar;
use rigctl::sheet::ReferencePath;
use rigctl::trace::synth::{render_scan, RenderSpec};
use rigctl::trace::{trace_image, Mapping, Trace, TraceError, TraceOptions};

/// The pencil as a robot might draw the thesis circle: radius 100 mm with a few tenths of a
/// millimetre of lobing, sampled every ~0.05 mm. Closed.
fn wobbly_circle() -> Vec<[f64; 2]> {
    let n = 12_566;
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            let r = 100.0 + 0.3 * (3.0 * a).sin() + 0.15 * (5.0 * a + 0.4).cos();
            [r * a.cos(), r * a.sin()]
        })
        .collect()
}

/// A slightly slanted, wavy line across the sheet, sampled every 0.05 mm. Open.
fn wobbly_line() -> Vec<[f64; 2]> {
    let n = 3_800;
    (0..=n)
        .map(|i| {
            let x = -95.0 + 190.0 * i as f64 / n as f64;
            [x, 0.4 - 0.0037 * x + 0.2 * (x / 15.0).sin()]
        })
        .collect()
}

fn spec(pencil: Vec<[f64; 2]>, closed: bool, dpi: f64, rotation_deg: f64, seed: u64) -> RenderSpec {
    RenderSpec {
        dpi,
        pencil_mm: pencil,
        pencil_closed: closed,
        reference: Some(if closed {
            ReferencePath::Circle
        } else {
            ReferencePath::Line
        }),
        rotation_deg,
        shift_mm: [2.5, -3.5],
        seed,
        ..RenderSpec::default()
    }
}

fn trace(spec: &RenderSpec, opts: &TraceOptions) -> Result<Trace, TraceError> {
    trace_image(&render_scan(spec), opts, &ProgressBar::hidden())
}

/// Nearest point of the truth polyline: (distance, arc length at the foot).
fn project(p: [f64; 2], truth: &[[f64; 2]], closed: bool) -> (f64, f64) {
    let n = truth.len();
    let segs = if closed { n } else { n - 1 };
    let (mut best, mut best_s, mut s0) = (f64::INFINITY, 0.0, 0.0);
    for i in 0..segs {
        let (a, b) = (truth[i], truth[(i + 1) % n]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = dx.hypot(dy);
        let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (len * len)).clamp(0.0, 1.0);
        let d = (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy);
        if d < best {
            (best, best_s) = (d, s0 + t * len);
        }
        s0 += len;
    }
    (best, best_s)
}

/// RMS distance of the points to the truth, and the fraction of the truth's 1 mm arc bins that
/// some point projects into.
fn accuracy(points: &[[f64; 2]], truth: &[[f64; 2]], closed: bool) -> (f64, f64, f64) {
    let total = rigctl::trace::polyline_length(truth, closed);
    let bins = total.floor() as usize;
    let mut hit = vec![false; bins];
    let (mut sum2, mut max) = (0.0, 0.0f64);
    for (i, p) in points.iter().enumerate() {
        let (d, s) = project(*p, truth, closed);
        sum2 += d * d;
        if d > 0.05 {
            eprintln!("  point {i}/{} at {p:?}: {d:.4} mm off", points.len());
        }
        max = max.max(d);
        if let Some(h) = hit.get_mut(s.floor() as usize) {
            *h = true;
        }
    }
    let coverage = hit.iter().filter(|&&h| h).count() as f64 / bins as f64;
    ((sum2 / points.len() as f64).sqrt(), max, coverage)
}

/// Traces `spec` and checks it against its truth; returns the RMS distance (mm).
fn check(spec: &RenderSpec, opts: &TraceOptions, rms_limit_mm: f64) -> f64 {
    let tr = trace(spec, opts).expect("trace");
    let stroke = tr.main_stroke().expect("a stroke");
    assert_eq!(
        tr.strokes.len(),
        1,
        "one stroke expected, got {:?}",
        tr.strokes.iter().map(|s| s.length_mm()).collect::<Vec<_>>()
    );
    assert_eq!(stroke.closed, spec.pencil_closed);
    for w in stroke.points_mm.windows(2) {
        assert!((w[0][0] - w[1][0]).hypot(w[0][1] - w[1][1]) <= 0.5 + 1e-9);
    }
    let (rms, max, coverage) = accuracy(&stroke.points_mm, &spec.pencil_mm, spec.pencil_closed);
    eprintln!(
        "dpi {} rot {} deg: {} points, rms {rms:.4} mm, max {max:.4} mm, coverage {:.2} %, dot residual {:?}",
        spec.dpi,
        spec.rotation_deg,
        stroke.points_mm.len(),
        100.0 * coverage,
        tr.dot_residual_mm
    );
    assert!(rms <= rms_limit_mm, "rms {rms} mm > {rms_limit_mm} mm");
    assert!(coverage > 0.99, "coverage {coverage}");
    rms
}

#[test]
fn circle_600dpi_rotated_is_within_10um() {
    let rms = check(
        &spec(wobbly_circle(), true, 600.0, 2.5, 11),
        &TraceOptions::default(),
        0.01,
    );
    record("circle_600dpi_rms_mm", rms);
}

#[test]
fn line_600dpi_rotated_is_within_10um() {
    let rms = check(
        &spec(wobbly_line(), false, 600.0, -2.0, 12),
        &TraceOptions::default(),
        0.01,
    );
    record("line_600dpi_rms_mm", rms);
}

#[test]
fn circle_300dpi_is_within_20um() {
    let rms = check(
        &spec(wobbly_circle(), true, 300.0, -3.0, 13),
        &TraceOptions::default(),
        0.02,
    );
    record("circle_300dpi_rms_mm", rms);
}

#[test]
fn line_300dpi_is_within_20um() {
    let rms = check(
        &spec(wobbly_line(), false, 300.0, 1.5, 14),
        &TraceOptions::default(),
        0.02,
    );
    record("line_300dpi_rms_mm", rms);
}

#[test]
fn upside_down_scan_is_corrected() {
    check(
        &spec(wobbly_line(), false, 300.0, 181.5, 15),
        &TraceOptions::default(),
        0.02,
    );
}

#[test]
fn printer_scale_is_undone_by_the_measured_spacing() {
    // The printer shrank the sheet by 2 %: the fiducials are 176.4 mm apart; the pencil is
    // physical and must come out in physical mm.
    let s = RenderSpec {
        print_scale: 0.98,
        ..spec(wobbly_line(), false, 300.0, 2.0, 16)
    };
    let opts = TraceOptions {
        mapping: Mapping::Fiducials { spacing_mm: 176.4 },
        ..TraceOptions::default()
    };
    check(&s, &opts, 0.02);
    // With the nominal spacing the trace comes out 180 / 176.4 = 2.04 % too long.
    let wrong = trace(&s, &TraceOptions::default()).expect("trace");
    let ratio = wrong.main_stroke().expect("a stroke").length_mm()
        / rigctl::trace::polyline_length(&s.pencil_mm, false);
    assert!(
        (ratio - 180.0 / 176.4).abs() < 0.003,
        "length ratio with the nominal spacing {ratio}"
    );
}

#[test]
fn mirrored_scan_is_refused() {
    let s = RenderSpec {
        mirrored: true,
        ..spec(wobbly_line(), false, 300.0, 1.0, 17)
    };
    let err = trace(&s, &TraceOptions::default()).expect_err("mirrored");
    assert!(matches!(err, TraceError::Mirrored), "{err}");
}

#[test]
fn blank_page_has_no_fiducials() {
    let s = RenderSpec {
        fiducials: false,
        reference: None,
        ..spec(Vec::new(), false, 300.0, 0.0, 18)
    };
    let err = trace(&s, &TraceOptions::default()).expect_err("blank");
    assert!(matches!(err, TraceError::NoFiducials { .. }), "{err}");
}

#[test]
fn sheet_without_pencil_has_no_trace() {
    for reference in [ReferencePath::Circle, ReferencePath::Line] {
        let s = RenderSpec {
            reference: Some(reference),
            ..spec(Vec::new(), false, 300.0, 2.0, 19)
        };
        let err = trace(&s, &TraceOptions::default()).expect_err("no pencil");
        assert!(
            matches!(err, TraceError::NoTrace { .. }),
            "{reference:?}: {err}"
        );
    }
}

#[test]
fn pencil_without_fiducials_needs_a_scale() {
    let s = RenderSpec {
        fiducials: false,
        ..spec(wobbly_line(), false, 300.0, 0.0, 20)
    };
    let img = render_scan(&s);
    let err = trace_image(&img, &TraceOptions::default(), &ProgressBar::hidden())
        .expect_err("no fiducials");
    assert!(matches!(err, TraceError::NoFiducials { .. }), "{err}");
    // With a plain scale the stroke is found; its length is the truth's (the scale mapping
    // ignores the page's placement, which is a rigid motion here).
    let opts = TraceOptions {
        mapping: Mapping::Scale {
            mm_per_px: 25.4 / 300.0,
        },
        ..TraceOptions::default()
    };
    let tr = trace_image(&img, &opts, &ProgressBar::hidden()).expect("scale mapping");
    let truth_len = rigctl::trace::polyline_length(&s.pencil_mm, false);
    let len = tr.main_stroke().expect("a stroke").length_mm();
    assert!(
        (len - truth_len).abs() < 0.01 * truth_len,
        "{len} vs {truth_len}"
    );
}
