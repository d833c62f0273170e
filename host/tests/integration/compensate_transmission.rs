//! `rigctl compensate` with a model file's transmission terms (joint scale, coupling,
//! hysteresis, compliance): the commanded joints, read back through `rigctl fk` with the same
//! model file (which applies the terms in the file's pose order), put the tool point on the
//! path; the same joints without the terms miss it. A reversal smaller than a joint's
//! hysteresis dead band is held and reported (a warning naming the path line and joint), never
//! failed.

use crate::common;
use crate::common::record::record;
use crate::common::spawn::output;

use std::path::Path;

use nalgebra::Vector3;
use rigctl::compensate::transmission::commands_for;
use rigctl::model::ik::{tool_target, IkTilt};
use rigctl::model::transmission::JointTerms;
use rigctl::model::{katana450, Model};

/// The Katana with a payload (tilting), geometric errors and transmission terms.
fn model_with_terms() -> Model {
    let mut m = katana450(200.0).unwrap();
    for (name, delta) in [("dth2", 0.3), ("dth3", -0.2), ("al3", 0.1)] {
        let v = m.param(name).unwrap();
        m.set_param(name, v + delta).unwrap();
    }
    m.set_param("payload_kg", 0.5).unwrap();
    let mut t = JointTerms::zeros(m.n_joints());
    t.scale[1] = 0.004;
    t.coupling[2][1] = 0.003;
    t.hysteresis_deg[1] = 0.05;
    t.hysteresis_deg[3] = 0.04;
    t.compliance_deg_per_kgfm[2] = 0.02;
    m.set_transmission(t);
    m
}

/// A line out and back (41 points, t every 0.1 s): every joint reverses at the far end.
fn path_csv() -> String {
    let nominal = katana450(200.0).unwrap();
    let start = tool_target(&nominal, &[-90.0, 60.0, -70.0, -20.0, 80.0], IkTilt::Off).unwrap();
    let span = Vector3::new(80.0, 40.0, -80.0);
    let mut s = String::from("t,x,y,z,ax,ay,az\n");
    for i in 0..41 {
        let u = if i <= 20 { i } else { 40 - i } as f64 / 20.0;
        let (x, a) = (start.position_mm + span * u, start.axis);
        s.push_str(&common::path_row(i as f64 * 0.1, &x, &a));
    }
    s
}

fn rows(csv: &str) -> Vec<Vec<f64>> {
    csv.lines()
        .skip(1)
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect()
}

fn fk(model: &Path, joints: &Path) -> Vec<Vec<f64>> {
    fk_tilt(model, joints, true)
}

