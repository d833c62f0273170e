//! `report` on a tree's run, through the CLI, on the independent generator of
//! [`super::tree_body`] with the elastic truth of `tree_lateral.rs` (0.4 mm noise at both hands,
//! 300 poses fitted, 150 held out): the run directory holds the tree model, the pose files,
//! `calibrate --compliance --json` with its calibrated tree, `diagnose --json` with its model
//! and a tree plan. The page speaks of the tree (not of a default chain), counts its figures in
//! points (one per hand of a pose), ends its stages at the diagnosis' final model, and evaluates
//! the pose files with the trees: the nominal column per hand equals the generator's own
//! kinematics, the calibrated tree's column equals the calibration's held-out figure. Without
//! the tree model file the page says the pose files were not evaluated and why.

use std::path::Path;

use nalgebra::Vector3;
use rigctl::report::{build_report, ReportOptions};

use super::tree_body::{tree_csv, Body};
use super::tree_lateral::{data, Poses};
use crate::common::spawn::{output_ok, path_arg, text};

/// Mean |measured - nominal| (mm) of hand `tip` over `poses`, by the generator's kinematics.
fn nominal_mean_mm(nominal: &Body, poses: &Poses, tip: usize) -> f64 {
    let e: Vec<f64> = poses
        .iter()
        .map(|(q, hands)| (hands[tip] - nominal.hands_mm(q)[tip]).norm())
        .collect();
    e.iter().sum::<f64>() / e.len() as f64
}

/// Mean of `|v|` over every hand of every pose.
fn mean_all(nominal: &Body, poses: &Poses) -> f64 {
    let e: Vec<Vector3<f64>> = poses
        .iter()
        .flat_map(|(q, hands)| {
            let fk = nominal.hands_mm(q);
            hands.iter().zip(fk).map(|(h, f)| h - f).collect::<Vec<_>>()
        })
        .collect();
    e.iter().map(|v| v.norm()).sum::<f64>() / e.len() as f64
}

/// The run directory: model, poses, calibration, diagnosis and plan.
fn write_run(d: &Path, nominal: &Body, cal: &Poses, val: &Poses) {
    let p = |name: &str| d.join(name).display().to_string();
    std::fs::write(d.join("body.toml"), nominal.model_toml()).unwrap();
    std::fs::write(d.join("cal.csv"), tree_csv(nominal, cal, 1.0)).unwrap();
    std::fs::write(d.join("val.csv"), tree_csv(nominal, val, 1.0)).unwrap();
    let (model, cal_csv, val_csv) = (p("body.toml"), p("cal.csv"), p("val.csv"));
    let files = [
        "--model",
        &model,
        "--poses",
        &cal_csv,
        "--validate",
        &val_csv,
    ];
    let (cj, ct, dj, dt) = (
        p("calibrate.json"),
        p("calibrated.toml"),
        p("diagnose.json"),
        p("diagnosed.toml"),
    );
    let mut a = vec!["calibrate"];
    a.extend(files);
    a.extend(["--compliance", "--json", &cj, "--out", &ct]);
    output_ok(&a);
    let mut a = vec!["diagnose"];
    a.extend(files);
    a.extend(["--instrument-mm", "0.4", "--json", &dj, "--out", &dt]);
    output_ok(&a);
    let (plan_csv, plan_json) = (p("plan.csv"), p("plan.json"));
    output_ok(&[
        "plan",
        "--model",
        &model,
        "--n",
        "20",
        "--candidates",
        "400",
        "--no-table",
        "--out",
        &plan_csv,
        "--json",
        &plan_json,
    ]);
}

