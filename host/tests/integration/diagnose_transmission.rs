//! `diagnose` on the transmission effects (FORMATS.md `joint_scale`, `joint_coupling`,
//! `hysteresis`), the independent floor (`--instrument-mm`), the final values and aliasing, on
//! the simulated Katana (118 ISO 9283 poses to calibrate, 60 held out, 0.01 mm noise).

use crate::common::record::record;

use rigctl::calib::MeasuredSet;
use rigctl::diagnose::{diagnose, DiagnoseOptions, Diagnosis};
use rigctl::model::katana450;
use rigctl::sim::effects::parse_effect;
use rigctl::sim::simulate::{simulate, SimConfig};

const NOISE_MM: f64 = 0.01;

struct Run {
    diag: Diagnosis,
    /// Held-out mean error of the true model (mm).
    floor_mm: f64,
}

fn run_with(effects: &[&str], seed: u64, opts: &DiagnoseOptions) -> Run {
    let declared = katana450(200.0).unwrap();
    let cfg = SimConfig {
        seed,
        noise_mm: NOISE_MM,
        effects: effects.iter().map(|e| parse_effect(e).unwrap()).collect(),
        ..SimConfig::default()
    };
    let out = simulate(&declared, &cfg).unwrap();
    let floor_mm = crate::common::held_out_noise_mm(&out);
    let diag = crate::common::diagnose_sim(&declared, &out, opts);
    Run { diag, floor_mm }
}

fn with_instrument() -> DiagnoseOptions {
    DiagnoseOptions {
        instrument_mm: Some(NOISE_MM),
        ..DiagnoseOptions::default()
    }
}

/// Named first, its value within 3 sigma of the truth, held out within 1.5 x the floor.
fn assert_found(effect: &str, id: &str, name: &str, truth: f64, seed: u64) {
    let r = run_with(&[effect], seed, &with_instrument());
    let rep = &r.diag.report;
    let table = rep.table();
    assert_eq!(
        rep.effects.first().map(|e| e.id.as_str()),
        Some(id),
        "{effect}\n{table}"
    );
    let e = &rep.effects[0];
    let v = e.parameters.get(name).unwrap();
    let s = e.sigma.get(name).flatten().unwrap();
    assert!(
        (v - truth).abs() <= 3.0 * s,
        "{effect}: {name} = {v} +- {s}, truth {truth}\n{table}"
    );
    assert!(
        rep.final_.validation.mean_mm <= 1.5 * r.floor_mm,
        "{effect}: held out {:.4} > 1.5 x {:.4}\n{table}",
        rep.final_.validation.mean_mm,
        r.floor_mm
    );
    assert!(
        rep.declared.validation.mean_mm > 1.5 * r.floor_mm,
        "{effect}: too small to test\n{table}"
    );
    eprintln!(
        "{effect}: {name} = {v:.3e} +- {s:.1e}; held out {:.4} -> {:.4} mm (floor {:.4})",
        rep.declared.validation.mean_mm, rep.final_.validation.mean_mm, r.floor_mm
    );
    // `joint_scale_j2_s11` for `joint_scale:j2=2e-4` on seed 11
    let kind = effect.split('=').next().unwrap_or(effect).replace(':', "_");
    let key = format!("{kind}_s{seed}");
    record(&format!("{key}_value"), v);
    record(&format!("{key}_sigma"), s);
    record(
        &format!("{key}_declared_mm"),
        rep.declared.validation.mean_mm,
    );
    record(&format!("{key}_final_mm"), rep.final_.validation.mean_mm);
    record(&format!("{key}_floor_mm"), r.floor_mm);
}

#[test]
fn joint_scale_is_named_with_its_ratio() {
    assert_found("joint_scale:j2=2e-4", "joint_scale:j2", "s", 2e-4, 11);
    assert_found("joint_scale:j3=-1e-4", "joint_scale:j3", "s", -1e-4, 12);
}

