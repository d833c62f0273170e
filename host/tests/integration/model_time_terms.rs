//! The time terms of a model (`[time]`: thermal growth, drifts) end to end: the simulator's
//! truth file reproduces its noise-free measurements through `fk` at each row's `t`; `diagnose
//! --out` writes the warm-up it finds and `fk` with that file predicts the held-out poses to
//! the noise; `compensate` through the growth returns joints whose `fk` at the same `t` is the
//! path; a model file reads back identical; absurd values are refused with the file's line.

use std::path::Path;

use rigctl::model::time_terms::TimeTerms;
use rigctl::model::{katana450, Model};

use super::common::spawn::output;

fn ok(args: &[&str]) -> String {
    let out = output(args);
    assert!(
        out.status.success(),
        "rigctl {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8")
}

/// Columns `names` of every row of a CSV text.
fn columns(text: &str, names: &[&str]) -> Vec<Vec<f64>> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let idx: Vec<usize> = names
        .iter()
        .map(|n| header.iter().position(|h| h == n).expect("column"))
        .collect();
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            idx.iter().map(|&i| f[i].parse().expect("number")).collect()
        })
        .collect()
}

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn truth_file_reproduces_noise_free_measurements_at_each_t() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("sim");
    ok(&[
        "simulate",
        "--out",
        path(&d),
        "--seed",
        "4",
        "--noise-mm",
        "0",
        "--pose-interval-s",
        "30",
        "--effect",
        "thermal=400,15",
        "--effect",
        "time_drift=0.02,0,-0.03",
        "--effect",
        "time_drift:j2=0.01",
    ]);
    let truth = std::fs::read_to_string(d.join("truth.toml")).unwrap();
    assert!(truth.contains("[time]"), "{truth}");
    for file in ["cal.csv", "val.csv"] {
        let poses = std::fs::read_to_string(d.join(file)).unwrap();
        let measured = columns(&poses, &["x", "y", "z"]);
        let fk = ok(&[
            "fk",
            "--model",
            path(&d.join("truth.toml")),
            "--joints",
            path(&d.join(file)),
            "--tilt",
        ]);
        let predicted = columns(&fk, &["x", "y", "z"]);
        let worst = measured
            .iter()
            .zip(&predicted)
            .flat_map(|(m, p)| m.iter().zip(p).map(|(a, b)| (a - b).abs()))
            .fold(0.0, f64::max);
        // the files have 9 decimals
        assert!(worst < 1e-6, "{file}: worst {worst} mm");
    }
}

#[test]
fn diagnose_out_writes_the_warm_up_and_fk_predicts_held_out_poses() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("sim");
    ok(&[
        "simulate",
        "--out",
        path(&d),
        "--seed",
        "8",
        "--noise-mm",
        "0.01",
        "--pose-interval-s",
        "20",
        "--effect",
        "thermal=250,20",
    ]);
    let model_out = dir.path().join("extended.toml");
    let cal = d.join("cal.csv");
    let val = d.join("val.csv");
    ok(&[
        "diagnose",
        "--poses",
        path(&cal),
        "--validate",
        path(&val),
        "--instrument-mm",
        "0.01",
        "--out",
        path(&model_out),
    ]);
    let m = Model::from_file(&model_out).unwrap();
    let t = m.time_terms();
    assert!(
        (t.thermal_ppm - 250.0).abs() < 40.0 && (t.thermal_tau_min - 20.0).abs() < 6.0,
        "{t:?}"
    );
    let fk = ok(&[
        "fk",
        "--model",
        path(&model_out),
        "--joints",
        path(&val),
        "--tilt",
    ]);
    let measured = columns(&std::fs::read_to_string(&val).unwrap(), &["x", "y", "z"]);
    let predicted = columns(&fk, &["x", "y", "z"]);
    let mean = measured
        .iter()
        .zip(&predicted)
        .map(|(m, p)| {
            ((m[0] - p[0]).powi(2) + (m[1] - p[1]).powi(2) + (m[2] - p[2]).powi(2)).sqrt()
        })
        .sum::<f64>()
        / measured.len() as f64;
    // the mean length of 3-D noise of 0.01 mm per coordinate is 0.016 mm
    assert!(mean < 1.25 * 0.016, "held-out mean {mean} mm");
}

