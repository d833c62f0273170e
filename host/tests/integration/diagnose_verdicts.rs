//! One verdict from the calibration residual, the cross-validation and the held-out set
//! (`rigctl::diagnose::verdict`), named right on simulated Katana sessions (0.01 mm noise,
//! `--instrument-mm 0.01`) over several seeds: `floor` (clean data), `missing_effect` (an
//! effect the selection may not add), `overfitting` (few poses for the parameters fitted, with
//! an error those parameters absorb on the calibration poses), `change_between_sets` (a
//! held-out file measured with another tool offset); no output says "down to the noise" and
//! "lacks something" at once. Also the physical bounds (`rigctl::diagnose::bounds`).

use nalgebra::Vector3;
use rigctl::diagnose::data::Dataset;
use rigctl::diagnose::{diagnose, DiagnoseOptions, Diagnosis};
use rigctl::model::katana450;
use rigctl::sim::effects::parse_effect;
use rigctl::sim::simulate::{simulate, SimConfig, SimOutput};

const NOISE_MM: f64 = 0.01;

fn session(effects: &[&str], seed: u64) -> SimOutput {
    let declared = katana450(200.0).unwrap();
    let cfg = SimConfig {
        seed,
        noise_mm: NOISE_MM,
        effects: effects.iter().map(|e| parse_effect(e).unwrap()).collect(),
        ..SimConfig::default()
    };
    simulate(&declared, &cfg).unwrap()
}

fn opts() -> DiagnoseOptions {
    DiagnoseOptions {
        instrument_mm: Some(NOISE_MM),
        ..DiagnoseOptions::default()
    }
}

fn run(cal: &Dataset, val: &Dataset, opts: &DiagnoseOptions) -> Diagnosis {
    diagnose(&katana450(200.0).unwrap(), cal, val, opts).unwrap()
}

/// The verdict's kind, and the outputs never contradict it.
fn kind(d: &Diagnosis) -> String {
    let r = &d.report;
    let table = r.table();
    let json = serde_json::to_string(r).unwrap();
    for text in [&table, &json] {
        assert!(
            !(text.contains("down to the noise") && text.contains("lacks something")),
            "{table}"
        );
    }
    let doc: serde_json::Value = serde_json::from_str(&json).unwrap();
    let v = rigctl::report::summary::verdict(&doc).unwrap_or_default();
    assert!(
        !(v.contains("At the") && v.contains("lacks something")),
        "{v}"
    );
    eprintln!("{}\n{v}", r.verdict.note);
    r.verdict.kind.clone()
}

#[test]
fn clean_data_is_at_the_floor() {
    for seed in [1, 2, 3] {
        let s = session(&[], seed);
        let d = run(
            &Dataset::from_sim_poses(&s.cal),
            &Dataset::from_sim_poses(&s.val),
            &opts(),
        );
        assert_eq!(kind(&d), "floor", "seed {seed}\n{}", d.report.table());
    }
}

#[test]
fn an_effect_not_added_is_a_missing_effect() {
    let mut o = opts();
    o.decide.max_effects = 0;
    for seed in [1, 2, 3] {
        let s = session(&["joint_scale:j2=5e-4"], seed);
        let d = run(
            &Dataset::from_sim_poses(&s.cal),
            &Dataset::from_sim_poses(&s.val),
            &o,
        );
        assert_eq!(kind(&d), "missing_effect", "seed {seed}\n{}", d.report.table());
        assert!(d.report.table().contains("lacks something"));
    }
}

/// A held-out file measured after the tool was remounted (another tool offset, same arm):
/// the calibration and its cross-validation are at the floor, the held-out set is not.
#[test]
fn another_tool_mounting_is_a_change_between_sets() {
    for seed in [1, 2, 3] {
        let s = session(&[], seed);
        // same seed: same arm, same poses, same noise; only the tool differs
        let moved = session(&["tool_offset=0.08,-0.06,0.05"], seed);
        let d = run(
            &Dataset::from_sim_poses(&s.cal),
            &Dataset::from_sim_poses(&moved.val),
            &opts(),
        );
        assert_eq!(
            kind(&d),
            "change_between_sets",
            "seed {seed}\n{}",
            d.report.table()
        );
    }
}

/// Few poses for the parameters fitted, and an error the declared model lacks: the fitted
/// parameters absorb it on the calibration poses (residual at the floor) but predict the
/// poses left out badly.
#[test]
fn few_poses_for_many_parameters_is_overfitting() {
    let mut o = opts();
    o.decide.max_effects = 0;
    let mut named = Vec::new();
    for seed in [1, 2, 3, 4] {
        let s = session(&[], seed);
        // the first 16 poses of the ISO sequence, with a smooth error no parameter describes
        let bump = |q: &[f64]| {
            let u = (q[1] - 60.0) / 25.0;
            let w = (q[2] + 40.0) / 30.0;
            0.06 * (-(u * u + w * w)).exp()
        };
        let with = |d: Dataset| {
            let mut d = d;
            for k in 0..d.len() {
                let b = bump(&d.poses.q_deg[k]);
                d.poses.xyz_mm[k] += Vector3::new(b, -0.5 * b, 0.8 * b);
            }
            d
        };
        let all = with(Dataset::from_sim_poses(&s.cal));
        let few: Vec<usize> = (0..16).collect();
        let d = run(&all.subset(&few), &with(Dataset::from_sim_poses(&s.val)), &o);
        let k = kind(&d);
        eprintln!("seed {seed}: {k}\n{}", d.report.table());
        named.push(k);
    }
    let right = named.iter().filter(|k| *k == "overfitting").count();
    assert!(right >= 3, "{named:?}");
}
