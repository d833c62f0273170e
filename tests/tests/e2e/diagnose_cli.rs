//! `rigctl diagnose` end to end: simulate a session with one undeclared effect, diagnose it, and
//! check the FORMATS.md JSON keys, the model file (loadable by `fk --model`), the plots and the
//! exit code on bad input.

use std::collections::BTreeSet;

use rig_tests::rigctl;

fn keys(v: &serde_json::Value) -> BTreeSet<String> {
    v.as_object()
        .map(|o| o.keys().cloned().collect())
        .unwrap_or_default()
}

#[test]
fn diagnose_writes_the_documented_json_model_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let st = rigctl()
        .args(["simulate", "--out"])
        .arg(d)
        .args(["--effect", "encoder_harmonic:j3:h1=0.04,20"])
        .status()
        .unwrap();
    assert!(st.success());
    let out = rigctl()
        .args(["diagnose", "--poses"])
        .arg(d.join("cal.csv"))
        .arg("--validate")
        .arg(d.join("val.csv"))
        .arg("--json")
        .arg(d.join("d.json"))
        .arg("--out")
        .arg(d.join("m.toml"))
        .arg("--plots")
        .arg(d.join("plots"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(table.contains("encoder_harmonic:j3:h1"), "{table}");

    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("d.json")).unwrap()).unwrap();
    for k in ["declared", "effects", "final", "unexplained"] {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    let stats_keys: BTreeSet<String> = [
        "n",
        "mean_mm",
        "rms_mm",
        "max_mm",
        "min_mm",
        "mean_abs_x_mm",
        "mean_abs_y_mm",
        "mean_abs_z_mm",
    ]
    .map(String::from)
    .into();
    for part in ["declared", "final"] {
        for set in ["calibration", "validation"] {
            assert_eq!(keys(&v[part][set]), stats_keys, "{part}.{set}");
        }
    }
    let e = &v["effects"][0];
    assert_eq!(e["id"], "encoder_harmonic:j3:h1");
    for k in [
        "parameters",
        "validation_mean_mm_before",
        "validation_mean_mm_after",
        "evidence",
    ] {
        assert!(e.get(k).is_some(), "effect key {k} missing");
    }
    assert!(
        e["validation_mean_mm_after"].as_f64().unwrap()
            < e["validation_mean_mm_before"].as_f64().unwrap()
    );
    assert!(v["unexplained"]["structured"].is_boolean() && v["unexplained"]["note"].is_string());

    // The extended model loads in fk and carries the harmonic.
    let text = std::fs::read_to_string(d.join("m.toml")).unwrap();
    assert!(text.contains("enc_j3_h1_sin"), "{text}");
    let fk = rigctl()
        .args(["fk", "--tilt", "--joints"])
        .arg(d.join("val.csv"))
        .arg("--model")
        .arg(d.join("m.toml"))
        .output()
        .unwrap();
    assert!(
        fk.status.success(),
        "{}",
        String::from_utf8_lossy(&fk.stderr)
    );
    let svg = std::fs::read_to_string(d.join("plots/01_encoder_harmonic_j3_h1.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") || svg.contains("<svg"),
        "not an SVG"
    );
}

#[test]
fn diagnose_bad_pose_file_is_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "q1,q2,q3,q4,q5,x,y,z\n0,0,0,0,0,1,2,nan\n").unwrap();
    let out = rigctl()
        .args(["diagnose", "--poses"])
        .arg(&bad)
        .arg("--validate")
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("bad.csv"));
}
