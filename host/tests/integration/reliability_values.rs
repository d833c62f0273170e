//! Finite values of any size (1e+-300, 0, subnormals) in every model-file field and every URDF
//! number, through every command that reads them: exit 1 or 2 (bad input refused at the edge
//! with its file and line), or 0 with finite output, within a time bound; never 101, never NaN.
//! The seeded draws make a failure reproducible; the case counts keep the run under a minute.

use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};

use super::common::record::record;
use super::common::spawn::{rig, Run};
use super::hostile_inputs::{model_text, with, JOINTS_CSV, MODEL_DEFAULTS, N_FIELDS, URDF};

/// A token of `text` that reads as a non-finite number (`NaN`, `inf`, `-inf`, `infinity`).
fn non_finite_token(text: &str) -> Option<&str> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || matches!(c, '.' | '+' | '-' | '_')))
        .find(|t| {
            matches!(
                t.to_ascii_lowercase().trim_start_matches(['+', '-']),
                "nan" | "inf" | "infinity"
            )
        })
}

/// Exit 0, 1 or 2 within the bound (never 101, never killed); with exit 0, no NaN on stdout
/// (a report may show an infinite sigma: a parameter the data do not determine) and only
/// finite numbers in every written file among `outputs`.
fn assert_sane(r: &Run, what: &str, outputs: &[&Path]) {
    assert!(
        !r.timed_out,
        "{what}: did not end within its bound: {}",
        r.show()
    );
    assert!(matches!(r.code, Some(0..=2)), "{what}: {}", r.show());
    if r.code != Some(0) {
        return;
    }
    let nan = non_finite_token(&r.stdout).filter(|t| t.to_ascii_lowercase().contains("nan"));
    if let Some(t) = nan {
        panic!("{what}: exit 0 with `{t}` on stdout: {}", r.stdout);
    }
    for p in outputs {
        let files: Vec<PathBuf> = if p.is_dir() {
            std::fs::read_dir(p)
                .unwrap()
                .map(|e| e.unwrap().path())
                .collect()
        } else {
            vec![p.to_path_buf()]
        };
        for f in files {
            if let Ok(text) = std::fs::read_to_string(&f) {
                if let Some(t) = non_finite_token(&text) {
                    panic!("{what}: exit 0 with `{t}` in {}:\n{text}", f.display());
                }
            }
        }
    }
}

/// A random finite value: one of the extremes (1e+-300, 1e+-308, 0, the smallest subnormal),
/// a value at or just inside a physical limit of the model ranges (100 m, 10 000 deg, 360 deg,
/// +-1, 1000, 1e12, 1e6 ppm), or a random mantissa with a random exponent in [-300, 300].
fn random_finite(rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
    const SPECIALS: [f64; 11] = [
        1e300, -1e300, 1e-300, -1e-300, 1e308, -1e308, 0.0, -0.0, 1e15, -1e15, 5e-324,
    ];
    const LIMITS: [f64; 14] = [
        1e5, -1e5, 99_999.0, 1e4, -1e4, 360.0, -360.0, 1000.0, 1.0, -1.0, 0.9999, 1e12, 1e6, -1e6,
    ];
    match rng.gen_range(0..3) {
        0 => SPECIALS[rng.gen_range(0..SPECIALS.len())],
        1 => LIMITS[rng.gen_range(0..LIMITS.len())],
        _ => rng.gen_range(-10.0..10.0) * 10f64.powi(rng.gen_range(-300..=300)),
    }
}

