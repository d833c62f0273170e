//! The inputs of every subcommand for the hostile-stream test, made once in a folder: a
//! simulated run, models, URDF, joint and tracker logs, inclinometer readings, a recording;
//! and each subcommand's command line on them.

use std::ffi::OsString;
use std::path::Path;

use rigctl::joints::{header, predicted_tilt_deg, row, TiltReading};
use rigctl::model::katana450;
use rigctl::sim::session::{simulate_session, write_session, SessionConfig};

use crate::common::spawn::{rigctl, text};

/// The inputs every command needs, made once in `dir`; returns (name, args) per command.
pub(super) fn commands(dir: &Path) -> Vec<(&'static str, Vec<OsString>)> {
    let d = |s: &str| dir.join(s).into_os_string();
    let o = |s: &str| OsString::from(s);

    // Poses (the CLI) and a short pose set for the slow diagnose.
    let sim = dir.join("sim");
    let out = rigctl()
        .args(["simulate", "--seed", "3", "--val", "20", "--out"])
        .arg(&sim)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    let cal = std::fs::read_to_string(sim.join("cal.csv")).unwrap();
    let short: Vec<&str> = cal.lines().take(41).collect();
    std::fs::write(dir.join("cal40.csv"), short.join("\n") + "\n").unwrap();

    // A pencil session (library, at the smallest scan resolution it allows, 300 dpi) and its ideal trace.
    let declared = katana450(330.0).unwrap();
    let cfg = SessionConfig {
        dpi: 300.0,
        ..SessionConfig::default()
    };
    let session = simulate_session(&declared, &cfg).unwrap();
    let sess = dir.join("sess");
    write_session(&sess, &session, &cfg).unwrap();
    let mut trace = String::from("x,y\n");
    for p in &session.pencil_mm {
        trace.push_str(&format!("{:.4},{:.4}\n", p[0], p[1]));
    }
    std::fs::write(dir.join("trace.csv"), trace).unwrap();
    let out = rigctl()
        .args(["potcal", "--points"])
        .arg(sess.join("potjig.csv"))
        .arg("--out")
        .arg(dir.join("pot.toml"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));

    std::fs::write(dir.join("path.csv"), "x,y,z\n300,0,200\n310,0,200\n").unwrap();
    std::fs::write(dir.join("tilt.csv"), tilt_readings()).unwrap();
    std::fs::write(dir.join("arm.urdf"), URDF).unwrap();
    let (log, points) = capture_logs();
    std::fs::write(dir.join("log.csv"), log).unwrap();
    std::fs::write(dir.join("points.csv"), points).unwrap();

    let s = |f: &str| sess.join(f).into_os_string();
    let p = |f: &str| sim.join(f).into_os_string();
    vec![
        ("--help", vec![o("--help")]),
        ("--version", vec![o("--version")]),
        ("calibrate --help", vec![o("calibrate"), o("--help")]),
        ("fk", vec![o("fk"), o("--joints"), p("val.csv")]),
        ("simulate", vec![o("simulate"), o("--out"), d("sim2")]),
        (
            "calibrate",
            vec![o("calibrate"), o("--poses"), p("cal.csv")],
        ),
        (
            "diagnose",
            vec![
                o("diagnose"),
                o("--poses"),
                d("cal40.csv"),
                o("--validate"),
                p("val.csv"),
            ],
        ),
        (
            "report",
            vec![
                o("report"),
                sim.clone().into_os_string(),
                o("--html"),
                d("r.html"),
            ],
        ),
        ("ports", vec![o("ports")]),
        (
            "export",
            vec![o("export"), s("pot.rec"), o("--csv"), d("export")],
        ),
        ("sheet", vec![o("sheet"), o("--out"), d("sheet.svg")]),
        (
            "trace",
            vec![
                o("trace"),
                s("scan.png"),
                o("--out"),
                d("traced.csv"),
                o("--overlay"),
                d("overlay.png"),
            ],
        ),
        (
            "potcal",
            vec![
                o("potcal"),
                o("--points"),
                s("potjig.csv"),
                o("--out"),
                d("pot2.toml"),
            ],
        ),
        (
            "fuse",
            vec![
                o("fuse"),
                o("--joints"),
                s("joints.csv"),
                o("--recording"),
                s("pot.rec"),
                o("--trace"),
                d("trace.csv"),
                o("--placement"),
                s("placement.toml"),
                o("--pot"),
                d("pot.toml"),
                o("--out"),
                d("fused.csv"),
            ],
        ),
        (
            "urdf2model",
            vec![
                o("urdf2model"),
                o("--urdf"),
                d("arm.urdf"),
                o("--tip"),
                o("tip"),
                o("--out"),
                d("arm.toml"),
            ],
        ),
        (
            "model2urdf",
            vec![
                o("model2urdf"),
                o("--robot"),
                o("ur5"),
                o("--out"),
                d("ur5.urdf"),
            ],
        ),
        (
            "joints",
            vec![
                o("joints"),
                o("--readings"),
                d("tilt.csv"),
                o("--out"),
                d("tilt.toml"),
            ],
        ),
        (
            "compensate",
            vec![
                o("compensate"),
                o("--path"),
                d("path.csv"),
                o("--out"),
                d("comp.csv"),
            ],
        ),
        (
            "plan",
            vec![
                o("plan"),
                o("--robot"),
                o("katana450"),
                o("--n"),
                o("8"),
                o("--candidates"),
                o("200"),
                o("--out"),
                d("plan.csv"),
            ],
        ),
        (
            "poses",
            vec![
                o("poses"),
                o("--joints"),
                d("log.csv"),
                o("--points"),
                d("points.csv"),
                o("--out"),
                d("poses.csv"),
            ],
        ),
        (
            "init",
            vec![
                o("init"),
                o("--robot"),
                o("ur5"),
                o("--force"),
                o("--out"),
                d("rigctl.toml"),
            ],
        ),
    ]
}

