//! One fit over a tree (`rigctl::calib::tree_fit`, the chains' identification on the tree's
//! unknowns) on an independent generator: a dual-arm
//! upper body (a torso of 2 joints, two 6-joint arms, modified-DH segments), geometric errors of
//! up to 1 mm and 0.2 deg on every segment, 300 poses measured at both hands with 0.3 mm noise
//! per coordinate, 150 held-out poses. The tree fit (every torso parameter one unknown) recovers
//! the truth within its sigmas and reaches the noise floor on the held-out poses; fitting each
//! hand's chain alone gives the torso two different sets of values, each less certain than the
//! tree's one.

use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

use rigctl::calib::fit::Fit;
use rigctl::calib::identifiability::DEFAULT_RTOL;
use rigctl::calib::lm::LmConfig;
use rigctl::calib::measured::MeasuredSet;
use rigctl::calib::tree_fit::{fit_tree, tree_rms_mm};
use rigctl::model::{Axis, Motion, Tilt, Tip, Tree, TreeElem, TreeJoint, TreeMass};

const NOISE_MM: f64 = 0.3;

/// A generated pose of the whole tree (the test's own record): its joints and the point of
/// every tip, `None` where the tip is not measured.
#[derive(Debug, Clone)]
struct TipPose {
    q: Vec<f64>,
    points_mm: Vec<Option<[f64; 3]>>,
}

/// The poses as the library's one measurement set (point k on tip k).
fn set_of(poses: &[TipPose]) -> MeasuredSet {
    MeasuredSet::from_tip_points(
        poses.iter().map(|p| p.q.clone()).collect(),
        poses
            .iter()
            .map(|p| p.points_mm.iter().map(|m| m.map(Into::into)).collect())
            .collect(),
    )
}

fn c(motion: Motion, axis: Axis, name: &str, value: f64) -> TreeElem {
    TreeElem {
        motion,
        axis,
        name: name.into(),
        value,
    }
}

/// Joint `name`: `Rx(al) Tx(a) Tz(d) Rz(q + off)` from its parent's frame.
fn mdh(name: &str, parent: Option<usize>, al: f64, a: f64, d: f64) -> TreeJoint {
    use Axis::{X, Z};
    use Motion::{Rot, Trans};
    TreeJoint {
        name: name.into(),
        parent,
        before: vec![
            c(Rot, X, &format!("al_{name}"), al),
            c(Trans, X, &format!("a_{name}"), a),
            c(Trans, Z, &format!("d_{name}"), d),
        ],
        prismatic: false,
        offset_name: format!("off_{name}"),
        offset: 0.0,
        limits: [-150.0, 150.0],
        masses: vec![TreeMass {
            mass_kg: 2.0,
            com_mm: [0.0, 0.0, 50.0],
        }],
        compliance_deg_per_kgfm: 0.0,
        lateral_compliance_deg_per_kgfm: 0.0,
    }
}

/// The nominal upper body: torso t1 (vertical), t2 (horizontal), arms l1..l6 and r1..r6.
fn nominal() -> Tree {
    let mut joints = vec![
        mdh("t1", None, 0.0, 0.0, 400.0),
        mdh("t2", Some(0), -90.0, 50.0, 0.0),
    ];
    for (side, sign) in [("l", 1.0), ("r", -1.0)] {
        let base = joints.len();
        let rows = [
            (90.0, 300.0, sign * 200.0),
            (-90.0, 0.0, 80.0),
            (90.0, 30.0, 280.0),
            (-90.0, -30.0, 0.0),
            (90.0, 0.0, 250.0),
            (-90.0, 0.0, 0.0),
        ];
        for (k, (al, a, d)) in rows.iter().enumerate() {
            let parent = if k == 0 { 1 } else { base + k - 1 };
            joints.push(mdh(&format!("{side}{}", k + 1), Some(parent), *al, *a, *d));
        }
    }
    Tree {
        name: "upper_body".into(),
        root: Vec::new(),
        masses_assumed: false,
        tips: vec![
            Tip {
                name: "left_hand".into(),
                joint: 7,
                after: Vec::new(),
                tool_mm: [20.0, 0.0, 120.0],
            },
            Tip {
                name: "right_hand".into(),
                joint: 13,
                after: Vec::new(),
                tool_mm: [-15.0, 10.0, 110.0],
            },
        ],
        joints,
        params: Default::default(),
    }
}

