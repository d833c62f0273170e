//! Writers escape everything their readers parse: model files (TOML), URDF (`model2urdf` ->
//! `urdf2model`) and the JSON outputs read back to what was written, for names with quotes,
//! markup characters, newlines and any Unicode; a name no reader can take is refused at the edge.

use std::path::Path;

use rand::{Rng, SeedableRng};
use rigctl::model::{Model, Tilt};
use rigctl::urdf::model_to_urdf;

use super::common::record::record;
use super::common::spawn::rig;

/// A random name: markup characters, quotes, entity-like text, Unicode, blanks inside.
fn random_name(rng: &mut rand_chacha::ChaCha8Rng) -> String {
    let len = rng.gen_range(1..10);
    let mut s = String::new();
    for _ in 0..len {
        match rng.gen_range(0..4) {
            0 => s.push(['&', '<', '>', '"', '\'', ';', '#', ' ', '\\', '='][rng.gen_range(0..10)]),
            1 => s.push(char::from_u32(rng.gen_range(0xa0..0x3000)).unwrap_or('x')),
            2 => s.push_str(["&#10;", "&amp;", "]]>", "<!--", "&lt"][rng.gen_range(0..5)]),
            _ => s.push(char::from(rng.gen_range(b'a'..=b'z'))),
        }
    }
    if rng.gen_bool(0.2) {
        s.push_str("&#10;");
    }
    // a joint name is a pose-file column: no comma, no outer blank, not empty
    let s = s.replace(',', ";");
    let t = s.trim();
    if t.is_empty() {
        "x".to_string()
    } else {
        t.to_string()
    }
}

/// The Katana preset with `names` as joint names.
fn katana_named(names: &[String]) -> Model {
    let mut m = rigctl::model::katana450(200.0).unwrap();
    m.set_joint_names(names.to_vec()).unwrap();
    m
}

/// Tool positions of `a` and `b` agree within 1e-6 mm at a few joint vectors.
fn same_fk(a: &Model, b: &Model, what: &str) {
    for q in [
        [0.0, 0.0, 0.0, 0.0, 0.0],
        [10.0, -40.0, 60.0, 15.0, -80.0],
        [-120.0, 30.0, -20.0, 90.0, 45.0],
    ] {
        let pa = a.fk(&q, Tilt::Off).unwrap().position_mm;
        let pb = b.fk(&q, Tilt::Off).unwrap().position_mm;
        assert!((pa - pb).norm() < 1e-6, "{what}: {q:?}: {pa} vs {pb}");
    }
}

/// `model2urdf` -> `urdf2model` keeps every joint name (markup, quotes, entity-like text,
/// Unicode) and the geometry.
#[test]
fn urdf_joint_names_round_trip() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(33);
    let cases = 200;
    for case in 0..cases {
        let names: Vec<String> = (0..5)
            .map(|k| format!("{}{k}", random_name(&mut rng)))
            .collect();
        let model = katana_named(&names);
        let text = model_to_urdf(&model).text;
        let back = super::common::import_to(&text, "tool0")
            .unwrap_or_else(|e| panic!("case {case} {names:?}: {e}\n{text}"));
        assert_eq!(back.joint_names, names, "case {case}");
        same_fk(&model, &back.model, &format!("case {case}"));
    }
    record("joint_name_sets", cases);
}

/// A model name with a newline, quotes, markup and a control character: the URDF written by
/// `model2urdf` parses (`urdf2model` exit 0), and the model file written by `calibrate --out`
/// reads back with the same name.
#[test]
fn a_model_name_with_a_newline_and_markup_reads_back_through_urdf() {
    let dir = tempfile::tempdir().unwrap();
    let mut model = katana_named(&(1..=5).map(|i| format!("a&b<{i}>\"")).collect::<Vec<_>>());
    let name = "two\nlines & <tags> \"q\" \u{7}";
    let text = model.to_toml_string().replacen(
        "name = \"katana450\"",
        &format!("name = {}", rigctl::model::toml_file::toml_string(name)),
        1,
    );
    model = Model::from_toml_str(&text, "t").unwrap();
    assert_eq!(model.name(), name);
    let m = dir.path().join("m.toml");
    std::fs::write(&m, &text).unwrap();
    let u = dir.path().join("u.urdf");
    let r = rig!(30; "model2urdf", "--model", m, "--out", u);
    assert_eq!(r.code, Some(0), "{}", r.show());
    let back = dir.path().join("back.toml");
    let r = rig!(30; "urdf2model", "--urdf", u, "--tip", "tool0", "--out", back);
    assert_eq!(r.code, Some(0), "{}", r.show());
    let again = Model::from_file(&back).unwrap();
    assert_eq!(again.joint_names(), model.joint_names());
    same_fk(&model, &again, "model2urdf -> urdf2model");
}

/// Parses `path` as JSON, failing with its text.
fn json_of(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap();
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}\n{text}", path.display()))
}

/// The JSON outputs (`simulate`'s truth.json, `calibrate --json`, `diagnose --json`, `plan
/// --json`) of a model whose names hold quotes, backslashes, newlines and Unicode parse back,
/// with the names as written.
#[test]
fn json_outputs_parse_back_with_odd_names() {
    let dir = tempfile::tempdir().unwrap();
    let names: Vec<String> = ["q\"1", "q\\2", "q é3", "q<4>", "q&5"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let mut text = katana_named(&names).to_toml_string();
    text = text.replacen(
        "name = \"katana450\"",
        "name = \"k\\n\\\"450\\\" \\\\ \\u00e9\"",
        1,
    );
    let m = dir.path().join("m.toml");
    std::fs::write(&m, &text).unwrap();
    let sim = dir.path().join("sim");
    let r = rig!(120; "simulate", "--model", m, "--val", "20", "--out", sim);
    assert_eq!(r.code, Some(0), "{}", r.show());
    let truth = json_of(&sim.join("truth.json"));
    assert!(truth.is_object());
    let cj = dir.path().join("c.json");
    let r = rig!(120; "calibrate", "--model", m, "--poses", sim.join("cal.csv"), "--json", cj);
    assert!(matches!(r.code, Some(0 | 1)), "{}", r.show());
    let c = json_of(&cj);
    let text_c = serde_json::to_string(&c).unwrap();
    assert!(text_c.contains("dth1"), "{text_c}");
    let pj = dir.path().join("p.json");
    let r = rig!(120; "plan", "--model", m, "--n", "6", "--candidates", "200", "--out",
        dir.path().join("p.csv"), "--json", pj);
    assert_eq!(r.code, Some(0), "{}", r.show());
    json_of(&pj);
    let dj = dir.path().join("d.json");
    let r = rig!(300; "diagnose", "--model", m, "--poses", sim.join("cal.csv"), "--validate",
        sim.join("val.csv"), "--json", dj);
    assert!(matches!(r.code, Some(0 | 1)), "{}", r.show());
    json_of(&dj);
}
