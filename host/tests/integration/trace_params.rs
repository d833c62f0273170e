//! The tracer's stage parameters are passed per call (`TraceOptions::params`), not read from
//! constants: a scan traced with other numbers changes the way the numbers' docs say; `rigctl
//! trace --params FILE` reads them from TOML and refuses a bad file naming its line and field.

use super::common::spawn::{output, path_arg, text};
use indicatif::ProgressBar;
use rigctl::sheet::ReferencePath;
use rigctl::trace::synth::{render_scan, RenderSpec};
use rigctl::trace::{trace_image, LeftOutKind, TraceError, TraceOptions, TraceParams};

/// A straight 8 mm pencil mark, from `at` along x.
fn mark(at: [f64; 2], len_mm: f64) -> Vec<[f64; 2]> {
    (0..=(len_mm / 0.05) as usize)
        .map(|i| [at[0] + 0.05 * i as f64, at[1]])
        .collect()
}

/// The printed line drawn across the sheet, and an 8 mm mark 60 mm from it.
fn sheet() -> RenderSpec {
    let line: Vec<[f64; 2]> = (0..=3_600)
        .map(|i| {
            let x = -90.0 + 0.05 * i as f64;
            [x, 0.3 + 0.15 * (x / 20.0).sin()]
        })
        .collect();
    RenderSpec {
        dpi: 200.0,
        pencil_mm: line,
        pencil_closed: false,
        more_pencil_mm: vec![(mark([-4.0, 60.0], 8.0), false)],
        reference: Some(ReferencePath::Line),
        rotation_deg: 0.7,
        shift_mm: [1.5, -2.0],
        seed: 4,
        ..RenderSpec::default()
    }
}

/// `LinkParams::min_mark_mm`: "marks shorter than this are specks". The 8 mm mark is a mark
/// with the tuned 5 mm and a speck with 12 mm; the drawn path is the same either way.
#[test]
fn a_longer_min_mark_makes_a_short_mark_a_speck() {
    let img = render_scan(&sheet());
    let run = |params: TraceParams| {
        let opts = TraceOptions {
            params,
            ..TraceOptions::default()
        };
        trace_image(&img, &opts, &ProgressBar::hidden()).expect("trace")
    };
    let tuned = run(TraceParams::default());
    let near_mark = |o: &&rigctl::trace::LeftOut| (o.from_mm[1] - 60.0).abs() < 2.0;
    let found = tuned
        .linking
        .left_out
        .iter()
        .find(near_mark)
        .unwrap_or_else(|| panic!("the 8 mm mark left out: {:?}", tuned.linking.left_out));
    assert!(
        (6.0..=9.0).contains(&found.length_mm),
        "{}",
        found.length_mm
    );
    assert_eq!(found.kind, LeftOutKind::Mark);

    let mut params = TraceParams::default();
    params.link.min_mark_mm = 12.0;
    let longer = run(params);
    let found = longer
        .linking
        .left_out
        .iter()
        .find(near_mark)
        .expect("the mark still left out");
    assert_eq!(found.kind, LeftOutKind::Speck, "{found:?}");
    assert_eq!(
        longer.main_stroke().map(|s| &s.points_mm),
        tuned.main_stroke().map(|s| &s.points_mm),
        "the drawn path does not depend on what a speck is"
    );
}

/// `FiducialParams::max_corner_candidates`: "how many of the largest discs are tried as
/// corners". Fewer than four make no square: the same scan has no fiducials.
#[test]
fn fewer_corner_candidates_than_corners_find_no_fiducials() {
    let img = render_scan(&sheet());
    let mut opts = TraceOptions::default();
    opts.params.fiducials.max_corner_candidates = 3;
    let err = trace_image(&img, &opts, &ProgressBar::hidden()).expect_err("no square of 3");
    assert!(matches!(err, TraceError::NoFiducials { .. }), "{err}");
    opts.params.fiducials.max_corner_candidates = 4;
    assert!(trace_image(&img, &opts, &ProgressBar::hidden()).is_ok());
}

/// `trace --params FILE`: a file's numbers reach the tracer (3 corner candidates: no
/// fiducials, exit 2); a number out of range, an unknown key or a value of the wrong type is
/// exit 2 naming the file, its line and the field, with nothing written.
#[test]
fn a_params_file_is_applied_or_refused_naming_line_and_field() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scan = dir.path().join("scan.png");
    render_scan(&sheet()).save(&scan).expect("save png");
    let out = dir.path().join("trace.csv");
    let params = dir.path().join("params.toml");
    let run = |toml: &str| {
        std::fs::write(&params, toml).expect("write params");
        output(&[
            "trace",
            path_arg(&scan),
            "--out",
            path_arg(&out),
            "--params",
            path_arg(&params),
        ])
    };
    let ok = run("[link]\nmin_mark_mm = 12.0\n");
    assert_eq!(ok.status.code(), Some(0), "{}", text(&ok.stderr));
    assert!(out.exists());
    std::fs::remove_file(&out).expect("rm");

    let few = run("# too few to make a square\n[fiducials]\nmax_corner_candidates = 3\n");
    assert_eq!(few.status.code(), Some(2), "{}", text(&few.stderr));
    assert!(
        text(&few.stderr).contains("fiducial"),
        "{}",
        text(&few.stderr)
    );
    assert!(!out.exists());

    for (toml, line, field) in [
        (
            "[link]\nmin_mark_mm = 5.0\nbridge_step_mm = 0\n",
            3,
            "link.bridge_step_mm",
        ),
        ("[lines]\npass_mm = -4.0\n", 2, "lines.pass_mm"),
        ("[centreline]\nfaint_run_step = 8\n", 2, "faint_run_step"),
        ("[camera]\n\ncentre_f = \"ten\"\n", 3, "centre_f"),
    ] {
        let bad = run(toml);
        let err = text(&bad.stderr);
        assert_eq!(bad.status.code(), Some(2), "{toml}: {err}");
        let at = format!("{}:{line}", params.display());
        assert!(err.contains(&at) && err.contains(field), "{toml}: {err}");
        assert!(!out.exists(), "{toml}: written");
    }
}
