//! TIAGo real data (FIGAROH examples) from the command line, as the README's "TIAGo from the
//! CLI" section types it: `urdf2model` (masses and joint names from the URDF, limits widened by
//! 1 %: the torso reads 350.18 mm against its 350 mm limit), then `calibrate`
//! on the training session (37 postures) with the validation session (62 postures) held out,
//! the posture files read as they are (metres, radians, joint columns by URDF name, 4 markers).
//!
//! FIGAROH's published held-out norm RMSE of the hand point BL (marker 1, data README):
//! registration 4.87, joint offsets 4.23, full parameters 3.07 mm. Here: the two levels defined
//! identically reproduce them; the chain constants chosen by leave-one-posture-out PRESS on the
//! training postures, with gravity compliance (about the joint axes and lateral) as candidates,
//! go below 3.07 and below 2.8 mm over all 62 held-out postures.

use crate::common;
use crate::common::record::record;
use crate::common::spawn::rigctl;

use std::path::{Path, PathBuf};

const DATA_DIR: &str = "data/real/thanhndv212__figaroh-examples/examples/tiago";
const URDF: &str = "urdf/tiago_48_schunk.urdf";
const TRAIN: &str = "data/calibration/mocap/qualisys_2021-11-30_static_postures.csv";
const VALID: &str = "data/calibration/mocap/qualisys_2021-11-26_static_postures.csv";

