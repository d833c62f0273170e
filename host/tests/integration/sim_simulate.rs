//! The simulated session: determinism, the truth files reproduce the measurements, and each
//! effect changes the truth the way its id says.

use nalgebra::Vector3;
use rigctl::model::{katana450, Model, Tilt};
use rigctl::sim::effects::parse_effect;
use rigctl::sim::output::write_outputs;
use rigctl::sim::simulate::{simulate, SimConfig};

fn cfg(seed: u64, effects: &[&str], noise_mm: f64) -> SimConfig {
    SimConfig {
        seed,
        noise_mm,
        effects: effects.iter().map(|e| parse_effect(e).unwrap()).collect(),
        n_val: 20,
        ..SimConfig::default()
    }
}

fn read_all(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    ["cal.csv", "val.csv", "truth.toml", "truth.json"]
        .iter()
        .map(|f| (f.to_string(), std::fs::read(dir.join(f)).unwrap()))
        .collect()
}

#[test]
fn same_seed_gives_byte_identical_files_and_another_seed_does_not() {
    let model = katana450(200.0).unwrap();
    let dirs: Vec<_> = (0..3).map(|_| tempfile::tempdir().unwrap()).collect();
    for (d, seed) in dirs.iter().zip([5, 5, 6]) {
        let c = cfg(seed, &["payload=0.2", "time_drift=0.1,0,0"], 0.01);
        let out = simulate(&model, &c).unwrap();
        write_outputs(d.path(), &out, &c).unwrap();
    }
    let (a, b, c) = (
        read_all(dirs[0].path()),
        read_all(dirs[1].path()),
        read_all(dirs[2].path()),
    );
    assert_eq!(a, b);
    for ((name, x), (_, y)) in a.iter().zip(&c) {
        assert_ne!(x, y, "{name} does not depend on the seed");
    }
}

#[test]
fn truth_model_file_reproduces_the_noise_free_measurements() {
    let model = katana450(200.0).unwrap();
    let c = cfg(9, &[], 0.0);
    let out = simulate(&model, &c).unwrap();
    let dir = tempfile::tempdir().unwrap();
    write_outputs(dir.path(), &out, &c).unwrap();
    let truth = Model::from_file(&dir.path().join("truth.toml")).unwrap();
    // and the declared model with truth.json's truth_parameters set
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("truth.json")).unwrap()).unwrap();
    let mut set = model.clone();
    for (name, v) in json["truth_parameters"].as_object().unwrap() {
        set.set_param(name, v.as_f64().unwrap()).unwrap();
    }
    assert_eq!(json["truth_parameters"].as_object().unwrap().len(), 12);
    let text = std::fs::read_to_string(dir.path().join("cal.csv")).unwrap();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let q: Vec<f64> = f[..5].iter().map(|v| v.parse().unwrap()).collect();
        let xyz = Vector3::new(
            f[5].parse().unwrap(),
            f[6].parse().unwrap(),
            f[7].parse::<f64>().unwrap(),
        );
        for m in [&truth, &set] {
            let p = m.position_mm(&q, Tilt::Static).unwrap();
            // 9 decimals written
            assert!((p - xyz).norm() < 2e-9, "{}: {p} vs {xyz}", f[9]);
        }
    }
}

#[test]
fn noise_has_the_requested_size() {
    let model = katana450(200.0).unwrap();
    let out = simulate(
        &model,
        &SimConfig {
            n_val: 200,
            ..cfg(2, &[], 0.05)
        },
    )
    .unwrap();
    let d: Vec<f64> = out
        .cal
        .iter()
        .chain(&out.val)
        .flat_map(|p| {
            (p.measured_mm - p.truth_mm)
                .iter()
                .copied()
                .collect::<Vec<_>>()
        })
        .collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    // 954 samples: the standard error of sd is about sd / sqrt(2n) = 2.3 %
    assert!((sd - 0.05).abs() < 0.005, "sd {sd}");
    assert!(mean.abs() < 0.006, "mean {mean}");
}

/// Truth positions of the calibration poses with and without `effect` (no noise, same seed).
fn with_and_without(
    effect: &str,
) -> (
    Vec<rigctl::sim::simulate::SimPose>,
    Vec<rigctl::sim::simulate::SimPose>,
    Model,
) {
    let model = katana450(200.0).unwrap();
    let plain = simulate(&model, &cfg(4, &[], 0.0)).unwrap();
    let eff = simulate(&model, &cfg(4, &[effect], 0.0)).unwrap();
    (plain.cal, eff.cal, plain.truth)
}

#[test]
fn translation_scale_and_drift_effects_are_exact() {
    let (plain, moved, _) = with_and_without("base_offset=0.3,-0.2,0.1");
    for (a, b) in plain.iter().zip(&moved) {
        assert!((b.measured_mm - a.measured_mm - Vector3::new(0.3, -0.2, 0.1)).norm() < 1e-9);
    }
    let (plain, scaled, _) = with_and_without("scale=100");
    for (a, b) in plain.iter().zip(&scaled) {
        assert!((b.measured_mm - a.measured_mm * (1.0 + 100e-6)).norm() < 1e-9);
    }
    let (plain, drifted, _) = with_and_without("time_drift=0,0,0.36");
    for (a, b) in plain.iter().zip(&drifted) {
        let want = Vector3::new(0.0, 0.0, 0.36 * a.t_s / 3600.0);
        assert!((b.measured_mm - a.measured_mm - want).norm() < 1e-9);
    }
    // the last pose is at t = 1170 s: 0.117 mm of drift
    assert!((drifted[117].t_s - 1170.0).abs() < 1e-9);
}

