//! Hostile inputs (docs/reliability.md): the diagnose -> plan loop, files that must read back,
//! inputs that must be refused; the shared two-joint URDF and model template. Outputs that are
//! inputs and concurrent runs are in `outputs`, finite absurd values, endless files and scaling
//! in `extremes`. Every test spawns the CLI with a time bound and never accepts exit 101.

mod extremes;
mod outputs;

use std::path::{Path, PathBuf};
use std::time::Duration;

use rand::{Rng, SeedableRng};

use super::common::spawn::{os, rig, run_for, Run};

/// `simulate --seed 3` into `dir/sim`.
fn simulated(dir: &Path) -> PathBuf {
    let out = dir.join("sim");
    let r = rig!(120; "simulate", "--seed", "3", "--out", out);
    assert_eq!(r.code, Some(0), "{}", r.show());
    out
}

/// Exit 2 and the file unchanged.
fn refused_and_kept(r: &Run, file: &Path, before: &[u8], what: &str) {
    assert_eq!(r.code, Some(2), "{what}: {}", r.show());
    assert_eq!(
        std::fs::read(file).unwrap(),
        before,
        "{what}: {} was changed",
        file.display()
    );
}

pub(crate) const URDF: &str = r#"<robot name="two">
  <link name="base"/>
  <link name="l1"><inertial><mass value="2"/><origin xyz="0.1 0 0"/></inertial></link>
  <link name="l2"><inertial><mass value="1"/><origin xyz="0.1 0 0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.2" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.3 0 0" rpy="1.5707963 0 0"/><axis xyz="0 0 1"/><limit lower="-2" upper="2"/></joint>
</robot>
"#;

pub(crate) const MODEL_TEMPLATE: &str = r#"name = "prop"
[[chain]]
op = "tz"
name = "mount_z"
value = {0}
[[chain]]
op = "rz"
joint = 1
name = "dth1"
value = {1}
[[chain]]
op = "dh"
joint = 2
theta = {2}
d = {3}
a = {4}
alpha = {5}
[[chain]]
op = "mdh"
joint = 3
alpha = {6}
a = {7}
beta = {8}
theta = {9}
d = {10}
[[joint]]
min = {11}
max = {12}
clearance_deg = {13}
backlash_deg = {14}
stiffness_kgfm_per_deg = {15}
joint_scale = {16}
joint_coupling = { j2 = {17} }
hysteresis_deg = {18}
compliance_deg_per_kgfm = {19}
{plain_joint}
{plain_joint}
[[mass]]
joint = 2
after = 0
kg = {20}
com_mm = [{21}, 0.0, 0.0]
[params]
tool_dz = {22}
payload_kg = {23}
scale_ppm = {24}
tool_dx = {25}
base_rx = {26}
base_z = {27}
"#;

/// Valid values of the template's fields.
pub(crate) const MODEL_DEFAULTS: [f64; N_FIELDS] = [
    200.0, 0.0, 0.0, 0.0, 190.0, 90.0, 0.0, 139.0, 0.0, 0.0, 0.0, -170.0, 170.0, 0.02, 0.06, 120.0,
    1e-4, 0.002, 0.03, 0.01, 1.5, 100.0, 12.5, 0.5, 10.0, 3.0, 0.01, 1.0,
];

/// The numbers of the template: chain values (0-10), joint limits (11, 12), tilting (13-15),
/// transmission terms (16-19), a link mass and its centre (20, 21), tool, payload, scale, base
/// (22-27).
pub(crate) const N_FIELDS: usize = 28;

/// `{:e}` gives `1e300`, `-2.5e-7`: valid TOML floats.
fn toml_float(v: f64) -> String {
    format!("{v:e}")
}

/// Joints 2 and 3 of the template.
const PLAIN_JOINT: &str = "[[joint]]
min = -170.0
max = 170.0
clearance_deg = 0.02
backlash_deg = 0.06
stiffness_kgfm_per_deg = 120.0";

pub(crate) fn model_text(values: &[f64; N_FIELDS]) -> String {
    let mut s = MODEL_TEMPLATE.replace("{plain_joint}", PLAIN_JOINT);
    for (k, v) in values.iter().enumerate().rev() {
        s = s.replace(&format!("{{{k}}}"), &toml_float(*v));
    }
    s
}

