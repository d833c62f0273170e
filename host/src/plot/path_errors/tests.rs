//! Unit tests of `path_errors.rs`.

use super::*;

/// Four samples in three segments (a gap of 1.9 s, then `t` decreasing); hand-computed
/// statistics in [`hand_summary_matches`].
pub(crate) const SAMPLE_CSV: &str = "\
# path errors, mm
t,q1,q2,dev_u_before,dev_n_before,dp_before,dev_u_after,dev_n_after,dp_after,dev_u_standard,dev_n_standard,dp_standard
0.0,10,20,3,4,5,0.3,0.4,0.5,0.6,0.8,1
0.1,11,21,-3,-4,5,0,0.1,0.1,0,-1,1

2.0,12,22,0,1,1,0.1,0,0.1,1,0,1
0.5,13,23,1,0,1,-0.5,0,0.5,-1,0,1
";

fn sample() -> PathErrors {
    parse_path_errors(SAMPLE_CSV, "err.csv").unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

#[test]
fn hand_summary_matches() {
    let p = sample();
    let s = p.summary();
    assert_eq!((s.n_samples, s.n_segments), (4, 3));
    // before: dp 5, 5, 1, 1 -> RMS sqrt(52 / 4), max 5, mean 3;
    // dev_u 3, -3, 0, 1 -> sqrt(19 / 4); dev_n 4, -4, 1, 0 -> sqrt(33 / 4)
    assert!(close(s.before.dp_rms_mm, 13f64.sqrt()), "{s:?}");
    assert!(close(s.before.dp_max_mm, 5.0) && close(s.before.dp_mean_mm, 3.0));
    assert!(close(s.before.dev_u_rms_mm, 4.75f64.sqrt()));
    assert!(close(s.before.dev_n_rms_mm, 8.25f64.sqrt()));
    // after: dp 0.5, 0.1, 0.1, 0.5 -> RMS sqrt(0.52 / 4), max 0.5, mean 0.3
    assert!(close(s.after.dp_rms_mm, 0.13f64.sqrt()), "{s:?}");
    assert!(close(s.after.dp_max_mm, 0.5) && close(s.after.dp_mean_mm, 0.3));
    // standard: dp 1 everywhere
    assert!(close(s.standard.dp_rms_mm, 1.0) && close(s.standard.dp_max_mm, 1.0));
    assert!(close(s.standard.dev_u_rms_mm, 0.59f64.sqrt()));
    assert_eq!(p.segments, vec![0..2, 2..3, 3..4]);
    assert_eq!(p.q_deg[3], vec![13.0, 23.0]);
    assert_eq!(p.after_label, AFTER_LABEL);
    // segments joined one typical step (0.1 s) apart
    let x = p.path_time_s();
    for (got, want) in x.iter().zip([0.0, 0.1, 0.2, 0.3]) {
        assert!((got - want).abs() < 1e-12, "{x:?}");
    }
}

#[test]
fn segments_split_at_gaps_and_decreases_only() {
    assert_eq!(segments_of(&[]), Vec::<Range<usize>>::new());
    assert_eq!(segments_of(&[5.0]), vec![0..1]);
    // a step of exactly SEGMENT_GAP_S and a repeated time stay in the segment
    assert_eq!(
        segments_of(&[0.0, 1.0, 1.0, 2.5, 2.4, 3.0]),
        vec![0..3, 3..4, 4..6]
    );
}

#[test]
fn svg_holds_the_three_series_with_their_rms() {
    let mut p = sample();
    p.after_label = "after (tilting)".into();
    let svg = path_errors_svg(&p).unwrap_or_else(|e| panic!("{e}"));
    assert!(svg.contains("<svg"), "not an SVG document");
    for text in [
        "before (nominal model), RMS 3.606 mm",
        "standard (rigid calibration), RMS 1.000 mm",
        "after (tilting), RMS 0.361 mm",
        // dev_u and dev_n panels
        "before (nominal model), RMS 2.179 mm",
        "before (nominal model), RMS 2.872 mm",
        "RMS |dP| before 3.606, standard 1.000, after 0.361 mm",
        "3 segments joined",
    ] {
        assert!(svg.contains(text), "missing {text:?}");
    }
}

#[test]
fn bad_files_name_file_line_and_column() {
    let bad = SAMPLE_CSV.replace("0.1,11,21,-3,-4,5,0,0.1", "0.1,11,21,-3,-4,5,0,x");
    let e = parse_path_errors(&bad, "err.csv").unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains("err.csv:4") && m.contains("`dev_n_after`"),
        "{m}"
    );
    assert_eq!(e.kind(), ErrorKind::BadInput);

    let e = parse_path_errors("t,q1\n0,1\n", "e.csv").unwrap_err();
    assert!(e.to_string().contains("`dev_u_before`"), "{e}");

    let wrong = SAMPLE_CSV.replace(",0.5,0.6,0.8,1\n", ",0.6,0.6,0.8,1\n");
    let e = parse_path_errors(&wrong, "err.csv").unwrap_err();
    assert!(
        matches!(&e, PathErrorsError::Magnitude { line: 3, column, .. } if column == "dp_after"),
        "{e}"
    );
    assert_eq!(e.kind(), ErrorKind::BadInput);
    assert!(matches!(
        parse_path_errors("", "e.csv"),
        Err(PathErrorsError::Table(TableError::NoHeader { .. }))
    ));
}

#[test]
fn reads_the_header_calibrate_writes() {
    // the header of `calibrate --errors-csv` (no joints), one hand-written row
    let empty: [Vec<nalgebra::Vector3<f64>>; 3] = Default::default();
    let mut text = crate::calib::projected::errors_csv(&[], &empty);
    text.push_str("7.5,0,2,2,0,0.5,0.5,1,0,1\n");
    let p = parse_path_errors(&text, "calibrate").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.t_s, vec![7.5]);
    assert_eq!(p.before.dev_n_mm, vec![2.0]);
    assert_eq!(p.after.dp_mm, vec![0.5]);
    assert_eq!(p.standard.dev_u_mm, vec![1.0]);
    assert!(p.q_deg[0].is_empty());
}

#[test]
fn inconsistent_data_is_a_plot_error_not_a_panic() {
    let mut p = sample();
    p.after.dp_mm.pop();
    assert!(matches!(path_errors_svg(&p), Err(PlotError::Data { .. })));
    let mut p = sample();
    p.segments = vec![0..2, 3..4];
    assert!(path_errors_svg(&p).is_err());
}
