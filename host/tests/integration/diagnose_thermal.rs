//! The `thermal` candidate (FORMATS.md): an arm that grows as it warms up, every length from the
//! origin of R to the tool point by `1 + s (1 - exp(-t / tau))`. Two generators: the
//! simulator's (`simulate --effect thermal=S,TAU`, poses in the ISO order at a fixed interval),
//! and one written here that applies the growth law to a clean simulated truth itself, with the
//! poses visited in a shuffled order at random times over the session and its own noise. Each
//! warm-up must be named first with `s` and `tau` within 3 sigma of the truth and the held-out
//! error within 1.25 x the floor (the held-out mean error of the true model); a linear drift is
//! still named `time_drift`; a file without times never gets a time candidate.

use crate::common::record::record;

use nalgebra::Vector3;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rigctl::calib::measured::PosePoints;
use rigctl::calib::MeasuredSet;
use rigctl::diagnose::{diagnose, DiagnoseOptions, Diagnosis};
use rigctl::model::katana450;
use rigctl::sim::effects::parse_effect;
use rigctl::sim::simulate::{simulate, SimConfig, SimPose};

const NOISE_MM: f64 = 0.01;

struct Case {
    diag: Diagnosis,
    floor_mm: f64,
}

fn options() -> DiagnoseOptions {
    DiagnoseOptions {
        instrument_mm: Some(NOISE_MM),
        ..DiagnoseOptions::default()
    }
}

/// The simulator's generator: `thermal=ppm,tau` with the poses `interval_s` apart.
fn simulated(effect: &str, seed: u64, interval_s: f64) -> Case {
    let declared = katana450(200.0).unwrap();
    let cfg = SimConfig {
        seed,
        noise_mm: NOISE_MM,
        effects: vec![parse_effect(effect).unwrap()],
        pose_interval_s: interval_s,
        ..SimConfig::default()
    };
    let out = simulate(&declared, &cfg).unwrap();
    Case {
        diag: crate::common::diagnose_sim(&declared, &out, &options()),
        floor_mm: crate::common::held_out_noise_mm(&out),
    }
}

/// The independent generator: a clean truth (no noise, no time terms), then every pose given a
/// random time in a session of `session_min` (shuffled order), grown about the origin of R by
/// the law written out here, and Gaussian noise of this file's own stream.
fn independent(ppm: f64, tau_min: f64, seed: u64, session_min: f64) -> Case {
    let declared = katana450(200.0).unwrap();
    let cfg = SimConfig {
        seed,
        noise_mm: 0.0,
        ..SimConfig::default()
    };
    let out = simulate(&declared, &cfg).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x7e57);
    let noise = Normal::new(0.0, NOISE_MM).unwrap();
    let n = out.cal.len() + out.val.len();
    let mut times: Vec<f64> = (0..n)
        .map(|_| rng.gen_range(0.0..session_min * 60.0))
        .collect();
    times.sort_by(f64::total_cmp);
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut rng);
    let all: Vec<&SimPose> = out.cal.iter().chain(&out.val).collect();
    let mut poses: Vec<(f64, &SimPose, Vector3<f64>)> = order
        .iter()
        .zip(&times)
        .map(|(&k, &t)| {
            let growth = 1.0 + ppm * 1e-6 * (1.0 - (-t / (tau_min * 60.0)).exp());
            let e = Vector3::new(
                noise.sample(&mut rng),
                noise.sample(&mut rng),
                noise.sample(&mut rng),
            );
            (t, all[k], all[k].truth_mm * growth + e)
        })
        .collect();
    // every fourth pose in time is held out (spread over the session)
    poses.sort_by(|a, b| a.0.total_cmp(&b.0));
    let set = |keep: &dyn Fn(usize) -> bool| {
        let chosen: Vec<&(f64, &SimPose, Vector3<f64>)> = poses
            .iter()
            .enumerate()
            .filter(|(i, _)| keep(*i))
            .map(|(_, p)| p)
            .collect();
        let mut d = MeasuredSet::from_poses(PosePoints {
            q_deg: chosen.iter().map(|p| p.1.q_deg.clone()).collect(),
            xyz_mm: chosen.iter().map(|p| p.2).collect(),
        });
        d.t_s = Some(chosen.iter().map(|p| p.0).collect());
        d
    };
    let cal = set(&|i| i % 4 != 3);
    let val = set(&|i| i % 4 == 3);
    let floor_mm = poses
        .iter()
        .enumerate()
        .filter(|(i, _)| i % 4 == 3)
        .map(|(_, (t, p, m))| {
            let growth = 1.0 + ppm * 1e-6 * (1.0 - (-t / (tau_min * 60.0)).exp());
            (m - p.truth_mm * growth).norm()
        })
        .sum::<f64>()
        / val.len() as f64;
    let diag = diagnose(&declared, &cal, &val, &options()).unwrap();
    Case { diag, floor_mm }
}

