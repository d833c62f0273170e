//! `diagnose` on a tree, through the CLI, on the independent generator of
//! [`super::tree_body`] with the elastic truth of `tree_lateral.rs` (the torso's pitch joint and
//! both shoulders compliant about their axes, three of them also across; 0.4 mm motion-capture
//! noise at both hands; 300 poses fitted, 150 held out): started from the geometric model, the
//! diagnosis names elastic effects on the elastic joints only (an axial and a lateral
//! compliance of one joint told apart, or each listed as the other's `equivalent`) and ends near
//! the floor on the held-out poses. Without link masses it offers no elastic candidate and says
//! so; with assumed masses it offers them and says the masses are assumed.

use std::collections::BTreeSet;

use super::tree_body::{tree_csv, Body};
use super::tree_compliance::NOISE_MM;
use super::tree_lateral::{data, LATERAL};
use crate::common::record::record;
use crate::common::spawn::{output, path_arg, text};

/// Held-out RMS per coordinate within this factor of the noise after the diagnosis.
const FLOOR_FACTOR: f64 = 1.3;

/// The tree joints (1-based) whose truth is elastic about the axis / across it.
fn elastic_joints(truth: &Body) -> (BTreeSet<usize>, BTreeSet<usize>) {
    let axial = (0..truth.segs.len())
        .filter(|&i| truth.segs[i].compliance != 0.0)
        .map(|i| i + 1)
        .collect();
    let lateral = (0..truth.segs.len())
        .filter(|&i| LATERAL.iter().any(|(n, _)| *n == truth.segs[i].name))
        .map(|i| i + 1)
        .collect();
    (axial, lateral)
}

/// The joint and kind of an elastic effect id (`compliance:j3`, `lateral_compliance:j3`).
fn joint_of(id: &str) -> (bool, usize) {
    let (kind, j) = id.split_once(":j").unwrap();
    (kind == "lateral_compliance", j.parse().unwrap())
}

/// Runs `rigctl diagnose ARGS` and returns its JSON and stdout.
fn diagnose(args: &[&str], json: &std::path::Path) -> (serde_json::Value, String) {
    let mut all = vec!["diagnose"];
    all.extend(args);
    all.extend(["--json", path_arg(json)]);
    let run = output(&all);
    let stdout = text(&run.stdout);
    assert!(
        run.status.success(),
        "rigctl {}: {stdout}\n{}",
        all.join(" "),
        text(&run.stderr)
    );
    let doc = serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    (doc, stdout)
}

/// Held-out RMS per coordinate (mm) of a diagnosis' `final` or `declared`.
fn held_out_mm(doc: &serde_json::Value, key: &str) -> f64 {
    doc[key]["validation"]["rms_mm"].as_f64().unwrap() / 3f64.sqrt()
}