/// The seed of the draws: `seed` unless `RELIABILITY_SEED` is set (to explore more cases by
/// hand; a failure names the case and its values).
fn seed_or_env(seed: u64) -> u64 {
    std::env::var("RELIABILITY_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(seed)
}

/// A measured pose file and held-out file of the template's default model (3 joints).
fn default_model_poses(dir: &Path) -> PathBuf {
    let m = dir.join("default.toml");
    std::fs::write(&m, model_text(&MODEL_DEFAULTS)).unwrap();
    let sim = dir.join("sim");
    let r = rig!(120; "simulate", "--model", m, "--val", "20", "--out", sim);
    assert_eq!(r.code, Some(0), "{}", r.show());
    sim
}

/// Runs every command that reads a model file on `model` (the text of `m.toml` in `dir`):
/// `fk`, `model2urdf` (and `urdf2model` on what it wrote), `calibrate`, and the slower one of
/// `plan`, `simulate` and `diagnose` chosen by `slow`.
fn every_model_reader(dir: &Path, sim: &Path, model: &str, slow: usize, what: &str) {
    let m = dir.join("m.toml");
    std::fs::write(&m, model).unwrap();
    let q = dir.join("q.csv");
    std::fs::write(&q, JOINTS_CSV).unwrap();
    let (cal, val) = (sim.join("cal.csv"), sim.join("val.csv"));
    for f in [
        "u.urdf",
        "back.toml",
        "c.toml",
        "c.json",
        "p.csv",
        "d.json",
        "d.toml",
    ] {
        let _ = std::fs::remove_file(dir.join(f));
    }
    let _ = std::fs::remove_dir_all(dir.join("s"));
    let r = rig!(30; "fk", "--model", m, "--joints", q);
    assert_sane(&r, &format!("{what}: fk"), &[]);
    assert!(
        r.code != Some(0) || non_finite_token(&r.stdout).is_none(),
        "{what}: fk {}",
        r.stdout
    );
    let u = dir.join("u.urdf");
    let r = rig!(30; "model2urdf", "--model", m, "--out", u);
    assert_sane(&r, &format!("{what}: model2urdf"), &[&u]);
    if r.code == Some(0) {
        let back = dir.join("back.toml");
        let r = rig!(30; "urdf2model", "--urdf", u, "--tip", "tool0", "--out", back);
        assert_sane(&r, &format!("{what}: urdf2model of model2urdf"), &[&back]);
    }
    let (c, cj) = (dir.join("c.toml"), dir.join("c.json"));
    let r = rig!(60; "calibrate", "--model", m, "--poses", cal, "--out", c, "--json", cj);
    assert_sane(&r, &format!("{what}: calibrate"), &[&c, &cj]);
    match slow % 3 {
        0 => {
            let p = dir.join("p.csv");
            let r = rig!(60; "plan", "--model", m, "--n", "4", "--candidates", "100",
                "--random-draws", "20", "--out", p);
            assert_sane(&r, &format!("{what}: plan --model"), &[&p]);
        }
        1 => {
            let s = dir.join("s");
            let r = rig!(60; "simulate", "--model", m, "--val", "5", "--out", s);
            assert_sane(&r, &format!("{what}: simulate --model"), &[&s]);
        }
        _ => {
            let (dj, dt) = (dir.join("d.json"), dir.join("d.toml"));
            let r = rig!(120; "diagnose", "--model", m, "--poses", cal, "--validate", val,
                "--json", dj, "--out", dt);
            assert_sane(&r, &format!("{what}: diagnose --model"), &[&dj, &dt]);
        }
    }
}

/// Random finite values (1e+-300 included) in every model-file field, one to three at a time:
/// every command that reads a model exits 0 with finite output, 1 or 2, within its bound.
#[test]
fn item2_property_random_finite_values_in_every_model_field() {
    let dir = tempfile::tempdir().unwrap();
    let sim = default_model_poses(dir.path());
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed_or_env(26));
    // every field once on its own, then random combinations
    record("model_numbers", N_FIELDS);
    for k in 0..N_FIELDS {
        let v = random_finite(&mut rng);
        let what = format!("field {k} = {v:e}");
        every_model_reader(dir.path(), &sim, &model_text(&with(k, v)), k, &what);
    }
    for case in 0..12 {
        let mut vals = MODEL_DEFAULTS;
        for _ in 0..rng.gen_range(2..=3) {
            vals[rng.gen_range(0..N_FIELDS)] = random_finite(&mut rng);
        }
        let what = format!("case {case}: {vals:?}");
        every_model_reader(dir.path(), &sim, &model_text(&vals), case, &what);
    }
}

