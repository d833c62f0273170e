//! Joint compliance on a model that declares no link masses (`diagnose --assume-masses`). The
//! data come from a generator written here, not `simulate`: the UR5's standard DH table, the
//! masses and centres of mass Universal Robots publishes, the gravity torque about each joint
//! axis summed link by link with its own cross products, and the joint deflected by
//! `c * torque` before its own forward kinematics; 0.01 mm noise. The model given to `diagnose`
//! is the UR5 without its `[[mass]]` rows. Without masses no compliance is offered and the
//! output says so; with assumed masses the compliance is named on the right joint and the
//! held-out error comes within a few times the result with the true masses.

use nalgebra::{Matrix4, Vector3, Vector4};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::common::record::record;
use super::common::spawn::rigctl;

pub(super) const NOISE_MM: f64 = 0.01;
const D_MM: [f64; 6] = [89.159, 0.0, 0.0, 109.15, 94.65, 82.3];
const A_MM: [f64; 6] = [0.0, -425.0, -392.25, 0.0, 0.0, 0.0];
const ALPHA_DEG: [f64; 6] = [90.0, 0.0, 0.0, 90.0, -90.0, 0.0];
/// The masses and centres of mass Universal Robots publishes (the preset's constants: data,
/// not an assumption of the generator).
pub(super) const MASS_KG: [f64; 6] = rigctl::model::UR5_LINK_MASS_KG;
pub(super) const COM_MM: [[f64; 3]; 6] = rigctl::model::UR5_LINK_COM_MM;

fn dh(theta_deg: f64, d: f64, a: f64, alpha_deg: f64) -> Matrix4<f64> {
    let (st, ct) = theta_deg.to_radians().sin_cos();
    let (sa, ca) = alpha_deg.to_radians().sin_cos();
    Matrix4::new(
        ct,
        -st * ca,
        st * sa,
        a * ct,
        st,
        ct * ca,
        -ct * sa,
        a * st,
        0.0,
        sa,
        ca,
        d,
        0.0,
        0.0,
        0.0,
        1.0,
    )
}

/// The frames 0..=6 (frame 0 the base) at `q` (deg).
pub(super) fn frames(q: &[f64]) -> Vec<Matrix4<f64>> {
    let mut t = vec![Matrix4::identity()];
    for i in 0..6 {
        let next = t[i] * dh(q[i], D_MM[i], A_MM[i], ALPHA_DEG[i]);
        t.push(next);
    }
    t
}

pub(super) fn origin(t: &Matrix4<f64>) -> Vector3<f64> {
    Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)])
}

/// Gravity torque about joint i's axis (z of frame i-1), kgf.m: the links i..6 below it.
fn torques_kgfm(q: &[f64]) -> Vec<f64> {
    let t = frames(q);
    let weight = |k: usize| Vector3::new(0.0, 0.0, -MASS_KG[k]);
    let com = |k: usize| {
        let c = COM_MM[k];
        (t[k + 1] * Vector4::new(c[0], c[1], c[2], 1.0)).xyz()
    };
    (0..6)
        .map(|i| {
            let axis = Vector3::new(t[i][(0, 2)], t[i][(1, 2)], t[i][(2, 2)]);
            let o = origin(&t[i]);
            let m: Vector3<f64> = (i..6).map(|k| (com(k) - o).cross(&weight(k))).sum();
            axis.dot(&m) * 1e-3
        })
        .collect()
}

/// Pose rows `q1..q6,x,y,z` with joint `joint` (0-based) compliant by `c` deg per kgf.m.
fn poses(n: usize, joint: usize, c: f64, rng: &mut ChaCha8Rng) -> String {
    pose_rows(n, rng, |q| {
        let mut bent = q.to_vec();
        bent[joint] += c * torques_kgfm(q)[joint];
        origin(&frames(&bent)[6])
    })
}

/// `n` pose rows `q1..q6,x,y,z`: joints uniform in [-170, 170] deg, the point `point(q)` plus
/// Gaussian noise of [`NOISE_MM`] per coordinate.
pub(super) fn pose_rows(
    n: usize,
    rng: &mut ChaCha8Rng,
    point: impl Fn(&[f64]) -> Vector3<f64>,
) -> String {
    let noise = Normal::new(0.0, NOISE_MM).unwrap();
    let mut out = String::from("q1,q2,q3,q4,q5,q6,x,y,z\n");
    for _ in 0..n {
        let q: Vec<f64> = (0..6).map(|_| rng.gen_range(-170.0..170.0)).collect();
        let p = point(&q);
        let row: Vec<String> = q
            .iter()
            .map(|v| format!("{v:.9}"))
            .chain((0..3).map(|k| format!("{:.6}", p[k] + noise.sample(rng))))
            .collect();
        out += &(row.join(",") + "\n");
    }
    out
}

/// The model file text without its `[[mass]]` rows.
fn without_masses(toml: &str) -> String {
    let mut out = String::new();
    let mut skip = false;
    for line in toml.lines() {
        if line.starts_with('[') {
            skip = line.trim() == "[[mass]]";
        }
        if !skip {
            out += line;
            out.push('\n');
        }
    }
    out
}

struct Run {
    stdout: String,
    json: serde_json::Value,
}

