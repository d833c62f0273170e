//! What a calibration on real data writes: the README's UR5 example keeps the tool frame's
//! orientation; a fit that moves the geometry further than a real arm's errors exits 1 and
//! writes no model; TIAGo's kept parameters keep their input values and its compliance stays
//! within its physical bound.

use super::{s, tiago_sets, ur5_files};
use crate::common;
use crate::common::spawn::{output, text};

/// The README's UR5 example: the SMR is 0.07 mm off joint 6's axis, so joint 6's offset and the
/// tool point's x are one direction; the tool point is fitted, joint 6 kept at its input, and
/// the calibrated tool frame's orientation stays within 1 deg of the nominal one at every
/// held-out pose (what `model2urdf` writes as tool0), the held-out error unchanged.
#[test]
fn ur5_frees_the_tool_point_not_joint_6s_offset() {
    let Some((model, cal, val)) = common::ur5_tracker("ur5_frees_the_tool_point") else {
        return;
    };
    let opts = rigctl::calib::CalibrateOptions {
        method: rigctl::calib::Method::Standard,
        base: true,
        ..Default::default()
    };
    let out = rigctl::calib::calibrate(&model, &cal, Some(&val), &opts).unwrap();
    let fitted = &out.model;
    assert_eq!(
        fitted.param("dth6"),
        model.param("dth6"),
        "joint 6's offset kept"
    );
    assert_ne!(
        fitted.param("tool_dx"),
        model.param("tool_dx"),
        "the tool point fitted"
    );
    assert!(rigctl::calib::large_changes::large_changes(&model, fitted).is_empty());
    let mut worst_deg: f64 = 0.0;
    for q in &val.poses.q_deg {
        let a = model.fk(q, rigctl::model::Tilt::Off).unwrap().rotation;
        let b = fitted.fk(q, rigctl::model::Tilt::Off).unwrap().rotation;
        let r = nalgebra::Rotation3::from_matrix_unchecked(a.transpose() * b);
        worst_deg = worst_deg.max(r.angle().to_degrees());
    }
    assert!(worst_deg < 1.0, "tool frame turned {worst_deg} deg");
    let after = out.report.validation.unwrap().after.mean_mm;
    assert!(after <= 0.1008, "held out {after}");
}

/// A model whose upper arm is 25 mm short of the robot's: the registration passes (a few per
/// cent of scale), the fit moves `a2` by 25 mm, beyond the 5 % of 425 mm a real arm is off by:
/// exit 1 naming it, the JSON lists it, no model written; `--allow-large-changes` writes it and
/// says so.
#[test]
fn a_calibration_that_moves_a_link_by_25_mm_is_not_written() {
    let Some((grid, random)) = ur5_files("a_calibration_that_moves_a_link") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (json, model) = (d.join("c.json"), d.join("c.toml"));
    let args = [
        "calibrate",
        "--robot",
        "ur5",
        "--set",
        "tool_dy=0.07",
        "--set",
        "tool_dz=31",
        "--set",
        "a2=-400",
        "--base",
        "--method",
        "standard",
        "--poses",
        s(&grid),
        "--validate",
        s(&random),
        "--json",
        s(&json),
        "--out",
        s(&model),
    ];
    let out = output(&args);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("a2 -400.0000 -> -42"), "{err}");
    assert!(!model.exists(), "model written");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let listed = doc["large_changes"].as_array().unwrap();
    assert!(listed.iter().any(|c| c["parameter"] == "a2"), "{listed:?}");
    let mut allowed = args.to_vec();
    allowed.push("--allow-large-changes");
    let out = output(&allowed);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("allowed by --allow-large-changes"));
    assert!(model.exists());
}

/// TIAGo with every identifiable parameter (`--base`, the default selection) on 37 postures:
/// every parameter the JSON lists as fixed is written at exactly its input value; among the
/// confounded ones the instrument frame is fitted (`base_z`, not the torso's height, which a
/// fit once traded for a 20 deg tilt of the torso), so nothing moves beyond a real arm's errors
/// and the model is written; the set is ill-posed (31 parameters on 37 postures), so a prior is
/// chosen by cross-validation and said; the held-out figure over all 62 postures is in the
/// JSON, and the two postures whose joints leave the training ranges are reported as
/// extrapolation, not gross errors.
#[test]
fn tiago_kept_parameters_keep_their_input_and_the_instrument_frame_is_fitted() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let Some((model, cal, val)) = tiago_sets("tiago_kept", d) else {
        return;
    };
    let (json, out_model) = (d.join("c.json"), d.join("c.toml"));
    let out = output(&[
        "calibrate",
        "--model",
        s(&model),
        "--poses",
        s(&cal),
        "--validate",
        s(&val),
        "--units",
        "m,rad",
        "--markers",
        "1",
        "--base",
        "--method",
        "standard",
        "--json",
        s(&json),
        "--out",
        s(&out_model),
    ]);
    let (err, said) = (text(&out.stderr), text(&out.stdout));
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(out_model.exists());
    assert!(
        said.contains("chosen by leave-one-pose-out cross-validation"),
        "{said}"
    );
    assert!(said.contains("held-out line 6"), "{said}");
    let input = rigctl::model::Model::from_file(&model).unwrap();
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let fixed = doc["fixed"].as_array().unwrap();
    assert!(fixed.len() > 10, "{fixed:?}");
    for name in fixed {
        let name = name.as_str().unwrap();
        let written = doc["parameters"][name].as_f64().unwrap();
        assert_eq!(written, input.param(name).unwrap(), "{name} kept but moved");
        assert!(doc["sigma"].get(name).is_none_or(|v| v.is_null()), "{name}");
        let file = rigctl::model::Model::from_file(&out_model).unwrap();
        assert_eq!(file.param(name), input.param(name), "{name} written moved");
    }
    assert!(doc["sigma"]["base_z"].is_number(), "{}", doc["sigma"]);
    assert!(fixed.iter().any(|f| f == "torso_lift_joint_z"), "{fixed:?}");
    assert!(
        doc.get("large_changes").is_none(),
        "{}",
        doc["large_changes"]
    );
    assert!(doc["prior"]["weight"].as_f64().unwrap() > 0.0);
    assert_eq!(doc["validation_all"]["after"]["n"], 62);
    let held_out_flags = doc["outliers"].as_array().unwrap();
    assert!(
        held_out_flags.iter().all(|o| o["file"] != "val"),
        "{held_out_flags:?}"
    );
    let lines: Vec<i64> = doc["extrapolated"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["line"].as_i64().unwrap())
        .collect();
    assert!(lines.contains(&2) && lines.contains(&6), "{lines:?}");
}

