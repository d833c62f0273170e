//! Nothing confidently wrong, on real data. Measurements that cannot be of the model as given
//! are refused before any fit (exit 2, the file named, nothing written): the UR5 laser-tracker
//! set (mm, deg) with its points in metres or inches, its joints in radians declared as degrees;
//! the TIAGo motion-capture set (m, rad) read without `--units`. A calibration that moves the
//! robot's geometry further than a real arm's errors exits 1 and writes no model. The README's
//! UR5 example frees the tool point, not joint 6's offset, so the calibrated tool frame keeps its
//! orientation.
//!
//! Here: the refusals before any fit; in `written_models`: what a calibration writes.

mod written_models;

use std::path::{Path, PathBuf};

use crate::common;
use crate::common::spawn::{output, text};

/// A copy of the pose file `src` in `dir` with the point columns times `length` and the joint
/// columns times `angle`.
fn converted(src: &Path, dir: &Path, name: &str, length: f64, angle: f64) -> PathBuf {
    let body = std::fs::read_to_string(src).unwrap();
    let mut lines = body.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut out = header.join(",") + "\n";
    for line in lines {
        let cells: Vec<String> = line
            .split(',')
            .zip(&header)
            .map(|(c, h)| {
                let f = match *h {
                    "x" | "y" | "z" => length,
                    h if h.starts_with('q') => angle,
                    _ => return c.to_string(),
                };
                format!("{}", c.trim().parse::<f64>().unwrap() * f)
            })
            .collect();
        out += &(cells.join(",") + "\n");
    }
    let path = dir.join(name);
    std::fs::write(&path, out).unwrap();
    path
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The TIAGo motion-capture folder and the URDF's arm chain as a model file in `dir`
/// (`urdf2model`), or `None` when the shared data is absent.
fn tiago(test: &str, dir: &Path) -> Option<(PathBuf, PathBuf)> {
    let rel = "data/real/thanhndv212__figaroh-examples/examples/tiago";
    let urdf = common::shared_file(test, &format!("{rel}/urdf/tiago_48_schunk.urdf"))?;
    let root = urdf.parent()?.parent()?.to_path_buf();
    let model = dir.join("tiago.toml");
    let out = output(&[
        "urdf2model",
        "--urdf",
        s(&urdf),
        "--base-link",
        "base_footprint",
        "--tip",
        "wrist_ft_tool_link",
        "--limit-margin-pct",
        "1",
        "--out",
        s(&model),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    Some((root.join("data/calibration/mocap"), model))
}

/// The TIAGo model in `dir` and its training and held-out posture files (FIGAROH's protocol).
fn tiago_sets(test: &str, dir: &Path) -> Option<(PathBuf, PathBuf, PathBuf)> {
    let (mocap, model) = tiago(test, dir)?;
    Some((
        model,
        mocap.join("qualisys_2021-11-30_static_postures.csv"),
        mocap.join("qualisys_2021-11-26_static_postures.csv"),
    ))
}

/// `rigctl ARGS` exits 2 with a message naming `file` and containing each of `words`; neither
/// `--json` nor `--out` (in `dir`) is written.
fn refused(args: &[&str], dir: &Path, file: &Path, words: &[&str]) {
    let out = output(args);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(err.contains(s(file)), "{err}");
    for w in words {
        assert!(err.contains(w), "{w:?} not in: {err}");
    }
    for f in ["c.json", "c.toml"] {
        assert!(!dir.join(f).exists(), "{f} written");
    }
}

#[test]
fn ur5_points_in_metres_or_inches_and_joints_in_radians_are_refused() {
    let Some(grid) = common::shared_file("plausible_ur5", "data/real/ur5_laser_tracker/grid.csv")
    else {
        return;
    };
    let random = grid.with_file_name("random.csv");
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let json = d.join("c.json");
    let model = d.join("c.toml");
    let to_rad = std::f64::consts::PI / 180.0;
    for (tag, length, angle, words) in [
        (
            "m",
            1e-3,
            1.0,
            &[
                "0.0010 x the size",
                "metres read as millimetres",
                "--units m",
            ][..],
        ),
        ("in", 1.0 / 25.4, 1.0, &["0.0394 x the size", "inches"][..]),
        (
            "rad",
            1.0,
            to_rad,
            &["taken as radians", "--units mm,rad"][..],
        ),
    ] {
        let cal = converted(&grid, d, &format!("grid_{tag}.csv"), length, angle);
        let val = converted(&random, d, &format!("random_{tag}.csv"), length, angle);
        let base = [
            "--robot",
            "ur5",
            "--set",
            "tool_dy=0.07",
            "--set",
            "tool_dz=31",
            "--poses",
            s(&cal),
            "--validate",
            s(&val),
        ];
        let mut calibrate = vec!["calibrate"];
        calibrate.extend(base);
        calibrate.extend([
            "--base",
            "--method",
            "standard",
            "--json",
            s(&json),
            "--out",
            s(&model),
        ]);
        refused(&calibrate, d, &cal, words);
        let mut diagnose = vec!["diagnose"];
        diagnose.extend(base);
        diagnose.extend(["--instrument-mm", "0.015", "--json", s(&json)]);
        refused(&diagnose, d, &cal, words);
    }
}

#[test]
fn tiago_in_metres_and_radians_read_as_millimetres_and_degrees_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let Some((mocap, model)) = tiago("plausible_tiago", d) else {
        return;
    };
    let poses = mocap.join("qualisys_2021-11-30_static_postures.csv");
    let json = d.join("c.json");
    let args = [
        "calibrate",
        "--model",
        s(&model),
        "--poses",
        s(&poses),
        "--markers",
        "1",
        "--method",
        "standard",
        "--params",
        "@base,@tool,@offsets",
        "--json",
        s(&json),
    ];
    // no --units: the metres are read as millimetres, the radians as degrees
    let out = output(&args);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(s(&poses)) && err.contains("--units m,rad"),
        "{err}"
    );
    assert!(!json.exists());
    // the same file with its units passes the check
    let mut right = args.to_vec();
    right.extend(["--units", "m,rad"]);
    let out = output(&right);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

fn ur5_files(test: &str) -> Option<(PathBuf, PathBuf)> {
    let grid = common::shared_file(test, "data/real/ur5_laser_tracker/grid.csv")?;
    let random = grid.with_file_name("random.csv");
    Some((grid, random))
}

/// A renamed copy of the calibration file given as held-out data: the held-out numbers would be
/// the calibration numbers, so `calibrate` and `diagnose` refuse it (exit 2, both lines named)
/// and write nothing.
#[test]
fn held_out_poses_that_repeat_the_calibration_poses_are_refused() {
    let Some((grid, _)) = ur5_files("held_out_repeats") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("held_out.csv");
    std::fs::copy(&grid, &copy).unwrap();
    let json = dir.path().join("out.json");
    for cmd in ["calibrate", "diagnose"] {
        let out = output(&[
            cmd,
            "--robot",
            "ur5",
            "--set",
            "tool_dy=0.07",
            "--set",
            "tool_dz=31",
            "--poses",
            s(&grid),
            "--validate",
            s(&copy),
            "--json",
            s(&json),
        ]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{cmd}: {err}");
        assert!(
            err.contains("repeat calibration poses exactly"),
            "{cmd}: {err}"
        );
        assert!(
            err.contains("held_out.csv") && err.contains("grid.csv"),
            "{err}"
        );
        assert!(!json.exists(), "{cmd} wrote its JSON");
    }
}