fn diagnose(dir: &std::path::Path, model: &str, extra: &[&str]) -> Run {
    let json = dir.join(format!("{model}{}.json", extra.len()));
    let o = rigctl()
        .arg("diagnose")
        .arg("--model")
        .arg(dir.join(format!("{model}.toml")))
        .arg("--poses")
        .arg(dir.join("cal.csv"))
        .arg("--validate")
        .arg(dir.join("val.csv"))
        .args(["--instrument-mm", &NOISE_MM.to_string(), "--json"])
        .arg(&json)
        .args(extra)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    // a rigid model misses the compliance: exit 1 (missing effect / not converged) is fine
    assert!(
        o.status.code() == Some(0) || o.status.code() == Some(1),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let json = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    Run { stdout, json }
}

fn effects(r: &Run) -> Vec<String> {
    r.json["effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["id"].as_str().unwrap().to_string())
        .collect()
}

fn held_out_mm(r: &Run) -> f64 {
    r.json["final"]["validation"]["mean_mm"].as_f64().unwrap()
}

#[test]
fn assumed_masses_offer_the_compliance_a_massless_model_cannot() {
    // the generator's geometry is the preset's
    let ur5 = rigctl::model::ur5().unwrap();
    let q = [10.0, -70.0, 95.0, -30.0, 60.0, 15.0];
    let p = ur5.position_mm(&q, rigctl::model::Tilt::Off).unwrap();
    assert!((p - origin(&frames(&q)[6])).norm() < 1e-6, "{p}");
    for (seed, joint, c) in [(11u64, 1usize, 0.02), (12, 2, 0.03)] {
        let dir = tempfile::tempdir().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        std::fs::write(dir.path().join("cal.csv"), poses(120, joint, c, &mut rng)).unwrap();
        std::fs::write(dir.path().join("val.csv"), poses(60, joint, c, &mut rng)).unwrap();
        let text = ur5.to_toml_string();
        std::fs::write(dir.path().join("masses.toml"), &text).unwrap();
        std::fs::write(dir.path().join("bare.toml"), without_masses(&text)).unwrap();
        let id = format!("compliance:j{}", joint + 1);
        let truth = diagnose(dir.path(), "masses", &[]);
        let bare = diagnose(dir.path(), "bare", &[]);
        let assumed = diagnose(dir.path(), "bare", &["--assume-masses"]);
        assert!(effects(&truth).contains(&id), "{:?}", effects(&truth));
        // without masses: said, and no compliance anywhere
        assert!(bare.stdout.contains("no link masses"), "{}", bare.stdout);
        assert!(
            !effects(&bare).iter().any(|e| e.starts_with("compliance")),
            "{:?}",
            effects(&bare)
        );
        assert!(bare.json.get("assumed_masses").is_none());
        // assumed: said, in the JSON, and the compliance named on the right joint
        assert!(
            assumed.stdout.contains("link masses ASSUMED"),
            "{}",
            assumed.stdout
        );
        let total = assumed.json["assumed_masses"]["total_kg"].as_f64().unwrap();
        assert!(total > 5.0 && total < 60.0, "{total}");
        assert!(effects(&assumed).contains(&id), "{:?}", effects(&assumed));
        let (t, b, a) = (
            held_out_mm(&truth),
            held_out_mm(&bare),
            held_out_mm(&assumed),
        );
        record(&format!("assumed_masses_j{}_true_mm", joint + 1), t);
        record(&format!("assumed_masses_j{}_none_mm", joint + 1), b);
        record(&format!("assumed_masses_j{}_assumed_mm", joint + 1), a);
        assert!(
            a < 3.0 * t,
            "{id}: assumed {a} mm against the true masses' {t}"
        );
        assert!(a < 0.5 * b, "{id}: assumed {a} mm against no masses' {b}");
    }
}

/// The user's mistakes: a robot mass in grams, and assumed masses on a model that declares its
/// own: exit 2, naming it, nothing written.
#[test]
fn a_mass_in_grams_or_on_a_model_with_masses_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    std::fs::write(dir.path().join("cal.csv"), poses(40, 1, 0.02, &mut rng)).unwrap();
    std::fs::write(dir.path().join("val.csv"), poses(20, 1, 0.02, &mut rng)).unwrap();
    let text = rigctl::model::ur5().unwrap().to_toml_string();
    std::fs::write(dir.path().join("masses.toml"), &text).unwrap();
    std::fs::write(dir.path().join("bare.toml"), without_masses(&text)).unwrap();
    for (model, flag, said) in [
        ("bare", "--robot-mass-kg=18400", "grams (18.4 kg)"),
        ("masses", "--assume-masses", "declares its link masses"),
    ] {
        let json = dir.path().join("d.json");
        let o = rigctl()
            .arg("diagnose")
            .arg("--model")
            .arg(dir.path().join(format!("{model}.toml")))
            .arg("--poses")
            .arg(dir.path().join("cal.csv"))
            .arg("--validate")
            .arg(dir.path().join("val.csv"))
            .arg("--json")
            .arg(&json)
            .arg(flag)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag}: {err}");
        assert!(err.contains(said), "{flag}: {err}");
        assert!(!json.exists(), "{flag}: JSON written");
    }
}
