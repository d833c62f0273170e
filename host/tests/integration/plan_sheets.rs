//! `rigctl plan --sheets`: what candidate pencil sheets identify on the Katana.

use nalgebra::Vector3;
use rigctl::model::{katana450, KATANA_PENCIL_TOOL_MM};
use rigctl::plan::sheets::{candidate_specs, rank_sheets, SheetPath, SheetRows, SheetScore};
use rigctl::plan::{plan, PlanConfig, Workspace};
use rigctl::sim::session::SESSION_SHEET_ORIGIN_MM;

use crate::common::record::record;
use crate::common::spawn::rigctl;

/// On the pencil rig (Katana with the 330 mm holder): the thesis's circle is reachable; a
/// single sheet can leave parameters blind (named null-space combinations: lines, in-plane
/// measurement) and the best pair of sheets leaves fewer (none) with smaller sigmas than the
/// thesis's circle alone.
#[test]
fn blind_parameters_of_single_sheets_and_pairs() {
    let declared = katana450(KATANA_PENCIL_TOOL_MM).unwrap();
    let cfg = PlanConfig::new(&declared, 12);
    let p = plan(&declared, &cfg, None).unwrap();
    let ws = Workspace::for_model(&declared);
    for what in [SheetRows::Fused, SheetRows::Plane, SheetRows::Trace] {
        let r = rank_sheets(
            &declared,
            &candidate_specs(),
            &ws,
            &p.parameters,
            &p.scale,
            0.01,
            what,
        )
        .unwrap();
        let label = |s: &SheetScore| r.sheets[s.sheets[0]].spec.label();
        let thesis = r
            .singles
            .iter()
            .find(|s| {
                let spec = r.sheets[s.sheets[0]].spec;
                let o = spec.placement().origin_mm;
                spec.path == SheetPath::Circle
                    && (o - Vector3::from(SESSION_SHEET_ORIGIN_MM)).norm() < 1e-9
                    && spec.facing_deg == -90.0
            })
            .expect("the thesis circle is reachable");
        let worst = r.singles.last().unwrap();
        let best_pair = &r.pairs[0];
        eprintln!(
            "{what:?}: {} of {} reachable; thesis circle blind {:?} median {:.4}; worst single {} blind {:?}; best pair blind {:?} median {:.4}",
            r.sheets.len(),
            r.tried,
            thesis.blind,
            thesis.median_scaled_sigma,
            label(worst),
            worst.blind,
            best_pair.blind,
            best_pair.median_scaled_sigma
        );
        assert!(!worst.blind.is_empty(), "{what:?}: {worst:?}");
        assert!(best_pair.blind.len() < worst.blind.len(), "{best_pair:?}");
        assert!(best_pair.blind.len() <= thesis.blind.len());
        assert!(best_pair.median_scaled_sigma < thesis.median_scaled_sigma);
        // every blind combination fixes one parameter: identifiable + blind = all
        assert_eq!(
            worst.identifiable.len() + worst.blind.len(),
            r.parameters.len()
        );
        let mode = format!("{what:?}").to_lowercase();
        record("reachable", r.sheets.len());
        record("tried", r.tried);
        record("parameters", r.parameters.len());
        record(&format!("{mode}_thesis_blind"), thesis.blind.len());
        record(&format!("{mode}_thesis_condition"), thesis.condition_number);
        record(
            &format!("{mode}_thesis_median_sigma_mm"),
            thesis.median_scaled_sigma,
        );
        record(&format!("{mode}_worst_label"), label(worst));
        record(&format!("{mode}_worst_blind"), worst.blind.clone());
        record(&format!("{mode}_best_pair_blind"), best_pair.blind.len());
        record(
            &format!("{mode}_best_pair_median_sigma_mm"),
            best_pair.median_scaled_sigma,
        );
        record(
            &format!("{mode}_thesis_over_best_pair"),
            thesis.median_scaled_sigma / best_pair.median_scaled_sigma,
        );
    }
}

#[test]
fn cli_writes_the_sheets_ranking() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    let out = rigctl()
        .args([
            "plan",
            "--tool-mm",
            "330",
            "--n",
            "12",
            "--out",
            &p("plan.csv"),
            "--json",
            &p("plan.json"),
            "--sheets",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("best pairs of sheets"), "{stdout}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("plan.json")).unwrap()).unwrap();
    let sheets = &doc["sheets"];
    let first = &sheets["ranked"][0];
    for key in [
        "placement",
        "path",
        "n_samples",
        "identifiable",
        "blind",
        "condition_number",
        "median_sigma",
    ] {
        assert!(first.get(key).is_some(), "sheets.ranked[0] lacks {key}");
    }
    assert!(sheets["pairs"][0]["sheets"].as_array().unwrap().len() == 2);
    // the report shows the ranking
    let html = p("r.html");
    let out = rigctl()
        .args(["report", &dir.path().to_string_lossy(), "--html", &html])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(
        page.contains("pencil sheets reachable"),
        "report lacks the sheets"
    );
    // the UR5 has no pencil rig IK: a clear refusal, exit 2
    let out = rigctl()
        .args([
            "plan",
            "--robot",
            "ur5",
            "--n",
            "12",
            "--out",
            &p("u.csv"),
            "--sheets",
        ])
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
