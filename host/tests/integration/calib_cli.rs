//! `rigctl calibrate` end to end: JSON keys, the written model, bad input.

use rigctl::model::{katana450, Tilt};

use super::common::poses::write_exact_poses;
use super::common::spawn::rigctl;

/// A Katana pose file from the declared model with `dth2 = 0.05`, `al3 = 0.03` (exact data).
fn write_poses(path: &std::path::Path, n: usize, seed: u64) {
    let mut truth = katana450(200.0).unwrap();
    truth.set_param("dth2", 0.05).unwrap();
    truth.set_param("al3", 0.03).unwrap();
    write_exact_poses(&truth, Tilt::Static, path, n, seed, "# synthetic\n");
}

#[test]
fn json_and_model_file() {
    let dir = tempfile::tempdir().unwrap();
    let (cal, val) = (dir.path().join("cal.csv"), dir.path().join("val.csv"));
    write_poses(&cal, 60, 1);
    write_poses(&val, 15, 2);
    let (json, toml) = (dir.path().join("out.json"), dir.path().join("model.toml"));
    let out = rigctl()
        .args(["calibrate", "--poses"])
        .arg(&cal)
        .arg("--validate")
        .arg(&val)
        .arg("--json")
        .arg(&json)
        .arg("--out")
        .arg(&toml)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("Average") && stdout.contains("|dP|"),
        "{stdout}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["method"], "tilting");
    for k in ["before", "after"] {
        for s in ["calibration", "validation"] {
            assert!(v[s][k]["mean_mm"].is_number(), "{s}.{k}");
        }
    }
    assert!(v["condition_number"].as_f64().unwrap() >= 1.0);
    assert!(v["unidentifiable"]
        .as_array()
        .unwrap()
        .iter()
        .any(|u| u == "be5"));
    // Exact data: the identified dth2 (deg) is the true one.
    assert!(
        (v["parameters"]["dth2"].as_f64().unwrap() - 0.05).abs() < 1e-6,
        "{}",
        v["parameters"]
    );
    assert!(v["validation"]["after"]["max_mm"].as_f64().unwrap() < 1e-4);
    // The written model reproduces the validation poses with --tilt, and calibrate loads it.
    let fk = rigctl()
        .args(["fk", "--tilt", "--model"])
        .arg(&toml)
        .arg("--joints")
        .arg(&val)
        .output()
        .unwrap();
    assert!(
        fk.status.success(),
        "{}",
        String::from_utf8_lossy(&fk.stderr)
    );
    let again = rigctl()
        .args(["calibrate", "--method", "standard", "--model"])
        .arg(&toml)
        .arg("--poses")
        .arg(&cal)
        .output()
        .unwrap();
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
}

#[test]
fn bad_input_exits_2_naming_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let cal = dir.path().join("bad.csv");
    std::fs::write(
        &cal,
        "q1,q2,q3,q4,q5,x,y,z\n0,10,20,30,40,1,2,3\n0,10,abc,30,40,1,2,3\n",
    )
    .unwrap();
    let json = dir.path().join("out.json");
    let out = rigctl()
        .args(["calibrate", "--poses"])
        .arg(&cal)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.csv") && err.contains('3') && err.contains("q3"),
        "{err}"
    );
    assert!(!json.exists());
    let good = dir.path().join("good.csv");
    write_poses(&good, 20, 3);
    let out = rigctl()
        .args(["calibrate", "--method", "magic", "--poses"])
        .arg(&good)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let out = rigctl()
        .args(["calibrate", "--params", "dth2,nonsense", "--poses"])
        .arg(&good)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nonsense"));
}
