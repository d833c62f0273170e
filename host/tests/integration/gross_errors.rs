//! Gross errors in measured poses (FORMATS.md "Gross errors in measured poses"): `calibrate` and
//! `diagnose` leave out the poses whose error is inconsistent with the others, list them, and
//! give the held-out statistics without them; on clean sets they flag (almost) nothing.
//!
//! Two sources of data: the simulated Katana (an undeclared encoder harmonic, 0.01 mm noise) and
//! the real UR5 laser-tracker set; the gross errors are added here, 1-5 % of the poses, 0.5-5 mm
//! in random directions, to the calibration and to the held-out file.

use crate::common;
use crate::common::record::{record, record_push};

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rigctl::calib::calibrate::{calibrate, CalibrateOptions, Method};
use rigctl::calib::MeasuredSet;
use rigctl::diagnose::{diagnose, DiagnoseOptions};
use rigctl::model::katana450;
use rigctl::sim::effects::parse_effect;
use rigctl::sim::simulate::{simulate, SimConfig, SimPose};

/// Adds gross errors of 0.5-5 mm to `share` of `xyz` (at least one), in random directions;
/// returns the indices, ascending.
fn corrupt(xyz: &mut [Vector3<f64>], share: f64, rng: &mut impl Rng) -> Vec<usize> {
    let n = ((share * xyz.len() as f64).round() as usize).max(1);
    let mut picked: Vec<usize> = Vec::new();
    while picked.len() < n {
        let k = rng.gen_range(0..xyz.len());
        if !picked.contains(&k) {
            picked.push(k);
        }
    }
    for &k in &picked {
        let dir = Vector3::new(
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        )
        .normalize();
        xyz[k] += dir * rng.gen_range(0.5..5.0);
    }
    picked.sort_unstable();
    picked
}

fn sim(seed: u64, effects: &[&str]) -> (Vec<SimPose>, Vec<SimPose>) {
    let cfg = SimConfig {
        seed,
        noise_mm: 0.01,
        effects: effects.iter().map(|e| parse_effect(e).unwrap()).collect(),
        ..SimConfig::default()
    };
    let out = simulate(&katana450(200.0).unwrap(), &cfg).unwrap();
    (out.cal, out.val)
}

fn flagged(list: &[rigctl::calib::outliers::OutlierReport], file: &str) -> Vec<usize> {
    let mut v: Vec<usize> = list
        .iter()
        .filter(|o| o.pose.file == file)
        .map(|o| o.pose.index)
        .collect();
    v.sort_unstable();
    v
}

fn within(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

#[test]
fn diagnose_flags_the_gross_errors_and_names_the_same_effect() {
    let declared = katana450(200.0).unwrap();
    let opts = DiagnoseOptions {
        instrument_mm: Some(0.01),
        ..DiagnoseOptions::default()
    };
    for seed in [3_u64, 8] {
        let (cal, val) = sim(seed, &["encoder_harmonic:j2:h1=0.03,40"]);
        let clean = diagnose(
            &declared,
            &MeasuredSet::from_sim_poses(&cal),
            &MeasuredSet::from_sim_poses(&val),
            &opts,
        )
        .unwrap()
        .report;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed + 100);
        let (mut c, mut v) = (
            MeasuredSet::from_sim_poses(&cal),
            MeasuredSet::from_sim_poses(&val),
        );
        let bad_cal = corrupt(&mut c.poses.xyz_mm, 0.03, &mut rng);
        let bad_val = corrupt(&mut v.poses.xyz_mm, 0.03, &mut rng);
        let dirty = diagnose(&declared, &c, &v, &opts).unwrap().report;
        let table = dirty.table();
        assert_eq!(
            flagged(&dirty.outliers, "cal"),
            bad_cal,
            "seed {seed}\n{table}"
        );
        assert_eq!(
            flagged(&dirty.outliers, "val"),
            bad_val,
            "seed {seed}\n{table}"
        );
        let ids = |r: &rigctl::diagnose::report::DiagnoseReport| -> Vec<String> {
            r.effects.iter().map(|e| e.id.clone()).collect()
        };
        assert_eq!(ids(&dirty), ids(&clean), "seed {seed}\n{table}");
        assert!(
            within(
                dirty.final_.validation.mean_mm,
                clean.final_.validation.mean_mm,
                0.1
            ),
            "seed {seed}: held out {} with the gross errors left out, {} clean\n{table}",
            dirty.final_.validation.mean_mm,
            clean.final_.validation.mean_mm
        );
        assert!(!dirty.unexplained.structured, "seed {seed}\n{table}");
        // kept: the gross errors stay in and break the verdict
        let kept = diagnose(
            &declared,
            &c,
            &v,
            &DiagnoseOptions {
                keep_outliers: true,
                ..opts.clone()
            },
        )
        .unwrap()
        .report;
        assert!(kept.outliers.is_empty());
        assert!(kept.final_.validation.mean_mm > 1.5 * dirty.final_.validation.mean_mm);
        record_push("katana_moved_poses", bad_cal.len() + bad_val.len());
        record_push("katana_clean_held_out_mm", clean.final_.validation.mean_mm);
        record_push("katana_held_out_mm", dirty.final_.validation.mean_mm);
        record_push(
            "katana_kept_over_left_out",
            kept.final_.validation.mean_mm / dirty.final_.validation.mean_mm,
        );
    }
}

