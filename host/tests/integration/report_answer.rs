//! The report's first screen for any robot: the one sentence, the registration-only "before"
//! (`calibrate --base` writes `registered`: the input model with only the instrument frame
//! fitted), the unregistered figure apart, the logarithmic stage chart (the small numbers
//! visible), the verdict in one line with its statistics folded, "N of M parameters
//! identified" with the list folded, and the held-out error through the exported URDF beside
//! the extended model's.

use rigctl::model::{katana450, Model, Tilt};
use rigctl::report::{build_report, render_html, ReportOptions};

use crate::common::poses::write_exact_poses;
use crate::common::spawn::output;

fn stats(n: usize, mean: f64, rms: f64) -> serde_json::Value {
    serde_json::json!({"n": n, "mean_mm": mean, "rms_mm": rms, "max_mm": 3.0 * mean,
        "min_mm": 0.1 * mean, "mean_abs_x_mm": 0.5 * mean, "mean_abs_y_mm": 0.5 * mean,
        "mean_abs_z_mm": 0.4 * mean})
}

/// An own robot's run, as `calibrate --base` and `diagnose` write it: unregistered 71.8 mm,
/// registered 2.06 mm, geometry 0.147 mm, with a compliance found 0.036 mm (issue 50's Panda).
fn own_robot_run(dir: &std::path::Path) {
    let calibrate = serde_json::json!({
        "method": "standard",
        "calibration": {"before": stats(150, 70.2, 74.0), "after": stats(150, 0.140, 0.160)},
        "validation": {"before": stats(60, 71.8, 75.5), "after": stats(60, 0.147, 0.171)},
        "registered": {"calibration": stats(150, 2.01, 2.30), "validation": stats(60, 2.06, 2.35)},
        "standard": {"calibration": stats(150, 0.140, 0.160), "validation": stats(60, 0.147, 0.171)},
        "parameters": {"base_x": 1.0, "base_y": 2.0, "dth1": 0.1, "dth2": 0.2, "d1": 333.1,
                       "a3": 82.4, "d5": 384.0},
        "sigma": {"base_x": 0.01, "base_y": 0.01, "dth1": 0.001, "dth2": 0.001, "d1": null,
                  "a3": 0.02, "d5": null},
        "fixed": ["d1", "d5"],
        "unidentifiable": ["base_z+d1", "d3+d5"],
        "condition_number": 120.0,
        "tilting_applied": false,
    });
    let diagnose = serde_json::json!({
        "declared": {"calibration": stats(150, 0.140, 0.160), "validation": stats(60, 0.147, 0.171)},
        "final": {"calibration": stats(150, 0.034, 0.040), "validation": stats(60, 0.036, 0.043)},
        "effects": [{"id": "compliance:j2", "parameters": {"c": 0.21}, "sigma": {"c": 0.004},
                     "validation_mean_mm_before": 0.147, "validation_mean_mm_after": 0.036,
                     "p_value": 1e-30, "delta_bic": -310.2, "evidence": "F = 400"}],
        "unexplained": {"structured": false, "note": "", "depends_on": [], "explainable_share": 0.02},
        "floor": {"instrument_mm": 0.02, "repeatability_mm": null, "residual_mm": 0.023,
                  "used": "instrument", "final_over_floor": 1.12},
        "verdict": {"kind": "floor", "note": "at the floor: calibration residual 0.023 mm per coordinate = 1.12 x the instrument floor (p = 0.21)"},
        "aliased": [{"a": "compliance:j2", "b": "dth2", "correlation": 0.93, "note": "the poses barely load joint 2"}],
        "robot": "katana450"
    });
    std::fs::write(dir.join("calibrate.json"), calibrate.to_string()).unwrap();
    std::fs::write(dir.join("diagnose.json"), diagnose.to_string()).unwrap();
    for m in ["calibrated.toml", "extended.toml"] {
        std::fs::write(dir.join(m), "not read by the first screen").unwrap();
    }
}

/// The text between `<section id="answer"` and its end: the first screen.
fn first_screen(html: &str) -> &str {
    let start = html.find("<section id=\"answer\"").expect("answer section");
    let end = start + html[start..].find("</section>").expect("end of the answer");
    &html[start..end]
}

/// The widths (px) of the bars of one fill colour in an inline SVG: the rectangles that start
/// where most of them start (the axis; the legend's swatch is elsewhere).
fn bar_widths(svg: &str, fill: &str) -> Vec<f64> {
    let attr = |r: &str, k: &str| -> Option<f64> {
        r.split(&format!(" {k}=\""))
            .nth(1)?
            .split('"')
            .next()?
            .parse()
            .ok()
    };
    let rects: Vec<(f64, f64)> = svg
        .split("<rect")
        .skip(1)
        .filter(|r| r.contains(&format!("fill=\"{fill}\"")))
        .filter_map(|r| Some((attr(r, "x")?, attr(r, "width")?)))
        .collect();
    let count = |x: f64| rects.iter().filter(|r| r.0 == x).count();
    let Some(axis) = rects.iter().map(|r| r.0).max_by_key(|x| count(*x)) else {
        return Vec::new();
    };
    rects.iter().filter(|r| r.0 == axis).map(|r| r.1).collect()
}