/// `thermal` named first, `s` and `tau` within 3 sigma, held out within 1.25 x the floor.
fn assert_thermal(c: &Case, ppm: f64, tau_min: f64, what: &str) {
    let r = &c.diag.report;
    let first = r.effects.first().unwrap_or_else(|| {
        panic!("{what}: nothing named\n{}", r.table());
    });
    assert_eq!(first.id, "thermal", "{what}\n{}", r.table());
    for (name, truth) in [("s_ppm", ppm), ("tau_min", tau_min)] {
        let v = first.parameters.get(name).unwrap_or(f64::NAN);
        let s = first.sigma.get(name).flatten().unwrap_or(f64::NAN);
        assert!(
            (v - truth).abs() <= 3.0 * s,
            "{what}: {name} = {v} +- {s}, truth {truth}\n{}",
            r.table()
        );
    }
    let held_out = r.final_.validation.mean_mm;
    assert!(
        held_out <= 1.25 * c.floor_mm,
        "{what}: held out {held_out:.4} mm > 1.25 x floor {:.4}\n{}",
        c.floor_mm,
        r.table()
    );
}

#[test]
fn warm_up_is_named_with_its_size_and_time_constant() {
    // sizes down to 3 x the noise at saturation (the ISO poses lie 340 mm from the origin of R
    // on average: 90 ppm = 0.03 mm); the session lasts about 1.5 tau or more, so the warm-up
    // is seen while it happens
    for (k, (ppm, tau, interval_s)) in [
        (300.0, 10.0, 20.0),
        (150.0, 30.0, 20.0),
        (150.0, 60.0, 40.0),
        (90.0, 20.0, 20.0),
    ]
    .into_iter()
    .enumerate()
    {
        let effect = format!("thermal={ppm},{tau}");
        let seed = 3 + k as u64;
        let c = simulated(&effect, seed, interval_s);
        assert_thermal(&c, ppm, tau, &effect);
        let r = &c.diag.report;
        let e = &r.effects[0];
        for name in ["s_ppm", "tau_min"] {
            record(&format!("s{seed}_{name}"), e.parameters.get(name));
            record(
                &format!("s{seed}_{name}_sigma"),
                e.sigma.get(name).flatten(),
            );
        }
        record(
            &format!("s{seed}_declared_mm"),
            r.declared.validation.mean_mm,
        );
        record(&format!("s{seed}_final_mm"), r.final_.validation.mean_mm);
    }
}

#[test]
fn warm_up_from_an_independent_generator_in_shuffled_order() {
    for (k, (ppm, tau, session_min)) in
        [(200.0, 15.0, 60.0), (100.0, 45.0, 90.0), (60.0, 25.0, 60.0)]
            .into_iter()
            .enumerate()
    {
        let c = independent(ppm, tau, 21 + k as u64, session_min);
        assert_thermal(&c, ppm, tau, &format!("independent s {ppm} tau {tau}"));
    }
}

#[test]
fn a_linear_drift_is_still_a_time_drift() {
    let c = simulated("time_drift=0,0,0.08", 5, 20.0);
    let r = &c.diag.report;
    assert_eq!(
        r.effects.first().map(|e| e.id.as_str()),
        Some("time_drift"),
        "{}",
        r.table()
    );
}

#[test]
fn no_time_no_time_candidate() {
    let declared = katana450(200.0).unwrap();
    let cfg = SimConfig {
        seed: 9,
        effects: vec![parse_effect("thermal=300,10").unwrap()],
        pose_interval_s: 20.0,
        ..SimConfig::default()
    };
    let out = simulate(&declared, &cfg).unwrap();
    let strip = |p: &[SimPose]| {
        let mut d = MeasuredSet::from_sim_poses(p);
        d.t_s = None;
        d
    };
    let diag = diagnose(&declared, &strip(&out.cal), &strip(&out.val), &options()).unwrap();
    let tried: Vec<&str> = diag.report.effects.iter().map(|e| e.id.as_str()).collect();
    assert!(
        !tried
            .iter()
            .any(|id| *id == "thermal" || id.starts_with("time_drift")),
        "{tried:?}"
    );
}