pub(crate) fn with(k: usize, v: f64) -> [f64; N_FIELDS] {
    let mut vals = MODEL_DEFAULTS;
    vals[k] = v;
    vals
}

pub(crate) const JOINTS_CSV: &str = "q1,q2,q3\n10,20,30\n-5,40,-60\n0,0,0\n";

// ---------------------------------------------------------------------------------------------
// 3. diagnose -> plan --from-diagnose for the path-dependent effect ids.

#[test]
fn item3_from_diagnose_takes_hysteresis_and_time_drift() {
    let dir = tempfile::tempdir().unwrap();
    for (a, b) in [
        ("hysteresis:j2", "dth2"),
        ("time_drift", "base_z"),
        ("time_drift:j3", "dth3"),
    ] {
        let doc = serde_json::json!({
            "declared": {"calibration": {"rms_mm": 0.05}},
            "effects": [],
            "final": {},
            "aliased": [{"a": a, "b": b, "correlation": 0.95, "note": ""}]
        });
        let d = dir.path().join("d.json");
        std::fs::write(&d, doc.to_string()).unwrap();
        let r = rig!(240; "plan", "--n", "8", "--candidates", "300", "--from-diagnose", d,
            "--out", dir.path().join("p.csv"));
        assert!(
            !r.stderr.contains("is neither an effect id"),
            "{a}: {}",
            r.show()
        );
        assert_eq!(r.code, Some(0), "{a}: {}", r.show());
        assert!(
            r.stdout.contains(&format!("aliased {a} / {b}")),
            "{a}: {}",
            r.stdout
        );
    }
}

// ---------------------------------------------------------------------------------------------
// 6. Files written read back.

#[test]
fn item6_a_model_name_with_a_newline_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(dir.path());
    let m = dir.path().join("m.toml");
    let text = std::fs::read_to_string(sim.join("truth.toml")).unwrap();
    let name_line = text.lines().find(|l| l.starts_with("name = ")).unwrap();
    std::fs::write(
        &m,
        text.replacen(name_line, "name = \"two\\nlines \\\"q\\\" \\u0007\"", 1),
    )
    .unwrap();
    let out = dir.path().join("out.toml");
    let r = rig!(60; "calibrate", "--model", m, "--poses", sim.join("cal.csv"), "--out", out);
    assert_eq!(r.code, Some(0), "{}", r.show());
    let r = rig!(30; "fk", "--model", out, "--joints", sim.join("val.csv"));
    assert_eq!(
        r.code,
        Some(0),
        "the written model does not read back: {}",
        r.show()
    );
    let back = rigctl::model::Model::from_file(&out).unwrap();
    assert_eq!(back.name(), "two\nlines \"q\" \u{7}");
}

#[test]
fn item6_a_urdf_joint_name_that_is_no_column_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let u = dir.path().join("u.urdf");
    std::fs::write(&u, URDF.replace("name=\"j2\"", "name=\"j&#10;2\"")).unwrap();
    let out = dir.path().join("m.toml");
    let r = rig!(30; "urdf2model", "--urdf", u, "--tip", "l2", "--out", out);
    if r.code == Some(0) {
        let q = dir.path().join("q.csv");
        std::fs::write(&q, "q1,q2\n1,2\n").unwrap();
        let r = rig!(30; "fk", "--model", out, "--joints", q);
        assert_eq!(r.code, Some(0), "written, not read back: {}", r.show());
    } else {
        assert_eq!(r.code, Some(2), "{}", r.show());
        assert!(!out.exists());
    }
}