/// The identifiable geometric unknowns: every segment's `al a d off`, but not the last joint's
/// `d` and offset of an arm (the tool point's z and direction), and each hand's tool point.
fn unknowns(tree: &Tree, tips: &[usize]) -> Vec<String> {
    let mut on_path: Vec<usize> = tips.iter().flat_map(|&t| tree.path(t)).collect();
    on_path.sort_unstable();
    on_path.dedup();
    let last: Vec<usize> = tree.tips.iter().map(|t| t.joint).collect();
    let mut out = Vec::new();
    for &j in &on_path {
        let n = &tree.joints[j].name;
        out.push(format!("al_{n}"));
        out.push(format!("a_{n}"));
        if !last.contains(&j) {
            out.push(format!("d_{n}"));
            out.push(format!("off_{n}"));
        }
    }
    for &t in tips {
        for axis in ["x", "y", "z"] {
            out.push(format!("tool_d{axis}@{}", tree.tips[t].name));
        }
    }
    out
}

fn poses(truth: &Tree, n: usize, rng: &mut rand::rngs::StdRng) -> Vec<TipPose> {
    let noise = Normal::new(0.0, NOISE_MM).unwrap();
    let chains = truth.chains().unwrap();
    (0..n)
        .map(|_| {
            let q: Vec<f64> = truth
                .joints
                .iter()
                .map(|_| rng.gen_range(-120.0..120.0))
                .collect();
            let points_mm = (0..truth.tips.len())
                .map(|t| {
                    let qc: Vec<f64> = truth.path(t).iter().map(|&j| q[j]).collect();
                    let p = chains[t].fk(&qc, Tilt::Off).unwrap().position_mm;
                    Some([0, 1, 2].map(|k| p[k] + noise.sample(rng)))
                })
                .collect();
            TipPose { q, points_mm }
        })
        .collect()
}

