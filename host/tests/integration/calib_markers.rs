//! Pose files with several measured points per pose, joint columns by name and `--units`, end
//! to end through `rigctl calibrate` on simulated data: the truth's point offsets and joint
//! offsets are recovered, unit conversion gives the same result, and a bad point column set is
//! refused with exit 2 naming the file, line and column.

use std::path::{Path, PathBuf};

use rigctl::model::{Model, ModelBuilder, Tilt};

use super::common::spawn::rigctl;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rigctl_markers_{name}_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 4-joint arm (a prismatic lift, three revolute joints) with named joints.
fn arm() -> Model {
    let mut b = ModelBuilder::new("arm4");
    b.joint(true, "lift_offset", 0.0, [0.0, 400.0], None)
        .unwrap();
    b.dh_row(2, 0.0, 300.0, 0.0, 90.0, [-170.0, 170.0], None)
        .unwrap();
    b.dh_row(3, 0.0, 0.0, 250.0, 0.0, [-120.0, 120.0], None)
        .unwrap();
    b.dh_row(4, 0.0, 0.0, 200.0, 0.0, [-120.0, 120.0], None)
        .unwrap();
    let mut m = b.build().unwrap();
    m.set_joint_names(
        ["lift", "shoulder", "elbow", "wrist"]
            .map(String::from)
            .to_vec(),
    )
    .unwrap();
    m
}

/// Truth offsets of points 2 and 3 relative to the tool frame (mm); point 1 is the tool point.
const P1: [f64; 3] = [10.0, -5.0, 30.0];
const P2: [f64; 3] = [60.0, 40.0, 20.0];
const P3: [f64; 3] = [-30.0, 70.0, 50.0];

