//! Issue 15, defects 4 (absurd finite values), 5 (BOM in every reader) and 8 (messages, URDF
//! loops, --rtol nan).

use std::path::Path;

use rigctl::io::table::Table;

use super::common::spawn::{rigctl, text};

const FUSED_HEADER: &str = "t,q1,q2,q3,q4,q5,nom_x,nom_y,nom_z,dev_u,u_x,u_y,u_z,dev_n,n_x,n_y,n_z";
const FUSED_ROW: &str = "1.5,10,100,-80,20,5,300,-100,200,0.01,1,0,0,0.02,0,0,1";

#[test]
fn defect4_absurd_finite_values_are_refused_with_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let poses = dir.path().join("p.csv");
    std::fs::write(
        &poses,
        "q1,q2,q3,q4,q5,x,y,z\n0,90,-90,0,0,1,2,3\n10,100,-80,20,5,1e300,2,3\n",
    )
    .unwrap();
    let o = rigctl()
        .args(["calibrate", "--poses"])
        .arg(&poses)
        .output()
        .unwrap();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("p.csv:3") && err.contains("`x`"), "{err}");

    let jig = dir.path().join("jig.csv");
    std::fs::write(&jig, "raw,travel_mm\n1000,0\n1e300,5\n3000,10\n").unwrap();
    let out = dir.path().join("pot.toml");
    let o = rigctl()
        .args(["potcal", "--points"])
        .arg(&jig)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains(":3"), "{}", text(&o.stderr));
    assert!(!out.exists());

    let fused = format!(
        "{FUSED_HEADER}\n{FUSED_ROW}\n{}\n",
        FUSED_ROW.replacen("1.5", "1e300", 1)
    );
    let e = rigctl::fusion::fused_file::parse_fused(&fused, Path::new("f.csv"), 5).unwrap_err();
    assert!(e.to_string().contains("f.csv:3"), "{e}");

    // The limits themselves: a century of seconds, 100 m, 10 000 deg.
    let ok = Table::parse("t,x,q1\n3e9,99999,-9999\n", "ok.csv").unwrap();
    assert!(ok.number(&ok.rows[0], 0).is_ok());
    assert!(ok.number(&ok.rows[0], 1).is_ok());
    assert!(ok.number(&ok.rows[0], 2).is_ok());
    let bad = Table::parse("t,x,q1\n4e9,100001,-10001\n", "bad.csv").unwrap();
    for col in 0..3 {
        let e = bad.number(&bad.rows[0], col).unwrap_err().to_string();
        assert!(
            e.contains("bad.csv:2") && e.contains("out of physical range"),
            "{e}"
        );
    }
}

#[test]
fn defect5_every_reader_accepts_a_utf8_bom() {
    let dir = tempfile::tempdir().unwrap();
    let bom = |name: &str, body: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, format!("\u{feff}{body}")).unwrap();
        p
    };
    let fused = bom("fused.csv", &format!("{FUSED_HEADER}\n{FUSED_ROW}\n"));
    assert_eq!(rigctl::fusion::read_fused(&fused, 5).unwrap().len(), 1);
    let trace = bom("trace.csv", "x,y\n0,0\n1,0\n2,0\n");
    assert_eq!(
        rigctl::fusion::curve::read_trace_csv(&trace).unwrap().len(),
        3
    );
    let jig = bom("jig.csv", "raw,travel_mm\n1000,0\n2000,5\n");
    assert!(rigctl::fusion::potcal::read_jig_csv(&jig).is_ok());
    let path = bom("path.csv", "x,y,z\n300,0,200\n310,0,200\n");
    assert_eq!(rigctl::compensate::read_path(&path).unwrap().len(), 2);
    let model = rigctl::model::katana450(200.0).unwrap();
    let readings = bom(
        "tilt.csv",
        "joint,config,q1,q2,q3,q4,q5,incl_x_deg,incl_y_deg,incl_z_deg\n2,a,0,90,-90,0,0,0.1,0.2,0\n",
    );
    assert!(rigctl::joints::read_readings(&readings, &model).is_ok());
}

#[test]
fn defect8_messages_name_the_file_urdf_loops_and_rtol_nan() {
    let dir = tempfile::tempdir().unwrap();
    // A blank scan: "no fiducials found" names the scan.
    let scan = dir.path().join("blank.png");
    image::RgbImage::from_pixel(400, 300, image::Rgb([250, 250, 250]))
        .save(&scan)
        .unwrap();
    let o = rigctl()
        .arg("trace")
        .arg(&scan)
        .arg("--out")
        .arg(dir.path().join("t.csv"))
        .output()
        .unwrap();
    let err = text(&o.stderr);
    assert_ne!(o.status.code(), Some(0));
    assert!(err.contains("blank.png"), "{err}");

    // A URDF whose joints loop is refused even with --base-link.
    let urdf = dir.path().join("loop.urdf");
    let joint = |name: &str, parent: &str, child: &str| {
        format!(
            "<joint name=\"{name}\" type=\"revolute\"><parent link=\"{parent}\"/><child link=\"{child}\"/>\
             <origin xyz=\"0 0 0.1\" rpy=\"0 0 0\"/><axis xyz=\"0 0 1\"/>\
             <limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>"
        )
    };
    std::fs::write(
        &urdf,
        format!(
            "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><link name=\"c\"/><link name=\"d\"/>{}{}{}{}</robot>",
            joint("j1", "a", "b"),
            joint("j2", "b", "c"),
            joint("j3", "c", "d"),
            joint("j4", "d", "b"),
        ),
    )
    .unwrap();
    let o = rigctl()
        .args(["urdf2model", "--urdf"])
        .arg(&urdf)
        .args(["--tip", "c", "--base-link", "b", "--out"])
        .arg(dir.path().join("m.toml"))
        .output()
        .unwrap();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("loop"), "{err}");

    // --rtol nan is usage error.
    let o = rigctl()
        .args(["calibrate", "--poses", "x.csv", "--rtol", "nan"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("rtol"));
}

/// Found by the `model_toml` fuzz target: `joint = 0` in a chain entry underflowed (a panic in
/// a debug build) instead of being refused.
#[test]
fn fuzz_finding_model_file_with_joint_0_is_refused() {
    let text = include_str!("../../fuzz/seeds/model_toml/regression-joint-0.toml");
    let e = rigctl::model::Model::from_toml_str(text, "joint0.toml").unwrap_err();
    assert!(e.to_string().contains("joint 0"), "{e}");
}