#[test]
fn joint_coupling_is_named_with_its_factor() {
    assert_found(
        "joint_coupling:j3:j2=0.002",
        "joint_coupling:j3:j2",
        "c",
        0.002,
        11,
    );
    assert_found(
        "joint_coupling:j4:j1=-0.0005",
        "joint_coupling:j4:j1",
        "c",
        -0.0005,
        12,
    );
}

#[test]
fn hysteresis_is_named_from_the_pose_order() {
    assert_found("hysteresis:j4=0.03", "hysteresis:j4", "b", 0.03, 11);
    // about 3 x the noise at the tool point
    assert_found("hysteresis:j2=0.005", "hysteresis:j2", "b", 0.005, 12);
}

#[test]
fn clean_data_with_the_instrument_floor_gets_nothing() {
    for seed in [1, 2] {
        let r = run_with(&[], seed, &with_instrument());
        let rep = &r.diag.report;
        assert!(rep.effects.is_empty(), "{}", rep.table());
        assert!(rep.floor.instrument_mm == Some(NOISE_MM));
        assert!(
            rep.floor.final_over_floor <= 1.3,
            "{:?}\n{}",
            rep.floor,
            rep.table()
        );
        assert!(!rep.unexplained.structured, "{}", rep.table());
        assert!(rep.table().contains("at the floor"), "{}", rep.table());
    }
}

#[test]
fn a_residual_above_the_instrument_floor_says_the_model_lacks_something() {
    // an effect the selection may not add (no effect allowed): the residual of the incomplete
    // model is judged against the instrument, not against itself (a direction-free effect, so
    // that the pose measured twice gives the repeatability of the noise)
    let mut opts = with_instrument();
    opts.decide.max_effects = 0;
    let r = run_with(&["joint_scale:j2=5e-4"], 3, &opts);
    let rep = &r.diag.report;
    assert!(rep.floor.used == "instrument" || rep.floor.used == "repeatability");
    assert!(rep.floor.final_over_floor > 1.5, "{:?}", rep.floor);
    assert!(rep.unexplained.structured, "{}", rep.table());
    assert!(
        rep.table().contains("the model still lacks something"),
        "{}",
        rep.table()
    );
    // without an independent floor it says it judges against the residual itself
    let mut opts = DiagnoseOptions::default();
    opts.decide.max_effects = 0;
    let declared = katana450(200.0).unwrap();
    let cfg = SimConfig {
        seed: 3,
        effects: vec![parse_effect("joint_scale:j2=5e-4").unwrap()],
        ..SimConfig::default()
    };
    let out = simulate(&declared, &cfg).unwrap();
    // drop the repeated pose so that no repeatability is known either
    let mut cal = MeasuredSet::from_sim_poses(&out.cal);
    let n = cal.len();
    let keep: Vec<usize> = (0..n)
        .filter(|&k| {
            !(0..k).any(|i| {
                cal.poses.q_deg[i]
                    .iter()
                    .zip(&cal.poses.q_deg[k])
                    .all(|(a, b)| (a - b).abs() < 1e-6)
            })
        })
        .collect();
    cal = cal.subset(&keep);
    let d = diagnose(
        &declared,
        &cal,
        &MeasuredSet::from_sim_poses(&out.val),
        &opts,
    )
    .unwrap();
    assert_eq!(d.report.floor.used, "residual", "{:?}", d.report.floor);
    assert!(d
        .report
        .table()
        .contains("estimated from the final residual itself"));
}

#[test]
fn reported_values_are_the_final_ones() {
    let r = run_with(&["base_tilt=0.03,-0.02"], 7, &with_instrument());
    let rep = &r.diag.report;
    let e = rep
        .effects
        .iter()
        .find(|e| e.id == "base_tilt")
        .unwrap_or_else(|| panic!("{}", rep.table()));
    for (name, truth) in [("rx", 0.03), ("ry", -0.02)] {
        let v = e.parameters.get(name).unwrap();
        let s = e.sigma.get(name).flatten().unwrap();
        assert!(
            (v - truth).abs() <= 3.0 * s,
            "{name} = {v} +- {s}\n{}",
            rep.table()
        );
        assert!(e.parameters_at_entry.get(name).is_some());
        record(&format!("base_tilt_s7_{name}"), v);
    }
    let json = serde_json::to_value(rep).unwrap();
    for key in ["floor", "aliased"] {
        assert!(json.get(key).is_some(), "{key}");
    }
    assert!(json["unexplained"].get("depends_on").is_some());
    assert!(json["effects"][0].get("parameters_at_entry").is_some());
}