#[test]
fn a_tree_run_is_reported_as_a_tree_counted_in_points_and_evaluated_per_hand() {
    let nominal = Body::nominal();
    let (_truth, cal, val) = data(&nominal);
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_run(d, &nominal, &cal, &val);
    let page = d.join("page.html");
    let model = d.join("body.toml");
    let stdout = text(
        &output_ok(&[
            "report",
            path_arg(d),
            "--model",
            path_arg(&model),
            "--html",
            path_arg(&page),
        ])
        .stdout,
    );
    assert!(stdout.contains(" 0 notes "), "{stdout}");
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        !html.contains("katana"),
        "a default chain named on a tree's page"
    );

    let opts = ReportOptions {
        model_file: Some(model.clone()),
        ..Default::default()
    };
    let report = build_report(d, &opts).unwrap();
    let about = report.summary.about.join("\n");
    assert!(
        about.contains("`upper_body`") && about.contains("l_hand, r_hand"),
        "{about}"
    );
    // the stages: held-out points (150 poses x 2 hands), the last one the diagnosis' final model
    let h = &report.summary.headlines[0];
    assert_eq!(h.set, "300 held-out points", "{h:?}");
    let diag: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("diagnose.json")).unwrap()).unwrap();
    let last = h.stages.last().unwrap();
    let final_mean = diag["final"]["validation"]["mean_mm"].as_f64().unwrap();
    assert!(last.label.contains("effects found"), "{h:?}");
    assert!((last.mean_mm - final_mean).abs() < 1e-9, "{h:?}");
    let declared_mean = diag["declared"]["validation"]["mean_mm"].as_f64().unwrap();
    assert!(
        h.stages
            .iter()
            .any(|s| (s.mean_mm - declared_mean).abs() < 1e-9),
        "{h:?}"
    );

    // the pose files evaluated with the trees: every hand's table, its nominal column by the
    // generator's kinematics, the calibrated tree's column the calibration's figure
    let cal_doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("calibrate.json")).unwrap()).unwrap();
    let table = |title: &str| {
        report
            .tables
            .iter()
            .find(|t| t.title == title)
            .unwrap_or_else(|| {
                let titles: Vec<&str> = report.tables.iter().map(|t| t.title.as_str()).collect();
                panic!("no table `{title}` in {titles:?}")
            })
    };
    let all = table("Held-out poses");
    assert_eq!((all.n, all.noun), (300, "points"));
    let nominal_all = all.get("Average", "|dP|", 0).unwrap();
    assert!(
        (nominal_all - mean_all(&nominal, &val)).abs() < 1e-3,
        "{nominal_all} vs the generator's {}",
        mean_all(&nominal, &val)
    );
    let calibrated = all
        .columns
        .iter()
        .position(|c| c.starts_with("calibrated.toml"))
        .unwrap_or_else(|| panic!("{:?}", all.columns));
    // the declared model file (in the run directory) is the nominal column, not one of its own
    assert!(
        !all.columns.iter().any(|c| c.starts_with("body.toml")),
        "{:?}",
        all.columns
    );
    let after = cal_doc["validation"]["after"]["mean_mm"].as_f64().unwrap();
    let got = all.get("Average", "|dP|", calibrated).unwrap();
    assert!((got - after).abs() < 1e-4 * after, "{got} vs {after}");
    for (k, hand) in ["l_hand", "r_hand"].iter().enumerate() {
        let t = table(&format!("Held-out poses, tip `{hand}`"));
        assert_eq!((t.n, t.noun), (150, "poses"));
        let ours = t.get("Average", "|dP|", 0).unwrap();
        let theirs = nominal_mean_mm(&nominal, &val, k);
        assert!((ours - theirs).abs() < 1e-3, "{hand}: {ours} vs {theirs}");
        // the hands are not the same numbers twice
        assert!(t.get("Average", "|dP|", calibrated).unwrap() > 0.0);
    }
    let captions: Vec<&str> = report.figures.iter().map(|f| f.caption.as_str()).collect();
    for hand in ["l_hand", "r_hand"] {
        assert!(
            captions
                .iter()
                .any(|c| c.starts_with(&format!("Held-out poses, tip `{hand}`"))),
            "{captions:?}"
        );
    }
    // the plan's poses drawn per hand
    let plan = report.plan.as_ref().expect("the plan section");
    assert_eq!(plan.n_poses, Some(20));
    let fig = plan.figure.as_ref().expect("the plan figure");
    assert!(fig.caption.contains("every tip's point"), "{}", fig.caption);

    // without the tree model file: the tree named from the documents, the pose files not
    // evaluated and said so
    let bare = build_report(d, &ReportOptions::default()).unwrap();
    assert!(
        bare.summary.about.join("\n").contains("`upper_body`"),
        "{:?}",
        bare.summary.about
    );
    assert!(
        bare.notes
            .iter()
            .any(|n| n.contains("pose files not evaluated") && n.contains("--model")),
        "{:?}",
        bare.notes
    );
    assert!(bare.tables.iter().all(|t| t.noun == "points"));

    // a held-out file of another robot (a joint this tree does not have): skipped with a note
    // naming it and the joint, the calibration file still evaluated
    let csv = std::fs::read_to_string(d.join("val.csv")).unwrap();
    let (header, rest) = csv.split_once('\n').unwrap();
    let first_joint = header.split(',').next().unwrap();
    let other = format!(
        "{}\n{rest}",
        header.replacen(first_joint, "other_robot_joint", 1)
    );
    std::fs::write(d.join("val.csv"), other).unwrap();
    let mixed = build_report(d, &opts).unwrap();
    assert!(
        mixed
            .notes
            .iter()
            .any(|n| n.starts_with("Held-out poses skipped") && n.contains("not in the file: t1)")),
        "{:?}",
        mixed.notes
    );
    let titles: Vec<&str> = mixed.tables.iter().map(|t| t.title.as_str()).collect();
    assert!(
        titles.contains(&"Calibration poses, tip `l_hand`"),
        "{titles:?}"
    );
    assert!(
        !titles.iter().any(|t| t.starts_with("Held-out poses, tip")),
        "{titles:?}"
    );
}