#[test]
fn one_fit_over_a_dual_arm_tree_shares_the_torso() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5252);
    let nominal = nominal();
    let all = unknowns(&nominal, &[0, 1]);
    let mut truth = nominal.clone();
    for u in &all {
        let err = if u.starts_with("al_") || u.starts_with("off_") {
            rng.gen_range(-0.2..0.2)
        } else {
            rng.gen_range(-1.0..1.0)
        };
        truth.set_param(u, nominal.param(u).unwrap() + err).unwrap();
    }
    let train = poses(&truth, 300, &mut rng);
    let held_out = poses(&truth, 150, &mut rng);

    let lm = LmConfig::default();
    let (train, held_out) = (set_of(&train), set_of(&held_out));
    let fit = fit_tree(&nominal, &train, &all, &lm, DEFAULT_RTOL).unwrap();
    // every unknown the generator perturbs is identified (none fixed), each once
    assert_eq!(fit.fitted, all);
    assert!(fit.fixed.is_empty() && fit.unidentifiable.is_empty());
    assert!(fit.converged && fit.rank == all.len());
    // a selection the poses cannot identify, as on a chain: the left arm's last `d` moves the
    // hand point along the same axis as the tool point's z; listed last, it is the one kept at
    // its value, named in the combination, its sigma infinite, and the rest fitted as before
    let mut confounded = all.clone();
    confounded.push("d_l6".into());
    let pinned = fit_tree(&nominal, &train, &confounded, &lm, DEFAULT_RTOL).unwrap();
    assert_eq!(pinned.fixed, ["d_l6"]);
    assert_eq!(pinned.fitted, all);
    let combination = pinned.unidentifiable.join(" ");
    assert!(
        combination.contains("d_l6") && combination.contains("tool_dz@left_hand"),
        "{combination}"
    );
    assert_eq!(pinned.model.param("d_l6"), nominal.param("d_l6"));
    assert!(pinned.sigma_of("d_l6".to_string()).is_infinite());
    let held_before = tree_rms_mm(&nominal, &held_out).unwrap();
    let held_after = tree_rms_mm(&fit.model, &held_out).unwrap();
    eprintln!(
        "tree fit: {} unknowns, {} coordinates; rms {:.3} -> {:.3} mm; held out {held_before:.3} \
         -> {held_after:.4} mm (noise {NOISE_MM} mm)",
        all.len(),
        fit.n_residuals,
        tree_rms_mm(&nominal, &train).unwrap(),
        (fit.rss_mm2 / fit.n_residuals as f64).sqrt()
    );
    assert!(
        held_before > 5.0 * NOISE_MM,
        "the errors matter: {held_before}"
    );
    assert!(
        held_after <= 1.1 * NOISE_MM,
        "held out {held_after} mm against the noise {NOISE_MM} mm"
    );
    let mut worst_z = 0.0f64;
    for (name, s) in fit.fitted.iter().zip(&fit.sigma) {
        let v = fit.model.param(name).unwrap();
        let z = (v - truth.param(name).unwrap()).abs() / s;
        worst_z = worst_z.max(z);
        assert!(
            z < 4.5,
            "{name}: {v} vs truth {} (sigma {s})",
            truth.param(name).unwrap()
        );
    }
    eprintln!("tree fit: worst |fit - truth| / sigma {worst_z:.2}");

    // each hand's chain alone: the torso fitted twice, differently, each less certain
    let torso: Vec<&str> = [
        "al_t1", "a_t1", "d_t1", "off_t1", "al_t2", "a_t2", "d_t2", "off_t2",
    ]
    .to_vec();
    let mut alone = Vec::new();
    for tip in 0..2 {
        // the other tip's points unmeasured
        let mut only = train.clone();
        only.present = Some(vec![(0..2).map(|t| t == tip).collect(); only.len()]);
        let selection = unknowns(&nominal, &[tip]);
        alone.push(fit_tree(&nominal, &only, &selection, &lm, DEFAULT_RTOL).unwrap());
    }
    let value = |f: &Fit<Tree, String>, n: &str| {
        let k = f.fitted.iter().position(|m| m == n).unwrap();
        (f.model.param(n).unwrap(), f.sigma[k])
    };
    let mut differ = 0;
    for n in &torso {
        let (vt, st) = value(&fit, n);
        let (vl, sl) = value(&alone[0], n);
        let (vr, sr) = value(&alone[1], n);
        eprintln!(
            "{n}: tree {vt:.4} +- {st:.4}, left chain {vl:.4} +- {sl:.4}, right chain {vr:.4} \
             +- {sr:.4}, truth {:.4}",
            truth.param(n).unwrap()
        );
        assert!(st < sl && st < sr, "{n}: the tree's sigma is the smallest");
        if (vl - vr).abs() > 0.5 * st {
            differ += 1;
        }
    }
    assert!(
        differ >= torso.len() / 2,
        "the two chains give the torso different values ({differ} of {} parameters)",
        torso.len()
    );
}

/// A pose file of a tree: the joints by name, `x<k>,y<k>,z<k>` per tip.
fn pose_csv(tree: &Tree, poses: &[TipPose]) -> String {
    let mut header = tree.joint_names();
    for k in 1..=tree.tips.len() {
        header.extend([format!("x{k}"), format!("y{k}"), format!("z{k}")]);
    }
    let mut text = header.join(",") + "\n";
    for p in poses {
        let mut cells: Vec<String> = p.q.iter().map(|v| format!("{v:e}")).collect();
        for point in &p.points_mm {
            cells.extend(point.unwrap().iter().map(|v| format!("{v:e}")));
        }
        text += &(cells.join(",") + "\n");
    }
    text
}

/// The top-level keys of a `calibrate --json` document.
fn json_keys(path: &std::path::Path) -> Vec<String> {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let mut keys: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    keys.sort();
    keys
}

/// The nominal tree, a truth with every unknown of both tips off by up to 0.3 (mm or deg), and
/// the generator that drew it (seeded).
fn perturbed(seed: u64) -> (Tree, Tree, rand::rngs::StdRng) {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let nominal = nominal();
    let mut truth = nominal.clone();
    for u in unknowns(&nominal, &[0, 1]) {
        let err = rng.gen_range(-0.3..0.3);
        truth
            .set_param(&u, nominal.param(&u).unwrap() + err)
            .unwrap();
    }
    (nominal, truth, rng)
}

