//! Elastic joints on a tree, through the CLI, on an independent generator ([`super::tree_body`]:
//! its own kinematics and statics, not the product's): a humanoid upper body (a torso of 2 joints, two
//! 6-joint arms, link masses), geometric errors on every segment, and joints that bend about
//! their axes under gravity (the torso's pitch joint and both shoulders, `q + c tau` with `tau`
//! the torque of every mass beyond the joint, both arms on the torso), measured by motion
//! capture at both hands with 0.4 mm noise per coordinate, 300 poses fitted and 150 held out.
//!
//! `calibrate --compliance` on the tree model reaches the noise floor on the held-out poses;
//! the geometric tree fit and the chain-by-chain fit (each hand's chain with its own
//! compliances, blind to the other arm's weight) do not. A pose file in metres is refused before
//! the fit, naming the file.

use rand::{Rng, SeedableRng};

use super::tree_body::{calibrate, chain_csv, measure, tree_csv, Body};
use crate::common::record::record;
use crate::common::spawn::{output, path_arg, text};

pub(crate) const NOISE_MM: f64 = 0.4;
/// The bar: held-out RMS per coordinate within this factor of the noise.
const FLOOR_FACTOR: f64 = 1.2;

/// The truth: every segment's geometry off by up to 0.5 mm / 0.1 deg, each tool point by up to
/// 0.5 mm, and the torso pitch joint and both shoulders (joints 1 and 2 of each arm) elastic.
pub(crate) fn truth(nominal: &Body, rng: &mut rand::rngs::StdRng) -> Body {
    let mut t = nominal.clone();
    for s in &mut t.segs {
        s.al_deg += rng.gen_range(-0.1..0.1);
        s.off_deg += rng.gen_range(-0.1..0.1);
        s.a_mm += rng.gen_range(-0.5..0.5);
        s.d_mm += rng.gen_range(-0.5..0.5);
    }
    for tip in &mut t.tips {
        for v in &mut tip.2 {
            *v += rng.gen_range(-0.5..0.5);
        }
    }
    for (name, c) in [
        ("t2", 0.03),
        ("l1", 0.06),
        ("l2", 0.05),
        ("r1", 0.05),
        ("r2", 0.07),
    ] {
        t.segs
            .iter_mut()
            .find(|s| s.name == name)
            .unwrap()
            .compliance = c;
    }
    t
}