#[test]
fn a_stand_in_is_reported_as_aliased_or_both_are_right() {
    let r = run_with(
        &[
            "payload=0.3",
            "link_length:d4=0.2",
            "encoder_harmonic:j4:h1=0.03,20",
        ],
        7,
        &with_instrument(),
    );
    let rep = &r.diag.report;
    let table = rep.table();
    let payload = rep.effects.iter().find(|e| e.id == "payload");
    let aliased = rep.aliased.iter().any(|a| {
        [&a.a, &a.b]
            .iter()
            .any(|x| *x == "payload" || *x == "link_length:d4")
    });
    let right = payload.is_some_and(|e| {
        let v = e.parameters.get("mass_kg").unwrap_or(f64::NAN);
        let s = e.sigma.get("mass_kg").flatten().unwrap_or(0.0);
        (v - 0.3).abs() <= 3.0 * s
    });
    assert!(aliased || right, "{table}");
    assert!(
        rep.effects.iter().any(|e| e.id == "encoder_harmonic:j4:h1"),
        "{table}"
    );
}

#[test]
fn the_iso_sequence_repeatability_is_too_thin_to_be_a_floor_and_says_so() {
    // the ISO 9283 sequence measures one pose twice: 3 degrees of freedom
    let r = run_with(&[], 3, &DiagnoseOptions::default());
    let f = &r.diag.report.floor;
    assert_eq!(f.repeatability_dof, Some(3), "{f:?}");
    assert_eq!(f.used, "residual", "{f:?}");
    assert!(f.note.contains("too uncertain"), "{}", f.note);
    assert!(r.diag.report.table().contains("3 degrees of freedom"));
}

#[test]
fn repeats_of_many_poses_are_pooled_into_the_floor() {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let declared = katana450(200.0).unwrap();
    let cfg = SimConfig {
        seed: 4,
        noise_mm: NOISE_MM,
        ..SimConfig::default()
    };
    let out = simulate(&declared, &cfg).unwrap();
    // every fourth calibration pose measured once more at the end, and two held-out poses
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let noise = Normal::new(0.0, NOISE_MM).unwrap();
    let mut remeasure = |p: &rigctl::sim::simulate::SimPose| {
        let mut q = p.clone();
        q.measured_mm = p.truth_mm + nalgebra::Vector3::from_fn(|_, _| noise.sample(&mut rng));
        q
    };
    let mut cal = out.cal.clone();
    cal.extend(
        out.cal
            .iter()
            .step_by(4)
            .map(&mut remeasure)
            .collect::<Vec<_>>(),
    );
    let mut val = out.val.clone();
    val.extend(
        out.val
            .iter()
            .take(2)
            .map(&mut remeasure)
            .collect::<Vec<_>>(),
    );
    let diag = diagnose(
        &declared,
        &MeasuredSet::from_sim_poses(&cal),
        &MeasuredSet::from_sim_poses(&val),
        &DiagnoseOptions::default(),
    )
    .unwrap();
    let f = &diag.report.floor;
    let dof = f.repeatability_dof.unwrap_or(0);
    assert!(dof >= 3 * 30, "{f:?}");
    assert_eq!(f.used, "repeatability", "{f:?}");
    let rep = f.repeatability_mm.unwrap();
    // pairs (measure, remeasure): the pooled SD estimates the noise (about 8 % relative SE)
    assert!((rep / NOISE_MM - 1.0).abs() < 0.3, "{f:?}");
    assert!(
        f.final_over_floor <= 1.3 && !f.above,
        "{f:?}\n{}",
        diag.report.table()
    );
    assert!(f.note.contains("degrees of freedom"), "{}", f.note);
}
