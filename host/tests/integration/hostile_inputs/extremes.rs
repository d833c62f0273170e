//! Absurd sizes and values (docs/reliability.md, items 2, 4 and 5): finite extreme values in a
//! model, an effect or the noise are refused at the edge (never a panic, a hang or NaN with exit
//! 0), endless inputs (`/dev/zero`) are refused at once, a wide header, a long chain and a large
//! `plan --n` stay bounded.

use std::path::Path;
use std::time::{Duration, Instant};

use super::{model_text, simulated, with, JOINTS_CSV, MODEL_DEFAULTS};
use crate::common::long_urdf::long_urdf;
use crate::common::spawn::{os, rig, run_for};

// ---------------------------------------------------------------------------------------------
// 2. Finite extreme values: refused at the edge, never a panic, a hang or NaN with exit 0.

/// fk on a model: exit 0 with finite output, or 1 / 2; never 101, never longer than the bound.
fn fk_is_sane(dir: &Path, model: &str, what: &str) -> Option<i32> {
    let m = dir.join("m.toml");
    let q = dir.join("q.csv");
    std::fs::write(&m, model).unwrap();
    std::fs::write(&q, JOINTS_CSV).unwrap();
    let r = rig!(30; "fk", "--model", m, "--joints", q);
    assert!(!r.timed_out, "{what}: fk hung: {}", r.show());
    assert!(
        matches!(r.code, Some(0..=2)),
        "{what}: fk exit {:?}: {}",
        r.code,
        r.show()
    );
    if r.code == Some(0) {
        let lower = r.stdout.to_ascii_lowercase();
        assert!(
            !lower.contains("nan") && !lower.contains("inf"),
            "{what}: exit 0 with non-finite output: {}",
            r.stdout
        );
    }
    r.code
}

#[test]
fn item2_extreme_model_values_are_refused_with_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.toml");
    let q = dir.path().join("q.csv");
    std::fs::write(&q, JOINTS_CSV).unwrap();
    assert_eq!(
        fk_is_sane(dir.path(), &model_text(&MODEL_DEFAULTS), "defaults"),
        Some(0)
    );
    for (k, v, what) in [
        (16, 1e308, "joint_scale = 1e308"),
        (17, 1e308, "joint_coupling j2 = 1e308"),
        (4, 1e308, "a chain value 1e308"),
        (11, -1e308, "joint min -1e308"),
        (12, 1e308, "joint max 1e308"),
        (20, 1e308, "mass 1e308 kg"),
    ] {
        std::fs::write(&m, model_text(&with(k, v))).unwrap();
        let r = rig!(30; "fk", "--model", m, "--joints", q);
        assert_eq!(r.code, Some(2), "fk, {what}: {}", r.show());
        let r = rig!(60; "plan", "--model", m, "--n", "8", "--candidates", "200", "--out",
            dir.path().join("p.csv"));
        assert_eq!(r.code, Some(2), "plan, {what}: {}", r.show());
        let r = rig!(60; "calibrate", "--model", m, "--poses", q);
        assert_eq!(r.code, Some(2), "calibrate, {what}: {}", r.show());
    }
    // the message names the file and the line of the value
    std::fs::write(&m, model_text(&with(4, 1e308))).unwrap();
    let r = rig!(30; "fk", "--model", m, "--joints", q);
    let line = model_text(&with(4, 1e308))
        .lines()
        .position(|l| l == "a = 1e308")
        .unwrap()
        + 1;
    assert!(
        r.stderr.contains(&format!("m.toml:{line}")),
        "no file:line in {}",
        r.show()
    );
}

#[test]
fn item2_extreme_effects_and_noise_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        vec!["--effect", "joint_scale:j1=1e308"],
        vec!["--effect", "joint_coupling:j2:j1=1e308"],
        vec!["--effect", "link_length:a2=1e308"],
        vec!["--effect", "time_drift=1e308,0,0"],
        vec!["--noise-mm", "1e308"],
    ] {
        let out = dir.path().join("s");
        let mut a: Vec<&std::ffi::OsStr> = vec![os("simulate"), os("--out"), os(&out)];
        a.extend(args.iter().map(os));
        let r = run_for(&a, Duration::from_secs(60));
        assert_eq!(r.code, Some(2), "simulate {args:?}: {}", r.show());
        assert!(
            !out.join("cal.csv").exists(),
            "simulate {args:?} wrote cal.csv"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// 4. Endless inputs are refused at once.

#[test]
fn item4_dev_zero_is_refused_by_every_reader() {
    if !Path::new("/dev/zero").exists() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(dir.path());
    let z = Path::new("/dev/zero");
    let p = dir.path().join("p.csv");
    let runs = [
        (
            "fk --model",
            rig!(20; "fk", "--model", z, "--joints", sim.join("cal.csv")),
        ),
        ("calibrate --poses", rig!(20; "calibrate", "--poses", z)),
        (
            "plan --from-diagnose",
            rig!(20; "plan", "--n", "8", "--from-diagnose", z, "--out", p),
        ),
        (
            "urdf2model --urdf",
            rig!(20; "urdf2model", "--urdf", z, "--tip", "x", "--out",
            dir.path().join("m.toml")),
        ),
        (
            "export",
            rig!(20; "export", z, "--csv", dir.path().join("csv")),
        ),
        (
            "diagnose --validate",
            rig!(20; "diagnose", "--poses", sim.join("cal.csv"),
            "--validate", z),
        ),
    ];
    for (what, r) in runs {
        assert!(!r.timed_out, "{what} /dev/zero: {}", r.show());
        assert_eq!(r.code, Some(2), "{what} /dev/zero: {}", r.show());
    }
}

// ---------------------------------------------------------------------------------------------
// 5. Scaling: the header check is linear; urdf2model on a long chain; plan --n bounded.

#[test]
fn item5_a_header_of_200k_columns_is_checked_in_linear_time() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("wide.csv");
    let mut head: Vec<String> = (1..=5).map(|j| format!("q{j}")).collect();
    head.extend((0..200_000).map(|k| format!("c{k}")));
    let row = vec!["0"; head.len()].join(",");
    std::fs::write(&f, format!("{}\n{row}\n", head.join(","))).unwrap();
    let t = Instant::now();
    let r = rig!(60; "fk", "--joints", f);
    assert_eq!(r.code, Some(0), "{}", r.show());
    assert!(t.elapsed() < Duration::from_secs(20), "{:?}", t.elapsed());
}

#[test]
fn item5_urdf2model_on_a_10k_joint_chain() {
    let dir = tempfile::tempdir().unwrap();
    let u = dir.path().join("long.urdf");
    std::fs::write(&u, long_urdf(10_000)).unwrap();
    let t = Instant::now();
    let r = rig!(120; "urdf2model", "--urdf", u, "--tip", "l10000", "--out",
        dir.path().join("m.toml"));
    assert_eq!(r.code, Some(0), "{}", r.show());
    assert!(t.elapsed() < Duration::from_secs(30), "{:?}", t.elapsed());
}

#[test]
fn item5_plan_n_is_bounded_by_the_candidates() {
    let dir = tempfile::tempdir().unwrap();
    let r = rig!(30; "plan", "--n", "1000000", "--out", dir.path().join("p.csv"));
    assert_eq!(r.code, Some(2), "{}", r.show());
    let r = rig!(30; "plan", "--n", "8", "--candidates", "100000000", "--out",
        dir.path().join("p.csv"));
    assert_eq!(r.code, Some(2), "{}", r.show());
}