fn write_file(path: &Path, truth: &Model, n: usize, metres: bool, by_name: bool) {
    let (ls, as_) = if metres {
        (1e-3, 1.0_f64.to_radians())
    } else {
        (1.0, 1.0)
    };
    let joints = if by_name {
        "note,lift,shoulder,elbow,wrist"
    } else {
        "note,q1,q2,q3,q4"
    };
    let mut text = format!("{joints},x1,y1,z1,x2,y2,z2,x3,y3,z3\n");
    for k in 0..n {
        let f = k as f64;
        let q = [
            40.0 + 300.0 * ((f * 0.37).sin() * 0.5 + 0.5),
            -150.0 + 300.0 * ((f * 0.61).cos() * 0.5 + 0.5),
            -100.0 + 200.0 * ((f * 0.83).sin() * 0.5 + 0.5),
            -100.0 + 200.0 * ((f * 1.13).cos() * 0.5 + 0.5),
        ];
        let mut row = format!(
            "p{k},{},{},{},{}",
            q[0] * ls,
            q[1] * as_,
            q[2] * as_,
            q[3] * as_
        );
        for p in [P1, P2, P3] {
            let mut m = truth.clone();
            for (name, v) in ["tool_dx", "tool_dy", "tool_dz"].iter().zip(p) {
                m.set_param(name, v).unwrap();
            }
            let x = m.position_mm(&q, Tilt::Off).unwrap();
            row.push_str(&format!(
                ",{:.12},{:.12},{:.12}",
                x.x * ls,
                x.y * ls,
                x.z * ls
            ));
        }
        text.push_str(&row);
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

fn calibrate(dir: &Path, file: &Path, units: &str) -> serde_json::Value {
    let json = dir.join(format!("out_{units}.json").replace(',', "_"));
    let out = rigctl()
        .args(["calibrate", "--model"])
        .arg(dir.join("arm.toml"))
        .arg("--poses")
        .arg(file)
        .args(["--units", units, "--method", "standard", "--params"])
        .arg("@tool,@offsets")
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

#[test]
fn three_points_by_joint_name_in_metres_recover_the_truth() {
    let dir = scratch("roundtrip");
    let nominal = arm();
    nominal.write_file(&dir.join("arm.toml")).unwrap();
    // dth4 turns the last frame, as the tool point does: not identifiable with it (kept 0).
    let mut truth = nominal.clone();
    for (n, v) in [("dth2", 0.3), ("dth3", -0.2), ("lift_offset", 1.5)] {
        truth.set_param(n, v).unwrap();
    }
    let (mm, m) = (dir.join("mm.csv"), dir.join("m.csv"));
    write_file(&mm, &truth, 30, false, false);
    write_file(&m, &truth, 30, true, true);
    let a = calibrate(&dir, &mm, "mm,deg");
    let b = calibrate(&dir, &m, "m,rad");
    for doc in [&a, &b] {
        let p = &doc["parameters"];
        let t = &doc["terms"];
        for (n, v) in [("dth2", 0.3), ("dth3", -0.2), ("lift_offset", 1.5)] {
            let got = p[n].as_f64().unwrap();
            assert!((got - v).abs() < 1e-6, "{n}: {got} vs {v}");
        }
        for (a, v) in ["x", "y", "z"].iter().zip(P1) {
            let got = p[format!("tool_d{a}")].as_f64().unwrap();
            assert!((got - v).abs() < 1e-6, "tool_d{a}: {got} vs {v}");
        }
        for (k, truth) in [(2, P2), (3, P3)] {
            for (a, v) in ["x", "y", "z"].iter().zip(truth) {
                let got = t[format!("marker{k}_{a}_mm")].as_f64().unwrap();
                assert!((got - v).abs() < 1e-6, "marker{k}_{a}_mm: {got} vs {v}");
            }
        }
        assert!(doc["calibration"]["after"]["rms_mm"].as_f64().unwrap() < 1e-6);
    }
    // Metres and radians by joint name give the same identification as mm and deg by q<i>.
    let (pa, pb) = (&a["parameters"]["dth2"], &b["parameters"]["dth2"]);
    assert!((pa.as_f64().unwrap() - pb.as_f64().unwrap()).abs() < 1e-9);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_incomplete_point_or_a_missing_cell_is_bad_input_naming_the_place() {
    let dir = scratch("bad");
    arm().write_file(&dir.join("arm.toml")).unwrap();
    let cases = [
        (
            "q1,q2,q3,q4,x1,y1,x2,y2,z2\n1,2,3,4,5,6,7,8,9\n",
            ":1:",
            "z1",
        ),
        ("q1,q2,q3,q4,x,y,x2,y2,z2\n1,2,3,4,5,6,8,9,10\n", ":1:", "x"),
        (
            "q1,q2,q3,q4,x1,y1,z1,x2,y2,z2\n1,2,3,4,5,6,7,8,,10\n",
            ":2:",
            "y2",
        ),
        // a joint missing: said as a joint count (another robot's file)
        (
            "lift,shoulder,elbow,x,y,z\n1,2,3,5,6,7\n",
            ":1:",
            "3 joints in the file",
        ),
    ];
    for (i, (text, line, column)) in cases.iter().enumerate() {
        let f = dir.join(format!("bad{i}.csv"));
        std::fs::write(&f, text).unwrap();
        let out = rigctl()
            .args(["calibrate", "--model"])
            .arg(dir.join("arm.toml"))
            .arg("--poses")
            .arg(&f)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "case {i}: {err}");
        assert!(
            err.contains(&format!("bad{i}.csv{line}")),
            "case {i}: {err}"
        );
        assert!(
            err.contains(&format!("`{column}`")) || err.contains(column),
            "case {i}: {err}"
        );
    }
    // A point number the file does not have.
    let f = dir.join("ok.csv");
    std::fs::write(&f, "q1,q2,q3,q4,x1,y1,z1\n10,2,3,4,5,6,7\n").unwrap();
    let out = rigctl()
        .args(["calibrate", "--model"])
        .arg(dir.join("arm.toml"))
        .arg("--poses")
        .arg(&f)
        .args(["--markers", "2"])
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn fk_reads_metres_and_radians() {
    let dir = scratch("fk");
    let model = arm();
    model.write_file(&dir.join("arm.toml")).unwrap();
    let q: [f64; 4] = [120.0, 30.0, -45.0, 60.0];
    std::fs::write(
        dir.join("q.csv"),
        format!(
            "lift,shoulder,elbow,wrist\n{},{},{},{}\n",
            q[0] / 1e3,
            q[1].to_radians(),
            q[2].to_radians(),
            q[3].to_radians()
        ),
    )
    .unwrap();
    let out = rigctl()
        .args(["fk", "--model"])
        .arg(dir.join("arm.toml"))
        .arg("--joints")
        .arg(dir.join("q.csv"))
        .args(["--units", "m,rad"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let row: Vec<f64> = text
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let p = model.position_mm(&q, Tilt::Off).unwrap();
    assert!(
        (row[0] - p.x).abs() < 1e-6 && (row[1] - p.y).abs() < 1e-6 && (row[2] - p.z).abs() < 1e-6
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Copies a pose file with two more columns whose names look like numbered points (`z2` with a
/// number, `x1` with text or nothing): FORMATS.md keeps them and ignores them.
fn with_point_like_columns(from: &Path, to: &Path) {
    let text = std::fs::read_to_string(from).unwrap();
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        let more = match i {
            0 => ",z2,x1",
            _ if i % 2 == 0 => ",7.5,",
            _ => ",-3,note",
        };
        out.push_str(line);
        out.push_str(more);
        out.push('\n');
    }
    std::fs::write(to, out).unwrap();
}

/// Runs rigctl with `args`, asserts exit 0, returns stdout.
fn run_ok(args: &[&std::ffi::OsStr]) -> String {
    let out = rigctl().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn plain_xyz_with_point_like_columns_is_read_by_calibrate_fk_and_diagnose() {
    let dir = scratch("plain");
    let os = |s: &str| std::ffi::OsString::from(s);
    let p = |name: &str| dir.join(name).into_os_string();
    run_ok(&[
        &os("simulate"),
        &os("--out"),
        &p("sim"),
        &os("--seed"),
        &os("5"),
    ]);
    for f in ["cal", "val"] {
        with_point_like_columns(
            &dir.join(format!("sim/{f}.csv")),
            &dir.join(format!("{f}2.csv")),
        );
    }
    let (cal, val) = (p("sim/cal.csv"), p("sim/val.csv"));
    let (cal2, val2) = (p("cal2.csv"), p("val2.csv"));
    // calibrate: the same identification as without the extra columns.
    let cal_json = |c: &std::ffi::OsStr, v: &std::ffi::OsStr, out: &str| {
        run_ok(&[
            &os("calibrate"),
            &os("--poses"),
            c,
            &os("--validate"),
            v,
            &os("--json"),
            &p(out),
        ]);
        let doc: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join(out)).unwrap()).unwrap();
        doc
    };
    let a = cal_json(&cal, &val, "a.json");
    let b = cal_json(&cal2, &val2, "b.json");
    assert_eq!(a["parameters"], b["parameters"]);
    assert_eq!(a["validation"], b["validation"]);
    // fk: the same positions.
    let fk = |c: &std::ffi::OsStr| run_ok(&[&os("fk"), &os("--joints"), c]);
    assert_eq!(fk(&cal), fk(&cal2));
    // diagnose reads it too (every pose, both files).
    run_ok(&[
        &os("diagnose"),
        &os("--poses"),
        &cal2,
        &os("--validate"),
        &val2,
        &os("--json"),
        &p("d.json"),
    ]);
    let d: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("d.json")).unwrap()).unwrap();
    assert_eq!(d["declared"]["validation"]["n"], 60);
    assert_eq!(d["final"]["calibration"]["n"], 118);
    let _ = std::fs::remove_dir_all(&dir);
}