#[test]
fn calibrate_takes_a_tree_model_and_its_pose_files() {
    let (nominal, truth, mut rng) = perturbed(5253);
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (model, cal, val, out, json) = (
        d.join("tree.toml"),
        d.join("cal.csv"),
        d.join("val.csv"),
        d.join("fitted.toml"),
        d.join("tree.json"),
    );
    nominal.write_file(&model).unwrap();
    let (cal_poses, val_poses) = (poses(&truth, 300, &mut rng), poses(&truth, 150, &mut rng));
    std::fs::write(&cal, pose_csv(&truth, &cal_poses)).unwrap();
    std::fs::write(&val, pose_csv(&truth, &val_poses)).unwrap();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let calibrate =
        |model: &std::path::Path, cal: &std::path::Path, val: &std::path::Path, json| {
            let mut args: Vec<String> = ["calibrate", "--model", &s(model), "--poses", &s(cal)]
                .map(String::from)
                .to_vec();
            args.extend(["--validate".into(), s(val), "--json".into(), s(json)]);
            args.extend(["--base".into(), "--rtol".into(), "1e-5".into()]);
            crate::common::spawn::output(&args)
        };
    let run = crate::common::spawn::output(&[
        "calibrate".to_string(),
        "--model".into(),
        s(&model),
        "--poses".into(),
        s(&cal),
        "--validate".into(),
        s(&val),
        "--json".into(),
        s(&json),
        "--out".into(),
        s(&out),
    ]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    eprintln!("{stdout}");
    let line = stdout
        .lines()
        .find(|l| l.starts_with("validation rms"))
        .expect("a validation line");
    let after: f64 = line
        .split("-> ")
        .nth(1)
        .and_then(|v| v.trim_end_matches(" mm").parse().ok())
        .expect("a number");
    assert!(after <= 1.1 * NOISE_MM, "{line}");
    // one unknown per torso parameter, with its sigma; the JSON's statistics are the text's
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let names: Vec<&String> = report["parameters"].as_object().unwrap().keys().collect();
    assert_eq!(names.iter().filter(|n| n.as_str() == "a_t1").count(), 1);
    assert!(report["sigma"]["a_t1"].as_f64().unwrap() > 0.0);
    assert!(names.iter().any(|n| n.as_str() == "tool_dz@left_hand"));
    let rms_after = report["validation"]["after"]["rms_mm"].as_f64().unwrap();
    assert!(
        (rms_after / 3f64.sqrt() - after).abs() < 1e-3,
        "{rms_after} vs {after}"
    );
    let fitted = Tree::from_file(&out).unwrap();
    let d_t2 = fitted.param("d_t2").unwrap() - truth.param("d_t2").unwrap();
    assert!(d_t2.abs() < 0.1, "d_t2 off by {d_t2} mm");

    // the same flags and the same JSON keys as a chain's calibration: the left hand's chain
    // alone, and the tree with --base and --rtol
    let chain = nominal.chain(0).unwrap();
    let (chain_model, chain_cal, chain_val, chain_json, tree_json) = (
        d.join("left.toml"),
        d.join("left_cal.csv"),
        d.join("left_val.csv"),
        d.join("left.json"),
        d.join("tree_base.json"),
    );
    chain.write_file(&chain_model).unwrap();
    let left_csv = |poses: &[TipPose]| {
        let path = nominal.path(0);
        let mut text: Vec<String> = (1..=path.len()).map(|k| format!("q{k}")).collect();
        text.extend(["x", "y", "z"].map(String::from));
        let mut text = text.join(",") + "\n";
        for p in poses {
            let mut cells: Vec<String> = path.iter().map(|&j| format!("{:e}", p.q[j])).collect();
            cells.extend(p.points_mm[0].unwrap().iter().map(|v| format!("{v:e}")));
            text += &(cells.join(",") + "\n");
        }
        text
    };
    std::fs::write(&chain_cal, left_csv(&cal_poses)).unwrap();
    std::fs::write(&chain_val, left_csv(&val_poses)).unwrap();
    let chain_run = calibrate(&chain_model, &chain_cal, &chain_val, &chain_json);
    let tree_run = calibrate(&model, &cal, &val, &tree_json);
    for r in [&chain_run, &tree_run] {
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    }
    // the chain's document, and the tree it is of
    let mut tree_keys = json_keys(&tree_json);
    assert!(tree_keys.contains(&"tree".to_string()), "{tree_keys:?}");
    tree_keys.retain(|k| k != "tree");
    assert_eq!(tree_keys, json_keys(&chain_json));
    let with_base: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&tree_json).unwrap()).unwrap();
    assert!(
        with_base["parameters"].get("base_x").is_some(),
        "--base frees the base frame"
    );

    // a pose file with one point per pose for a tree of two tips is refused
    std::fs::write(&cal, "t1,x,y,z\n0,0,0,0\n").unwrap();
    let bad = crate::common::spawn::output(&[
        "calibrate".to_string(),
        "--model".into(),
        s(&model),
        "--poses".into(),
        s(&cal),
    ]);
    assert_eq!(bad.status.code(), Some(2));
}