/// TIAGo, the PRESS level with compliance: no compliance is kept below its physical bound (the
/// one bounds table; the negative one is held at 0 and said), the written model reproduces the
/// reported held-out RMS through `fk` (the gravity torques of the calibrated chain in the fit
/// and in `fk`), and `diagnose` started from that model ends no worse than it started.
#[test]
fn tiago_compliance_level_is_bounded_reproducible_and_diagnose_keeps_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let Some((model, cal, val)) = tiago_sets("tiago_compliance_level", d) else {
        return;
    };
    let (json, out_model) = (d.join("c.json"), d.join("c.toml"));
    let common_args = [
        "--units",
        "m,rad",
        "--poses",
        s(&cal),
        "--validate",
        s(&val),
    ];
    let mut args = vec!["calibrate", "--model", s(&model), "--markers", "1"];
    args.extend(common_args);
    args.extend([
        "--method",
        "standard",
        "--params",
        "@base,@tool,@offsets",
        "--select",
        "press",
        "--compliance",
        "--json",
        s(&json),
        "--out",
        s(&out_model),
    ]);
    let out = output(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for (name, v) in doc["terms"].as_object().unwrap() {
        if name.starts_with("compliance") || name.starts_with("lateral_compliance") {
            assert!(v.as_f64().unwrap() >= 0.0, "{name} = {v}");
        }
    }
    let reported = doc["validation"]["after"]["rms_mm"].as_f64().unwrap();
    let fk = output(&[
        "fk",
        "--model",
        s(&out_model),
        "--joints",
        s(&val),
        "--units",
        "m,rad",
    ]);
    assert!(fk.status.success(), "{}", text(&fk.stderr));
    let body = std::fs::read_to_string(&val).unwrap();
    let mut rows = body.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let (x1, y1, z1) = (col("x1"), col("y1"), col("z1"));
    let predicted = text(&fk.stdout);
    let mut ss = 0.0;
    let mut n = 0;
    for (m, p) in rows.zip(predicted.lines().skip(1)) {
        let m: Vec<f64> = m
            .split(',')
            .map(|c| c.parse().unwrap_or(f64::NAN))
            .collect();
        let p: Vec<f64> = p.split(',').map(|c| c.parse().unwrap()).collect();
        let e = [
            m[x1] * 1000.0 - p[0],
            m[y1] * 1000.0 - p[1],
            m[z1] * 1000.0 - p[2],
        ];
        ss += e.iter().map(|v| v * v).sum::<f64>();
        n += 1;
    }
    let through_fk = (ss / n as f64).sqrt();
    assert_eq!(n, 62);
    assert!(
        (through_fk - reported).abs() < 1e-6,
        "fk {through_fk} vs reported {reported}"
    );
    let dj = d.join("d.json");
    let mut args = vec!["diagnose", "--model", s(&out_model), "--marker", "1"];
    args.extend(common_args);
    args.extend(["--instrument-mm", "0.3", "--json", s(&dj)]);
    let out = output(&args);
    assert!(
        out.status.code().is_some_and(|c| c <= 1),
        "{}",
        text(&out.stderr)
    );
    let dd: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&dj).unwrap()).unwrap();
    let start = doc["calibration"]["after"]["rms_mm"].as_f64().unwrap();
    let end = dd["final"]["calibration"]["rms_mm"].as_f64().unwrap();
    assert!(end <= start * (1.0 + 1e-9), "diagnose {start} -> {end}");
    // its held-out figures are over all 62 postures: 2 and 6 leave the training ranges and are
    // extrapolation, not gross errors
    for stage in ["declared", "final"] {
        assert_eq!(dd[stage]["validation_all"]["n"], 62, "{stage}");
    }
    let flagged = dd["outliers"].as_array().unwrap();
    assert!(flagged.iter().all(|o| o["file"] != "val"), "{flagged:?}");
    // the model as given is the declared fit (its geometric refit ends above it): a candidate is
    // tested with its own unknowns, not with every geometric parameter freed again beside it
    // (which counted 34 added parameters for one hysteresis and made every BIC +90)
    let tested: Vec<&serde_json::Value> = dd["rejected"]
        .as_array()
        .unwrap()
        .iter()
        .chain(dd["effects"].as_array().unwrap())
        .collect();
    assert!(!tested.is_empty(), "{dd}");
    for t in tested {
        let added = t["added_parameters"].as_u64().unwrap();
        assert!((1..=3).contains(&added), "{t}");
    }
}
