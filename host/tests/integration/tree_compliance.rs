//! Elastic joints on a tree, through the CLI, on an independent generator (this file's own
//! kinematics and statics, not the product's): a humanoid upper body (a torso of 2 joints, two
//! 6-joint arms, link masses), geometric errors on every segment, and joints that bend about
//! their axes under gravity (the torso's pitch joint and both shoulders, `q + c tau` with `tau`
//! the torque of every mass beyond the joint, both arms on the torso), measured by motion
//! capture at both hands with 0.4 mm noise per coordinate, 300 poses fitted and 150 held out.
//!
//! `calibrate --compliance` on the tree model reaches the noise floor on the held-out poses;
//! the geometric tree fit and the chain-by-chain fit (each hand's chain with its own
//! compliances, blind to the other arm's weight) do not. A pose file in metres is refused before
//! the fit, naming the file.

use nalgebra::{Matrix3, Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

use crate::common::record::record;
use crate::common::spawn::{output, path_arg, text};

const NOISE_MM: f64 = 0.4;
/// The bar: held-out RMS per coordinate within this factor of the noise.
const FLOOR_FACTOR: f64 = 1.2;

/// One segment of the body: `Rx(al) Tx(a) Tz(d) Rz(q + off)` from its parent's joint frame.
#[derive(Clone)]
pub(crate) struct Seg {
    pub(crate) name: String,
    pub(crate) parent: Option<usize>,
    pub(crate) al_deg: f64,
    pub(crate) a_mm: f64,
    pub(crate) d_mm: f64,
    pub(crate) off_deg: f64,
    /// (kg, centre of mass in the joint frame, mm)
    pub(crate) mass: (f64, [f64; 3]),
    /// deg per kgf.m about the axis
    pub(crate) compliance: f64,
}

#[derive(Clone)]
pub(crate) struct Body {
    pub(crate) segs: Vec<Seg>,
    /// (tip name, last joint, tool point in its frame, mm)
    pub(crate) tips: Vec<(String, usize, [f64; 3])>,
}

fn rot_x(deg: f64) -> Matrix3<f64> {
    *Rotation3::from_axis_angle(&Vector3::x_axis(), deg.to_radians()).matrix()
}

fn rot_z(deg: f64) -> Matrix3<f64> {
    *Rotation3::from_axis_angle(&Vector3::z_axis(), deg.to_radians()).matrix()
}

impl Body {
    pub(crate) fn nominal() -> Body {
        let seg = |name: &str, parent, al, a, d, kg, com: [f64; 3]| Seg {
            name: name.into(),
            parent,
            al_deg: al,
            a_mm: a,
            d_mm: d,
            off_deg: 0.0,
            mass: (kg, com),
            compliance: 0.0,
        };
        // torso: t1 yaw about the vertical, t2 pitch (horizontal axis)
        let mut segs = vec![
            seg("t1", None, 0.0, 0.0, 400.0, 12.0, [0.0, 0.0, 80.0]),
            seg("t2", Some(0), -90.0, 40.0, 0.0, 10.0, [150.0, 0.0, 0.0]),
        ];
        let mut tips = Vec::new();
        for (side, sign) in [("l", 1.0), ("r", -1.0)] {
            let base = segs.len();
            let rows = [
                (90.0, 320.0, sign * 200.0, 3.0, [0.0, 0.0, sign * 40.0]),
                (-90.0, 0.0, 60.0, 2.5, [60.0, 0.0, 0.0]),
                (90.0, 20.0, 260.0, 2.0, [0.0, 0.0, -120.0]),
                (-90.0, -20.0, 0.0, 1.5, [0.0, 60.0, 0.0]),
                (90.0, 0.0, 240.0, 1.0, [0.0, 0.0, -100.0]),
                (-90.0, 0.0, 0.0, 0.5, [0.0, 0.0, 20.0]),
            ];
            for (k, (al, a, d, kg, com)) in rows.into_iter().enumerate() {
                let parent = if k == 0 { 1 } else { base + k - 1 };
                segs.push(seg(
                    &format!("{side}{}", k + 1),
                    Some(parent),
                    al,
                    a,
                    d,
                    kg,
                    com,
                ));
            }
            let tool = [sign * 15.0, 10.0, 110.0];
            tips.push((format!("{side}_hand"), segs.len() - 1, tool));
        }
        Body { segs, tips }
    }

    /// Joint frames (rotation, origin mm) in R at joint angles `q` (deg).
    fn frames(&self, q: &[f64]) -> Vec<(Matrix3<f64>, Vector3<f64>)> {
        let mut out: Vec<(Matrix3<f64>, Vector3<f64>)> = Vec::new();
        for (s, q) in self.segs.iter().zip(q) {
            let (r0, p0) = s
                .parent
                .map_or((Matrix3::identity(), Vector3::zeros()), |p| out[p]);
            let r = r0 * rot_x(s.al_deg);
            let p = p0 + r * Vector3::new(s.a_mm, 0.0, s.d_mm);
            out.push((r * rot_z(q + s.off_deg), p));
        }
        out
    }

    /// Gravity torque about every joint's axis (kgf.m): the moment about its origin of the
    /// weight (1 kgf per kg, -z of R) of every segment whose chain passes through it, in its
    /// frame, z component. Brute force over (joint, segment) pairs.
    pub(crate) fn torques_kgfm(&self, q: &[f64]) -> Vec<f64> {
        let f = self.frames(q);
        (0..self.segs.len())
            .map(|i| {
                let (ri, oi) = f[i];
                let mut m = Vector3::zeros();
                for (j, s) in self.segs.iter().enumerate() {
                    let mut at = Some(j);
                    while let Some(k) = at.filter(|&k| k != i) {
                        at = self.segs[k].parent;
                    }
                    if at.is_none() {
                        continue;
                    }
                    let (rj, oj) = f[j];
                    let c = rj * Vector3::from(s.mass.1) + oj;
                    m += ((c - oi) * 1e-3).cross(&Vector3::new(0.0, 0.0, -s.mass.0));
                }
                (ri.transpose() * m).z
            })
            .collect()
    }

    /// The hands' points (mm) at the readings `q`: the joints bent by their compliances.
    fn hands_mm(&self, q: &[f64]) -> Vec<Vector3<f64>> {
        let tau = self.torques_kgfm(q);
        let q_eff: Vec<f64> = q
            .iter()
            .zip(&self.segs)
            .zip(&tau)
            .map(|((q, s), t)| q + s.compliance * t)
            .collect();
        let f = self.frames(&q_eff);
        self.tips
            .iter()
            .map(|(_, j, tool)| f[*j].0 * Vector3::from(*tool) + f[*j].1)
            .collect()
    }

    /// The body as a tree model file (docs/model-files.md "Tree models").
    pub(crate) fn model_toml(&self) -> String {
        let mut s = String::from("name = \"upper_body\"\n");
        for (i, g) in self.segs.iter().enumerate() {
            let n = &g.name;
            for (op, name, v) in [
                ("rx", format!("al_{n}"), g.al_deg),
                ("tx", format!("a_{n}"), g.a_mm),
                ("tz", format!("d_{n}"), g.d_mm),
            ] {
                s += &format!("\n[[chain]]\nop = \"{op}\"\nname = \"{name}\"\nvalue = {v:?}\n");
            }
            s += &format!(
                "\n[[chain]]\nop = \"rz\"\njoint = {}\nname = \"off_{n}\"\nvalue = {:?}\n",
                i + 1,
                g.off_deg
            );
        }
        for g in &self.segs {
            s += &format!(
                "\n[[joint]]\nname = \"{}\"\nparent = {}\nmin = -170.0\nmax = 170.0\n",
                g.name,
                g.parent.map_or(0, |p| p + 1)
            );
        }
        for (i, g) in self.segs.iter().enumerate() {
            let [x, y, z] = g.mass.1;
            s += &format!(
                "\n[[mass]]\njoint = {}\nkg = {:?}\ncom_mm = [{x:?}, {y:?}, {z:?}]\n",
                i + 1,
                g.mass.0
            );
        }
        for (name, j, [x, y, z]) in &self.tips {
            s += &format!(
                "\n[[tip]]\nname = \"{name}\"\njoint = {}\ntool_mm = [{x:?}, {y:?}, {z:?}]\n",
                j + 1
            );
        }
        s
    }
}

/// The truth: every segment's geometry off by up to 0.5 mm / 0.1 deg, each tool point by up to
/// 0.5 mm, and the torso pitch joint and both shoulders (joints 1 and 2 of each arm) elastic.
fn truth(nominal: &Body, rng: &mut rand::rngs::StdRng) -> Body {
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

/// Poses over the joints' ranges, the hands measured with noise: (joints, points per tip).
fn measure(
    body: &Body,
    n: usize,
    rng: &mut rand::rngs::StdRng,
) -> Vec<(Vec<f64>, Vec<Vector3<f64>>)> {
    let noise = Normal::new(0.0, NOISE_MM).unwrap();
    (0..n)
        .map(|_| {
            let q: Vec<f64> = body
                .segs
                .iter()
                .map(|_| rng.gen_range(-110.0..110.0))
                .collect();
            let hands = body
                .hands_mm(&q)
                .into_iter()
                .map(|p| p.map(|v| v + noise.sample(rng)))
                .collect();
            (q, hands)
        })
        .collect()
}

/// A tree pose file: the joints by name, `x<k>,y<k>,z<k>` per tip (points scaled by `unit`).
fn tree_csv(body: &Body, poses: &[(Vec<f64>, Vec<Vector3<f64>>)], unit: f64) -> String {
    let mut header: Vec<String> = body.segs.iter().map(|s| s.name.clone()).collect();
    for k in 1..=body.tips.len() {
        header.extend([format!("x{k}"), format!("y{k}"), format!("z{k}")]);
    }
    let mut text = header.join(",") + "\n";
    for (q, hands) in poses {
        let mut cells: Vec<String> = q.iter().map(|v| format!("{v:e}")).collect();
        for p in hands {
            cells.extend(p.iter().map(|v| format!("{:e}", v * unit)));
        }
        text += &(cells.join(",") + "\n");
    }
    text
}

/// A chain pose file of tip `tip`: `q1..qn` along its path, `x,y,z`.
fn chain_csv(body: &Body, tip: usize, poses: &[(Vec<f64>, Vec<Vector3<f64>>)]) -> String {
    let mut path = Vec::new();
    let mut at = Some(body.tips[tip].1);
    while let Some(j) = at {
        path.push(j);
        at = body.segs[j].parent;
    }
    path.reverse();
    let mut header: Vec<String> = (1..=path.len()).map(|k| format!("q{k}")).collect();
    header.extend(["x", "y", "z"].map(String::from));
    let mut text = header.join(",") + "\n";
    for (q, hands) in poses {
        let mut cells: Vec<String> = path.iter().map(|&j| format!("{:e}", q[j])).collect();
        cells.extend(hands[tip].iter().map(|v| format!("{v:e}")));
        text += &(cells.join(",") + "\n");
    }
    text
}

/// Runs `calibrate` and returns the held-out RMS per coordinate after the fit (mm) and stdout:
/// `validation rms A -> B mm` (a tree, a chain's standard fit) or `validation RMS of point 1: B mm`
/// (a chain's fit with compliance).
fn calibrate(args: &[&str]) -> (f64, String) {
    let mut all = vec!["calibrate"];
    all.extend(args);
    let run = output(&all);
    let stdout = text(&run.stdout);
    assert!(
        run.status.success(),
        "rigctl {}: {stdout}\n{}",
        all.join(" "),
        text(&run.stderr)
    );
    let line = stdout
        .lines()
        .find(|l| l.starts_with("validation rms") || l.starts_with("validation RMS of point 1:"))
        .unwrap_or_else(|| panic!("a validation line in {stdout}"));
    let rms = line
        .rsplit([' ', '>'])
        .nth(1)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("a number in {line}"));
    (rms, stdout)
}

#[test]
fn tree_compliance_reaches_the_floor_where_geometry_and_chains_do_not() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5260);
    let nominal = Body::nominal();
    let truth = truth(&nominal, &mut rng);
    let (cal, val) = (
        measure(&truth, 300, &mut rng),
        measure(&truth, 150, &mut rng),
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
    let poses = measure(&nominal, 40, &mut rng);
    let dir = tempfile::tempdir().unwrap();
    let (model, cal) = (
        dir.path().join("body.toml"),
        dir.path().join("in_metres.csv"),
    );
    std::fs::write(&model, nominal.model_toml()).unwrap();
    std::fs::write(&cal, tree_csv(&nominal, &poses, 1e-3)).unwrap();
    let run = output(&[
        "calibrate",
        "--model",
        path_arg(&model),
        "--poses",
        path_arg(&cal),
    ]);
    let stderr = text(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("in_metres.csv") && stderr.contains("metres"),
        "{stderr}"
    );
}