#[test]
fn calibrate_flags_the_gross_errors_of_the_real_ur5_set() {
    let Some((model, grid, random)) = common::ur5_tracker("calibrate_flags_the_gross_errors")
    else {
        return;
    };
    let opts = CalibrateOptions {
        method: Method::Standard,
        base: true,
        ..CalibrateOptions::default()
    };
    let clean = calibrate(&model, &grid, Some(&random), &opts)
        .unwrap()
        .report;
    println!(
        "UR5 clean: {} flagged ({:?}), held out {:.4} mm",
        clean.outliers.len(),
        clean
            .outliers
            .iter()
            .map(|o| (o.pose.file.clone(), o.pose.index, o.pose.error_mm))
            .collect::<Vec<_>>(),
        clean.validation.unwrap().after.mean_mm
    );
    record("ur5_clean_flagged", clean.outliers.len());
    record(
        "ur5_clean_held_out_mm",
        clean.validation.unwrap().after.mean_mm,
    );
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut g, mut r): (MeasuredSet, MeasuredSet) = (grid.clone(), random.clone());
    let bad_cal = corrupt(&mut g.poses.xyz_mm, 0.02, &mut rng);
    let bad_val = corrupt(&mut r.poses.xyz_mm, 0.05, &mut rng);
    let dirty = calibrate(&model, &g, Some(&r), &opts).unwrap().report;
    let cal_flags = flagged(&dirty.outliers, "cal");
    let val_flags = flagged(&dirty.outliers, "val");
    for k in &bad_cal {
        assert!(
            cal_flags.contains(k),
            "calibration pose {k} not flagged: {cal_flags:?}"
        );
    }
    for k in &bad_val {
        assert!(
            val_flags.contains(k),
            "held-out pose {k} not flagged: {val_flags:?}"
        );
    }
    // what the clean set flags is flagged here too, nothing else
    assert!(cal_flags.len() <= bad_cal.len() + flagged(&clean.outliers, "cal").len());
    let (d, c) = (
        dirty.validation.unwrap().after.mean_mm,
        clean.validation.unwrap().after.mean_mm,
    );
    assert!(
        within(d, c, 0.1),
        "held out {d} with gross errors left out, {c} clean"
    );
    record("ur5_moved_poses", bad_cal.len() + bad_val.len());
    record("ur5_held_out_mm", d);
    for (name, v) in &clean.parameters.0 {
        let w = dirty.parameters.get(name).unwrap();
        let s = clean.sigma.get(name).unwrap_or(0.0);
        assert!(
            (w - v).abs() <= 3.0 * s.max(1e-9) + 1e-6 * v.abs(),
            "{name}: {w} with gross errors left out, {v} clean (sigma {s})"
        );
    }
}

#[test]
fn clean_sets_flag_almost_nothing() {
    let declared = katana450(200.0).unwrap();
    let (mut poses, mut flags_cal, mut flags_diag) = (0_usize, 0_usize, 0_usize);
    let mut flagged_cal_mm = Vec::new();
    for seed in 0..50_u64 {
        let (cal, val) = sim(1000 + seed, &["encoder_harmonic:j3:h2=0.02,10"]);
        let to_poses = |p: &[SimPose]| {
            MeasuredSet::from_points(
                p.iter().map(|x| x.q_deg.clone()).collect(),
                p.iter().map(|x| x.measured_mm).collect(),
            )
        };
        let rep = calibrate(
            &declared,
            &to_poses(&cal),
            Some(&to_poses(&val)),
            &CalibrateOptions::default(),
        )
        .unwrap()
        .report;
        flags_cal += rep.outliers.len();
        flagged_cal_mm.extend(rep.outliers.iter().map(|o| o.pose.error_mm));
        for o in &rep.outliers {
            println!(
                "seed {seed}: calibrate flagged {} pose {} at {:.4} mm: {}",
                o.pose.file, o.pose.index, o.pose.error_mm, o.note
            );
        }
        let d = diagnose(
            &declared,
            &MeasuredSet::from_sim_poses(&cal),
            &MeasuredSet::from_sim_poses(&val),
            &DiagnoseOptions {
                instrument_mm: Some(0.01),
                ..DiagnoseOptions::default()
            },
        )
        .unwrap()
        .report;
        flags_diag += d.outliers.len();
        poses += cal.len() + val.len();
    }
    println!(
        "clean: {poses} poses per command, calibrate flagged {flags_cal}, diagnose {flags_diag}"
    );
    record("clean_poses", poses);
    record("clean_calibrate_flagged", flags_cal);
    record("clean_calibrate_flagged_mm", flagged_cal_mm);
    record("clean_diagnose_flagged", flags_diag);
    assert!(
        flags_cal * 1000 <= poses,
        "calibrate flagged {flags_cal} of {poses}"
    );
    assert!(
        flags_diag * 1000 <= poses,
        "diagnose flagged {flags_diag} of {poses}"
    );
}