#[test]
fn item6_property_model_names_round_trip() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
    let base = rigctl::model::katana450(200.0).unwrap();
    let text = base.to_toml_string();
    for _ in 0..300 {
        let len = rng.gen_range(0..12);
        let name: String = (0..len)
            .map(|_| match rng.gen_range(0..4) {
                0 => char::from(rng.gen_range(0u8..0x20)),
                1 => ['"', '\\', '\u{7f}', '\u{85}', '\'', '#'][rng.gen_range(0..6)],
                2 => char::from_u32(rng.gen_range(0x80..0x3000)).unwrap_or('x'),
                _ => char::from(rng.gen_range(b' '..b'~')),
            })
            .collect();
        let line = text.lines().find(|l| l.starts_with("name = ")).unwrap();
        let renamed = text.replacen(
            line,
            &format!("name = {}", rigctl::model::toml_file::toml_string(&name)),
            1,
        );
        let m = rigctl::model::Model::from_toml_str(&renamed, "t")
            .unwrap_or_else(|e| panic!("{name:?}: {e}"));
        assert_eq!(m.name(), name);
        let again = rigctl::model::Model::from_toml_str(&m.to_toml_string(), "t").unwrap();
        assert_eq!(again.name(), name);
        assert_eq!(again.to_toml_string(), m.to_toml_string());
    }
}

// ---------------------------------------------------------------------------------------------
// 8. Inputs that must be refused.

#[test]
fn item8_inputs_that_must_be_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sim = simulated(d);
    let cal = sim.join("cal.csv");
    let val = sim.join("val.csv");
    let p = d.join("p.csv");

    // report on a diagnose.json of the wrong shape
    let run = d.join("run");
    std::fs::create_dir(&run).unwrap();
    std::fs::copy(&cal, run.join("cal.csv")).unwrap();
    std::fs::write(run.join("diagnose.json"), r#"{"effects": "none"}"#).unwrap();
    let r = rig!(60; "report", run, "--html", d.join("r.html"));
    assert_eq!(r.code, Some(2), "report: {}", r.show());

    // potcal --recording with a jig of raw counts (the recording is not used)
    let jig = d.join("jig.csv");
    std::fs::write(&jig, "raw,travel_mm\n1000,0\n2000,5\n3000,10\n").unwrap();
    let pot_out = d.join("pot.toml");
    for strict in [false, true] {
        let mut a = vec![
            os("potcal"),
            os("--points"),
            os(&jig),
            os("--recording"),
            os("/nonexistent"),
            os("--out"),
            os(&pot_out),
        ];
        if strict {
            a.push(os("--strict"));
        }
        let r = run_for(&a, Duration::from_secs(30));
        assert_eq!(r.code, Some(2), "potcal --recording: {}", r.show());
    }

    // URDF link mass 1e308
    let u = d.join("u.urdf");
    std::fs::write(
        &u,
        URDF.replace("<mass value=\"2\"/>", "<mass value=\"1e308\"/>"),
    )
    .unwrap();
    let r = rig!(30; "urdf2model", "--urdf", u, "--tip", "l2", "--out", d.join("m.toml"));
    assert_eq!(r.code, Some(2), "URDF mass 1e308: {}", r.show());

    // fused samples with u parallel to n
    let fused = d.join("fused.csv");
    let mut text = format!(
        "# {}\n{}\n",
        rigctl::fusion::fused_file::FUSED_FORMAT,
        rigctl::fusion::fused_file::fused_header(5)
    );
    for k in 0..40 {
        let q = 5.0 * k as f64;
        text.push_str(&format!(
            "{k},{q},{},{},{},0,300,0,200,0.01,0,0,1,0.02,0,0,1\n",
            80.0 + q / 10.0,
            -30.0,
            q / 2.0
        ));
    }
    std::fs::write(&fused, text).unwrap();
    let r = rig!(60; "calibrate", "--samples", fused);
    assert_eq!(r.code, Some(2), "u parallel to n: {}", r.show());
    assert!(r.stderr.contains("perpendicular"), "{}", r.show());

    // plan --cone-deg nan
    let r = rig!(30; "plan", "--n", "8", "--visible-from", "0,0,2000", "--cone-deg", "nan",
        "--out", p);
    assert_eq!(r.code, Some(2), "--cone-deg nan: {}", r.show());

    // a pot calibration with raw_min > raw_max
    let pot = |min: f64, max: f64| {
        format!(
            "format = \"rigctl-potcal/1\"\npoints = 3\ncoefficients = [0.0, 5.0]\n\
             centre_raw = 2000.0\nhalf_range_raw = 1000.0\nraw_min = {min:?}\nraw_max = {max:?}\n"
        )
    };
    let read = |text: String| {
        rigctl::fusion::potcal::PotCalibration::from_toml_str(&text, Path::new("pot.toml"))
    };
    assert!(
        read(pot(1000.0, 3000.0)).is_ok(),
        "{:?}",
        read(pot(1000.0, 3000.0)).err()
    );
    assert!(
        read(pot(3000.0, 1000.0)).is_err(),
        "raw_min > raw_max accepted"
    );

    // two spellings of one coupling key
    let m = d.join("m.toml");
    let model = model_text(&MODEL_DEFAULTS).replace("{ j2 = ", "{ j02 = 0.2, j2 = ");
    std::fs::write(&m, model).unwrap();
    let q = d.join("q.csv");
    std::fs::write(&q, JOINTS_CSV).unwrap();
    let r = rig!(30; "fk", "--model", m, "--joints", q);
    assert_eq!(r.code, Some(2), "j2 and j02: {}", r.show());

    // a from-diagnose file with a == b, or effects that are not an array
    for doc in [
        r#"{"aliased": [{"a": "dth2", "b": "dth2", "correlation": 1.0}]}"#,
        r#"{"effects": "x", "aliased": [{"a": "dth2", "b": "dth3", "correlation": 0.95}]}"#,
    ] {
        let f = d.join("d.json");
        std::fs::write(&f, doc).unwrap();
        let r = rig!(60; "plan", "--n", "8", "--candidates", "200", "--from-diagnose", f,
            "--out", p);
        assert_eq!(r.code, Some(2), "{doc}: {}", r.show());
    }

    // calibrate on one pose
    let one = d.join("one.csv");
    let cal_text = std::fs::read_to_string(&cal).unwrap();
    let mut lines = cal_text.lines().filter(|l| !l.starts_with('#'));
    std::fs::write(
        &one,
        format!("{}\n{}\n", lines.next().unwrap(), lines.next().unwrap()),
    )
    .unwrap();
    let r = rig!(60; "calibrate", "--poses", one);
    assert_eq!(r.code, Some(2), "calibrate on 1 pose: {}", r.show());

    // the same file as calibration and held-out data
    let r = rig!(60; "diagnose", "--poses", cal, "--validate", cal);
    assert_eq!(r.code, Some(2), "--poses X --validate X: {}", r.show());
    let r = rig!(60; "calibrate", "--poses", val, "--validate", val);
    assert_eq!(r.code, Some(2), "--poses X --validate X: {}", r.show());
}

