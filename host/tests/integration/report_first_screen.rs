//! The report's first screen and the newer run-directory files, from hand-written documents:
//! a diagnose JSON with the newer keys (floor, aliased, unexplained.depends_on /
//! explainable_share, effects[].sigma, parameters_at_entry), one without them (older runs),
//! plan.csv + plan.json, and a trace overlay PNG; and the first screen of the demo's run.

use rigctl::report::{build_report, render_html, ReportOptions};

use crate::common::record::record;
use crate::common::spawn::output;

fn stats(n: usize, mean: f64, rms: f64) -> serde_json::Value {
    serde_json::json!({"n": n, "mean_mm": mean, "rms_mm": rms, "max_mm": 3.0 * mean,
        "min_mm": 0.1 * mean, "mean_abs_x_mm": 0.5 * mean, "mean_abs_y_mm": 0.5 * mean,
        "mean_abs_z_mm": 0.4 * mean})
}

fn diagnose_new() -> serde_json::Value {
    serde_json::json!({
        "declared": {"calibration": stats(644, 0.041, 0.050), "validation": stats(580, 0.0396, 0.049)},
        "final": {"calibration": stats(644, 0.0049, 0.0061), "validation": stats(580, 0.0046, 0.0058)},
        "effects": [{
            "id": "encoder_harmonic:j2:h1",
            "parameters": {"A": 0.0491, "phi": 30.5},
            "sigma": {"A": 0.0012, "phi": 1.4},
            "parameters_at_entry": {"A": 0.050, "phi": 29.0},
            "validation_mean_mm_before": 0.0240, "validation_mean_mm_after": 0.0046,
            "cv_mean_mm_before": 0.0396, "cv_mean_mm_after": 0.0379,
            "p_value": 1e-12, "delta_bic": -85.2,
            "evidence": "F = 80.1"
        }],
        "unexplained": {"structured": true, "note": "smooth in q2", "depends_on": ["q2"],
                        "explainable_share": 0.31},
        "floor": {"instrument_mm": 0.003, "repeatability_mm": null, "residual_mm": 0.0049,
                  "used": "instrument", "final_over_floor": 1.9},
        "aliased": [{"a": "payload", "b": "dth3", "correlation": 0.97,
                     "note": "the circle does not separate them"}],
        "measurements": "partial",
        "robot": "katana450"
    })
}

fn diagnose_old() -> serde_json::Value {
    serde_json::json!({
        "declared": {"calibration": stats(118, 0.030, 0.036), "validation": stats(60, 0.031, 0.037)},
        "final": {"calibration": stats(118, 0.030, 0.036), "validation": stats(60, 0.031, 0.037)},
        "effects": [],
        "unexplained": {"structured": false, "note": ""},
        "noise": {"sigma_mm": 0.0099, "expected_mean_mm": 0.0158}
    })
}

#[test]
fn newer_diagnose_keys_reach_the_first_screen() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("diagnose_samples.json"),
        diagnose_new().to_string(),
    )
    .unwrap();
    let r = build_report(dir.path(), &ReportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let s = &r.summary;
    assert_eq!(s.headlines.len(), 1);
    let h = &s.headlines[0];
    assert_eq!(h.set, "580 held-out samples");
    assert_eq!(h.stages.len(), 2);
    let d = &s.diagnoses[0];
    assert_eq!(d.noun, "samples");
    assert_eq!(
        d.effects[0].values[0],
        ("A".to_string(), 0.0491, Some(0.0012))
    );
    // 1 - 0.0046 / 0.0240 = 80.8 %
    assert!(
        d.effects[0]
            .evidence
            .contains("removes 81 % of the held-out mean error (0.0240 -> 0.0046 mm)"),
        "{}",
        d.effects[0].evidence
    );
    assert!(d.effects[0]
        .evidence
        .contains("cross-validated 0.0396 -> 0.0379 mm"));
    let v = d.verdict.as_deref().unwrap();
    assert!(
        v.starts_with("The model still lacks something: the residual depends on q2 (31 %"),
        "{v}"
    );
    assert!(
        v.contains("1.90 x the instrument floor of 0.0030 mm"),
        "{v}"
    );
    assert_eq!(d.aliased[0].correlation, Some(0.97));
    assert!(s.next_steps.iter().any(|n| n.contains(&format!(
        "--from-diagnose {}",
        dir.path().join("diagnose_samples.json").display()
    ))));

    let html = render_html(&r);
    let first = &html[..html.find("<table").expect("detail tables")];
    for want in [
        "On 580 held-out samples the mean error goes from 0.0396 mm (RMS 0.0490)",
        "to 0.0046 mm (RMS 0.0058) with the 1 effect found",
        "<code>encoder_harmonic:j2:h1</code> A = 0.0491 &plusmn; 0.0012, phi = 30.500 &plusmn; 1.400",
        "Aliased: <code>payload</code> and <code>dth3</code> (correlation 0.97)",
        "<code>rigctl plan --n 60",
        "<svg",
    ] {
        assert!(first.contains(want), "first screen lacks {want:?}:\n{first}");
    }
    // details: samples, not poses; units in the headers; no row without a number
    assert!(html.contains("Held-out samples, 580 samples"));
    assert!(!html.contains("580 poses"));
    assert!(html.contains("<th class=\"num\">calibrated declared model, mm</th>"));
    assert!(!html.contains("<td class=\"num\">&ndash;</td>"));
    assert!(
        !html.contains("<th>Maximum</th><th>|dX|</th>"),
        "JSON has no per-axis maximum"
    );
}

