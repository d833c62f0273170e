//! Captions true to their plots: for every figure of a report whose caption makes a claim about
//! the data ("stays near zero", "at most X mm", "no trend remains", "each stage lowers it"),
//! the claim is checked here against the values the chart draws (`Figure::series`), computed
//! again independently (maximum, median tail, Pearson r). The demo's run (a simulated Katana
//! with an undeclared harmonic) has the known case: the path planned with the calibrated
//! model's rigid IK stays 1.2-1.45 mm off (the robot's tilting), which a caption once called
//! "near zero".

use rigctl::plot::summary::fmt_mm;
use rigctl::report::{build_report, Figure, ReportOptions};

use crate::common::spawn::output;

fn series<'a>(f: &'a Figure, name: &str) -> &'a [f64] {
    f.series
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| v.as_slice())
        .unwrap_or_else(|| panic!("{:?}: no series {name}", f.caption))
}

fn max(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
}

fn min(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::INFINITY, f64::min)
}

/// The text between `start` and the next `end` in `s`.
fn between<'a>(s: &'a str, start: &str, end: &str) -> Option<&'a str> {
    let from = s.find(start)? + start.len();
    let to = from + s[from..].find(end)?;
    Some(&s[from..to])
}

fn pearson(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let syy: f64 = y.iter().map(|b| (b - my).powi(2)).sum();
    sxy / (sxx * syy).sqrt()
}

/// Checks every claim of `f`'s caption against its series; returns how many were checked.
fn check(f: &Figure) -> usize {
    let c = f.caption.as_str();
    let mut checked = 0;
    let near = |b: &[f64], a: &[f64]| max(a) <= 0.1 * max(b);
    if let Some(rest) = between(c, "stays near zero, at most ", " mm") {
        let (b, a) = (series(f, "before"), series(f, "after"));
        assert!(near(b, a), "{c}: after up to {} mm", max(a));
        assert_eq!(rest, fmt_mm(max(a)), "{c}");
        checked += 1;
    }
    if let Some(range) = between(c, "lies between ", " mm, not near zero") {
        let (b, a) = (series(f, "before"), series(f, "after"));
        assert!(!near(b, a), "{c}");
        assert_eq!(
            range,
            format!("{} and {}", fmt_mm(min(a)), fmt_mm(max(a))),
            "{c}"
        );
        checked += 1;
    }
    if let Some(x) = between(c, "the red bars (after) are short: at most ", " mm") {
        let (b, a) = (series(f, "before"), series(f, "after"));
        assert!(near(b, a), "{c}");
        assert_eq!(x, fmt_mm(max(a)), "{c}");
        checked += 1;
    }
    if let Some(x) = between(c, "the red bars (after) reach ", " mm") {
        let (b, a) = (series(f, "before"), series(f, "after"));
        assert!(!near(b, a), "{c}");
        assert_eq!(x, fmt_mm(max(a)), "{c}");
        checked += 1;
    }
    if let Some(x) = between(c, "the errors reach ", " mm at most") {
        let a = series(f, "after");
        assert_eq!(x, fmt_mm(max(a)), "{c}");
        let mut sorted = a.to_vec();
        sorted.sort_by(f64::total_cmp);
        let median = sorted[sorted.len() / 2];
        let tail = a.iter().filter(|v| **v > 3.0 * median).count();
        let said = if c.contains("no pose after is over 3 x their median") {
            0
        } else {
            between(c, "); ", " pose")
                .and_then(|k| k.parse().ok())
                .unwrap_or_else(|| panic!("{c}: tail count"))
        };
        assert_eq!(said, tail, "{c}");
        checked += 1;
    }
    if let Some(r) = between(c, "after calibration r = ", " with q") {
        let r_said: f64 = r.parse().unwrap();
        let r_data = pearson(series(f, "x"), series(f, "after"));
        assert_eq!(r, format!("{r_data:.2}"), "{c}");
        assert_eq!(c.contains("no trend remains"), r_said.abs() < 0.3, "{c}");
        checked += 1;
    }
    if c.contains("each stage lowers it") || c.contains("not every stage lowers it") {
        let m = series(f, "mean");
        let lowers = m.windows(2).all(|w| w[1] <= w[0]);
        assert_eq!(c.contains("each stage lowers it"), lowers, "{c}: {m:?}");
        checked += 1;
    }
    if let Some(x) = between(c, "the last stage's RMS is ", " x it") {
        let rms = series(f, "rms");
        let floor = series(f, "floor");
        assert_eq!(x, format!("{:.1}", rms[rms.len() - 1] / floor[0]), "{c}");
        checked += 1;
    }
    checked
}

fn run_ok(args: &[&str]) {
    let o = output(args);
    assert!(
        o.status.success() || o.status.code() == Some(1),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn every_caption_claim_matches_its_plotted_data() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let p = |n: &str| d.join(n).to_string_lossy().into_owned();
    let (cal, val) = (p("cal.csv"), p("val.csv"));
    run_ok(&[
        "simulate",
        "--out",
        &p(""),
        "--seed",
        "7",
        "--effect",
        "encoder_harmonic:j2:h1=0.03,40",
    ]);
    run_ok(&[
        "calibrate",
        "--poses",
        &cal,
        "--validate",
        &val,
        "--json",
        &p("calibrate.json"),
        "--out",
        &p("calibrated.toml"),
    ]);
    run_ok(&[
        "diagnose",
        "--poses",
        &cal,
        "--validate",
        &val,
        "--json",
        &p("diagnose.json"),
        "--out",
        &p("extended.toml"),
    ]);
    let r = build_report(d, &ReportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let figures: Vec<&Figure> = r.summary.figure.iter().chain(&r.figures).collect();
    let mut claims = 0;
    for f in &figures {
        let n = check(f);
        assert!(
            f.series.is_empty() || n > 0,
            "a figure with data and no checked claim: {}",
            f.caption
        );
        claims += n;
        for prescription in ["should stay near zero", "should be short", "should remain"] {
            assert!(!f.caption.contains(prescription), "{}", f.caption);
        }
    }
    // stage chart (2), two pose sets x (bars, histogram, scatter), the path error
    assert!(claims >= 8, "{claims} claims checked");
    // the known case: the calibrated plan's path error is not near zero, and says so
    let path = figures
        .iter()
        .find(|f| f.caption.starts_with("Position error along"))
        .expect("path error figure (truth.toml and a model file)");
    assert!(path.caption.contains("not near zero"), "{}", path.caption);
}