fn run(args: &[&str]) -> std::process::Output {
    let out = rigctl().args(args).output().expect("rigctl runs");
    assert!(
        out.status.success(),
        "rigctl {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The data directory and a scratch directory with `tiago.toml` from `urdf2model`.
fn setup(name: &str) -> Option<(PathBuf, PathBuf)> {
    let dir = common::shared_file("TIAGo data", DATA_DIR)?;
    let tmp = std::env::temp_dir().join(format!("rigctl_tiago_{name}_{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let model = tmp.join("tiago.toml");
    run(&[
        "urdf2model",
        "--urdf",
        dir.join(URDF).to_str().unwrap(),
        "--base-link",
        "base_footprint",
        "--tip",
        "wrist_ft_tool_link",
        "--limit-margin-pct",
        "1",
        "--out",
        model.to_str().unwrap(),
    ]);
    Some((dir, tmp))
}

/// `calibrate --json` on the training postures with the validation postures held out; returns
/// the JSON document.
fn calibrate(dir: &Path, tmp: &Path, tag: &str, extra: &[&str]) -> serde_json::Value {
    let json = tmp.join(format!("{tag}.json"));
    let model = tmp.join("tiago.toml");
    let mut args = vec![
        "calibrate",
        "--model",
        model.to_str().unwrap(),
        "--units",
        "m,rad",
        "--method",
        "standard",
        "--json",
        json.to_str().unwrap(),
    ];
    let (train, valid) = (dir.join(TRAIN), dir.join(VALID));
    args.extend(["--poses", train.to_str().unwrap()]);
    args.extend(["--validate", valid.to_str().unwrap()]);
    args.extend(extra);
    let out = run(&args);
    println!("== {tag}\n{}", String::from_utf8_lossy(&out.stdout));
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

fn rms(doc: &serde_json::Value, set: &str) -> f64 {
    doc[set]["after"]["rms_mm"].as_f64().unwrap()
}

const REGISTRATION: &str = "@base,@tool";
const OFFSETS: &str = "@base,@tool,@offsets";

#[test]
fn figaroh_levels_and_the_press_compliance_model_from_the_cli() {
    let Some((dir, tmp)) = setup("levels") else {
        return;
    };
    let bl = ["--markers", "1"];
    let reg = calibrate(
        &dir,
        &tmp,
        "registration",
        &[&bl[..], &["--params", REGISTRATION]].concat(),
    );
    let off = calibrate(
        &dir,
        &tmp,
        "offsets",
        &[&bl[..], &["--params", OFFSETS]].concat(),
    );
    let geo = calibrate(
        &dir,
        &tmp,
        "geometric",
        &[&bl[..], &["--params", OFFSETS, "--select", "press"]].concat(),
    );
    let comp = calibrate(
        &dir,
        &tmp,
        "compliance",
        &[
            &bl[..],
            &["--params", OFFSETS, "--select", "press", "--compliance"],
        ]
        .concat(),
    );
    for (name, d) in [
        ("registration", &reg),
        ("offsets", &off),
        ("geometric", &geo),
        ("compliance", &comp),
    ] {
        println!(
            "{name:>12}: training {:.3} mm, validation {:.3} mm, terms {}",
            rms(d, "calibration"),
            rms(d, "validation"),
            d["terms"]
        );
        record(&format!("{name}_training_mm"), rms(d, "calibration"));
        record(&format!("{name}_validation_mm"), rms(d, "validation"));
    }
    record(
        "compliance_validation_max_mm",
        comp["validation"]["after"]["max_mm"].clone(),
    );
    // FIGAROH's published values (2 decimals) for the two levels defined identically.
    assert_eq!(reg["parameters"].as_object().unwrap().len(), 9);
    assert!((rms(&reg, "calibration") - 3.37).abs() < 0.01);
    assert!((rms(&reg, "validation") - 4.87).abs() < 0.01);
    assert!((rms(&off, "calibration") - 2.88).abs() < 0.01);
    assert!((rms(&off, "validation") - 4.23).abs() < 0.01);
    // The PRESS-selected chain constants generalise better than the offsets alone, and with
    // the gravity compliances as candidates (about each joint's axis and lateral, every one
    // within its physical bound, the torques of the calibrated chain as `fk` computes them)
    // below FIGAROH's full-parameter 3.07 mm and below 2.8 mm over all 62 held-out postures.
    assert!(rms(&geo, "validation") < rms(&off, "validation"));
    assert_eq!(comp["validation"]["after"]["n"], 62);
    assert!(
        rms(&comp, "validation") < 2.8,
        "{}",
        rms(&comp, "validation")
    );
    // PRESS takes a lateral (bearing) compliance of the shoulder: the arm's weight bends it
    // about the axes perpendicular to it
    let lateral: Vec<&String> = comp["terms"]
        .as_object()
        .unwrap()
        .keys()
        .filter(|k| k.starts_with("lateral_compliance"))
        .collect();
    assert!(!lateral.is_empty(), "{}", comp["terms"]);
    record("lateral_terms", serde_json::json!(lateral));
    assert!(comp["terms"].as_object().is_some_and(|t| !t.is_empty()));
    let key = "compliance_j7_deg_per_kgfm";
    record("compliance_j7", comp["terms"][key].clone());
    record("compliance_j7_sigma", comp["sigma"][key].clone());
    // joint 5's compliance is fitted below 0 and held at its bound: said, not kept
    assert!(comp["terms"].get("compliance_j5_deg_per_kgfm").is_none());
    let held = comp["unphysical"].as_array().unwrap();
    assert!(
        held.iter()
            .any(|u| u.as_str().unwrap().starts_with("compliance_j5")),
        "{held:?}"
    );
    let _ = std::fs::remove_dir_all(&tmp);
}

/// The backlash of the wrist as PRESS finds it: with `--hysteresis` every joint's hysteresis
/// (an angle offset by the direction from which the joint approached the posture, in the file
/// order: a backlash whose side the path sets; FIGAROH's authors report about 40 mrad of free
/// play at arm_6) is a candidate beside the chain constants and the compliances, chosen or not
/// by the same leave-one-posture-out PRESS on the 37 training postures. The written model
/// reproduces the reported held-out error through `fk` (same pose order, same hysteresis).
#[test]
fn press_takes_the_wrist_hysteresis_below_2_5_mm() {
    let Some((dir, tmp)) = setup("hysteresis") else {
        return;
    };
    let out = tmp.join("hysteresis.toml");
    let d = calibrate(
        &dir,
        &tmp,
        "hysteresis",
        &[
            "--markers",
            "1",
            "--params",
            OFFSETS,
            "--select",
            "press",
            "--compliance",
            "--hysteresis",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    let (train, valid) = (rms(&d, "calibration"), rms(&d, "validation"));
    let terms = d["terms"].as_object().unwrap();
    let hysteresis: Vec<&String> = terms
        .keys()
        .filter(|k| k.starts_with("hysteresis"))
        .collect();
    println!("hysteresis level: training {train:.4} mm, validation {valid:.4} mm, terms {terms:?}");
    record("hysteresis_training_mm", train);
    record("hysteresis_validation_mm", valid);
    record(
        "hysteresis_validation_max_mm",
        d["validation"]["after"]["max_mm"].clone(),
    );
    record("hysteresis_terms", serde_json::json!(hysteresis));
    let key = "hysteresis_j7_deg";
    record("hysteresis_j7", d["terms"][key].clone());
    record("hysteresis_j7_sigma", d["sigma"][key].clone());
    assert_eq!(d["validation"]["after"]["n"], 62);
    // arm_6 (model joint 7) is the joint with the reported free play
    assert!(terms.contains_key(key), "{terms:?}");
    assert!(valid < 2.5, "{valid}");
    // `fk` on the written model, the held-out file in its own order: the same RMS
    let fk = run(&[
        "fk",
        "--model",
        out.to_str().unwrap(),
        "--units",
        "m,rad",
        "--joints",
        dir.join(VALID).to_str().unwrap(),
    ]);
    let predicted: Vec<[f64; 3]> = String::from_utf8_lossy(&fk.stdout)
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').take(3).map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let text = std::fs::read_to_string(dir.join(VALID)).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (cx, cy, cz) = (col("x1"), col("y1"), col("z1"));
    let measured: Vec<[f64; 3]> = lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            [v[cx] * 1e3, v[cy] * 1e3, v[cz] * 1e3]
        })
        .collect();
    assert_eq!(predicted.len(), measured.len());
    let sum: f64 = predicted
        .iter()
        .zip(&measured)
        .map(|(p, m)| (0..3).map(|a| (p[a] - m[a]).powi(2)).sum::<f64>())
        .sum();
    let through_fk = (sum / measured.len() as f64).sqrt();
    println!("through fk: {through_fk:.6} mm");
    assert!((through_fk - valid).abs() < 1e-6, "{through_fk} vs {valid}");
    let _ = std::fs::remove_dir_all(&tmp);
}

/// All 4 hand points of every posture: one model and one offset per further marker, fitted
/// together; the offsets recover the mocap rigid body (data README: |BL-BR| = 158.24 mm,
/// |BL-TR| = 165.65 mm).
#[test]
fn four_markers_recover_the_rigid_body_geometry() {
    let Some((dir, tmp)) = setup("markers") else {
        return;
    };
    let d = calibrate(&dir, &tmp, "markers", &["--params", OFFSETS]);
    let p = &d["parameters"];
    let t = &d["terms"];
    let bl = [
        p["tool_dx"].as_f64().unwrap(),
        p["tool_dy"].as_f64().unwrap(),
        p["tool_dz"].as_f64().unwrap(),
    ];
    let point = |k: usize| -> [f64; 3] {
        ["x", "y", "z"].map(|a| t[format!("marker{k}_{a}_mm")].as_f64().unwrap())
    };
    let dist = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let (bl_br, bl_tr) = (dist(bl, point(2)), dist(bl, point(3)));
    println!("|BL-BR| {bl_br:.2} mm, |BL-TR| {bl_tr:.2} mm");
    record("bl_br_mm", bl_br);
    record("bl_tr_mm", bl_tr);
    assert!((bl_br - 158.24).abs() < 0.5, "{bl_br}");
    assert!((bl_tr - 165.65).abs() < 0.5, "{bl_tr}");
    let _ = std::fs::remove_dir_all(&tmp);
}

/// Every identifiable parameter with the base (`calibrate --base` on the URDF model: 37
/// postures, an ill-conditioned problem) converges in one run: the run says so
/// (`"converged": true`), and a second run started from its `--out` cannot lower the training
/// residual. The least-squares fit itself (`--prior off`: a prior would be centred on each
/// run's input, so a second run would fit a different problem); the default, with the prior
/// chosen by cross-validation, is recorded beside it (held out over all 62 postures).
#[test]
fn full_identification_converges_in_one_run() {
    let Some((dir, tmp)) = setup("converge") else {
        return;
    };
    let first_model = tmp.join("first.toml");
    let first = calibrate(
        &dir,
        &tmp,
        "full_first",
        &[
            "--markers",
            "1",
            "--base",
            "--prior",
            "off",
            "--out",
            first_model.to_str().unwrap(),
        ],
    );
    let default = calibrate(&dir, &tmp, "full_prior", &["--markers", "1", "--base"]);
    let all62 =
        |doc: &serde_json::Value| doc["validation_all"]["after"]["rms_mm"].as_f64().unwrap();
    println!(
        "held out over all 62: {:.4} mm without prior, {:.4} mm with the prior (weight {})",
        all62(&first),
        all62(&default),
        default["prior"]["weight"]
    );
    record("full_validation_all_mm", all62(&first));
    record("full_prior_validation_all_mm", all62(&default));
    record("full_prior_weight", default["prior"]["weight"].clone());
    assert_eq!(first["converged"], serde_json::Value::Bool(true));
    let again = |model: &Path, tag: &str| -> serde_json::Value {
        let json = tmp.join(format!("{tag}.json"));
        let train = dir.join(TRAIN);
        run(&[
            "calibrate",
            "--model",
            model.to_str().unwrap(),
            "--units",
            "m,rad",
            "--method",
            "standard",
            "--markers",
            "1",
            "--base",
            "--prior",
            "off",
            "--poses",
            train.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
        ]);
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
    };
    let second = again(&first_model, "full_second");
    let (r1, r2) = (rms(&first, "calibration"), rms(&second, "calibration"));
    println!(
        "full identification: {} iterations, training RMS {r1:.6} mm; second run {} iterations, {r2:.6} mm; validation {:.4} mm",
        first["iterations"], second["iterations"], rms(&first, "validation")
    );
    record("full_training_mm", r1);
    record("full_iterations", first["iterations"].clone());
    record("full_second_iterations", second["iterations"].clone());
    record("full_second_training_mm", r2);
    record("full_validation_mm", rms(&first, "validation"));
    assert!(
        r2 >= r1 * (1.0 - 1e-6),
        "a second run improved: {r1} -> {r2}"
    );
}
