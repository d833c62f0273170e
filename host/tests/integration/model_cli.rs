//! `rigctl fk` end to end: the reference rows of katana_fk.csv (grouped by their overrides,
//! tilt flag and tool length), the output format, and bad input (exit code 2, message naming
//! the line or listing the valid names).

use crate::common;
use crate::common::spawn::output;

use std::collections::BTreeMap;
use std::process::Output;

use rigctl::model::{choose_model, ModelChoice, Tilt};

fn parse_output(out: &Output) -> Vec<[f64; 6]> {
    assert!(
        out.status.success(),
        "rigctl failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("x,y,z,phi,theta,psi"));
    lines
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .map(|f| {
                    let decimals = f.split_once('.').map_or(0, |(_, d)| d.len());
                    assert!(decimals >= 9, "`{f}` has fewer than 9 decimals");
                    f.parse().unwrap()
                })
                .collect();
            v.try_into().unwrap()
        })
        .collect()
}

#[test]
fn fk_prints_the_reference_rows() {
    let Some(path) = common::shared_file(
        "fk_prints_the_reference_rows",
        "data/reference/katana_fk.csv",
    ) else {
        return;
    };
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap();
    // (set, tilt, tool_mm) -> rows
    let mut groups: BTreeMap<(String, String, String), Vec<Vec<String>>> = BTreeMap::new();
    for l in lines {
        let f: Vec<String> = l.split(',').map(str::to_string).collect();
        groups
            .entry((f[5].clone(), f[6].clone(), f[7].clone()))
            .or_default()
            .push(f);
    }
    assert!(groups.len() >= 20);
    let dir = tempfile::tempdir().unwrap();
    let mut checked = 0;
    for ((set, tilt, tool), rows) in &groups {
        let path = dir.path().join("joints.csv");
        let body: String = rows.iter().map(|r| r.join(",") + "\n").collect();
        std::fs::write(&path, format!("# reference rows\n{header}\n{body}")).unwrap();
        let mut args = vec![
            "fk".to_string(),
            "--joints".into(),
            path.display().to_string(),
            "--tool-mm".into(),
            tool.clone(),
        ];
        let sets: Vec<String> = set
            .split(';')
            .filter(|s| !s.is_empty())
            .map(str::to_string)
            .collect();
        for s in &sets {
            args.extend(["--set".to_string(), s.clone()]);
        }
        if tilt == "1" {
            args.push("--tilt".into());
        }
        let out = parse_output(&output(
            &args.iter().map(String::as_str).collect::<Vec<_>>(),
        ));
        assert_eq!(out.len(), rows.len());
        let tool_mm: f64 = tool.parse().unwrap();
        let model = choose_model(&ModelChoice {
            tool_mm: Some(tool_mm),
            sets: &sets,
            ..Default::default()
        })
        .unwrap();
        for (row, got) in rows.iter().zip(&out) {
            let q: Vec<f64> = row[..5].iter().map(|v| v.parse().unwrap()).collect();
            let fk = model
                .fk(&q, if tilt == "1" { Tilt::Static } else { Tilt::Off })
                .unwrap();
            let [phi, theta, psi] = fk.zxz_deg();
            let lib = [
                fk.position_mm.x,
                fk.position_mm.y,
                fk.position_mm.z,
                phi,
                theta,
                psi,
            ];
            let reference: Vec<f64> = row[8..14].iter().map(|v| v.parse().unwrap()).collect();
            for k in 0..6 {
                // Printed to 9 decimals: within half a unit of the last digit of the library.
                assert!(
                    (got[k] - lib[k]).abs() <= 5.1e-10,
                    "row {row:?} output {k}: {} vs {}",
                    got[k],
                    lib[k]
                );
                // The reference itself (to the joint rounding of the file, see model_reference).
                assert!(
                    (got[k] - reference[k]).abs() < 1e-4,
                    "row {row:?} output {k}: {} vs reference {}",
                    got[k],
                    reference[k]
                );
                if q.iter().all(|&v| v == 0.0) {
                    assert!(
                        (got[k] - reference[k]).abs() < 1e-6,
                        "exact row {row:?} output {k}"
                    );
                }
            }
            checked += 1;
        }
    }
    assert_eq!(
        checked,
        text.lines().filter(|l| !l.starts_with('#')).count() - 1
    );
}

#[test]
fn fk_model_file_and_ur5() {
    let dir = tempfile::tempdir().unwrap();
    let katana = dir.path().join("k.csv");
    std::fs::write(&katana, "q1,q2,q3,q4,q5\n10,20,30,40,50\n").unwrap();
    let model_file = concat!(env!("CARGO_MANIFEST_DIR"), "/models/katana450.toml");
    let k = katana.to_str().unwrap();
    let preset = parse_output(&output(&["fk", "--joints", k, "--tilt"]));
    let from_file = parse_output(&output(&[
        "fk", "--joints", k, "--tilt", "--model", model_file,
    ]));
    assert_eq!(preset, from_file);
    let ur = dir.path().join("u.csv");
    std::fs::write(&ur, "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n").unwrap();
    let out = parse_output(&output(&[
        "fk",
        "--joints",
        ur.to_str().unwrap(),
        "--robot",
        "ur5",
    ]));
    // UR5 zero pose, standard DH: x = a2 + a3 = -817.25, y = -(d4 + d6) = -191.45, z = d1 - d5.
    let want = [-817.25, -191.45, 89.159 - 94.65];
    for k in 0..3 {
        assert!((out[0][k] - want[k]).abs() < 1e-9, "{:?}", out[0]);
    }
}

fn assert_bad_input(out: &Output, fragments: &[&str]) {
    assert_eq!(
        out.status.code(),
        Some(2),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stdout.is_empty(), "nothing may be printed on bad input");
    let err = String::from_utf8_lossy(&out.stderr);
    for f in fragments {
        assert!(err.contains(f), "stderr `{err}` lacks `{f}`");
    }
}

#[test]
fn fk_bad_input_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "# poses\nq1,q2,q3,q4,q5\n0,0,0,0,0\n1,2,3,4,oops\n").unwrap();
    let b = bad.to_str().unwrap();
    assert_bad_input(
        &output(&["fk", "--joints", b]),
        &["bad.csv:4", "q5", "not a number"],
    );
    let good = dir.path().join("good.csv");
    std::fs::write(&good, "q1,q2,q3,q4,q5\n0,0,0,0,0\n").unwrap();
    let g = good.to_str().unwrap();
    assert_bad_input(
        &output(&["fk", "--joints", g, "--set", "dth9=1"]),
        &["dth9", "valid names", "dth1", "al4", "clearance_j1"],
    );
    assert_bad_input(
        &output(&["fk", "--joints", g, "--set", "dth2"]),
        &["NAME=VALUE"],
    );
    assert_bad_input(
        &output(&["fk", "--joints", g, "--robot", "puma"]),
        &["puma"],
    );
    assert_bad_input(
        &output(&["fk", "--joints", g, "--robot", "ur5"]),
        &["5 joints in the file (q1..q5), 6 in the model"],
    );
    let ur = dir.path().join("u.csv");
    std::fs::write(&ur, "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n").unwrap();
    assert_bad_input(
        &output(&[
            "fk",
            "--joints",
            ur.to_str().unwrap(),
            "--robot",
            "ur5",
            "--tilt",
        ]),
        &["tilting"],
    );
    assert_bad_input(
        &output(&["fk", "--joints", "/nonexistent.csv"]),
        &["/nonexistent.csv"],
    );
}
