//! `rigctl poses` on a simulated session from an independent generator
//! (`host/tests/py/capture_session.py`: quintic joint moves between 30 poses with dwells, a
//! 100 Hz controller CSV, the same log as a ROS 2 bag written with rosbags, a 120 Hz instrument
//! log with a clock offset of -12.3456 s, 0.02 mm noise, settling oscillations after each stop,
//! 1 % gross outliers and 0.5 % missing samples, as a generic CSV and as a Vicon Nexus export
//! in a German locale). The true points are `rigctl fk` of the true joints on a robot whose
//! dth2, dth3 and al3 are off; `poses` must find every standstill, the points within the
//! instrument's noise of the truth and the offset within one instrument sample; the written
//! pose file then calibrates back to the robot's errors.

use crate::common;
use crate::common::record::record;
use crate::common::spawn::{output, text};

use std::path::Path;
use std::process::{Command, Output};

const KATANA_NAMES: &str = "katana_motor1_pan_joint,katana_motor2_lift_joint,katana_motor3_lift_joint,katana_motor4_lift_joint,katana_motor5_wrist_roll_joint";
/// The robot's errors the instrument sees (deg).
const TRUE_ERRORS: [(&str, f64); 3] = [("dth2", 0.05), ("dth3", -0.03), ("al3", 0.04)];

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn py(python: &Path, args: &[&str]) {
    let out = Command::new(python)
        .args(args)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn rig(args: &[&str]) -> Output {
    let out = output(args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "rigctl {}: {}\n{}",
        args.join(" "),
        text(&out.stdout),
        text(&out.stderr)
    );
    out
}

/// Numeric rows of a CSV with a header (comment lines skipped), by column name.
fn table(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let t = std::fs::read_to_string(path).unwrap();
    let mut lines = t
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    (head, rows)
}

fn col(head: &[String], name: &str) -> usize {
    head.iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name}"))
}

/// The clock offset a pose file's comment states.
fn stated_offset(path: &Path) -> f64 {
    let t = std::fs::read_to_string(path).unwrap();
    let l = t
        .lines()
        .find(|l| l.starts_with("# clock offset "))
        .expect("offset comment");
    l["# clock offset ".len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

/// Checks a written pose file against the generator's truth; returns the largest point error.
fn check_poses(dir: &Path, poses: &Path, true_offset: f64, what: &str) -> f64 {
    let session: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("session.json")).unwrap()).unwrap();
    let n = session["n"].as_u64().unwrap() as usize;
    let noise = session["noise_mm"].as_f64().unwrap();
    let period = 1.0 / session["inst_hz"].as_f64().unwrap();
    let (th, tq) = table(&dir.join("truth_joints.csv"));
    let (_, tp) = table(&dir.join("truth_points.csv"));
    let (h, rows) = table(poses);
    assert_eq!(rows.len(), n, "{what}: every standstill is a pose");
    let offset = stated_offset(poses);
    eprintln!("{what}: offset {offset:.5} s, true {true_offset:.5} s");
    assert!(
        (offset - true_offset).abs() < period,
        "{what}: offset {offset} vs {true_offset} (period {period})"
    );
    let (mut worst, mut ss, mut n_min) = (0.0f64, 0.0, usize::MAX);
    let mut spreads = Vec::new();
    for (k, r) in rows.iter().enumerate() {
        let t = r[col(&h, "t")];
        let (a, b) = (tq[k][col(&th, "start")], tq[k][col(&th, "end")]);
        assert!(
            a < t && t < b,
            "{what}: pose {k} at {t} s outside its dwell {a}..{b}"
        );
        for j in 1..=5 {
            let name = format!("q{j}");
            let d = (r[col(&h, &name)] - tq[k][col(&th, &name)]).abs();
            assert!(d <= 6e-4, "{what}: pose {k} {name} off by {d} deg");
        }
        let e = (0..3)
            .map(|c| (r[col(&h, ["x", "y", "z"][c])] - tp[k][1 + c]).powi(2))
            .sum::<f64>()
            .sqrt();
        worst = worst.max(e);
        ss += e * e;
        n_min = n_min.min(r[col(&h, "n_samples")] as usize);
        spreads.push(r[col(&h, "spread_mm")]);
    }
    let rms = (ss / n as f64).sqrt();
    spreads.sort_by(f64::total_cmp);
    let repeat = spreads[n / 2];
    eprintln!("{what}: point error max {worst:.4} rms {rms:.4} mm, fewest samples {n_min}, repeatability {repeat:.4} mm");
    assert!(
        worst < noise,
        "{what}: a point {worst} mm from the truth (noise {noise})"
    );
    assert!(
        rms < 3.0 * noise * (3.0 / n_min as f64).sqrt(),
        "{what}: rms {rms} mm over {n_min} samples of {noise} mm noise"
    );
    assert!(
        (0.8 * noise..1.2 * noise).contains(&repeat),
        "{what}: repeatability {repeat} vs noise {noise}"
    );
    worst
}