// 9. A duplicate link name is named as such.
#[test]
fn item9_a_duplicate_link_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let u = dir.path().join("u.urdf");
    std::fs::write(
        &u,
        URDF.replace("<link name=\"l1\">", "<link name=\"base\">"),
    )
    .unwrap();
    let r = rig!(30; "urdf2model", "--urdf", u, "--tip", "l2", "--out", dir.path().join("m.toml"));
    assert_eq!(r.code, Some(2), "{}", r.show());
    assert!(
        r.stderr.contains("second link named `base`"),
        "{}",
        r.show()
    );
}

// 9. A truncated JPEG is named as such.
#[test]
fn item9_a_truncated_jpeg_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let img = image::RgbImage::from_fn(256, 256, |x, y| {
        image::Rgb([(x % 251) as u8, (y % 241) as u8, ((x * y) % 239) as u8])
    });
    let mut bytes = Vec::new();
    image::DynamicImage::ImageRgb8(img)
        .write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Jpeg,
        )
        .unwrap();
    let whole = dir.path().join("whole.jpg");
    let cut = dir.path().join("cut.jpg");
    std::fs::write(&whole, &bytes).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let r = rig!(60; "trace", cut, "--out", dir.path().join("t.csv"));
    assert!(r.stderr.contains("truncated"), "{}", r.show());
    assert!(matches!(r.code, Some(1..=2)), "{}", r.show());
    let r = rig!(60; "trace", whole, "--out", dir.path().join("t.csv"));
    assert!(!r.stderr.contains("truncated"), "{}", r.show());
}
