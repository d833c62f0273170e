//! URDF import: the imported model's forward kinematics against an independent 4x4-matrix FK
//! computed here straight from the URDF XML, and a DH-form UR5 URDF against the `ur5` preset.

use crate::common;

use nalgebra::{Matrix3, Matrix4, Rotation3, Unit, Vector3};
use rand::{Rng, SeedableRng};
use rigctl::model::{ur5, Tilt};
use rigctl::urdf::{import_chain, ImportOptions, Urdf};

/// Independent FK: 4x4 homogeneous matrices of the URDF joints from `base` to `tip`, joint values
/// in URDF units (rad, m) keyed by joint name.
fn reference_fk(xml: &str, base: &str, tip: &str, q: &dyn Fn(&str) -> f64) -> Matrix4<f64> {
    let doc = roxmltree::Document::parse(xml).unwrap();
    let joints: Vec<roxmltree::Node> = doc
        .root_element()
        .children()
        .filter(|n| n.has_tag_name("joint"))
        .collect();
    let child_of = |j: &roxmltree::Node, tag: &str| {
        j.children()
            .find(|n| n.has_tag_name(tag))
            .and_then(|n| n.attribute("link"))
            .unwrap()
            .to_string()
    };
    let nums = |n: Option<roxmltree::Node>, attr: &str, default: [f64; 3]| -> [f64; 3] {
        match n.and_then(|n| n.attribute(attr)) {
            None => default,
            Some(t) => {
                let v: Vec<f64> = t.split_whitespace().map(|s| s.parse().unwrap()).collect();
                [v[0], v[1], v[2]]
            }
        }
    };
    let mut out = Matrix4::identity();
    let mut link = tip.to_string();
    while link != base {
        let j = joints
            .iter()
            .find(|j| child_of(j, "child") == link)
            .unwrap();
        let origin = j.children().find(|n| n.has_tag_name("origin"));
        let xyz = nums(origin, "xyz", [0.0; 3]);
        let [r, p, y] = nums(origin, "rpy", [0.0; 3]);
        let mut t = Matrix4::identity();
        let rot = Rotation3::from_euler_angles(r, p, y); // = Rz(y) Ry(p) Rx(r)
        t.fixed_view_mut::<3, 3>(0, 0).copy_from(rot.matrix());
        t.fixed_view_mut::<3, 1>(0, 3)
            .copy_from(&Vector3::from(xyz));
        let axis = nums(
            j.children().find(|n| n.has_tag_name("axis")),
            "xyz",
            [1.0, 0.0, 0.0],
        );
        let axis = Unit::new_normalize(Vector3::from(axis));
        let name = j.attribute("name").unwrap();
        let mut m = Matrix4::identity();
        match j.attribute("type").unwrap() {
            "revolute" | "continuous" => {
                let rot = Rotation3::from_axis_angle(&axis, q(name));
                m.fixed_view_mut::<3, 3>(0, 0).copy_from(rot.matrix());
            }
            "prismatic" => {
                m.fixed_view_mut::<3, 1>(0, 3)
                    .copy_from(&(axis.into_inner() * q(name)));
            }
            _ => {}
        }
        out = t * m * out;
        link = child_of(j, "parent");
    }
    out
}

/// Imports `base..tip` of `xml` and compares position (1e-9 mm) and orientation (1e-10: the
/// TIAGo tail folds to pitch -90 deg within 1e-11, where rpy extraction loses digits) of the
/// tool point `tool_mm` with the reference at 50 random joint vectors within the limits.
fn check_against_reference(xml: &str, base: &str, tip: &str, tool_mm: [f64; 3]) {
    let urdf = Urdf::parse(xml, "test.urdf").unwrap();
    let imp = import_chain(
        &urdf,
        &ImportOptions {
            base_link: Some(base),
            tip_link: tip,
            tool_mm,
        },
    )
    .unwrap();
    let model = &imp.model;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for _ in 0..50 {
        let q_model: Vec<f64> = model
            .joint_limits()
            .iter()
            .map(|[lo, hi]| rng.gen_range(*lo..=*hi))
            .collect();
        let by_name = |name: &str| {
            let i = imp.joint_names.iter().position(|n| n == name).unwrap();
            if model.joints()[i].prismatic {
                q_model[i] * 1e-3
            } else {
                q_model[i].to_radians()
            }
        };
        let t = reference_fk(xml, base, tip, &by_name);
        let r: Matrix3<f64> = t.fixed_view::<3, 3>(0, 0).into();
        let p_ref = (r * Vector3::from(tool_mm) * 1e-3 + t.fixed_view::<3, 1>(0, 3)) * 1e3;
        let fk = model.fk(&q_model, Tilt::Off).unwrap();
        assert!(
            (fk.position_mm - p_ref).norm() < 1e-9,
            "{:?} vs {:?} at {q_model:?}",
            fk.position_mm,
            p_ref
        );
        assert!((fk.rotation - r).norm() < 1e-10, "rotation at {q_model:?}");
    }
}

