//! `rigctl simulate` end to end: the written truth, fed back to `rigctl fk`, reproduces the
//! measurements up to the noise; files are reproducible; bad effects exit with code 2.

use std::path::Path;

use rig_tests::rigctl;

fn simulate(dir: &Path, extra: &[&str]) -> std::process::Output {
    rigctl()
        .args(["simulate", "--out"])
        .arg(dir)
        .args(extra)
        .output()
        .expect("run rigctl simulate")
}

fn xyz_rows(csv: &str, first_col: usize) -> Vec<[f64; 3]> {
    csv.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let f: Vec<f64> = l
                .split(',')
                .skip(first_col)
                .take(3)
                .map(|v| v.parse().expect("number"))
                .collect();
            [f[0], f[1], f[2]]
        })
        .collect()
}

fn fk(args: &[&str], joints: &Path) -> Vec<[f64; 3]> {
    let out = rigctl()
        .args(["fk", "--joints"])
        .arg(joints)
        .args(args)
        .output()
        .expect("run rigctl fk");
    assert!(
        out.status.success(),
        "fk failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    xyz_rows(&String::from_utf8_lossy(&out.stdout), 0)
}

fn max_dist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

#[test]
fn fk_with_the_truth_reproduces_the_simulated_positions() {
    let dir = tempfile::tempdir().unwrap();
    let out = simulate(dir.path(), &["--seed", "21", "--noise-mm", "0.01"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("truth.json")).unwrap()).unwrap();
    let mut sets = Vec::new();
    for (name, v) in json["truth_parameters"].as_object().unwrap() {
        sets.push("--set".to_string());
        sets.push(format!("{name}={}", v.as_f64().unwrap()));
    }
    let mut args: Vec<&str> = vec!["--tilt"];
    args.extend(sets.iter().map(String::as_str));
    for file in ["cal.csv", "val.csv"] {
        let path = dir.path().join(file);
        let measured = xyz_rows(&std::fs::read_to_string(&path).unwrap(), 5);
        let by_set = fk(&args, &path);
        let model_path = dir.path().join("truth.toml");
        let by_file = fk(&["--tilt", "--model", model_path.to_str().unwrap()], &path);
        // 0.01 mm per coordinate: |noise| < 0.08 mm (4.6 sigma of the 3-D norm) for all poses
        let d = max_dist(&measured, &by_set);
        assert!(
            d < 0.08,
            "{file}: fk --set differs from the measurements by up to {d} mm"
        );
        assert!(
            max_dist(&by_set, &by_file) < 1e-8,
            "{file}: --set and --model disagree"
        );
        // and without the truth (declared model) the error is much larger than the noise
        let declared = fk(&["--tilt"], &path);
        assert!(
            max_dist(&measured, &declared) > 0.3,
            "{file}: geometric errors invisible"
        );
    }
    assert_eq!(
        xyz_rows(
            &std::fs::read_to_string(dir.path().join("cal.csv")).unwrap(),
            5
        )
        .len(),
        118
    );
    assert_eq!(
        xyz_rows(
            &std::fs::read_to_string(dir.path().join("val.csv")).unwrap(),
            5
        )
        .len(),
        60
    );
}

#[test]
fn noise_free_simulation_is_reproduced_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let out = simulate(
        dir.path(),
        &[
            "--seed",
            "3",
            "--noise-mm",
            "0",
            "--val",
            "10",
            "--tool-mm",
            "330",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let model_path = dir.path().join("truth.toml");
    let path = dir.path().join("cal.csv");
    let measured = xyz_rows(&std::fs::read_to_string(&path).unwrap(), 5);
    let by_file = fk(&["--tilt", "--model", model_path.to_str().unwrap()], &path);
    assert!(max_dist(&measured, &by_file) < 1e-8);
}

#[test]
fn same_seed_same_bytes() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let args = [
        "--seed",
        "8",
        "--effect",
        "encoder_harmonic:j2:h1=0.05,30",
        "--effect",
        "tool_offset=0.1,0,-0.2",
        "--val",
        "15",
    ];
    for d in [&a, &b] {
        let out = simulate(d.path(), &args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    for f in ["cal.csv", "val.csv", "truth.toml", "truth.json"] {
        assert_eq!(
            std::fs::read(a.path().join(f)).unwrap(),
            std::fs::read(b.path().join(f)).unwrap(),
            "{f}"
        );
    }
}

#[test]
fn bad_effects_and_values_exit_2_and_write_nothing() {
    for bad in [
        vec!["--effect", "warp_drive=1"],
        vec!["--effect", "tool_offset=1,2"],
        vec!["--effect", "payload=heavy"],
        vec!["--effect", "stiffness:j2=-100"],
        vec!["--noise-mm", "-1"],
        vec!["--robot", "r2d2"],
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out_dir = dir.path().join("out");
        let out = simulate(&out_dir, &bad);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{bad:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(!out_dir.join("cal.csv").exists(), "{bad:?} wrote files");
    }
}

#[test]
fn ur5_gets_random_calibration_poses() {
    let dir = tempfile::tempdir().unwrap();
    let out = simulate(
        dir.path(),
        &["--robot", "ur5", "--val", "5", "--noise-mm", "0"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let cal = std::fs::read_to_string(dir.path().join("cal.csv")).unwrap();
    assert!(cal.starts_with("q1,q2,q3,q4,q5,q6,x,y,z,t,id\n"));
    let model_path = dir.path().join("truth.toml");
    let path = dir.path().join("cal.csv");
    let by_file = fk(&["--model", model_path.to_str().unwrap()], &path);
    assert!(max_dist(&xyz_rows(&cal, 6), &by_file) < 1e-8);
}