#[test]
fn older_documents_without_the_newer_keys_still_give_an_answer() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("diagnose.json"), diagnose_old().to_string()).unwrap();
    let r = build_report(dir.path(), &ReportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let d = &r.summary.diagnoses[0];
    assert!(d.effects.is_empty() && d.aliased.is_empty());
    let v = d.verdict.as_deref().unwrap();
    assert!(v.starts_with("At the noise floor"), "{v}");
    assert!(v.contains("0.0099 mm"), "{v}");
    // one stage only: nothing was added
    assert_eq!(r.summary.headlines[0].stages.len(), 1);
    let html = render_html(&r);
    let first = &html[..html.find("<table").unwrap()];
    assert!(first.contains("No effect the declared model lacks could be established"));
    assert!(first.contains("On 60 held-out poses: mean error 0.0310 mm, RMS 0.0370 mm"));
}

#[test]
fn plan_and_overlay_get_their_sections() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(
        p.join("plan.csv"),
        "q1,q2,q3,q4,q5,nom_x,nom_y,nom_z\n0,90,-90,0,0,100,-200,150\n10,80,-80,5,0,120,-180,170\n",
    )
    .unwrap();
    std::fs::write(
        p.join("plan.json"),
        serde_json::json!({"robot": "katana450", "n": 2, "criterion": "D-optimal",
            "candidates": 5000, "parameters": ["dth2", "a2"],
            "expected_sigma": {"dth2": 0.0021, "a2": 0.013},
            "random_sigma": {"dth2": 0.0040, "a2": 0.030},
            "condition_number": 12.5, "random_condition_number": 40.2,
            "median_sigma_ratio": 0.48, "unidentifiable": [], "from_diagnose": null,
            "sheets": null, "optimum": {"median_sigma_ratio": 0.47, "efficiency": 0.985}})
        .to_string(),
    )
    .unwrap();
    std::fs::write(
        p.join("calibrate.json"),
        r#"{"method": "tilting", "parameters": {"dth2": 0.1, "a2": 190.1}, "sigma": {"dth2": 0.0025, "a2": 0.02}}"#,
    )
    .unwrap();
    // a wide overlay: embedded downscaled
    let img = image::RgbImage::from_fn(2000, 500, |x, _| image::Rgb([(x % 256) as u8, 200, 90]));
    img.save(p.join("scan_overlay.png")).unwrap();
    let r = build_report(p, &ReportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let plan = r.plan.as_ref().expect("plan section");
    assert_eq!(plan.n_poses, Some(2));
    assert!(plan.figure.is_some(), "{:?}", r.notes);
    let dth2 = plan.sigma.iter().find(|s| s.name == "dth2").unwrap();
    assert_eq!(
        (dth2.expected, dth2.random, dth2.achieved),
        (Some(0.0021), Some(0.0040), Some(0.0025))
    );
    assert_eq!(plan.achieved_source.as_deref(), Some("calibrate.json"));
    assert_eq!(r.overlays.len(), 1);
    assert_eq!(
        (r.overlays[0].width_px, r.overlays[0].height_px),
        (1400, 350)
    );
    let html = render_html(&r);
    assert!(html.contains("<a href=\"#plan\">Planned poses</a>"));
    assert!(html.contains("<a href=\"#overlay\">Trace overlay</a>"));
    assert!(html.contains("src=\"data:image/png;base64,iVBORw0KGgo"));
    assert!(html.contains("condition number, planned / random poses</th><td>12.5 / 40.2"));
    assert!(html.contains("median sigma / random; plan&#39;s efficiency</th><td>0.470; 0.985"));
    // a broken plan file is a note naming file, line and column
    std::fs::write(p.join("plan.csv"), "q1,nom_x,nom_y,nom_z\n0,1,x,3\n").unwrap();
    let r = build_report(p, &ReportOptions::default()).unwrap();
    assert!(
        r.notes
            .iter()
            .any(|n| n.contains("plan.csv") && n.contains("nom_y")),
        "{:?}",
        r.notes
    );
}