#[test]
fn tree_diagnosis_names_the_elastic_joints_and_reaches_the_floor() {
    let nominal = Body::nominal();
    let (truth, cal, val) = data(&nominal);
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (model, cal_csv, val_csv, json) = (
        d.join("body.toml"),
        d.join("cal.csv"),
        d.join("val.csv"),
        d.join("d.json"),
    );
    std::fs::write(&model, nominal.model_toml()).unwrap();
    std::fs::write(&cal_csv, tree_csv(&nominal, &cal, 1.0)).unwrap();
    std::fs::write(&val_csv, tree_csv(&nominal, &val, 1.0)).unwrap();
    let out_model = d.join("out.toml");
    let (doc, stdout) = diagnose(
        &[
            "--model",
            path_arg(&model),
            "--poses",
            path_arg(&cal_csv),
            "--validate",
            path_arg(&val_csv),
            "--instrument-mm",
            "0.4",
            "--out",
            path_arg(&out_model),
        ],
        &json,
    );
    eprintln!("{stdout}");
    let (axial, lateral) = elastic_joints(&truth);
    let effects = doc["effects"].as_array().unwrap();
    assert!(!effects.is_empty(), "{stdout}");
    let mut named = BTreeSet::new();
    for e in effects {
        let id = e["id"].as_str().unwrap();
        let (is_lateral, j) = joint_of(id);
        let right_kind = if is_lateral {
            lateral.contains(&j)
        } else {
            axial.contains(&j)
        };
        let equivalent: Vec<&str> = e["equivalent"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        // the other kind on the same joint, listed as equivalent, is a right answer too
        let other_right = equivalent.iter().any(|o| {
            let (l, k) = joint_of(o);
            k == j
                && if l {
                    lateral.contains(&k)
                } else {
                    axial.contains(&k)
                }
        });
        assert!(
            right_kind || other_right,
            "{id} named on a joint without that elasticity (equivalent {equivalent:?}): {stdout}"
        );
        named.insert(j);
    }
    let elastic: BTreeSet<usize> = axial.union(&lateral).copied().collect();
    let declared = held_out_mm(&doc, "declared");
    let fin = held_out_mm(&doc, "final");
    eprintln!(
        "named joints {named:?} of the elastic {elastic:?}; held out per coordinate \
         {declared:.4} -> {fin:.4} mm (noise {NOISE_MM})"
    );
    record("named_effects", effects.len() as u64);
    record("elastic_joints", elastic.len() as u64);
    record(
        "named_elastic_joints",
        named.intersection(&elastic).count() as u64,
    );
    record("declared_mm", declared);
    record("final_mm", fin);
    assert!(declared > FLOOR_FACTOR * NOISE_MM, "{declared}");
    assert!(
        fin <= FLOOR_FACTOR * NOISE_MM,
        "held out {fin} mm > {FLOOR_FACTOR} x {NOISE_MM}"
    );
    // the torso joint, which carries both arms, is named
    let t2 = truth.segs.iter().position(|s| s.name == "t2").unwrap() + 1;
    assert!(named.contains(&t2), "{named:?}");
    // the written tree carries the accepted values and reproduces the final held-out figure
    let fk_tree = rigctl::model::Tree::from_file(&out_model).unwrap();
    let mut ss = 0.0;
    let mut n = 0usize;
    for (q, hands) in &val {
        for (p, h) in fk_tree.tip_points_mm(q).unwrap().iter().zip(hands) {
            ss += (p - h).norm_squared();
            n += 3;
        }
    }
    let written = (ss / n as f64).sqrt();
    assert!(
        (written - fin).abs() < 1e-6,
        "the written tree gives {written} mm, the report {fin}"
    );
}

#[test]
fn without_masses_no_elastic_candidate_and_assumed_masses_are_said() {
    let nominal = Body::nominal();
    let (_, cal, val) = data(&nominal);
    // without masses: a held-out pose with the wrong marker on one hand (15 mm off) is listed by
    // its line, out of the held-out figures, in `validation_all`
    let mut val_bad = val.clone();
    val_bad[5].1[0].x += 15.0;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (model, cal_csv, val_csv, json) = (
        d.join("bare.toml"),
        d.join("cal.csv"),
        d.join("val.csv"),
        d.join("d.json"),
    );
    std::fs::write(&model, nominal.model_file(false)).unwrap();
    std::fs::write(&cal_csv, tree_csv(&nominal, &cal, 1.0)).unwrap();
    std::fs::write(&val_csv, tree_csv(&nominal, &val, 1.0)).unwrap();
    let files = [
        "--model",
        path_arg(&model),
        "--poses",
        path_arg(&cal_csv),
        "--validate",
        path_arg(&val_csv),
        "--instrument-mm",
        "0.4",
    ];
    let val_bad_csv = d.join("val_bad.csv");
    std::fs::write(&val_bad_csv, tree_csv(&nominal, &val_bad, 1.0)).unwrap();
    let mut bad_files = files;
    bad_files[5] = path_arg(&val_bad_csv);
    let (doc, stdout) = diagnose(&bad_files, &json);
    let listed: Vec<(&str, u64)> = doc["outliers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| (o["file"].as_str().unwrap(), o["line"].as_u64().unwrap()))
        .filter(|(file, _)| *file == "val")
        .collect();
    assert_eq!(listed, [("val", 7)], "{stdout}");
    let all = doc["final"]["validation_all"]["rms_mm"].as_f64().unwrap() / 3f64.sqrt();
    assert!(all > 1.1 * held_out_mm(&doc, "final"), "{stdout}");
    assert!(doc["candidates"].as_array().unwrap().is_empty());
    assert!(doc["effects"].as_array().unwrap().is_empty());
    assert!(stdout.contains("no link masses"), "{stdout}");
    assert_eq!(doc["verdict"], "missing_effect", "{stdout}");
    // where to look: the joints whose angles carry the elastic bends the model lacks, each a
    // joint of the tree, with the share it explains
    let depends: Vec<&str> = doc["unexplained"]["depends_on"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    eprintln!(
        "where to look: {depends:?} {}",
        doc["unexplained"]["depends_on_shares"]
    );
    assert!(!depends.is_empty(), "{stdout}");
    let joints = nominal.segs.len();
    for v in &depends {
        let i: usize = v.trim_start_matches('q').parse().unwrap();
        assert!((1..=joints).contains(&i), "{v}");
    }
    let mut args = files.to_vec();
    args.push("--assume-masses");
    let (doc, stdout) = diagnose(&args, &json);
    assert!(stdout.contains("link masses ASSUMED"), "{stdout}");
    assert!(doc["assumed_masses"]["total_kg"].as_f64().unwrap() > 0.0);
    assert!(!doc["effects"].as_array().unwrap().is_empty(), "{stdout}");
    let fin = held_out_mm(&doc, "final");
    eprintln!("{stdout}\nassumed masses: held out {fin:.4} mm per coordinate");
    record("assumed_final_mm", fin);
    assert!(
        fin <= 1.4 * NOISE_MM,
        "assumed masses: held out {fin} mm > 1.4 x {NOISE_MM}"
    );
}