#[test]
fn compensate_through_the_warm_up_lands_on_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let mut model = katana450(200.0).unwrap();
    model.set_time_terms(TimeTerms {
        thermal_ppm: 500.0,
        thermal_tau_min: 10.0,
        drift_mm_per_h: nalgebra::Vector3::new(0.0, 0.05, 0.0),
        joint_drift_deg_per_h: vec![0.0, 0.02, 0.0, 0.0, 0.0],
        ..TimeTerms::default()
    });
    let model_file = dir.path().join("warm.toml");
    model.write_file(&model_file).unwrap();
    let mut csv = String::from("t,x,y,z\n");
    for k in 0..21 {
        let _ = std::fmt::Write::write_fmt(
            &mut csv,
            format_args!("{},{},{},150\n", k * 120, 300 + 5 * k, -100 + 5 * k),
        );
    }
    let path_file = dir.path().join("path.csv");
    std::fs::write(&path_file, &csv).unwrap();
    let joints = dir.path().join("joints.csv");
    ok(&[
        "compensate",
        "--model",
        path(&model_file),
        "--no-tilt",
        "--no-nominal",
        "--path",
        path(&path_file),
        "--out",
        path(&joints),
    ]);
    let fk = ok(&[
        "fk",
        "--model",
        path(&model_file),
        "--joints",
        path(&joints),
    ]);
    let want = columns(&csv, &["x", "y", "z"]);
    let got = columns(&fk, &["x", "y", "z"]);
    let worst = want
        .iter()
        .zip(&got)
        .flat_map(|(w, g)| w.iter().zip(g).map(|(a, b)| (a - b).abs()))
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "worst {worst} mm");
    // the same joints without the time terms miss the path by the growth (0.5 mm at 1 m)
    let rigid = dir.path().join("rigid.toml");
    katana450(200.0).unwrap().write_file(&rigid).unwrap();
    let fk0 = ok(&["fk", "--model", path(&rigid), "--joints", path(&joints)]);
    let miss = columns(&fk0, &["x"])
        .iter()
        .zip(&want)
        .map(|(g, w)| (g[0] - w[0]).abs())
        .fold(0.0, f64::max);
    assert!(miss > 1e-3, "the time terms changed nothing: {miss}");
}

#[test]
fn time_terms_read_back_identical_and_absurd_values_are_refused() {
    let mut model = katana450(200.0).unwrap();
    model.set_time_terms(TimeTerms {
        thermal_ppm: 123.456,
        thermal_tau_min: 17.5,
        drift_mm_per_h: nalgebra::Vector3::new(0.1, -0.2, 0.3),
        joint_drift_deg_per_h: vec![0.0, 0.01, -0.02, 0.0, 0.005],
        // changes within the session read back as `[[change]]` rows
        changes: vec![
            rigctl::model::changes::Step {
                t_s: 600.5,
                kind: rigctl::model::changes::StepKind::Tool(nalgebra::Vector3::new(
                    0.1, -0.05, 0.02,
                )),
            },
            rigctl::model::changes::Step {
                t_s: 1200.0,
                kind: rigctl::model::changes::StepKind::Payload(0.25),
            },
        ],
    });
    let text = model.to_toml_string();
    let back = Model::from_toml_str(&text, "m.toml").unwrap();
    assert_eq!(back, model);
    for (bad, what) in [
        ("thermal_tau_min = 17.5", "thermal_tau_min = 0"),
        ("thermal_tau_min = 17.5", "thermal_tau_min = -3"),
        ("thermal_ppm = 123.456", "thermal_ppm = 1e300"),
    ] {
        let text = text.replace(bad, what);
        let e = Model::from_toml_str(&text, "m.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("m.toml:"), "{what}: {e}");
    }
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("bad.toml");
    std::fs::write(
        &file,
        text.replace("thermal_tau_min = 17.5", "thermal_tau_min = 0"),
    )
    .unwrap();
    let q = dir.path().join("q.csv");
    std::fs::write(&q, "q1,q2,q3,q4,q5\n0,90,-90,0,0\n").unwrap();
    let out = output(&["fk", "--model", path(&file), "--joints", path(&q)]);
    assert_eq!(out.status.code(), Some(2));
}
