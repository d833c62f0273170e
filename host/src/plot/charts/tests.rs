//! Unit tests of `charts.rs`.

use super::*;
use crate::plot::svg_string;

#[test]
fn ranges_pad_by_five_percent_and_never_collapse() {
    let (lo, hi) = finite_range(&[2.0, f64::NAN, 4.0]).unwrap();
    assert!(
        (lo - 1.9).abs() < 1e-12 && (hi - 4.1).abs() < 1e-12,
        "{lo} {hi}"
    );
    // a single value: +-5 % of max(|v|, 1)
    assert_eq!(finite_range(&[0.0]), Some((-0.05, 0.05)));
    assert_eq!(finite_range(&[f64::NAN]), None);
    // lines use the exact extent unless it is a single value
    assert_eq!(line_x_range(&[3.0, 1.0, f64::INFINITY]), Some((1.0, 3.0)));
    assert_eq!(line_x_range(&[2.0, 2.0]), finite_range(&[2.0]));
}

#[test]
fn histogram_counts_by_hand() {
    // bins of width 1 over 0..4; 4.0 goes to the last bin, negatives and NaN are dropped
    let c = ErrorHistogram::counts(&[0.0, 0.5, 1.0, 3.9, 4.0, -1.0, f64::NAN], 4, 4.0);
    assert_eq!(c, vec![2, 1, 0, 2]);
}

#[test]
fn every_chart_draws_its_legend_labels() {
    let before = vec![1.0, 3.0, 2.0];
    let after = vec![0.5, 0.25, 0.125];
    let labels = ["lbl-before".to_string(), "lbl-after".to_string()];
    let svgs = [
        svg_string(&PoseErrorBars {
            title: "bars".into(),
            before_mm: before.clone(),
            after_mm: after.clone(),
            labels: labels.clone(),
        }),
        svg_string(&ErrorHistogram {
            title: "hist".into(),
            before_mm: before.clone(),
            after_mm: after.clone(),
            bins: 3,
            labels: labels.clone(),
        }),
        svg_string(&Scatter {
            title: "scatter".into(),
            x_label: "q1 (deg)".into(),
            y_label: "|dP| (mm)".into(),
            x: vec![1.0, 2.0, 3.0],
            before: before.clone(),
            after: after.clone(),
            labels: labels.clone(),
        }),
        svg_string(&LineChart::path_error(
            vec![0.0, 1.0, 2.0],
            before.clone(),
            after.clone(),
            ["lbl-before", "lbl-after"],
        )),
    ];
    for svg in svgs {
        let svg = svg.unwrap_or_else(|e| panic!("{e}"));
        assert!(svg.contains("lbl-before") && svg.contains("lbl-after"));
    }
}

#[test]
fn bad_data_is_a_data_error() {
    let bars = PoseErrorBars {
        title: "bars".into(),
        before_mm: vec![1.0, 2.0],
        after_mm: vec![1.0],
        labels: ["a".into(), "b".into()],
    };
    assert!(matches!(svg_string(&bars), Err(PlotError::Data { .. })));
    let mut line = LineChart::path_error(vec![0.0, 1.0], vec![1.0], vec![1.0, 2.0], ["a", "b"]);
    assert!(matches!(svg_string(&line), Err(PlotError::Data { .. })));
    line.x = vec![f64::NAN, f64::NAN];
    assert!(matches!(svg_string(&line), Err(PlotError::Data { .. })));
}