#[test]
fn own_robot_first_screen_has_the_answer_first() {
    let dir = tempfile::tempdir().unwrap();
    own_robot_run(dir.path());
    let r = build_report(dir.path(), &ReportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let s = &r.summary;
    // the one sentence: now, what was wrong, what to do
    assert!(
        s.sentence
            .starts_with("0.0360 mm mean error on 60 held-out poses now with the 1 effect found (was 2.060 mm with the input model with only the instrument frame fitted)"),
        "{}",
        s.sentence
    );
    assert!(
        s.sentence.contains("lacked compliance:j2"),
        "{}",
        s.sentence
    );
    assert!(
        s.sentence
            .ends_with("use extended.toml: nothing is left to find in these data."),
        "{}",
        s.sentence
    );
    // before = registered, the unregistered figure apart (not a stage, not in the chart)
    let h = &s.headlines[0];
    assert_eq!(h.stages[0].mean_mm, 2.06);
    assert_eq!(h.unregistered.as_ref().map(|u| u.mean_mm), Some(71.8));
    assert!(h.stages.iter().all(|st| st.mean_mm != 71.8));
    // N of M identified
    let i = &s.identified[0];
    assert_eq!((i.identified, i.total), (5, 7));
    // URDF beside the extended model
    let u = s.urdf.as_ref().expect("URDF line");
    assert_eq!((u.urdf.mean_mm, u.model.mean_mm), (0.147, 0.036));
    assert_eq!(u.lacks, vec!["compliance:j2".to_string()]);

    let html = render_html(&r);
    let screen = first_screen(&html);
    for want in [
        "<p class=\"sentence\">0.0360 mm mean error on 60 held-out poses now",
        "Apart: the input model as it is (instrument frame not fitted) gives 71.800 mm",
        "Through the exported URDF",
        "<b>0.147 mm</b>",
        "<b>0.0360 mm</b>",
        "A URDF cannot hold <code>compliance:j2</code>",
        "<summary><b>5 of 7 parameters identified</b>",
        "held-out error (mm, logarithmic)",
    ] {
        assert!(
            screen.contains(want),
            "first screen lacks {want:?}:\n{screen}"
        );
    }
    assert!(
        !screen.contains("71.800 mm (RMS 75.500) with"),
        "unregistered is not the before"
    );
    // the verdict in one line; its statistics, the evidence and the aliased pair folded
    let verdict = screen
        .split("<p class=\"verdict\">")
        .nth(1)
        .and_then(|v| v.split("</p>").next())
        .expect("verdict line");
    assert!(verdict.contains("At the instrument floor."), "{verdict}");
    assert!(
        !verdict.contains("p ="),
        "statistics belong in the fold: {verdict}"
    );
    let folded = |what: &str| {
        let at = screen
            .find(what)
            .unwrap_or_else(|| panic!("{what} missing"));
        let open = screen[..at].rfind("<details").unwrap_or(0);
        let close = screen[..at].rfind("</details>").unwrap_or(0);
        open > close && open > 0
    };
    assert!(folded("F-test p &lt; 1e-16"));
    assert!(folded("Aliased: <code>compliance:j2</code>"));
    assert!(folded(
        "Kept at their input values: <code>d1</code>, <code>d5</code>"
    ));
    assert!(folded("<code>base_z+d1</code>"));
    // the chart shows the small numbers: on a logarithmic axis the 0.036 mm bar is not lost
    // beside the 2.06 mm one (linear: 1.7 % of it)
    let fig = s.figure.as_ref().expect("stage chart");
    let widths = bar_widths(&fig.svg, "#1F77B4");
    assert_eq!(widths.len(), h.stages.len(), "{widths:?}");
    let (lo, hi) = widths
        .iter()
        .fold((f64::MAX, 0f64), |(a, b), w| (a.min(*w), b.max(*w)));
    assert!(lo > 0.15 * hi, "bars {widths:?}");
}

/// `calibrate --base` on synthetic Katana poses whose instrument frame is offset and turned:
/// with only the frame wrong the registration-only "before" is the truth (zero error), with
/// geometric errors too it lies between the calibrated and the unregistered figures.
#[test]
fn calibrate_writes_the_registration_only_figure() {
    let frame = [
        ("base_x", 40.0),
        ("base_y", -25.0),
        ("base_z", 12.0),
        ("base_rx", 1.5),
    ];
    let run = |geometry: &[(&str, f64)]| {
        let dir = tempfile::tempdir().unwrap();
        let mut truth = katana450(200.0).unwrap();
        // offsets from the declared values
        for (k, v) in frame.iter().chain(geometry) {
            let declared = truth.param(k).unwrap();
            truth.set_param(k, declared + *v).unwrap();
        }
        let (cal, val) = (dir.path().join("cal.csv"), dir.path().join("val.csv"));
        write_poses(&truth, &cal, 80, 1);
        write_poses(&truth, &val, 20, 2);
        let json = dir.path().join("calibrate.json");
        let o = output(&[
            "calibrate".as_ref(),
            "--base".as_ref(),
            "--method".as_ref(),
            "standard".as_ref(),
            "--poses".as_ref(),
            cal.as_os_str(),
            "--validate".as_ref(),
            val.as_os_str(),
            "--json".as_ref(),
            json.as_os_str(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let d: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        let mean = |v: &serde_json::Value| v["mean_mm"].as_f64().unwrap();
        (
            mean(&d["validation"]["before"]),
            mean(&d["registered"]["validation"]),
            mean(&d["validation"]["after"]),
        )
    };
    let (unregistered, registered, _) = run(&[]);
    assert!(unregistered > 10.0, "{unregistered}");
    assert!(registered < 1e-3, "frame only: registered {registered}");
    let (unregistered, registered, after) = run(&[("dth2", 0.3), ("al3", 0.2)]);
    assert!(
        after < 0.1 * registered && registered < 0.1 * unregistered,
        "after {after}, registered {registered}, unregistered {unregistered}"
    );
}

/// Exact poses of `truth` (rigid: the standard method's model) at random joint values.
fn write_poses(truth: &Model, path: &std::path::Path, n: usize, seed: u64) {
    write_exact_poses(truth, Tilt::Off, path, n, seed, "");
}
