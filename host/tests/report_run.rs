//! `rigctl report` on a run directory made in the test: simulate + calibrate through the
//! library, then the page is checked against the calibrate numbers.

use rigctl::calib::{calibrate, CalibrateOptions, Method, Poses};
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
    let cal = Poses::read(&dir.path().join("cal.csv"), &declared).unwrap();
    let val = Poses::read(&dir.path().join("val.csv"), &declared).unwrap();
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
    // tables from the JSON: before / standard / tilting, both pose sets
    let json_cal = report
        .tables
        .iter()
        .find(|t| t.title == "Calibration poses" && t.source == "calibrate.json")
        .expect("calibration table from the JSON");
    assert_eq!(
        json_cal.columns,
        ["before", "after standard", "after tilting"]
    );
    let r = &outcome.report;
    // (through JSON text: equal to the last bit or two)
    let close = |a: Option<f64>, b: f64| a.is_some_and(|a| (a - b).abs() <= 1e-12 * b.abs());
    assert!(close(
        json_cal.get("Average", "|dP|", 0),
        r.calibration.before.mean_mm
    ));
    assert!(close(
        json_cal.get("Average", "|dP|", 2),
        r.calibration.after.mean_mm
    ));
    assert!(close(
        json_cal.get("Average", "|dP|", 1),
        r.standard.calibration.mean_mm
    ));
    // recomputed from the pose files: the nominal column equals calibrate's "before", and the
    // calibrated model (evaluated in its best tilt mode) reproduces calibrate's "after"
    let rec = report
        .tables
        .iter()
        .find(|t| t.title == "Calibration poses (recomputed)")
        .expect("recomputed table");
    let before = rec.get("Average", "|dP|", 0).unwrap();
    assert!(
        (before - r.calibration.before.mean_mm).abs() < 1e-9,
        "{before}"
    );
    let after = rec.get("Average", "|dP|", 1).unwrap();
    assert!(
        (after - r.calibration.after.mean_mm).abs() < 1e-6,
        "{after} vs {}",
        r.calibration.after.mean_mm
    );
    assert_eq!(rec.columns[1], "calibrated (tilting)");
    assert!(
        rec.get("Maximum", "|dX|", 1).is_some(),
        "per-axis extremes are recomputed"
    );
    assert!(report
        .tables
        .iter()
        .any(|t| t.title == "Validation poses (recomputed)"));
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
        "sorted by the error before",
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
