//! Tests of the URDF export, alone ([`super::model_to_urdf`]) and into the original
//! ([`crate::urdf::model_into_urdf`]).

use super::*;
use crate::model::{Axis, ModelBuilder, Tilt};
use crate::urdf::{import_chain, ImportOptions};
use crate::urdf::{model_into_urdf, Urdf};

/// A chain with a pitch of exactly 90 deg in an origin (gimbal lock of rpy), a prismatic
/// joint and a joint offset.
fn gimbal_model() -> Model {
    let mut b = ModelBuilder::new("gimbal");
    b.constant(Motion::Trans, Axis::Z, "h", 250.0).unwrap();
    b.joint(false, "o1", 3.0, [-170.0, 170.0], None).unwrap();
    b.constant(Motion::Rot, Axis::Y, "p1", 90.0).unwrap();
    b.constant(Motion::Rot, Axis::Z, "y1", 30.0).unwrap();
    b.constant(Motion::Trans, Axis::X, "a1", 120.0).unwrap();
    b.joint(true, "o2", 5.0, [0.0, 300.0], None).unwrap();
    b.constant(Motion::Rot, Axis::Y, "p2", -90.0).unwrap();
    b.joint(false, "o3", -1.0, [-360.0, 360.0], None).unwrap();
    b.constant(Motion::Trans, Axis::Y, "a3", 40.0).unwrap();
    let mut m = b.build().unwrap();
    m.set_param("base_rx", 0.4).unwrap();
    m.set_param("tool_dz", 60.0).unwrap();
    m
}

#[test]
fn gimbal_origins_and_prismatic_joints_read_back_exactly() {
    let model = gimbal_model();
    let e = model_to_urdf(&model);
    assert!(e.text.contains("type=\"prismatic\""), "{}", e.text);
    assert!(e.text.contains("type=\"continuous\""), "{}", e.text);
    let urdf = Urdf::parse(&e.text, "g.urdf").unwrap();
    let back = import_chain(
        &urdf,
        &ImportOptions {
            base_link: None,
            tip_link: "tool0",
            tool_mm: [0.0; 3],
        },
    )
    .unwrap()
    .model;
    for q in [
        [0.0, 0.0, 0.0],
        [40.0, 120.0, -200.0],
        [-160.0, 299.0, 350.0],
    ] {
        let a = model.fk(&q, Tilt::Off).unwrap();
        let b = back.fk(&q, Tilt::Off).unwrap();
        assert!((a.position_mm - b.position_mm).norm() < 1e-9, "{q:?}");
        assert!((a.rotation - b.rotation).norm() < 1e-12, "{q:?}");
    }
    assert!(e.not_representable.is_empty(), "{:?}", e.not_representable);
}

#[test]
fn what_a_urdf_cannot_hold_is_named() {
    let mut model = gimbal_model();
    let mut terms = crate::model::transmission::JointTerms::zeros(3);
    terms.hysteresis_deg[0] = 0.05;
    model.set_transmission(terms);
    model.set_param("enc_j1_h1_sin", 0.01).unwrap();
    model.set_param("scale_ppm", 20.0).unwrap();
    model.set_param("payload_kg", 1.5).unwrap();
    let notes = model_to_urdf(&model).not_representable.join("\n");
    for word in [
        "hysteresis",
        "enc_j1_h1_sin",
        "scale_ppm = 20",
        "prismatic",
        "payload_kg",
    ] {
        assert!(notes.contains(word), "{word}: {notes}");
    }
}

#[test]
fn numbers_read_back_to_the_same_double() {
    for v in [
        0.0,
        -0.0,
        0.39225,
        1.0 / 3.0,
        1e-17,
        -2.5e-300,
        std::f64::consts::FRAC_PI_2,
        123456.789,
    ] {
        let t = num(v);
        assert_eq!(t.parse::<f64>().unwrap(), v, "{t}");
        assert!(!t.starts_with("-0") || v != 0.0, "{t}");
    }
    assert_eq!(num(0.39225), "0.39225");
    assert_eq!(num(1e-17), "1e-17");
}

#[test]
fn a_urdf_whose_base_hangs_from_another_link_is_refused() {
    let text = r#"<robot name="r">
  <link name="a"/><link name="b"/><link name="c"/>
  <joint name="fix" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="j" type="revolute"><parent link="b"/><child link="c"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"#;
    let urdf = Urdf::parse(text, "r.urdf").unwrap();
    let model = import_chain(
        &urdf,
        &ImportOptions {
            base_link: Some("b"),
            tip_link: "c",
            tool_mm: [0.0; 3],
        },
    )
    .unwrap()
    .model;
    let err = model_into_urdf(&model, text, "r.urdf", Some("b")).unwrap_err();
    assert!(err.to_string().contains("hangs from `a`"), "{err}");
    // From the root it is written, the fixed joint kept and an origin added to `j`.
    let model = import_chain(
        &urdf,
        &ImportOptions {
            base_link: None,
            tip_link: "c",
            tool_mm: [0.0; 3],
        },
    )
    .unwrap()
    .model;
    let e = model_into_urdf(&model, text, "r.urdf", None).unwrap();
    assert!(e.text.contains("<joint name=\"world_joint\""), "{}", e.text);
    assert!(e.text.contains("<child link=\"a\"/>"), "{}", e.text);
    let j = e.text.find("<joint name=\"j\"").unwrap();
    assert!(
            e.text[j..].starts_with(
                "<joint name=\"j\" type=\"revolute\"><origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n<parent link=\"b\"/>"
            ),
            "{}",
            e.text
        );
    // Everything before the added elements is the original's, but for that origin.
    let added = e.text.find("  <!-- rigctl model2urdf").unwrap();
    assert_eq!(
        e.text[..added].replace("<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n", ""),
        text[..text.rfind("</robot>").unwrap()]
    );
}
