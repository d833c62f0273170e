//! Model files: the example files equal the presets, write -> read gives the identical model
//! (and bit-identical FK), the row forms expand as documented, and malformed files are bad
//! input naming the file.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigctl::error::{Classify, ErrorKind};
use rigctl::model::{katana450, ur5, GammaLaw, Model, Tilt};

fn example(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("models")
        .join(name)
}

fn random_q(m: &Model, rng: &mut ChaCha8Rng) -> Vec<f64> {
    m.joint_limits()
        .iter()
        .map(|[lo, hi]| rng.gen_range(*lo..*hi))
        .collect()
}

#[test]
fn example_files_equal_the_presets() {
    assert_eq!(
        Model::from_file(&example("katana450.toml")).unwrap(),
        katana450(200.0).unwrap()
    );
    assert_eq!(
        Model::from_file(&example("ur5.toml")).unwrap(),
        ur5().unwrap()
    );
}

#[test]
fn round_trip_is_identical() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut katana = katana450(330.0).unwrap();
    for i in 0..katana.params().len() {
        let v = katana.params()[i].value;
        // Values with long binary expansions, to catch any lossy formatting.
        katana
            .set_param_at(i, v + rng.gen_range(0.001..0.1) / 3.0)
            .unwrap();
    }
    katana.set_gamma_law(GammaLaw::Atan2);
    let mut arm = ur5().unwrap();
    arm.set_param("tool_dy", 0.07).unwrap();
    arm.set_param("tool_dz", 31.0).unwrap();
    arm.set_param("enc_j3_h2_cos", -1e-7).unwrap();
    for model in [katana, arm] {
        let text = model.to_toml_string();
        let back = Model::from_toml_str(&text, "round-trip").unwrap();
        assert_eq!(back, model, "model changed through its file:\n{text}");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.toml");
        model.write_file(&path).unwrap();
        let back = Model::from_file(&path).unwrap();
        let tilt = if model.has_tilt() {
            Tilt::Static
        } else {
            Tilt::Off
        };
        for _ in 0..20 {
            let q = random_q(&model, &mut rng);
            let (a, b) = (model.fk(&q, tilt).unwrap(), back.fk(&q, tilt).unwrap());
            assert_eq!(a.position_mm, b.position_mm);
            assert_eq!(a.rotation, b.rotation);
        }
    }
}

const ONE_JOINT_LIMITS: &str = "[[joint]]\nmin = -180.0\nmax = 180.0\n";

/// The same two-joint arm as rows and as elementary transforms must give the same FK.
#[test]
fn rows_expand_as_documented() {
    let rows = format!(
        "name = \"rows\"\n\
         [[chain]]\nop = \"dh\"\njoint = 1\ntheta = 5.0\nd = 7.0\na = 20.0\nalpha = 10.0\n\
         [[chain]]\nop = \"mdh\"\njoint = 2\nalpha = -30.0\na = 40.0\nbeta = 3.0\ntheta = -4.0\nd = 9.0\n\
         {ONE_JOINT_LIMITS}{ONE_JOINT_LIMITS}"
    );
    let elementary = format!(
        "name = \"elementary\"\n\
         [[chain]]\nop = \"rz\"\njoint = 1\nname = \"o1\"\nvalue = 5.0\n\
         [[chain]]\nop = \"tz\"\nname = \"c1\"\nvalue = 7.0\n\
         [[chain]]\nop = \"tx\"\nname = \"c2\"\nvalue = 20.0\n\
         [[chain]]\nop = \"rx\"\nname = \"c3\"\nvalue = 10.0\n\
         [[chain]]\nop = \"rx\"\nname = \"c4\"\nvalue = -30.0\n\
         [[chain]]\nop = \"tx\"\nname = \"c5\"\nvalue = 40.0\n\
         [[chain]]\nop = \"ry\"\nname = \"c6\"\nvalue = 3.0\n\
         [[chain]]\nop = \"rz\"\njoint = 2\nname = \"o2\"\nvalue = -4.0\n\
         [[chain]]\nop = \"tz\"\nname = \"c7\"\nvalue = 9.0\n\
         {ONE_JOINT_LIMITS}{ONE_JOINT_LIMITS}"
    );
    let a = Model::from_toml_str(&rows, "rows").unwrap();
    let b = Model::from_toml_str(&elementary, "elementary").unwrap();
    let names: Vec<&str> = a.param_names().take(5 + 9).collect();
    assert_eq!(
        names,
        [
            "base_x", "base_y", "base_z", "base_rx", "base_ry", "dth1", "d1", "a1", "al1", "al2",
            "a2", "be2", "dth2", "d2"
        ]
    );
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..10 {
        let q = random_q(&a, &mut rng);
        let (fa, fb) = (a.fk(&q, Tilt::Off).unwrap(), b.fk(&q, Tilt::Off).unwrap());
        assert!((fa.position_mm - fb.position_mm).norm() < 1e-12);
    }
}

#[test]
fn malformed_files_are_bad_input() {
    let good_chain = "name = \"x\"\n[[chain]]\nop = \"rz\"\njoint = 1\nname = \"dth1\"\n";
    let cases = [
        (format!("{good_chain}{ONE_JOINT_LIMITS}colour = 3\n"), "colour"),
        (good_chain.to_string(), "[[joint]]"),
        (format!("{good_chain}{ONE_JOINT_LIMITS}[params]\nnope = 1.0\n"), "nope"),
        (format!("{good_chain}{ONE_JOINT_LIMITS}[[mass]]\njoint = 1\nafter = 9\nkg = 1.0\ncom_mm = [0.0, 0.0, 0.0]\n"), "beyond"),
        (format!("{good_chain}[[joint]]\nmin = 0.0\nmax = 1.0\nclearance_deg = 0.1\n"), "clearance_deg"),
        (format!("name = \"x\"\n[[chain]]\nop = \"rz\"\njoint = 2\nname = \"q\"\n{ONE_JOINT_LIMITS}"), "order"),
        (format!("name = \"x\"\n[[chain]]\nop = \"rq\"\nname = \"q\"\nvalue = 1.0\n{ONE_JOINT_LIMITS}"), "op must be"),
        (format!("{good_chain}[[chain]]\nop = \"tx\"\nname = \"dth1\"\nvalue = 1.0\n{ONE_JOINT_LIMITS}"), "twice"),
        ("name = \"x\"\nchain = [\n".to_string(), "sample.toml"),
    ];
    for (text, needle) in cases {
        let err = Model::from_toml_str(&text, "sample.toml").unwrap_err();
        assert_eq!(err.kind(), ErrorKind::BadInput, "{err}");
        let msg = err.to_string();
        assert!(
            msg.contains("sample.toml") && msg.contains(needle),
            "message `{msg}` lacks `{needle}`"
        );
    }
    let missing = Model::from_file(std::path::Path::new("/nonexistent/m.toml")).unwrap_err();
    assert_eq!(missing.kind(), ErrorKind::BadInput);
}