/// The demo's first screen (`bash scripts/demo.sh`, steps 2-4 and 6: simulate with an undeclared
/// encoder harmonic, seed 7, calibrate standard and tilting, diagnose, report): the held-out
/// error at each stage and the effect found with its values, as the page shows them.
#[test]
fn demo_first_screen_names_the_harmonic() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let p = |n: &str| d.join(n).to_string_lossy().into_owned();
    let run = |args: &[String]| {
        let o = output(args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    let args = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let (cal, val) = (p("cal.csv"), p("val.csv"));
    run(&args(&[
        "simulate",
        "--out",
        &p(""),
        "--seed",
        "7",
        "--noise-mm",
        "0.01",
        "--effect",
        "encoder_harmonic:j2:h1=0.03,40",
    ]));
    run(&args(&[
        "calibrate",
        "--poses",
        &cal,
        "--validate",
        &val,
        "--method",
        "standard",
        "--json",
        &p("calibrate_standard.json"),
    ]));
    run(&args(&[
        "calibrate",
        "--poses",
        &cal,
        "--validate",
        &val,
        "--json",
        &p("calibrate.json"),
        "--out",
        &p("calibrated.toml"),
    ]));
    run(&args(&[
        "diagnose",
        "--poses",
        &cal,
        "--validate",
        &val,
        "--json",
        &p("diagnose.json"),
        "--out",
        &p("extended.toml"),
    ]));
    let r = build_report(d, &ReportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let h = &r.summary.headlines[0];
    assert!(h.held_out, "{h:?}");
    let (first, last) = (&h.stages[0], h.stages.last().unwrap());
    assert_eq!(first.label, "nominal model");
    assert_eq!(last.label, "with the 1 effect found");
    let e = &r.summary.diagnoses[0].effects[0];
    assert_eq!(e.id, "encoder_harmonic:j2:h1");
    let value = |k: &str| {
        e.values
            .iter()
            .find(|v| v.0 == k)
            .map(|v| (v.1, v.2.unwrap()))
            .unwrap()
    };
    let ((a, sa), (phi, sphi)) = (value("A"), value("phi"));
    assert!((a - 0.03).abs() < 3.0 * sa && (phi - 40.0).abs() < 3.0 * sphi);
    let html = render_html(&r);
    let screen = &html[..html.find("<table").expect("detail tables")];
    let fmt = rigctl::plot::summary::fmt_mm;
    for v in [first.mean_mm, first.rms_mm, last.mean_mm, last.rms_mm] {
        assert!(screen.contains(&fmt(v)), "first screen lacks {}", fmt(v));
    }
    record("demo_held_out", h.n);
    record("demo_nominal_mean_mm", first.mean_mm);
    record("demo_nominal_rms_mm", first.rms_mm);
    record("demo_final_mean_mm", last.mean_mm);
    record("demo_final_rms_mm", last.rms_mm);
    record("demo_a_deg", a);
    record("demo_a_sigma_deg", sa);
    record("demo_phi_deg", phi);
    record("demo_phi_sigma_deg", sphi);
}