#[test]
fn poses_from_a_bag_and_a_csv_joint_log_recover_the_session() {
    let Some(python) =
        common::python_env("poses_from_a_bag_and_a_csv_joint_log_recover_the_session")
    else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let gen = common::py_script("capture_session.py");
    let limits = "-160:160,-25:95,-115:115,-105:105,-160:160";
    py(
        &python,
        &[
            s(&gen),
            "joints",
            s(d),
            "--n",
            "30",
            "--seed",
            "7",
            "--limits",
            limits,
        ],
    );
    let mut fk = vec![
        "fk".to_string(),
        "--joints".into(),
        s(&d.join("fk_in.csv")).into(),
    ];
    for (name, v) in TRUE_ERRORS {
        fk.push("--set".into());
        fk.push(format!("{name}={v}"));
    }
    let truth = rig(&fk.iter().map(String::as_str).collect::<Vec<_>>());
    std::fs::write(d.join("fk_out.csv"), &truth.stdout).unwrap();
    py(
        &python,
        &[s(&gen), "instrument", s(d), s(&d.join("fk_out.csv"))],
    );
    let bag = d.join("session_bag");
    py(
        &python,
        &[
            s(&common::py_script("write_bag.py")),
            "csv",
            s(&d.join("joints.csv")),
            s(&bag),
            "--names",
            KATANA_NAMES,
            "--extra",
            "katana_r_finger_joint",
        ],
    );
    let session: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("session.json")).unwrap()).unwrap();
    let offset = session["offset_s"].as_f64().unwrap();
    let vicon_offset = session["vicon_offset_s"].as_f64().unwrap();

    // the bag with the generic tracker CSV
    let from_bag = d.join("poses_bag.csv");
    let out = rig(&[
        "poses",
        "--joints",
        s(&bag),
        "--joint-names",
        KATANA_NAMES,
        "--points",
        s(&d.join("points.csv")),
        "--out",
        s(&from_bag),
    ]);
    let report = text(&out.stdout);
    eprintln!("{report}");
    let missing = session["missing"].as_u64().unwrap();
    assert!(report.contains(&format!("{missing} missing")), "{report}");
    assert!(report.contains("standstills 30, poses 30"), "{report}");
    let w_bag = check_poses(d, &from_bag, offset, "bag + generic CSV");

    // the controller CSV with the Vicon export (`;`, decimal commas: recognised)
    let from_csv = d.join("poses_csv.csv");
    rig(&[
        "poses",
        "--joints",
        s(&d.join("joints.csv")),
        "--points",
        s(&d.join("points_vicon.csv")),
        "--out",
        s(&from_csv),
    ]);
    let w_csv = check_poses(d, &from_csv, vicon_offset, "CSV + Vicon");
    record("poses_point_error_max_mm", w_bag.max(w_csv));
    record(
        "poses_offset_error_s",
        (stated_offset(&from_bag) - offset).abs(),
    );

    // the written poses calibrate back to the robot's errors
    let json = d.join("cal.json");
    rig(&[
        "calibrate",
        "--poses",
        s(&from_bag),
        "--method",
        "standard",
        "--json",
        s(&json),
    ]);
    let cal: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let after = cal["calibration"]["after"]["mean_mm"].as_f64().unwrap();
    let before = cal["calibration"]["before"]["mean_mm"].as_f64().unwrap();
    eprintln!("calibrate: mean error {before:.4} -> {after:.4} mm");
    assert!(before > 0.1 && after < 0.01, "{before} -> {after}");
    for (name, v) in TRUE_ERRORS {
        let got = cal["parameters"][name].as_f64().unwrap();
        assert!((got - v).abs() < 0.003, "{name} = {got}, true {v}");
    }
}

/// A standstill the instrument log does not cover is partial: the other poses are written,
/// the gap is named, exit 1.
#[test]
fn a_standstill_without_instrument_samples_is_partial() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // two dwells of 3 s joined by a 1 s move of joint 1; the instrument stops before the second
    let mut joints = String::from("t,q1,q2,q3,q4,q5\n");
    let mut points = String::from("t,x,y,z\n");
    for k in 0..=700 {
        let t = f64::from(k) * 0.01;
        let u = ((t - 3.0) / 1.0).clamp(0.0, 1.0);
        let q1 = 10.0 + 20.0 * (0.5 - 0.5 * (u * std::f64::consts::PI).cos());
        joints.push_str(&format!("{t:.2},{q1:.4},10,20,30,40\n"));
        if t < 3.9 {
            points.push_str(&format!("{t:.2},{:.4},{:.4},0\n", 5.0 * q1, 2.0 * q1));
        }
    }
    std::fs::write(d.join("j.csv"), joints).unwrap();
    std::fs::write(d.join("p.csv"), points).unwrap();
    let out = output(&[
        "poses",
        "--joints",
        s(&d.join("j.csv")),
        "--points",
        s(&d.join("p.csv")),
        "--out",
        s(&d.join("poses.csv")),
        "--offset-s",
        "0",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    assert!(
        err.contains("standstill 2") && err.contains("no instrument samples"),
        "{err}"
    );
    let (_, rows) = table(&d.join("poses.csv"));
    assert_eq!(rows.len(), 1, "the first pose is written");
}