#[test]
fn tree_compliance_reaches_the_floor_where_geometry_and_chains_do_not() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5260);
    let nominal = Body::nominal();
    let truth = truth(&nominal, &mut rng);
    let (cal, val) = (
        measure(&truth, 300, NOISE_MM, &mut rng),
        measure(&truth, 150, NOISE_MM, &mut rng),
    );
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (model, cal_csv, val_csv, json) = (
        d.join("body.toml"),
        d.join("cal.csv"),
        d.join("val.csv"),
        d.join("fit.json"),
    );
    std::fs::write(&model, nominal.model_toml()).unwrap();
    std::fs::write(&cal_csv, tree_csv(&nominal, &cal, 1.0)).unwrap();
    std::fs::write(&val_csv, tree_csv(&nominal, &val, 1.0)).unwrap();
    let files = [
        "--model",
        path_arg(&model),
        "--poses",
        path_arg(&cal_csv),
        "--validate",
        path_arg(&val_csv),
    ];

    // the tree with the joints' compliances: the noise floor held out
    let fitted = d.join("fitted.toml");
    let mut args = files.to_vec();
    args.extend([
        "--compliance",
        "--json",
        path_arg(&json),
        "--out",
        path_arg(&fitted),
    ]);
    let (elastic, stdout) = calibrate(&args);
    eprintln!("{stdout}");
    // the fitted tree file carries the compliances, and `fk` on it bends the joints: its tip
    // points are the held-out measurements within the noise
    let fk = output(&[
        "fk",
        "--model",
        path_arg(&fitted),
        "--joints",
        path_arg(&val_csv),
    ]);
    assert!(fk.status.success(), "{}", text(&fk.stderr));
    let (mut ss, mut n) = (0.0, 0);
    for (line, (_, hands)) in text(&fk.stdout).lines().skip(1).zip(&val) {
        let v: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        for (k, h) in hands.iter().enumerate() {
            ss += (0..3).map(|a| (v[6 * k + a] - h[a]).powi(2)).sum::<f64>();
            n += 3;
        }
    }
    let fk_rms = (ss / n as f64).sqrt();
    assert_eq!(n, 3 * 2 * val.len());
    assert!(
        (fk_rms - elastic).abs() < 1e-3,
        "fk {fk_rms} vs calibrate {elastic}"
    );
    // the geometric tree
    let (geometric, _) = calibrate(&files);
    // chain by chain: each hand's chain with its own compliances (its own arm's masses only)
    let tree = rigctl::model::Tree::from_file(&model).unwrap();
    let mut chain_ss = 0.0;
    for tip in 0..2 {
        let (m, c, v) = (
            d.join(format!("chain{tip}.toml")),
            d.join(format!("chain{tip}_cal.csv")),
            d.join(format!("chain{tip}_val.csv")),
        );
        tree.chain(tip).unwrap().write_file(&m).unwrap();
        std::fs::write(&c, chain_csv(&nominal, tip, &cal)).unwrap();
        std::fs::write(&v, chain_csv(&nominal, tip, &val)).unwrap();
        let (rms, _) = calibrate(&[
            "--model",
            path_arg(&m),
            "--poses",
            path_arg(&c),
            "--validate",
            path_arg(&v),
            "--compliance",
        ]);
        eprintln!("chain of tip {tip} with compliance: held out {rms:.4} mm");
        chain_ss += rms * rms;
    }
    let chains = (chain_ss / 2.0).sqrt();
    let bar = FLOOR_FACTOR * NOISE_MM;
    eprintln!(
        "held-out rms per coordinate (noise {NOISE_MM} mm, bar {bar:.2} mm): tree + compliance \
         {elastic:.4} mm ({:.2} x), geometric tree {geometric:.4} mm ({:.2} x), chain by chain \
         with compliance {chains:.4} mm ({:.2} x)",
        elastic / NOISE_MM,
        geometric / NOISE_MM,
        chains / NOISE_MM
    );
    record("noise_mm", NOISE_MM);
    record("elastic_mm", elastic);
    record("geometric_mm", geometric);
    record("chains_mm", chains);
    assert!(elastic <= bar, "tree + compliance {elastic} mm > {bar} mm");
    assert!(
        geometric > bar,
        "the geometric tree reaches the floor: {geometric} mm"
    );
    assert!(
        chains > bar,
        "chain by chain reaches the floor: {chains} mm"
    );

    // the elastic joints' compliances recovered, one value per tree joint
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for s in &truth.segs {
        let i = nominal.segs.iter().position(|g| g.name == s.name).unwrap() + 1;
        let name = format!("compliance_j{i}_deg_per_kgfm");
        let Some(v) = report["parameters"][&name].as_f64() else {
            continue;
        };
        let sigma = report["sigma"][&name].as_f64().unwrap_or(f64::INFINITY);
        eprintln!(
            "{name} ({}): {v:.5} +- {sigma:.5}, truth {}",
            s.name, s.compliance
        );
        if s.compliance != 0.0 {
            assert!(
                (v - s.compliance).abs() < (5.0 * sigma).max(0.1 * s.compliance),
                "{name}: {v} vs {}",
                s.compliance
            );
        }
    }
}

#[test]
fn a_tree_pose_file_in_metres_is_refused_before_the_fit() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5261);
    let nominal = Body::nominal();
    let poses = measure(&nominal, 40, NOISE_MM, &mut rng);
    let dir = tempfile::tempdir().unwrap();
    let (model, cal) = (
        dir.path().join("body.toml"),
        dir.path().join("in_metres.csv"),
    );
    std::fs::write(&model, nominal.model_toml()).unwrap();
    std::fs::write(&cal, tree_csv(&nominal, &poses, 1e-3)).unwrap();
    let files = ["--model", path_arg(&model), "--poses", path_arg(&cal)];
    // calibrate, and diagnose (which reads the same files held out too): refused, nothing fitted
    for command in [
        vec!["calibrate"],
        vec![
            "diagnose",
            "--validate",
            path_arg(&cal),
            "--instrument-mm",
            "0.4",
        ],
    ] {
        let mut args = command.clone();
        args.extend(files);
        let run = output(&args);
        let stderr = text(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{command:?}: {stderr}");
        assert!(
            stderr.contains("in_metres.csv") && stderr.contains("metres"),
            "{command:?}: {stderr}"
        );
    }
}
