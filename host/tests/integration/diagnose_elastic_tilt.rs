//! An elastic effect that one library effect describes exactly (issue 51): the UR5's first
//! joint tilts elastically in the arm's plane, in proportion to the gravity moment about the
//! axis through joint 2's origin perpendicular to that plane. Joint 2's axis is that axis, so the
//! tilt is exactly a compliance of joint 2: `diagnose` must name `compliance:j2` alone (not a
//! chain of stand-ins) with the generator's value, held out at the noise.
//!
//! The generator is written here, not `simulate`: the UR5's standard DH frames and published
//! masses of `diagnose_assumed_masses`' generator; the moment summed link by link with its own
//! cross products about the horizontal axis `(-sin q1, cos q1, 0)`; the tool point rotated about
//! that axis through the joint-2 origin (Rodrigues) - no joint angle is changed.
//!
//! Sags of 0.01-0.02 deg per kgf.m (0.1-0.25 deg at the UR5's largest joint-2 torques): from
//! 0.025 the declared geometric fit, given a residual of about 1 mm it cannot explain, walks
//! along the `dth5 + a5` valley that is singular at the nominal a5 = 0 (a5 -77 mm at 0.03);
//! `diagnose` still names the compliance with its value, but its final fit carries the walk
//! (1.15 x the floor and no sigma at 0.025; unconverged, exit 1, at 0.03). A known limit.

use nalgebra::{Rotation3, Unit, Vector3, Vector4};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::common::record::record_push;
use super::common::spawn::{output, text};
use super::diagnose_assumed_masses::{frames, origin, pose_rows, COM_MM, MASS_KG, NOISE_MM};

/// The tool point at `q` (deg) with the arm beyond joint 2's origin turned about the axis
/// perpendicular to the arm's plane by `c` deg per kgf.m of the gravity moment about it.
fn tilted_point(q: &[f64], c_deg_per_kgfm: f64) -> Vector3<f64> {
    let t = frames(q);
    let o = origin(&t[1]);
    let (s1, c1) = q[0].to_radians().sin_cos();
    let n = Vector3::new(-s1, c1, 0.0);
    let moment_kgfm: f64 = (1..6)
        .map(|k| {
            let c = COM_MM[k];
            let com = (t[k + 1] * Vector4::new(c[0], c[1], c[2], 1.0)).xyz();
            (com - o)
                .cross(&Vector3::new(0.0, 0.0, -MASS_KG[k]))
                .dot(&n)
                * 1e-3
        })
        .sum();
    let angle = (c_deg_per_kgfm * moment_kgfm).to_radians();
    let rot = Rotation3::from_axis_angle(&Unit::new_normalize(n), angle);
    o + rot * (origin(&t[6]) - o)
}

fn poses(n: usize, c: f64, rng: &mut ChaCha8Rng) -> String {
    pose_rows(n, rng, |q| tilted_point(q, c))
}

/// `diagnose --robot ur5` on poses of the tilt `c` (seed `seed`): exit code, JSON, stdout.
fn run(seed: u64, c: f64) -> (Option<i32>, serde_json::Value, String) {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    std::fs::write(dir.path().join("cal.csv"), poses(120, c, &mut rng)).unwrap();
    std::fs::write(dir.path().join("val.csv"), poses(60, c, &mut rng)).unwrap();
    let json = dir.path().join("d.json");
    let p = |f: &str| dir.path().join(f).display().to_string();
    let out = output(&[
        "diagnose",
        "--robot",
        "ur5",
        "--poses",
        &p("cal.csv"),
        "--validate",
        &p("val.csv"),
        "--instrument-mm",
        &NOISE_MM.to_string(),
        "--json",
        &json.display().to_string(),
    ]);
    let d = serde_json::from_str(&std::fs::read_to_string(&json).unwrap_or_default())
        .unwrap_or_else(|e| panic!("seed {seed}: {e}: {}", text(&out.stderr)));
    (out.status.code(), d, text(&out.stdout))
}

fn ids(d: &serde_json::Value) -> Vec<String> {
    d["effects"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|e| e["id"].as_str().map(str::to_string))
        .collect()
}

#[test]
fn an_elastic_tilt_of_joint_1_in_the_arms_plane_is_named_as_the_compliance_of_joint_2() {
    // without the tilt the generator is the preset's chain
    let ur5 = rigctl::model::ur5().unwrap();
    let q = [10.0, -70.0, 95.0, -30.0, 60.0, 15.0];
    let p = ur5.position_mm(&q, rigctl::model::Tilt::Off).unwrap();
    assert!((p - tilted_point(&q, 0.0)).norm() < 1e-6, "{p}");
    for (seed, c) in [(21u64, 0.02), (22, 0.015), (23, 0.01)] {
        let (code, d, stdout) = run(seed, c);
        assert_eq!(code, Some(0), "seed {seed}: {stdout}");
        assert_eq!(ids(&d), ["compliance:j2"], "seed {seed}: {stdout}");
        let e = &d["effects"][0];
        let v = e["parameters"]["deg_per_kgfm"].as_f64().unwrap();
        let s = e["sigma"]["deg_per_kgfm"]
            .as_f64()
            .unwrap_or_else(|| panic!("seed {seed}: sigma {}: {stdout}", e["sigma"]));
        // the compliance deflects q2 about z1 = -n: the same rotation, the same sign
        assert!(
            (v - c).abs() < 4.0 * s + 1e-4,
            "seed {seed}: {v} +- {s}, truth {c}"
        );
        let held_out = d["final"]["validation"]["mean_mm"].as_f64().unwrap();
        let ratio = held_out / (NOISE_MM * (8.0 / std::f64::consts::PI).sqrt());
        assert!(ratio < 1.3, "seed {seed}: held out {ratio:.2} x the noise");
        record_push("held_out_over_noise", ratio);
    }
}

/// A tilt against gravity (a negative compliance) is not a physical explanation: the refit's
/// negative value is held at the bound before the tests, so the compliance is rejected with
/// that reason, never accepted and then zeroed.
#[test]
fn a_tilt_against_gravity_is_not_accepted_as_a_compliance() {
    let (_, d, stdout) = run(24, -0.03);
    assert!(
        !ids(&d).iter().any(|i| i.starts_with("compliance")),
        "{stdout}"
    );
    let rejected = d["rejected"].as_array().unwrap();
    let j2 = rejected
        .iter()
        .find(|r| r["id"] == "compliance:j2")
        .unwrap_or_else(|| panic!("{stdout}"));
    let reason = j2["reason"].as_str().unwrap();
    assert!(reason.contains("physical bound"), "{reason}");
    assert!(
        d["bounds"].as_array().unwrap().is_empty(),
        "{}",
        d["bounds"]
    );
}