/// `rigctl fk` of `joints` through `model`, with the declared tilting or without.
fn fk_tilt(model: &Path, joints: &Path, tilt: bool) -> Vec<Vec<f64>> {
    let mut args = vec![
        "fk".as_ref(),
        "--model".as_ref(),
        model.as_os_str(),
        "--joints".as_ref(),
        joints.as_os_str(),
    ];
    if tilt {
        args.push("--tilt".as_ref());
    }
    let o = output(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    rows(&String::from_utf8_lossy(&o.stdout))
}

/// `rigctl compensate --path path --model model --no-nominal [extra] --out out`; its output.
fn compensate(path: &Path, model: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "compensate".as_ref(),
        "--path".as_ref(),
        path.as_os_str(),
        "--model".as_ref(),
        model.as_os_str(),
        "--no-nominal".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ];
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    let o = output(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

#[test]
fn compensated_joints_through_fk_recover_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let (model_file, plain_file) = (dir.path().join("m.toml"), dir.path().join("plain.toml"));
    let model = model_with_terms();
    model.write_file(&model_file).unwrap();
    let mut plain = model.clone();
    plain.set_transmission(JointTerms::default());
    plain.write_file(&plain_file).unwrap();
    let text = path_csv();
    let (path, out) = (dir.path().join("path.csv"), dir.path().join("joints.csv"));
    std::fs::write(&path, &text).unwrap();
    let o = compensate(&path, &model_file, &out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    let want = rows(&text);
    let got = fk(&model_file, &out);
    let without = fk(&plain_file, &out);
    assert_eq!(got.len(), want.len());
    // The path lines the warning lists (q2 turns round mid-line in small steps).
    let held: Vec<usize> = stderr
        .split("line ")
        .skip(1)
        .filter_map(|s| s.split_whitespace().next()?.parse().ok())
        .collect();
    let (mut worst, mut worst_held) = (0.0f64, 0.0f64);
    let (mut least_without, mut worst_without) = (f64::INFINITY, 0.0f64);
    for (i, ((w, g), n)) in want.iter().zip(&got).zip(&without).enumerate() {
        let d = |p: &[f64]| {
            (0..3)
                .map(|c| (p[c] - w[1 + c]).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        match held.contains(&(i + 2)) {
            true => worst_held = worst_held.max(d(g)),
            false => worst = worst.max(d(g)),
        }
        least_without = least_without.min(d(n));
        worst_without = worst_without.max(d(n));
    }
    println!(
        "through the terms: worst {worst:.2e} mm, {} held point(s) worst {worst_held:.3} mm; \
         without the terms at least {least_without:.3} mm",
        held.len()
    );
    record("free_points", want.len() - held.len());
    record("held_points", held.len());
    record("worst_mm", worst);
    record("worst_held_mm", worst_held);
    record("least_without_mm", least_without);
    record("worst_without_mm", worst_without);
    assert!(worst < 1e-6, "compensated path missed by {worst} mm");
    assert!(
        least_without > 0.05,
        "the terms change only {least_without} mm"
    );
    // Held: q2 within 2 x 0.05 deg of its angle, < 1.1 mm at the Katana's reach.
    assert!(
        (1..=6).contains(&held.len()) && stderr.contains("(q2)"),
        "{stderr}"
    );
    assert!(worst_held < 1.1, "held points off by {worst_held} mm");
}

/// One joint with hysteresis b: a reversal by less than 2b is held (the joint stays where
/// it was, the point listed), a larger one is reached exactly; fk's pose order is used.
#[test]
fn a_reversal_inside_the_dead_band_is_held() {
    let mut m = katana450(200.0).unwrap();
    let mut t = JointTerms::zeros(m.n_joints());
    t.hysteresis_deg[0] = 0.03;
    t.scale[0] = 0.01;
    m.set_transmission(t);
    let base = [-90.0, 60.0, -70.0, -20.0, 80.0];
    let with_q1 = |q1: f64| {
        let mut q = base.to_vec();
        q[0] = q1;
        q
    };
    // up, up, back by 0.02 (< 0.06: held), back by 0.2 (reached), then still.
    let q_eff: Vec<Vec<f64>> = [-90.0, -80.0, -80.02, -80.2, -80.2]
        .into_iter()
        .map(with_q1)
        .collect();
    let c = commands_for(&m, &q_eff, None).unwrap();
    assert_eq!(c.held, [(2, 0)]);
    assert_eq!(c.q_deg[2][0], c.q_deg[1][0]);
    let back = m.effective_pose_joints(&c.q_deg, None).unwrap();
    for (k, (b, w)) in back.iter().zip(&q_eff).enumerate() {
        let err = (b[0] - w[0]).abs();
        match k {
            2 => assert!(err > 0.0 && err < 0.06, "held point off by {err}"),
            _ => assert!(err < 1e-9, "point {k} off by {err}"),
        }
        assert!((1..5).all(|j| (b[j] - w[j]).abs() < 1e-12));
    }
    // The same angles in another time order are another visit order.
    let times = [0.0, 1.0, 2.0, 4.0, 3.0];
    let c = commands_for(&m, &q_eff, Some(&times)).unwrap();
    let back = m.effective_pose_joints(&c.q_deg, Some(&times)).unwrap();
    assert!((back[3][0] - q_eff[3][0]).abs() < 1e-9);
}

/// A joint that bends across its axis (`lateral_compliance`, part of the chain with or without
/// the declared tilting): the compensated joints put the bent arm on the path, through `fk` on
/// the same model, in both tilting modes; the same joints through the model without the bend
/// miss it.
#[test]
fn a_lateral_bend_is_compensated() {
    let dir = tempfile::tempdir().unwrap();
    let (model_file, plain_file) = (dir.path().join("m.toml"), dir.path().join("plain.toml"));
    let mut model = katana450(200.0).unwrap();
    model.set_param("payload_kg", 0.5).unwrap();
    let plain = model.clone();
    model.set_lateral_compliance(1, 1.0).unwrap();
    model.set_lateral_compliance(2, 0.5).unwrap();
    model.write_file(&model_file).unwrap();
    plain.write_file(&plain_file).unwrap();
    let text = path_csv();
    let want = rows(&text);
    let path = dir.path().join("path.csv");
    std::fs::write(&path, &text).unwrap();
    for tilt in ["--tilt", "--no-tilt"] {
        let out = dir.path().join(format!("joints{tilt}.csv"));
        compensate(&path, &model_file, &out, &[tilt]);
        let through = |m: &Path| fk_tilt(m, &out, tilt == "--tilt");
        let miss = |got: &[Vec<f64>]| {
            assert_eq!(got.len(), want.len());
            want.iter()
                .zip(got)
                .map(|(w, g)| {
                    (0..3)
                        .map(|c| (g[c] - w[1 + c]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(0.0, f64::max)
        };
        let (bent, rigid) = (miss(&through(&model_file)), miss(&through(&plain_file)));
        println!("{tilt}: through the bent model {bent:.2e} mm, without the bend {rigid:.3} mm");
        assert!(bent < 1e-6, "{tilt}: compensated path missed by {bent} mm");
        assert!(rigid > 0.05, "{tilt}: the bend changes only {rigid} mm");
    }
}
