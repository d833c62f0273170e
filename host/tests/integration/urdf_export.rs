//! `rigctl model2urdf` checked by a consumer rigctl did not write: pinocchio (PyPI `pin`, in the
//! venv of `common::python_env`) loads the exported URDF, and its forward kinematics `world` ->
//! `tool0` must equal `rigctl fk --model` within 1e-6 mm: the real UR5 after `calibrate --base`,
//! a calibrated Katana (tilting off), and the TIAGo URDF through `urdf2model` -> `calibrate` ->
//! `model2urdf --urdf`, whose other elements Python's ElementTree finds unchanged.

use crate::common;
use crate::common::record::record;
use crate::common::spawn;

use crate::common::spawn::{output_ok as rigctl, path_arg as s};
use std::path::{Path, PathBuf};
use std::process::Command;

use rigctl::model::{Model, Tilt};

/// Reads a CSV of numbers with a header (comment lines `#` skipped): (header, rows).
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let mut lines = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let header = lines
        .next()
        .expect("a header")
        .split(',')
        .map(|c| c.trim().to_string())
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|c| c.trim().to_string()).collect())
        .collect();
    (header, rows)
}

fn xyz_rows(path: &Path) -> Vec<[f64; 3]> {
    let (header, rows) = read_csv(path);
    let col = |n: &str| header.iter().position(|h| h == n).expect("x,y,z columns");
    let (x, y, z) = (col("x"), col("y"), col("z"));
    rows.iter()
        .map(|r| [x, y, z].map(|c| r[c].parse::<f64>().expect("a number")))
        .collect()
}

/// Joint vectors (deg, mm for prismatic joints) of a pose file, by the model's joint columns.
fn pose_joints(model: &Model, poses: &Path, units: &str) -> Vec<Vec<f64>> {
    let spec = rigctl::io::pose_csv::PoseSpec {
        units: units.parse().expect("units"),
        ..rigctl::io::pose_csv::PoseSpec::for_model(model, false)
    };
    rigctl::io::pose_csv::read_poses(poses, &spec)
        .expect("the pose file reads")
        .joints()
}

