//! Changes within a session (`tool_change`, `payload_change`; docs/diagnose.md): the tool point
//! knocked by about a tenth of a millimetre, or a payload picked up, half-way through a session
//! whose poses carry `t`. Two generators: `rigctl simulate --effect` (the ISO poses, 10 s apart),
//! and one written here that draws random joint values, computes the point through the project's
//! `Model` with the change applied by setting the parameters itself (tool offset, payload mass)
//! from the change time on, and adds its own noise. `diagnose` must name the change first, with
//! `t_s` within one pose interval of the truth and the final calibration residual within 1.2 x
//! the instrument's noise; the same sets without a change get no change named and no step in the
//! probe (3 seeds); a step no candidate describes (the instrument moved) is found by the probe's
//! change-point scan.

use std::path::Path;

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rigctl::model::{katana450, Model, ParamKind, Tilt};
use serde_json::Value;

use crate::common::record::record;
use crate::common::spawn::{os, output, text};

const NOISE_MM: f64 = 0.01;
/// The simulator's pose interval, s.
const SIM_INTERVAL_S: f64 = 10.0;
/// This file's pose interval, s.
const INTERVAL_S: f64 = 15.0;

/// `rigctl diagnose` of `cal`/`val` with the instrument's noise; its JSON.
fn diagnose_json(dir: &Path, cal: &Path, val: &Path) -> Value {
    let json = dir.join("d.json");
    let r = output(&[
        os("diagnose"),
        os("--poses"),
        os(cal),
        os("--validate"),
        os(val),
        os("--instrument-mm"),
        os(&NOISE_MM.to_string()),
        os("--json"),
        os(&json),
    ]);
    assert_eq!(r.status.code(), Some(0), "{}", text(&r.stderr));
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

/// `rigctl simulate --effect EFFECT` (none: no effect) into `dir`, then `diagnose`.
fn simulated(dir: &Path, seed: u64, effect: Option<&str>) -> Value {
    let out = dir.join("sim");
    let mut args = vec![
        os("simulate").to_owned(),
        os("--out").to_owned(),
        out.clone().into_os_string(),
        os("--seed").to_owned(),
        seed.to_string().into(),
        os("--noise-mm").to_owned(),
        NOISE_MM.to_string().into(),
    ];
    if let Some(e) = effect {
        args.push("--effect".into());
        args.push(e.into());
    }
    let r = output(&args);
    assert_eq!(r.status.code(), Some(0), "{}", text(&r.stderr));
    diagnose_json(dir, &out.join("cal.csv"), &out.join("val.csv"))
}

/// What changes at `t_s` in this file's generator.
#[derive(Clone, Copy)]
enum Knock {
    None,
    Tool(Vector3<f64>),
    Payload(f64),
    /// The instrument moves: every measured point after `t_s` by this offset in R (no candidate
    /// describes it).
    Instrument(Vector3<f64>),
}

/// The independent generator: a truth with random errors of the joint offsets and twists
/// (this file's stream), `n_cal` + `n_val` random poses within the limits at `INTERVAL_S`
/// apart (the held-out poses interleaved in time), the change applied from `t_s` on by setting
/// the truth's parameters here, Gaussian noise; written as pose files with `t`, then `diagnose`.
fn independent(dir: &Path, seed: u64, knock: Knock, t_s: f64) -> Value {
    let declared = katana450(200.0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x51c);
    let mut truth = declared.clone();
    for i in 0..truth.params().len() {
        let p = &truth.params()[i];
        let delta = match p.kind {
            ParamKind::JointOffset | ParamKind::Twist => rng.gen_range(-0.05..0.05),
            _ => continue,
        };
        let v = p.value + delta;
        truth.set_param_at(i, v).unwrap();
    }
    let mut after = truth.clone();
    match knock {
        Knock::Tool(d) => {
            for (a, name) in ["tool_dx", "tool_dy", "tool_dz"].iter().enumerate() {
                let v = after.param(name).unwrap() + d[a];
                after.set_param(name, v).unwrap();
            }
        }
        Knock::Payload(kg) => {
            let v = after.param("payload_kg").unwrap() + kg;
            after.set_param("payload_kg", v).unwrap();
        }
        Knock::None | Knock::Instrument(_) => {}
    }
    let noise = Normal::new(0.0, NOISE_MM).unwrap();
    let (n_cal, n_val) = (120, 60);
    let cols: Vec<String> = (1..=declared.n_joints()).map(|j| format!("q{j}")).collect();
    let mut files = [
        format!("{},x,y,z,t\n", cols.join(",")),
        format!("{},x,y,z,t\n", cols.join(",")),
    ];
    for k in 0..n_cal + n_val {
        // every third pose in time is held out
        let held_out = k % 3 == 2;
        let t = k as f64 * INTERVAL_S * (n_cal as f64 / (n_cal + n_val) as f64);
        let q: Vec<f64> = declared
            .joint_limits()
            .iter()
            .map(|l| {
                let margin = 0.1 * (l[1] - l[0]);
                rng.gen_range(l[0] + margin..l[1] - margin)
            })
            .collect();
        let model: &Model = if t >= t_s { &after } else { &truth };
        let mut p = model.position_mm(&q, Tilt::Static).unwrap();
        if let (Knock::Instrument(d), true) = (knock, t >= t_s) {
            p += d;
        }
        p += Vector3::new(
            noise.sample(&mut rng),
            noise.sample(&mut rng),
            noise.sample(&mut rng),
        );
        let qs: Vec<String> = q.iter().map(|v| format!("{v:.9}")).collect();
        files[usize::from(held_out)].push_str(&format!(
            "{},{:.9},{:.9},{:.9},{t:.3}\n",
            qs.join(","),
            p.x,
            p.y,
            p.z
        ));
    }
    let (cal, val) = (dir.join("cal.csv"), dir.join("val.csv"));
    std::fs::write(&cal, &files[0]).unwrap();
    std::fs::write(&val, &files[1]).unwrap();
    diagnose_json(dir, &cal, &val)
}

/// The calibration poses' interval of this file's generator, s.
fn cal_interval_s() -> f64 {
    // two of every three poses are calibration poses: at most two intervals apart
    2.0 * INTERVAL_S * 120.0 / 180.0
}

fn table(d: &Value) -> String {
    let ids: Vec<String> = d["effects"]
        .as_array()
        .map(|a| a.iter().map(|e| e.to_string()).collect())
        .unwrap_or_default();
    format!("effects {ids:?}\nnote {}", d["unexplained"]["note"])
}

/// The change named first, its time within `interval_s` of `t_true`, the final calibration
/// residual at the floor (<= 1.2 x the instrument's noise); returns (t_s, final / floor).
fn assert_change(d: &Value, id: &str, t_true: f64, interval_s: f64, what: &str) -> (f64, f64) {
    let first = &d["effects"][0];
    assert_eq!(first["id"].as_str(), Some(id), "{what}: {}", table(d));
    let t = first["parameters"]["t_s"].as_f64().unwrap_or(f64::NAN);
    assert!(
        (t - t_true).abs() <= interval_s,
        "{what}: t_s {t} vs truth {t_true} (interval {interval_s}): {}",
        table(d)
    );
    let ratio = d["floor"]["final_over_floor"].as_f64().unwrap_or(f64::NAN);
    assert!(ratio <= 1.2, "{what}: final / floor {ratio}: {}", table(d));
    (t, ratio)
}

/// No change named and no step found by the probe.
fn assert_no_change(d: &Value, what: &str) {
    let named: Vec<&str> = d["effects"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|e| e["id"].as_str())
        .filter(|id| id.ends_with("_change"))
        .collect();
    assert!(named.is_empty(), "{what}: {named:?}: {}", table(d));
    assert!(
        d["probe"].get("change_point").is_none(),
        "{what}: {}",
        d["probe"]["change_point"]
    );
}

#[test]
fn a_knocked_tool_is_named_with_its_time() {
    let dir = tempfile::tempdir().unwrap();
    // rigctl simulate: the change between the poses at 580 and 590 s (118 poses, 0..1170 s)
    let d = simulated(dir.path(), 3, Some("tool_change=0.06,-0.05,0.06,585"));
    let (t, r) = assert_change(&d, "tool_change", 585.0, SIM_INTERVAL_S, "simulate");
    record("sim_tool_t_s", t);
    record("sim_tool_final_over_floor", r);
    let dx = d["effects"][0]["parameters"]["dx"].as_f64().unwrap();
    assert!((dx - 0.06).abs() < 0.01, "dx {dx}");
    // this file's generator: random poses, the change half-way through the session
    let d = independent(
        dir.path(),
        7,
        Knock::Tool(Vector3::new(-0.05, 0.07, 0.04)),
        901.0,
    );
    let (t, r) = assert_change(&d, "tool_change", 901.0, cal_interval_s(), "independent");
    record("independent_tool_t_s", t);
    record("independent_tool_final_over_floor", r);
}

#[test]
fn a_payload_picked_up_is_named_with_its_time() {
    let dir = tempfile::tempdir().unwrap();
    let d = simulated(dir.path(), 4, Some("payload_change=1.0,585"));
    let (t, r) = assert_change(&d, "payload_change", 585.0, SIM_INTERVAL_S, "simulate");
    record("sim_payload_t_s", t);
    record("sim_payload_final_over_floor", r);
    let kg = d["effects"][0]["parameters"]["mass_kg"].as_f64().unwrap();
    assert!((kg - 1.0).abs() < 0.15, "mass {kg}");
    let d = independent(dir.path(), 8, Knock::Payload(1.0), 901.0);
    let (t, r) = assert_change(&d, "payload_change", 901.0, cal_interval_s(), "independent");
    record("independent_payload_t_s", t);
    record("independent_payload_final_over_floor", r);
}

#[test]
fn no_change_is_named_where_there_is_none() {
    let dir = tempfile::tempdir().unwrap();
    for seed in [11, 12, 13] {
        let d = simulated(dir.path(), seed, None);
        assert_no_change(&d, &format!("simulate seed {seed}"));
        let d = independent(dir.path(), seed, Knock::None, f64::INFINITY);
        assert_no_change(&d, &format!("independent seed {seed}"));
    }
}

#[test]
fn the_probe_finds_a_step_no_candidate_describes() {
    let dir = tempfile::tempdir().unwrap();
    // the instrument moved: a constant offset in R from t on (no library effect)
    let d = independent(
        dir.path(),
        9,
        Knock::Instrument(Vector3::new(0.08, 0.0, -0.05)),
        901.0,
    );
    let cp = &d["probe"]["change_point"];
    let t = cp["t_s"].as_f64().unwrap_or(f64::NAN);
    assert!(
        (t - 901.0).abs() <= cal_interval_s(),
        "change point {cp}: {}",
        table(&d)
    );
    let note = d["unexplained"]["note"].as_str().unwrap_or("");
    assert!(note.contains("something changed at t ="), "{note}");
    record("probe_step_t_s", t);
}

#[test]
fn fk_applies_a_change_from_the_model_file_at_each_rows_t() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sim");
    let r = output(&[
        os("simulate"),
        os("--out"),
        os(&out),
        os("--noise-mm"),
        os("0"),
        os("--effect"),
        os("tool_change=0.3,0,0,585"),
    ]);
    assert_eq!(r.status.code(), Some(0), "{}", text(&r.stderr));
    let truth = std::fs::read_to_string(out.join("truth.toml")).unwrap();
    assert!(truth.contains("[[change]]"), "{truth}");
    let r = output(&[
        os("fk"),
        os("--tilt"),
        os("--joints"),
        os(&out.join("cal.csv")),
        os("--model"),
        os(&out.join("truth.toml")),
    ]);
    assert_eq!(r.status.code(), Some(0), "{}", text(&r.stderr));
    let fk = text(&r.stdout);
    let cal = std::fs::read_to_string(out.join("cal.csv")).unwrap();
    let mut worst: f64 = 0.0;
    for (a, b) in cal.lines().skip(1).zip(fk.lines().skip(1)) {
        let m: Vec<f64> = a
            .split(',')
            .skip(5)
            .take(3)
            .map(|v| v.parse().unwrap())
            .collect();
        let p: Vec<f64> = b.split(',').take(3).map(|v| v.parse().unwrap()).collect();
        let d = Vector3::new(m[0] - p[0], m[1] - p[1], m[2] - p[2]).norm();
        worst = worst.max(d);
    }
    // the poses after 585 s are 0.3 mm off without the change
    assert!(worst < 1e-6, "worst {worst} mm");
}
