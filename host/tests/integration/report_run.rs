//! `rigctl report` on a run directory made in the test: simulate + calibrate through the
//! library, then the page is checked against the calibrate numbers.

use rigctl::calib::MeasuredSet;
use rigctl::calib::{calibrate, CalibrateOptions, Method};
use rigctl::model::katana450;
use rigctl::report::{build_report, render_html, write_report, ReportError, ReportOptions};
use rigctl::sim::output::write_outputs;
use rigctl::sim::simulate::{simulate, SimConfig};

fn run_dir() -> (tempfile::TempDir, rigctl::calib::Outcome) {
    let dir = tempfile::tempdir().unwrap();
    let declared = katana450(200.0).unwrap();
    let cfg = SimConfig {
        seed: 7,
        n_val: 20,
        ..SimConfig::default()
    };
    let out = simulate(&declared, &cfg).unwrap();
    write_outputs(dir.path(), &out, &cfg).unwrap();
    let cal = MeasuredSet::read(&dir.path().join("cal.csv"), &declared).unwrap();
    let val = MeasuredSet::read(&dir.path().join("val.csv"), &declared).unwrap();
    let opts = CalibrateOptions {
        method: Method::Tilting,
        ..Default::default()
    };
    let outcome = calibrate(&declared, &cal, Some(&val), &opts).unwrap();
    let json = serde_json::to_string_pretty(&outcome.report).unwrap();
    std::fs::write(dir.path().join("calibrate.json"), json).unwrap();
    outcome
        .model
        .write_file(&dir.path().join("calibrated.toml"))
        .unwrap();
    std::fs::write(
        dir.path().join("commands.txt"),
        "rigctl simulate --seed 7\n",
    )
    .unwrap();
    (dir, outcome)
}

#[test]
fn report_of_a_simulated_and_calibrated_run() {
    let (dir, outcome) = run_dir();
    let report = build_report(dir.path(), &ReportOptions::default()).unwrap();
    // one table per pose set: the pose file recomputed with the nominal model and every model
    // file, plus the calibrate JSON's columns that are not the same model again
    let cal = report
        .tables
        .iter()
        .find(|t| t.title == "Calibration poses")
        .expect("calibration table");
    assert_eq!(cal.source, "cal.csv, calibrate.json");
    assert_eq!(
        cal.columns,
        [
            "nominal model",
            "calibrated.toml (tilting)",
            "after standard"
        ]
    );
    assert_eq!(cal.noun, "poses");
    let r = &outcome.report;
    // recomputed: the nominal column equals calibrate's "before", and the calibrated model
    // (evaluated in its best tilt mode) reproduces calibrate's "after"
    let before = cal.get("Average", "|dP|", 0).unwrap();
    assert!(
        (before - r.calibration.before.mean_mm).abs() < 1e-9,
        "{before}"
    );
    let after = cal.get("Average", "|dP|", 1).unwrap();
    assert!(
        (after - r.calibration.after.mean_mm).abs() < 1e-6,
        "{after} vs {}",
        r.calibration.after.mean_mm
    );
    // the standard column from the JSON (through JSON text: equal to the last bit or two)
    let std_mean = cal.get("Average", "|dP|", 2).unwrap();
    assert!((std_mean - r.standard.calibration.mean_mm).abs() <= 1e-12 * std_mean);
    assert!(
        cal.get("Maximum", "|dX|", 1).is_some(),
        "per-axis extremes are recomputed"
    );
    assert_eq!(
        cal.get("Maximum", "|dX|", 2),
        None,
        "not in the JSON: a gap, not a number"
    );
    assert_eq!(report.tables.len(), 2, "one table per pose set");
    assert!(report
        .tables
        .iter()
        .any(|t| t.title == "Held-out poses" && t.n == 20));
    // the first screen: held-out error at each stage, from the calibrate document
    let h = &report.summary.headlines[0];
    assert!(h.held_out && h.n == 20, "{h:?}");
    let labels: Vec<&str> = h.stages.iter().map(|s| s.label.as_str()).collect();
    assert_eq!(
        labels,
        [
            "nominal model",
            "calibrated model (standard)",
            "calibrated model (tilting)"
        ]
    );
    let val = r.validation.as_ref().expect("validation stats");
    assert!((h.stages[0].mean_mm - val.before.mean_mm).abs() <= 1e-12 * val.before.mean_mm);
    assert!((h.stages[2].rms_mm - val.after.rms_mm).abs() <= 1e-12 * val.after.rms_mm);
    assert!(report.summary.figure.is_some(), "{:?}", report.notes);
    // parameters with sigma and truth
    let p = &report.parameters[0];
    assert_eq!(p.method, "tilting");
    let dth2 = p.rows.iter().find(|r| r.name == "dth2").expect("dth2");
    assert!(dth2.sigma.is_some() && dth2.truth.is_some() && dth2.nominal.is_some());
    // figures: bars + histogram + residual for 2 sets, influence, moments/tilts, path error
    let caps: Vec<&str> = report.figures.iter().map(|f| f.caption.as_str()).collect();
    for want in [
        "fig. 3.8",
        "fig. 5.8-5.10",
        "fig. 5.12",
        "histogram",
        "sorted by its error",
    ] {
        assert!(
            caps.iter().any(|c| c.contains(want)),
            "no figure with {want:?}: {caps:#?}; notes {:?}",
            report.notes
        );
    }
    assert!(report
        .files
        .iter()
        .any(|f| f.name == "cal.csv" && f.sha256.len() == 64));
    let html = render_html(&report);
    assert!(!html.contains("<script"));
    // the answer comes before any table: held-out numbers, 3 significant digits
    let first = &html[..html.find("<table").expect("a table")];
    assert!(
        first.contains("On 20 held-out poses the mean error goes from"),
        "{first}"
    );
    assert!(first.contains(&rigctl::plot::summary::fmt_mm(val.after.mean_mm)));
    assert!(first.contains("What to do next") && first.contains("rigctl diagnose"));
    assert!(html.contains("rigctl simulate --seed 7"));
    assert!(html.contains(&format!("{:.4}", r.calibration.after.mean_mm)));
}

#[test]
fn missing_pieces_are_notes_and_an_empty_dir_is_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r.html");
    let err = write_report(dir.path(), &out, &ReportOptions::default()).unwrap_err();
    assert!(matches!(err, ReportError::NothingUsable { .. }), "{err}");
    assert_eq!(
        rigctl::error::Classify::kind(&err),
        rigctl::error::ErrorKind::BadInput
    );
    assert!(!out.exists());
    // only a calibrate JSON: the tables and parameters, notes for the rest
    let (full, _) = run_dir();
    std::fs::copy(
        full.path().join("calibrate.json"),
        dir.path().join("calibrate.json"),
    )
    .unwrap();
    let report = write_report(dir.path(), &out, &ReportOptions::default()).unwrap();
    assert_eq!(report.tables.len(), 2);
    assert!(
        report.figures.is_empty()
            || report
                .figures
                .iter()
                .all(|f| !f.caption.contains("per pose"))
    );
    assert!(
        report.notes.iter().any(|n| n.contains("path error")),
        "{:?}",
        report.notes
    );
    assert!(std::fs::read_to_string(&out)
        .unwrap()
        .contains("id=\"table-0\""));
}