/// pinocchio's `tool0` positions (mm) for `q` (deg / mm, converted here to rad / m with the
/// same conversion rigctl uses), joints named `names`.
fn pinocchio_fk(
    py: &Path,
    dir: &Path,
    urdf: &Path,
    model: &Model,
    names: &[String],
    q: &[Vec<f64>],
) -> Vec<[f64; 3]> {
    let qcsv = dir.join("q_rad.csv");
    let mut text = names.join(",") + "\n";
    for row in q {
        let cells: Vec<String> = row
            .iter()
            .zip(model.joints())
            .map(|(v, j)| {
                let si = if j.prismatic { v / 1e3 } else { v.to_radians() };
                format!("{si:e}")
            })
            .collect();
        text += &(cells.join(",") + "\n");
    }
    std::fs::write(&qcsv, text).unwrap();
    let out = dir.join("pin.csv");
    let run = Command::new(py)
        .arg(common::py_script("pin_fk.py"))
        .args([s(urdf), s(&qcsv), s(&out)])
        .output()
        .expect("python runs");
    assert!(
        run.status.success(),
        "pin_fk.py: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    xyz_rows(&out)
}

/// Compares pinocchio with `rigctl fk` (its CSV, 9 decimals) and with the library's FK at full
/// precision; returns the largest difference to the latter (mm). Records the largest difference
/// to `rigctl fk` as `<key>_vs_fk_mm`.
fn compare(
    case: &str,
    key: &str,
    pin: &[[f64; 3]],
    fk_csv: &[[f64; 3]],
    model: &Model,
    q: &[Vec<f64>],
) -> f64 {
    assert_eq!(pin.len(), fk_csv.len(), "{case}: row counts");
    assert_eq!(pin.len(), q.len(), "{case}: row counts");
    assert!(!q.is_empty());
    let (mut worst_cli, mut worst) = (0.0f64, 0.0f64);
    for ((p, c), qi) in pin.iter().zip(fk_csv).zip(q) {
        let lib = model.fk(qi, Tilt::Off).unwrap().position_mm;
        for k in 0..3 {
            worst_cli = worst_cli.max((p[k] - c[k]).abs());
            worst = worst.max((p[k] - lib[k]).abs());
        }
    }
    eprintln!(
        "{case}: {} poses, pinocchio vs rigctl fk (CSV, 9 decimals) max {worst_cli:.3e} mm, vs \
         the model's FK at full precision max {worst:.3e} mm",
        q.len()
    );
    assert!(
        worst_cli <= 1e-6,
        "{case}: pinocchio vs rigctl fk {worst_cli} mm"
    );
    assert!(worst <= 1e-6, "{case}: pinocchio vs model FK {worst} mm");
    record(&format!("{key}_vs_fk_mm"), worst_cli);
    worst
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().expect("a temporary directory")
}

#[test]
fn ur5_tracker_after_calibrate_base_in_pinocchio() {
    let test = "ur5_tracker_after_calibrate_base_in_pinocchio";
    let Some(data) = common::shared_file(test, "data/real/ur5_laser_tracker") else {
        return;
    };
    let Some(py) = common::python_env(test) else {
        return;
    };
    let dir = tmp();
    let d = dir.path();
    let model_path = d.join("ur5cal.toml");
    let [tx, ty, tz] = rigctl::model::UR5_SMR_TOOL_MM;
    let sets = [
        format!("tool_dx={tx}"),
        format!("tool_dy={ty}"),
        format!("tool_dz={tz}"),
    ];
    rigctl(&[
        "calibrate",
        "--robot",
        "ur5",
        "--set",
        &sets[0],
        "--set",
        &sets[1],
        "--set",
        &sets[2],
        "--poses",
        s(&data.join("grid.csv")),
        "--base",
        "--out",
        s(&model_path),
    ]);
    let model = Model::from_file(&model_path).unwrap();
    for p in ["base_x", "base_y", "base_rx", "base_ry"] {
        assert!(model.param(p).unwrap() != 0.0, "{p} was calibrated");
    }
    let urdf = d.join("ur5cal.urdf");
    let out = rigctl(&["model2urdf", "--model", s(&model_path), "--out", s(&urdf)]);
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(
        report.contains("joint_1") && report.contains("tool0_joint"),
        "{report}"
    );
    let test_poses = data.join("random.csv");
    let fk_csv = d.join("fk.csv");
    let fk = rigctl(&["fk", "--model", s(&model_path), "--joints", s(&test_poses)]);
    std::fs::write(&fk_csv, &fk.stdout).unwrap();
    let q = pose_joints(&model, &test_poses, "mm,deg");
    let names: Vec<String> = (1..=6).map(|i| format!("joint_{i}")).collect();
    let pin = pinocchio_fk(&py, d, &urdf, &model, &names, &q);
    compare(
        "UR5 after calibrate --base",
        "ur5",
        &pin,
        &xyz_rows(&fk_csv),
        &model,
        &q,
    );
}

#[test]
fn calibrated_katana_in_pinocchio_names_the_tilting() {
    let Some(py) = common::python_env("calibrated_katana_in_pinocchio_names_the_tilting") else {
        return;
    };
    let dir = tmp();
    let d = dir.path();
    let sim = d.join("sim");
    rigctl(&[
        "simulate",
        "--out",
        s(&sim),
        "--seed",
        "5",
        "--effect",
        "link_length:a2=0.8",
        "--effect",
        "base_offset=1.5,-0.7,0.4",
    ]);
    let model_path = d.join("katana.toml");
    rigctl(&[
        "calibrate",
        "--poses",
        s(&sim.join("cal.csv")),
        "--method",
        "standard",
        "--out",
        s(&model_path),
    ]);
    let model = Model::from_file(&model_path).unwrap();
    assert!(model.has_tilt(), "the Katana model carries tilting values");
    let urdf = d.join("katana.urdf");
    let out = rigctl(&["model2urdf", "--model", s(&model_path), "--out", s(&urdf)]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("joint tilting"), "{stderr}");
    let poses = sim.join("val.csv");
    let fk_csv = d.join("fk.csv");
    let fk = rigctl(&["fk", "--model", s(&model_path), "--joints", s(&poses)]);
    std::fs::write(&fk_csv, &fk.stdout).unwrap();
    let q = pose_joints(&model, &poses, "mm,deg");
    let names: Vec<String> = (1..=model.n_joints())
        .map(|i| format!("joint_{i}"))
        .collect();
    let pin = pinocchio_fk(&py, d, &urdf, &model, &names, &q);
    compare(
        "calibrated Katana (tilting off)",
        "katana",
        &pin,
        &xyz_rows(&fk_csv),
        &model,
        &q,
    );
}

const TIAGO_JOINTS: [&str; 8] = [
    "torso_lift_joint",
    "arm_1_joint",
    "arm_2_joint",
    "arm_3_joint",
    "arm_4_joint",
    "arm_5_joint",
    "arm_6_joint",
    "arm_7_joint",
];

#[test]
fn tiago_round_trip_keeps_the_urdf_and_matches_pinocchio() {
    let test = "tiago_round_trip_keeps_the_urdf_and_matches_pinocchio";
    let Some(t) = common::shared_file(
        test,
        "data/real/thanhndv212__figaroh-examples/examples/tiago",
    ) else {
        return;
    };
    let Some(py) = common::python_env(test) else {
        return;
    };
    let original = t.join("urdf/tiago_48_schunk.urdf");
    let mocap = t.join("data/calibration/mocap");
    let train = mocap.join("qualisys_2021-11-30_static_postures.csv");
    let val = mocap.join("qualisys_2021-11-26_static_postures.csv");
    let dir = tmp();
    let d = dir.path();
    let nominal = d.join("tiago.toml");
    rigctl(&[
        "urdf2model",
        "--urdf",
        s(&original),
        "--base-link",
        "base_footprint",
        "--tip",
        "wrist_ft_tool_link",
        "--limit-margin-pct",
        "1",
        "--out",
        s(&nominal),
    ]);
    let cal = d.join("tiago_cal.toml");
    rigctl(&[
        "calibrate",
        "--model",
        s(&nominal),
        "--poses",
        s(&train),
        "--units",
        "m,rad",
        "--markers",
        "1",
        "--method",
        "standard",
        "--params",
        "@base,@tool,@offsets,arm_5_joint_x,arm_3_joint_rz,arm_1_joint_rx",
        // base_rz and arm_1's offset split a turn about the vertical that 37 postures barely
        // tell apart (+-10 deg each): beyond a real arm's errors, written here only to test the
        // round trip of whatever model calibrate writes
        "--allow-large-changes",
        "--out",
        s(&cal),
    ]);
    let model = Model::from_file(&cal).unwrap();
    let nominal_model = Model::from_file(&nominal).unwrap();
    assert!(
        (model.param("arm_5_joint_x").unwrap() - nominal_model.param("arm_5_joint_x").unwrap())
            .abs()
            > 1.0,
        "a chain constant was calibrated"
    );
    let urdf = d.join("tiago_cal.urdf");
    let out = rigctl(&[
        "model2urdf",
        "--model",
        s(&cal),
        "--urdf",
        s(&original),
        "--base-link",
        "base_footprint",
        "--out",
        s(&urdf),
    ]);
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(
        report.contains("arm_5_joint\n  before xyz -0.162"),
        "{report}"
    );

    // The XML trees: everything of the original but the chain's joint origins is unchanged.
    let tree = Command::new(&py)
        .arg(common::py_script("urdf_tree.py"))
        .args([s(&original), s(&urdf), &TIAGO_JOINTS.join(",")])
        .output()
        .expect("python runs");
    assert!(
        tree.status.success(),
        "{}",
        String::from_utf8_lossy(&tree.stderr)
    );
    let verdict: serde_json::Value = serde_json::from_slice(&tree.stdout).unwrap();
    eprintln!("TIAGo XML trees: {verdict}");
    assert_eq!(verdict["same_elsewhere"], true, "{verdict}");
    assert_eq!(verdict["removed"], serde_json::json!([]), "{verdict}");
    assert_eq!(
        verdict["added"],
        serde_json::json!([
            "link:world",
            "joint:world_joint",
            "link:tool0",
            "joint:tool0_joint"
        ]),
        "{verdict}"
    );
    let changed: Vec<&str> = verdict["changed_origins"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|v| v.as_str())
        .collect();
    for j in ["arm_1_joint", "arm_3_joint", "arm_5_joint"] {
        assert!(
            changed.contains(&j),
            "{j} carries calibrated values: {verdict}"
        );
    }

    // pinocchio's FK of the whole TIAGo (its other joints at their neutral values) vs rigctl.
    let fk_csv = d.join("fk.csv");
    let fk = rigctl(&[
        "fk",
        "--model",
        s(&cal),
        "--joints",
        s(&val),
        "--units",
        "m,rad",
    ]);
    std::fs::write(&fk_csv, &fk.stdout).unwrap();
    let q = pose_joints(&model, &val, "m,rad");
    let names: Vec<String> = TIAGO_JOINTS.iter().map(|n| n.to_string()).collect();
    let pin = pinocchio_fk(&py, d, &urdf, &model, &names, &q);
    compare(
        "TIAGo urdf2model -> calibrate -> model2urdf --urdf",
        "tiago",
        &pin,
        &xyz_rows(&fk_csv),
        &model,
        &q,
    );
}

#[test]
fn model2urdf_refuses_a_model_that_does_not_fit_the_urdf() {
    let Some(t) = common::shared_file(
        "model2urdf_refuses_a_model_that_does_not_fit_the_urdf",
        "data/real/thanhndv212__figaroh-examples/examples/tiago",
    ) else {
        return;
    };
    let dir = tmp();
    let out = spawn::rigctl()
        .args(["model2urdf", "--robot", "ur5", "--urdf"])
        .arg(t.join("urdf/tiago_48_schunk.urdf"))
        .arg("--out")
        .arg(dir.path().join("x.urdf"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("names no joints"), "{err}");
    assert!(!dir.path().join("x.urdf").exists());
}

#[test]
fn exported_urdf_reads_back_as_the_same_model() {
    // The export read by rigctl's own URDF import gives the same FK (no Python needed).
    let dir = tmp();
    let mut model = rigctl::model::katana450(200.0).unwrap();
    for (p, v) in [
        ("base_x", 2.0),
        ("base_ry", 0.3),
        ("a2", 191.2),
        ("dth3", -0.4),
    ] {
        let v = model.param(p).unwrap() + v;
        model.set_param(p, v).unwrap();
    }
    let exported = rigctl::urdf::model_to_urdf(&model);
    let path: PathBuf = dir.path().join("k.urdf");
    std::fs::write(&path, &exported.text).unwrap();
    let urdf = rigctl::urdf::Urdf::from_file(&path).unwrap();
    let back = rigctl::urdf::import_chain(
        &urdf,
        &rigctl::urdf::ImportOptions {
            base_link: None,
            tip_link: "tool0",
            tool_mm: [0.0; 3],
        },
    )
    .unwrap()
    .model;
    for q in [
        [0.0, 0.0, 0.0, 0.0, 0.0],
        [10.0, 100.0, -40.0, 30.0, -77.0],
        [-120.0, 60.0, 95.0, -100.0, 170.0],
    ] {
        let a = model.fk(&q, Tilt::Off).unwrap().position_mm;
        let b = back.fk(&q, Tilt::Off).unwrap().position_mm;
        assert!((a - b).norm() < 1e-9, "{q:?}: {a} vs {b}");
    }
}

/// The effect table's `urdf_holds` is what `model2urdf` does: an effect a URDF cannot hold is
/// named in `not_representable`, one it holds is not, on the UR5 (no tilting, link masses: every
/// row but the tilting's is offered).
#[test]
fn the_effect_tables_urdf_column_is_what_the_export_says() {
    use rigctl::model::effect::{library, Offers};
    let model = rigctl::model::ur5().unwrap();
    assert!(rigctl::urdf::model_to_urdf(&model)
        .not_representable
        .is_empty());
    let offers = Offers {
        approach: true,
        time: true,
    };
    for id in library(&model, offers) {
        let (counts, _) = id.row().sim_values;
        let mut values = vec!["0.01".to_string(); counts[0]];
        if id.to_string() == "thermal" {
            values[1] = "20".into();
        }
        let effect =
            rigctl::sim::effects::parse_effect(&format!("{id}={}", values.join(","))).unwrap();
        let mut changed = model.clone();
        effect.apply(&mut changed).unwrap();
        let notes = rigctl::urdf::model_to_urdf(&changed).not_representable;
        assert_eq!(
            notes.is_empty(),
            id.row().urdf_holds,
            "{id}: urdf_holds {} but the export says {notes:?}",
            id.row().urdf_holds
        );
    }
}