/// A tree's calibration leaves gross errors out as a chain's does: two poses with one tip
/// measured 5 mm off are listed in `outliers` with their lines and left out of the fit (held
/// out at the noise); a held-out pose with a hand 5 mm off is listed (`"file": "val"`) and left
/// out of the held-out statistics, kept in `validation_all`; `--keep-outliers` keeps them all
/// (none listed, the fit pulled off).
#[test]
fn gross_errors_on_a_tree_are_left_out_and_named() {
    let (nominal, truth, mut rng) = perturbed(91);
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (model, cal, val) = (d.join("tree.toml"), d.join("cal.csv"), d.join("val.csv"));
    nominal.write_file(&model).unwrap();
    let mut cal_poses = poses(&truth, 200, &mut rng);
    let mut val_poses = poses(&truth, 100, &mut rng);
    // pose 7: the right hand 5 mm off in z; pose 120: the left hand 5 mm off in x
    for (k, tip, axis) in [(7, 1, 2), (120, 0, 0)] {
        if let Some(p) = cal_poses[k].points_mm[tip].as_mut() {
            p[axis] += 5.0;
        }
    }
    // held out, pose 40: the left hand 5 mm off in y (or the right when the left is unseen)
    let tip = usize::from(val_poses[40].points_mm[0].is_none());
    if let Some(p) = val_poses[40].points_mm[tip].as_mut() {
        p[1] += 5.0;
    }
    std::fs::write(&cal, pose_csv(&truth, &cal_poses)).unwrap();
    // two comment lines ahead of the held-out header: its poses' lines differ from the
    // calibration file's
    let val_text = format!(
        "# held out\n# by another session\n{}",
        pose_csv(&truth, &val_poses)
    );
    std::fs::write(&val, val_text).unwrap();
    let run = |extra: &[&str]| -> serde_json::Value {
        let json = d.join("t.json");
        let mut args: Vec<String> = ["calibrate", "--model"].map(String::from).to_vec();
        args.push(model.to_str().unwrap().to_string());
        args.extend(["--poses".into(), cal.to_str().unwrap().into()]);
        args.extend(["--validate".into(), val.to_str().unwrap().into()]);
        args.extend(["--json".into(), json.to_str().unwrap().into()]);
        args.extend(extra.iter().map(|s| s.to_string()));
        let r = crate::common::spawn::output(&args);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
    };
    let trimmed = run(&[]);
    let listed: Vec<(String, u64)> = trimmed["outliers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| {
            (
                o["file"].as_str().unwrap().to_string(),
                o["line"].as_u64().unwrap(),
            )
        })
        .collect();
    // the header is line 1: pose k is on line k + 2 (k + 4 in the held-out file)
    let want = [("cal", 9), ("cal", 122), ("val", 44)].map(|(f, l)| (f.to_string(), l));
    assert_eq!(listed, want, "{}", trimmed["outliers"]);
    let held_trimmed = trimmed["validation"]["after"]["rms_mm"].as_f64().unwrap() / 3f64.sqrt();
    assert!(held_trimmed <= 1.1 * NOISE_MM, "held out {held_trimmed}");
    let held_all = trimmed["validation_all"]["after"]["rms_mm"]
        .as_f64()
        .unwrap()
        / 3f64.sqrt();
    assert!(
        held_all > 1.1 * held_trimmed,
        "the listed held-out pose stays in validation_all: {held_all} vs {held_trimmed}"
    );
    let kept = run(&["--keep-outliers"]);
    assert!(kept["outliers"].as_array().unwrap().is_empty());
    let cal_kept = kept["calibration"]["after"]["rms_mm"].as_f64().unwrap();
    let cal_trimmed = trimmed["calibration"]["after"]["rms_mm"].as_f64().unwrap();
    assert!(
        cal_kept > 1.1 * cal_trimmed,
        "the two gross errors stay in the kept fit's statistics: {cal_kept} vs {cal_trimmed}"
    );
}