/// A chain with every kind of axis, fixed joints between and after, a prismatic joint along a
/// non-z axis and a continuous joint (and a transmission `<joint>` reference that must be
/// ignored).
const MIXED: &str = r#"<?xml version="1.0"?>
<robot name="mixed-axes">
  <link name="world"/><link name="a"/><link name="b"/><link name="c"/><link name="d"/>
  <link name="e"/><link name="f"/><link name="g"/><link name="tip"/><link name="side"/>
  <joint name="mount" type="fixed"><parent link="world"/><child link="a"/>
    <origin xyz="0.1 -0.2 0.3" rpy="0.1 0.2 0.3"/></joint>
  <joint name="j-1" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0 0 0.2" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-1.5" upper="1.5" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="b"/><child link="c"/>
    <origin xyz="0.05 0.1 0.3" rpy="1.5707963 -0.4 2.0"/><axis xyz="0 -1 0"/>
    <limit lower="-2" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j3" type="prismatic"><parent link="c"/><child link="d"/>
    <origin xyz="0.2 0 0" rpy="0 1.5707963267948966 0"/><axis xyz="0.6 0 0.8"/>
    <limit lower="-0.1" upper="0.25" effort="1" velocity="1"/></joint>
  <joint name="j4" type="continuous"><parent link="d"/><child link="e"/>
    <origin xyz="0 0.1 0.05"/><axis xyz="0 0 -1"/></joint>
  <joint name="bend" type="fixed"><parent link="e"/><child link="f"/>
    <origin xyz="0.01 0.02 0.03" rpy="-0.5 0.3 3.0"/></joint>
  <joint name="j5" type="revolute"><parent link="f"/><child link="g"/>
    <origin xyz="0 0 0.1" rpy="0 -1.5707963267948966 0"/><axis xyz="0.3 -0.4 0.5"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="flange" type="fixed"><parent link="g"/><child link="tip"/>
    <origin xyz="0 0 0.07" rpy="0.2 0 -0.7"/></joint>
  <joint name="other" type="fixed"><parent link="a"/><child link="side"/></joint>
  <transmission name="t"><joint name="j2"/></transmission>
</robot>"#;

#[test]
fn mixed_axes_chain_matches_matrix_fk() {
    check_against_reference(MIXED, "world", "tip", [12.0, -5.0, 30.0]);
}

#[test]
fn sub_chain_from_an_inner_base_link() {
    check_against_reference(MIXED, "c", "g", [0.0, 0.0, 0.0]);
}

#[test]
fn tiago_chain_matches_matrix_fk() {
    let rel = "data/real/thanhndv212__figaroh-examples/examples/tiago/urdf/tiago_48_schunk.urdf";
    let Some(path) = common::shared_file("tiago_chain_matches_matrix_fk", rel) else {
        return;
    };
    let xml = std::fs::read_to_string(&path).expect("read the TIAGo URDF");
    check_against_reference(
        &xml,
        "base_footprint",
        "wrist_ft_tool_link",
        [64.5, 1.1, 68.4],
    );
    // Arm only, from the torso.
    check_against_reference(&xml, "torso_lift_link", "arm_tool_link", [0.0, 0.0, 0.0]);
}

/// The UR5 DH table written as a URDF: joint i's origin is row i-1's `Tz(d) Tx(a) Rx(al)`
/// (`xyz = a 0 d`, `rpy = al 0 0`), the flange a fixed joint with row 6's.
fn ur5_dh_urdf() -> String {
    const A_M: [f64; 6] = [0.0, -0.425, -0.39225, 0.0, 0.0, 0.0];
    const AL_RAD: [f64; 6] = [
        std::f64::consts::FRAC_PI_2,
        0.0,
        0.0,
        std::f64::consts::FRAC_PI_2,
        -std::f64::consts::FRAC_PI_2,
        0.0,
    ];
    const D_M: [f64; 6] = [0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823];
    let mut s = String::from("<robot name=\"ur5_dh\"><link name=\"l0\"/>");
    for i in 0..7 {
        let (xyz, rpy) = if i == 0 {
            ("0 0 0".to_string(), "0 0 0".to_string())
        } else {
            (
                format!("{} 0 {}", A_M[i - 1], D_M[i - 1]),
                format!("{} 0 0", AL_RAD[i - 1]),
            )
        };
        let kind = if i < 6 { "revolute" } else { "fixed" };
        s += &format!(
            "<link name=\"l{}\"/><joint name=\"q{}\" type=\"{kind}\"><parent link=\"l{i}\"/>\
             <child link=\"l{}\"/><origin xyz=\"{xyz}\" rpy=\"{rpy}\"/><axis xyz=\"0 0 1\"/>\
             <limit lower=\"-6.28\" upper=\"6.28\" effort=\"1\" velocity=\"1\"/></joint>",
            i + 1,
            i + 1,
            i + 1
        );
    }
    s + "</robot>"
}