/// A joint log (100 Hz) of the Katana dwelling at three poses with 1 s moves, and a tracker
/// log (50 Hz, 0.4 s behind) of its tool point: inputs for `poses`.
fn capture_logs() -> (String, String) {
    let model = katana450(200.0).unwrap();
    let poses = [
        [10.0, 20.0, 30.0, 40.0, 50.0],
        [-30.0, 60.0, -10.0, 0.0, 20.0],
        [50.0, 40.0, 60.0, -40.0, 0.0],
    ];
    let q = |t: f64| -> Vec<f64> {
        let k = ((t / 3.0).floor() as usize).min(2);
        let u = ((t - 3.0 * k as f64 - 2.0) / 1.0).clamp(0.0, 1.0);
        let s = 0.5 - 0.5 * (u * std::f64::consts::PI).cos();
        let b = poses[(k + 1).min(2)];
        (0..5)
            .map(|j| poses[k][j] + s * (b[j] - poses[k][j]))
            .collect()
    };
    let mut log = String::from("t,q1,q2,q3,q4,q5\n");
    for i in 0..=900 {
        let t = f64::from(i) * 0.01;
        let qs: Vec<String> = q(t).iter().map(|v| format!("{v:.4}")).collect();
        log.push_str(&format!("{t:.2},{}\n", qs.join(",")));
    }
    let mut points = String::from("t,x,y,z\n");
    for i in 0..450 {
        let t = f64::from(i) * 0.02;
        let p = model
            .fk(&q((t - 0.4).max(0.0)), rigctl::model::Tilt::Off)
            .unwrap()
            .position_mm;
        points.push_str(&format!("{t:.3},{:.4},{:.4},{:.4}\n", p.x, p.y, p.z));
    }
    (log, points)
}

/// Paired inclinometer readings (a configuration and its mirror, 0 and 3 kg) of the declared
/// Katana, exact: enough for `joints` to fit every joint.
fn tilt_readings() -> String {
    let model = katana450(200.0).unwrap();
    let limits = model.joint_limits();
    let mut text = format!("{}\n", header(5));
    for joint in 0..5 {
        for pair in 0..6 {
            let q: Vec<f64> = (0..5)
                .map(|k| {
                    let [lo, hi] = limits[k];
                    let f = ((pair * 7 + k * 3 + joint) % 10) as f64 / 10.0;
                    lo.max(-100.0) + f * (hi.min(100.0) - lo.max(-100.0))
                })
                .collect();
            let mut mirror = q.clone();
            for k in 1..5 {
                mirror[k] = (-q[k]).clamp(limits[k][0], limits[k][1]);
            }
            let payload_kg = if pair % 2 == 0 { 0.0 } else { 3.0 };
            for (tag, qq) in [("a", q), ("b", mirror)] {
                let tilt = predicted_tilt_deg(&model, &qq, payload_kg, joint).unwrap();
                let r = TiltReading {
                    line: 0,
                    joint,
                    config: format!("j{}_{pair}{tag}", joint + 1),
                    q_deg: qq,
                    payload_kg,
                    incl_deg: [Some(tilt[0]), Some(tilt[1]), Some(tilt[2])],
                };
                text.push_str(&row(&r));
                text.push('\n');
            }
        }
    }
    text
}

const URDF: &str = r#"<robot name="arm">
  <link name="base"/><link name="l1"/><link name="tip"/>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.2" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <joint name="j2" type="revolute">
    <parent link="l1"/><child link="tip"/>
    <origin xyz="0.3 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/>
  </joint>
</robot>
"#;