#[test]
fn tool_offset_moves_along_the_tool_frame() {
    let (plain, moved, truth) = with_and_without("tool_offset=0.1,0,-0.2");
    for (a, b) in plain.iter().zip(&moved) {
        let fk = truth.fk(&a.q_deg, Tilt::Static).unwrap();
        let want = fk.rotation * Vector3::new(0.1, 0.0, -0.2);
        // the tool point carries no mass, so moments and tilts are unchanged: the shift is exact
        assert!((b.measured_mm - a.measured_mm - want).norm() < 1e-9);
    }
}

#[test]
fn encoder_harmonic_is_a_joint_angle_error() {
    let (plain, with, truth) = with_and_without("encoder_harmonic:j2:h1=0.05,30");
    for (a, b) in plain.iter().zip(&with).take(20) {
        let mut q = a.q_deg.clone();
        q[1] += 0.05 * (q[1] + 30.0).to_radians().sin();
        let want = truth.position_mm(&q, Tilt::Static).unwrap();
        assert!((b.measured_mm - want).norm() < 1e-9);
    }
}

#[test]
fn link_payload_tilt_and_joint_values_change_the_truth() {
    for (effect, at_least_mm) in [
        ("link_length:a3=0.5", 0.2),
        ("payload=0.5", 0.05),
        ("base_tilt=0.05,-0.05", 0.1),
        ("stiffness:j2=-45", 0.01),
        ("backlash:j3=0.05", 0.05),
        ("clearance:j2=0.03", 0.02),
        ("time_drift:j1=0.5", 0.05),
    ] {
        let (plain, with, _) = with_and_without(effect);
        let worst = plain
            .iter()
            .zip(&with)
            .map(|(a, b)| (a.measured_mm - b.measured_mm).norm())
            .fold(0.0, f64::max);
        assert!(worst > at_least_mm, "{effect}: largest change {worst} mm");
        assert!(worst < 5.0, "{effect}: largest change {worst} mm");
    }
}

#[test]
fn bad_effects_are_rejected() {
    for bad in [
        "nope=1",
        "link_length:mount_x=1",
        "encoder_harmonic:j2:h4=1",
        "tool_offset=1,2",
        "payload=abc",
        "payload",
        "scale=inf",
    ] {
        assert!(parse_effect(bad).is_err(), "{bad} accepted");
    }
    let model = katana450(200.0).unwrap();
    // well-formed ids the model has no value for
    for bad in [
        "link_length:a9=1",
        "stiffness:j9=1",
        "stiffness:j2=-200",
        "time_drift:j7=1",
    ] {
        let c = SimConfig {
            effects: vec![parse_effect(bad).unwrap()],
            ..SimConfig::default()
        };
        assert!(simulate(&model, &c).is_err(), "{bad} accepted");
    }
}

/// Every effect the candidate library offers (the effect table) can be simulated: its id reads
/// back, takes the row's value count, and changes the truth model.
#[test]
fn every_offered_effect_can_be_simulated() {
    use rigctl::model::effect::{library, Offers};
    let offers = Offers {
        approach: true,
        time: true,
    };
    for model in [katana450(200.0).unwrap(), rigctl::model::ur5().unwrap()] {
        let ids = library(&model, offers);
        for id in &ids {
            let (counts, _) = id.row().sim_values;
            let mut values = vec!["0.01".to_string(); counts[0]];
            if id.to_string() == "thermal" {
                values[1] = "20".into();
            }
            let arg = format!("{id}={}", values.join(","));
            let effect = parse_effect(&arg).unwrap_or_else(|e| panic!("{arg}: {e}"));
            let mut truth = model.clone();
            effect
                .apply(&mut truth)
                .unwrap_or_else(|e| panic!("{arg}: {e}"));
            assert_ne!(
                format!("{truth:?}"),
                format!("{model:?}"),
                "{arg} changed nothing"
            );
        }
    }
}

#[test]
fn a_tool_length_change_lengthens_tool_dz() {
    let model = katana450(200.0).unwrap();
    let mut truth = model.clone();
    parse_effect("tool_length=0.5")
        .unwrap()
        .apply(&mut truth)
        .unwrap();
    let dz = |m: &rigctl::model::Model| m.param("tool_dz").unwrap();
    assert!((dz(&truth) - dz(&model) - 0.5).abs() < 1e-12);
    let q = [10.0, 100.0, -60.0, 30.0, 20.0];
    let at = |m: &rigctl::model::Model| m.position_mm(&q, rigctl::model::Tilt::Off).unwrap();
    let (a, b) = (at(&model), at(&truth));
    assert!(((b - a).norm() - 0.5).abs() < 1e-9, "{}", (b - a).norm());
}