/// The spans of the numbers in `urdf` (attribute values split on blanks).
fn urdf_numbers(urdf: &str) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let b = urdf.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let starts = (b[i].is_ascii_digit() || b[i] == b'-')
            && i > 0
            && (b[i - 1] == b'"' || b[i - 1] == b' ');
        if starts {
            let mut j = i + 1;
            while j < b.len()
                && (b[j].is_ascii_digit() || b[j] == b'.' || b[j] == b'e' || b[j] == b'-')
            {
                j += 1;
            }
            if j < b.len() && (b[j] == b'"' || b[j] == b' ') {
                out.push((i, j));
            }
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// Random finite values in every URDF number (origins, axes, limits, masses, inertias):
/// `urdf2model` exits 0, 1 or 2 within its bound, and a model it writes goes through `fk`,
/// `model2urdf` and `plan` / `simulate` the same way.
#[test]
fn item2_property_random_finite_values_in_every_urdf_number() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed_or_env(2626));
    let full = urdf_inertial();
    let numbers = urdf_numbers(&full);
    assert!(numbers.len() > 30, "{}", numbers.len());
    record("urdf_numbers", numbers.len());
    let out = dir.path().join("out.toml");
    let q = dir.path().join("q.csv");
    std::fs::write(&q, "j1,j2\n10,20\n-30,45\n").unwrap();
    let u = dir.path().join("u.urdf");
    let cases = numbers.len() + 10;
    for case in 0..cases {
        // every number once, then random ones
        let (i, j) = numbers[if case < numbers.len() {
            case
        } else {
            rng.gen_range(0..numbers.len())
        }];
        let v = random_finite(&mut rng);
        let text = format!("{}{v:e}{}", &full[..i], &full[j..]);
        let what = format!("case {case} ({v:e} for `{}`)", &full[i..j]);
        std::fs::write(&u, &text).unwrap();
        let _ = std::fs::remove_file(&out);
        let r = rig!(30; "urdf2model", "--urdf", u, "--tip", "l2", "--out", out);
        assert_sane(&r, &format!("{what}: urdf2model"), &[&out]);
        if r.code != Some(0) {
            continue;
        }
        let r = rig!(30; "fk", "--model", out, "--joints", q);
        assert_sane(&r, &format!("{what}: fk"), &[]);
        let back = dir.path().join("back.urdf");
        let r = rig!(30; "model2urdf", "--model", out, "--urdf", u, "--out", back);
        assert_sane(&r, &format!("{what}: model2urdf"), &[&back]);
        if case % 2 == 0 {
            let p = dir.path().join("p.csv");
            let r = rig!(60; "plan", "--model", out, "--n", "4", "--candidates", "100",
                "--random-draws", "20", "--out", p);
            assert_sane(&r, &format!("{what}: plan"), &[&p]);
        } else {
            let s = dir.path().join("s");
            let _ = std::fs::remove_dir_all(&s);
            let r = rig!(60; "simulate", "--model", out, "--val", "5", "--out", s);
            assert_sane(&r, &format!("{what}: simulate"), &[&s]);
        }
    }
}

/// The two-joint URDF of the hostile-input tests with inertias, limits with effort and velocity,
/// a rotated centre of mass and a fixed tool joint: every kind of number a URDF holds.
fn urdf_inertial() -> String {
    URDF.replace(
        "<mass value=\"2\"/><origin xyz=\"0.1 0 0\"/>",
        "<mass value=\"2\"/><origin xyz=\"0.1 0 0\" rpy=\"0 0.1 0\"/>\
         <inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.02\" iyz=\"0\" izz=\"0.03\"/>",
    )
    .replace(
        "<limit lower=\"-2\" upper=\"2\"/>",
        "<limit lower=\"-2\" upper=\"2\" effort=\"5\" velocity=\"1\"/>",
    )
    .replace(
        "</robot>",
        "<link name=\"tip\"/><joint name=\"tool\" type=\"fixed\"><parent link=\"l2\"/>\
         <child link=\"tip\"/><origin xyz=\"0.05 0 0.01\" rpy=\"0 0 0.2\"/></joint></robot>",
    )
}

/// A writer handed a non-finite number refuses the whole file (a failure of the run, exit 1)
/// and names the value and where it is; nothing is written.
#[test]
fn item2_a_non_finite_number_never_reaches_a_written_file() {
    use rigctl::error::{Classify, ErrorKind};
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("trace.csv");
    let e = rigctl::trace::write_csv(&csv, &[[1.0, 2.0], [3.0, f64::NAN]]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Failure);
    let msg = e.to_string();
    assert!(
        msg.contains("line 3, column y") && msg.contains("NaN"),
        "{msg}"
    );
    assert!(!csv.exists());
    rigctl::trace::write_csv(&csv, &[[1.0, 2.0]]).unwrap();
    let kept = std::fs::read(&csv).unwrap();
    assert!(rigctl::trace::write_csv(&csv, &[[f64::INFINITY, 2.0]]).is_err());
    assert_eq!(
        std::fs::read(&csv).unwrap(),
        kept,
        "the old file was replaced"
    );
    use rigctl::io::finite::TextFormat;
    for (format, name, text) in [
        (
            TextFormat::Toml,
            "m.toml",
            "name = \"m\"\n[params]\ntool_dz = nan\n",
        ),
        (
            TextFormat::Xml,
            "u.urdf",
            "<robot name=\"r\"><joint name=\"j\"><origin xyz=\"0 inf 0\"/></joint></robot>",
        ),
        (TextFormat::Csv, "p.csv", "q1,x\n1,-inf\n"),
    ] {
        let path = dir.path().join(name);
        let e = rigctl::io::atomic::write_text_atomic(&path, format, text).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Failure, "{name}");
        assert!(e.to_string().contains(name), "{e}");
        assert!(!path.exists(), "{name}");
    }
}