#[test]
fn ur5_dh_urdf_matches_the_ur5_preset() {
    let xml = ur5_dh_urdf();
    let urdf = Urdf::parse(&xml, "ur5_dh.urdf").unwrap();
    let imp = import_chain(
        &urdf,
        &ImportOptions {
            base_link: None,
            tip_link: "l7",
            tool_mm: [0.0, 0.07, 31.0],
        },
    )
    .unwrap();
    let mut preset = ur5().unwrap();
    preset.set_param("tool_dy", 0.07).unwrap();
    preset.set_param("tool_dz", 31.0).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for _ in 0..50 {
        let q: Vec<f64> = (0..6).map(|_| rng.gen_range(-180.0..180.0)).collect();
        let a = imp.model.fk(&q, Tilt::Off).unwrap();
        let b = preset.fk(&q, Tilt::Off).unwrap();
        assert!((a.position_mm - b.position_mm).norm() < 1e-9, "at {q:?}");
        assert!((a.rotation - b.rotation).norm() < 1e-12, "at {q:?}");
    }
}

#[test]
fn names_units_and_limits() {
    let imp = super::common::import_to(MIXED, "tip").unwrap();
    let m = &imp.model;
    assert_eq!(imp.joint_names, ["j-1", "j2", "j3", "j4", "j5"]);
    // `j-1` sanitised; its origin folds the fixed `mount` joint in.
    assert!(m.param_index("j_1_offset").is_some());
    assert!(m.param_index("base_rz").is_some());
    // j2 follows an unfolded joint whose x axis alignment is undone into j2's constants, so
    // only the offsets and the unfolded first constants equal the file: j3 is prismatic in mm.
    assert!(m.joints()[2].prismatic);
    assert_eq!(m.joint_limits()[2], [-100.0, 250.0]);
    let [lo, hi] = m.joint_limits()[0];
    assert!((lo + 1.5f64.to_degrees()).abs() < 1e-12 && (hi - 1.5f64.to_degrees()).abs() < 1e-12);
    assert_eq!(m.joint_limits()[3], [-360.0, 360.0]);
    // The tail (flange + last alignment) exists as tip_* constants.
    assert!(m.param_index("tip_rz").is_some());
}

#[test]
fn bad_inputs_are_errors_with_positions() {
    use rigctl::error::{Classify, ErrorKind};
    let cases: [(&str, &str); 5] = [
        ("<robot><link name=\"a\"/>", "XML error"),
        (
            "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>\n<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><origin xyz=\"0 x 0\"/></joint></robot>",
            ":2:",
        ),
        (
            "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"hinge\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>",
            "unknown type",
        ),
        (
            "<robot name=\"r\"><link name=\"a\"/><joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"zz\"/></joint></robot>",
            "no link `zz`",
        ),
        (
            "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>",
            "needs a <limit",
        ),
    ];
    for (xml, expect) in cases {
        let err = Urdf::parse(xml, "bad.urdf").and_then(|u| {
            import_chain(
                &u,
                &ImportOptions {
                    base_link: None,
                    tip_link: "b",
                    tool_mm: [0.0; 3],
                },
            )
        });
        let err = err.expect_err(xml);
        assert!(err.to_string().contains(expect), "{err} lacks {expect}");
        assert_eq!(err.kind(), ErrorKind::BadInput);
    }
    let urdf = Urdf::parse(MIXED, "mixed.urdf").unwrap();
    let opts = |tip| ImportOptions {
        base_link: Some("c"),
        tip_link: tip,
        tool_mm: [0.0; 3],
    };
    assert!(import_chain(&urdf, &opts("side"))
        .unwrap_err()
        .to_string()
        .contains("not below"));
}
