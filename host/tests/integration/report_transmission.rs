//! `rigctl report` evaluates a model file with its transmission terms (model file `[[joint]]`
//! keys), as `fk` and `calibrate` do: on poses simulated with joint hysteresis and a joint
//! scale error, the model file that carries the terms explains them down to the noise, the
//! same model without them does not.

use crate::common::record::record;
use crate::common::spawn::rigctl;

use rigctl::model::katana450;
use rigctl::model::transmission::JointTerms;
use rigctl::report::{build_report, ReportOptions};

#[test]
fn report_applies_a_model_files_transmission_terms() {
    let dir = tempfile::tempdir().unwrap();
    let out = rigctl()
        .args(["simulate", "--seed", "7", "--geometric-sigma-deg", "0"])
        .args(["--noise-mm", "0.001", "--effect", "hysteresis:j2=0.05"])
        .args(["--effect", "joint_scale:j3=0.002", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let declared = katana450(200.0).unwrap();
    declared
        .write_file(&dir.path().join("without.toml"))
        .unwrap();
    let mut with = declared.clone();
    let mut terms = JointTerms::zeros(with.n_joints());
    terms.hysteresis_deg[1] = 0.05;
    terms.scale[2] = 0.002;
    with.set_transmission(terms);
    with.write_file(&dir.path().join("with.toml")).unwrap();
    let report = build_report(dir.path(), &ReportOptions::default()).unwrap();
    for title in ["Calibration poses", "Held-out poses"] {
        let t = report.tables.iter().find(|t| t.title == title).unwrap();
        let mean = |name: &str| {
            let c = t.columns.iter().position(|c| c.starts_with(name)).unwrap();
            let row = t
                .rows
                .iter()
                .find(|r| r.statistic == "Average" && r.quantity == "|dP|")
                .unwrap();
            row.values[c].unwrap()
        };
        let (w, wo) = (mean("with.toml"), mean("without.toml"));
        println!("{title}: with the terms {w:.4} mm, without {wo:.4} mm");
        let set = match title {
            "Calibration poses" => "calibration",
            _ => "held_out",
        };
        record(&format!("{set}_with_mm"), w);
        record(&format!("{set}_without_mm"), wo);
        assert!(w < 0.005, "{title}: with the terms {w} mm");
        assert!(wo > 0.1, "{title}: without the terms {wo} mm");
    }
}
