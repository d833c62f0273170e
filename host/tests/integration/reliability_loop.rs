//! The documented loop `diagnose --json D.json` -> `plan --from-diagnose D.json` for every effect
//! id of FORMATS.md: each id, set as an aliased pair in diagnose's own JSON, is planned (exit 0).
//! An effect of the pose gets correlations before and after; a path-dependent one (hysteresis,
//! time drift, thermal) gets the measuring order that separates it, and no correlation.

use std::path::{Path, PathBuf};

use rigctl::diagnose::candidates::library_for;
use rigctl::diagnose::extended::ExtModel;

use super::common::record::record;
use super::common::spawn::rig;

/// The effect ids of FORMATS.md's table (`### Effect ids`), as written there (`<i>` unexpanded).
fn formats_ids() -> Option<Vec<String>> {
    let path = super::common::shared_file("formats_ids", "docs/FORMATS.md")?;
    let text = std::fs::read_to_string(path).unwrap();
    let table = text.split("### Effect ids").nth(1)?;
    let mut ids = Vec::new();
    for line in table.lines().skip(3).take_while(|l| l.starts_with('|')) {
        let first = line.split('|').nth(1).unwrap_or("");
        ids.extend(first.split('`').skip(1).step_by(2).map(str::to_string));
    }
    Some(ids)
}

/// Every id `plan --from-diagnose` is tested with: the diagnose library of the Katana (the
/// path-dependent ids included) and `thermal`.
fn every_id() -> Vec<String> {
    let mut ids = ids_of(rigctl::model::katana450(200.0).unwrap());
    ids.push("thermal".into());
    ids
}

/// The ids of the diagnose library of `model`, the path-dependent ones included.
fn ids_of(model: rigctl::model::Model) -> Vec<String> {
    library_for(&ExtModel::new(model), &[], true, true)
        .into_iter()
        .map(|c| c.id)
        .collect()
}

/// The ids only a model without tilting but with link masses has (`compliance:j<i>`, UR5).
fn ur5_only_ids() -> Vec<String> {
    let katana = every_id();
    ids_of(rigctl::model::ur5().unwrap())
        .into_iter()
        .filter(|id| !katana.contains(id))
        .collect()
}

/// `pattern` (`stiffness:j<i>`, `encoder_harmonic:j<i>:h<n>`) matches `id`.
fn matches_pattern(pattern: &str, id: &str) -> bool {
    let (p, i): (Vec<&str>, Vec<&str>) = (pattern.split(':').collect(), id.split(':').collect());
    p.len() == i.len()
        && p.iter().zip(&i).all(|(p, i)| match p.split_once('<') {
            Some((pre, _)) => i
                .strip_prefix(pre)
                .is_some_and(|n| n.parse::<u32>().is_ok()),
            None => p == i,
        })
}

/// A diagnosis written by `diagnose` itself (Katana with hysteresis on joint 2).
fn diagnose_json(dir: &Path) -> PathBuf {
    let sim = dir.join("sim");
    let r = rig!(120; "simulate", "--seed", "5", "--effect", "hysteresis:j2=0.03", "--val", "30",
        "--out", sim);
    assert_eq!(r.code, Some(0), "{}", r.show());
    let d = dir.join("d.json");
    let r = rig!(600; "diagnose", "--poses", sim.join("cal.csv"), "--validate",
        sim.join("val.csv"), "--json", d);
    assert!(matches!(r.code, Some(0 | 1)), "{}", r.show());
    d
}

#[test]
fn every_formats_effect_id_is_known_to_plan_from_diagnose() {
    let mut ids = every_id();
    ids.extend(ur5_only_ids());
    let Some(patterns) = formats_ids() else {
        return;
    };
    assert!(patterns.len() >= 14, "{patterns:?}");
    for p in &patterns {
        assert!(
            ids.iter().any(|id| matches_pattern(p, id)),
            "FORMATS.md effect `{p}` is not among {ids:?}"
        );
    }
}

#[test]
fn the_diagnose_plan_loop_closes_for_every_effect_id() {
    let dir = tempfile::tempdir().unwrap();
    let d = diagnose_json(dir.path());
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&d).unwrap()).unwrap();
    let (f, out, json) = (
        dir.path().join("f.json"),
        dir.path().join("p.csv"),
        dir.path().join("p.json"),
    );
    let katana = every_id().into_iter().map(|id| (id, "katana450"));
    let ur5 = ur5_only_ids().into_iter().map(|id| (id, "ur5"));
    // the Katana's library without `thermal`, which every_id() adds
    record("katana_ids", every_id().len() - 1);
    record("ur5_only_ids", ur5_only_ids().len());
    let mut path_dependent_ids = 0;
    for (id, robot) in katana.chain(ur5) {
        let mut doc = doc.clone();
        let partner = if id.contains("j2") { "dth3" } else { "dth2" };
        doc["aliased"] = serde_json::json!([
            {"a": id, "b": partner, "correlation": 0.97, "note": "set by the test"}
        ]);
        std::fs::write(&f, doc.to_string()).unwrap();
        let r = rig!(120; "plan", "--robot", robot, "--n", "12", "--candidates", "200",
            "--random-draws", "20", "--from-diagnose", f, "--out", out, "--json", json);
        assert_eq!(r.code, Some(0), "{id}: {}", r.show());
        assert!(
            r.stdout.contains(&format!("aliased {id} / {partner}")),
            "{id}: {}",
            r.stdout
        );
        let plan: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let fd = &plan["from_diagnose"];
        let pair = &fd["aliased"][0];
        let path_dependent =
            id.starts_with("hysteresis") || id.starts_with("time_drift") || id == "thermal";
        if path_dependent {
            let protocol = pair["protocol"]
                .as_str()
                .unwrap_or_else(|| panic!("{id}: {pair}"));
            assert!(protocol.starts_with(&id), "{id}: {protocol}");
            assert!(pair["correlation_after"].is_null(), "{id}: {pair}");
            assert!(
                fd["path_dependent"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .any(|p| p["id"] == id.as_str()),
                "{id}: {fd}"
            );
            assert!(r.stdout.contains("path-dependent: "), "{id}: {}", r.stdout);
            path_dependent_ids += 1;
        } else {
            let after = pair["correlation_after"]
                .as_f64()
                .unwrap_or_else(|| panic!("{id}: no correlation after: {pair}"));
            assert!((0.0..=1.0 + 1e-9).contains(&after), "{id}: {after}");
            assert!(pair["protocol"].is_null(), "{id}: {pair}");
            assert!(
                fd["separated"].as_array().is_some_and(|s| !s.is_empty()),
                "{id}: {fd}"
            );
        }
    }
    record("path_dependent_ids", path_dependent_ids);
}
