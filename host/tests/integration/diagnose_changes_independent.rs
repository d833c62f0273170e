//! Changes within a session on data this project's code did not make (issue 51, item 1): a
//! generator that shares nothing with `rigctl::model` — its own standard-DH forward kinematics of
//! a UR5 from Universal Robots' published table (checked against `rigctl fk --robot ur5` first),
//! its own random truth (joint offsets and twists off by up to 0.05 deg), random joint values,
//! poses `INTERVAL_S` apart with `t`, every third pose held out, Gaussian noise — written as pose
//! files (FORMATS.md: `q1..q6` deg, `x,y,z` mm, `t` s). Cases: (a) a tool knocked (the tool point
//! moves in the flange's x-y plane), (b) a marker re-mounted (it moves along the flange normal),
//! (c) the instrument bumped (every point after `t` shifted by a vector in the base frame: no
//! candidate describes it, the probe's change-point scan must find the time); the same sets
//! without a change over many seeds give the false-alarm rate.

use std::f64::consts::FRAC_PI_2;
use std::path::Path;

use nalgebra::{Matrix4, Vector3, Vector4};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde_json::Value;

use crate::common::record::{record, record_push};
use crate::common::spawn::{os, output, text};

/// The published UR5 DH table (standard DH: `Rz(q) Tz(d) Tx(a) Rx(alpha)`), mm and rad.
const D_MM: [f64; 6] = [89.159, 0.0, 0.0, 109.15, 94.65, 82.3];
const A_MM: [f64; 6] = [0.0, -425.0, -392.25, 0.0, 0.0, 0.0];
const ALPHA_RAD: [f64; 6] = [FRAC_PI_2, 0.0, 0.0, FRAC_PI_2, -FRAC_PI_2, 0.0];
/// Pose interval, s; calibration poses are at most two intervals apart.
const INTERVAL_S: f64 = 10.0;
/// Poses per set (two thirds calibration, one third held out, interleaved in time).
const POSES: usize = 240;
/// "Within a few poses": the change time within this many pose intervals of the truth.
const TIME_TOLERANCE_INTERVALS: f64 = 3.0;
/// The held-out error's bar, x the floor.
const HELD_OUT_BAR: f64 = 1.5;

/// A truth of this file: joint offsets and twists (rad) added to the published table.
struct Truth {
    offset_rad: [f64; 6],
    alpha_rad: [f64; 6],
}

impl Truth {
    fn published() -> Self {
        Truth {
            offset_rad: [0.0; 6],
            alpha_rad: ALPHA_RAD,
        }
    }

    fn random(rng: &mut ChaCha8Rng) -> Self {
        let mut t = Truth::published();
        for j in 0..6 {
            t.offset_rad[j] = rng.gen_range(-0.05f64..0.05).to_radians();
            t.alpha_rad[j] += rng.gen_range(-0.05f64..0.05).to_radians();
        }
        t
    }

    /// The point `tool_mm` (flange frame) in the base frame at joint values `q_rad`.
    fn point_mm(&self, q_rad: &[f64; 6], tool_mm: &Vector3<f64>) -> Vector3<f64> {
        let mut t = Matrix4::identity();
        for j in 0..6 {
            let (s, c) = (q_rad[j] + self.offset_rad[j]).sin_cos();
            let (sa, ca) = self.alpha_rad[j].sin_cos();
            #[rustfmt::skip]
            let row = Matrix4::new(
                c, -s * ca, s * sa, A_MM[j] * c,
                s, c * ca, -c * sa, A_MM[j] * s,
                0.0, sa, ca, D_MM[j],
                0.0, 0.0, 0.0, 1.0,
            );
            t *= row;
        }
        let p = t * Vector4::new(tool_mm.x, tool_mm.y, tool_mm.z, 1.0);
        Vector3::new(p.x, p.y, p.z)
    }
}

/// What changes at `t_s`.
#[derive(Clone, Copy)]
enum Change {
    None,
    /// The tool point moves by this vector in the flange frame (a tool knocked, a marker
    /// re-mounted).
    Tool(Vector3<f64>),
    /// Every measured point moves by this vector in the base frame (the instrument bumped).
    Instrument(Vector3<f64>),
}

/// One set: `POSES` random poses of `seed`'s truth with `change` from `t_s` on, noise
/// `noise_mm` per coordinate, written to `dir`/cal.csv and val.csv.
fn write_set(dir: &Path, seed: u64, change: Change, t_s: f64, noise_mm: f64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xd51c);
    let truth = Truth::random(&mut rng);
    let noise = Normal::new(0.0, noise_mm).unwrap();
    let header = "q1,q2,q3,q4,q5,q6,x,y,z,t\n";
    let mut files = [header.to_string(), header.to_string()];
    for k in 0..POSES {
        let t = k as f64 * INTERVAL_S;
        let q: [f64; 6] = std::array::from_fn(|_| rng.gen_range(-170f64..170.0).to_radians());
        let mut tool = Vector3::zeros();
        let mut shift = Vector3::zeros();
        match change {
            Change::Tool(d) if t >= t_s => tool = d,
            Change::Instrument(d) if t >= t_s => shift = d,
            _ => {}
        }
        let mut p = truth.point_mm(&q, &tool) + shift;
        p += Vector3::from_fn(|_, _| noise.sample(&mut rng));
        let qs: Vec<String> = q.iter().map(|v| format!("{:.9}", v.to_degrees())).collect();
        files[usize::from(k % 3 == 2)].push_str(&format!(
            "{},{:.9},{:.9},{:.9},{t:.3}\n",
            qs.join(","),
            p.x,
            p.y,
            p.z
        ));
    }
    std::fs::write(dir.join("cal.csv"), &files[0]).unwrap();
    std::fs::write(dir.join("val.csv"), &files[1]).unwrap();
}

/// `rigctl diagnose --robot ur5` of the set in `dir`; its JSON. Exit 1 (the final fit did not
/// converge: outputs written with `"converged": false`) is accepted and shows in the JSON.
fn diagnose(dir: &Path, noise_mm: f64) -> Value {
    let json = dir.join("d.json");
    let _ = std::fs::remove_file(&json);
    let r = output(&[
        os("diagnose"),
        os("--robot"),
        os("ur5"),
        os("--poses"),
        os(&dir.join("cal.csv")),
        os("--validate"),
        os(&dir.join("val.csv")),
        os("--instrument-mm"),
        os(&noise_mm.to_string()),
        os("--json"),
        os(&json),
    ]);
    assert!(
        matches!(r.status.code(), Some(0 | 1)),
        "{:?}: {}",
        r.status.code(),
        text(&r.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

fn table(d: &Value) -> String {
    let ids: Vec<String> = d["effects"]
        .as_array()
        .map(|a| a.iter().map(|e| e.to_string()).collect())
        .unwrap_or_default();
    format!("effects {ids:?}\nnote {}", d["unexplained"]["note"])
}

/// The times of the changes named (`*_change` effects), in the order named.
fn changes_named(d: &Value) -> Vec<f64> {
    d["effects"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter(|e| e["id"].as_str().is_some_and(|id| id.ends_with("_change")))
                .map(|e| e["parameters"]["t_s"].as_f64().unwrap_or(f64::NAN))
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn this_files_fk_is_rigctls_ur5() {
    let dir = tempfile::tempdir().unwrap();
    let truth = Truth::published();
    let mut rng = ChaCha8Rng::seed_from_u64(51);
    let qs: Vec<[f64; 6]> = (0..6)
        .map(|_| std::array::from_fn(|_| rng.gen_range(-300f64..300.0)))
        .collect();
    let mut csv = String::from("q1,q2,q3,q4,q5,q6\n");
    for q in &qs {
        let cells: Vec<String> = q.iter().map(|v| format!("{v:.12}")).collect();
        csv.push_str(&format!("{}\n", cells.join(",")));
    }
    let joints = dir.path().join("q.csv");
    std::fs::write(&joints, csv).unwrap();
    let r = output(&[
        os("fk"),
        os("--robot"),
        os("ur5"),
        os("--joints"),
        os(&joints),
    ]);
    assert_eq!(r.status.code(), Some(0), "{}", text(&r.stderr));
    let fk = text(&r.stdout);
    let mut worst: f64 = 0.0;
    for (q, line) in qs.iter().zip(fk.lines().skip(1)) {
        let q_rad: [f64; 6] = std::array::from_fn(|j| q[j].to_radians());
        let mine = truth.point_mm(&q_rad, &Vector3::zeros());
        let theirs: Vec<f64> = line
            .split(',')
            .take(3)
            .map(|v| v.parse().unwrap())
            .collect();
        worst = worst.max((mine - Vector3::new(theirs[0], theirs[1], theirs[2])).norm());
    }
    assert_eq!(fk.lines().count(), qs.len() + 1, "{fk}");
    assert!(worst < 1e-6, "worst {worst} mm");
}

/// (a) tools knocked in the flange's x-y plane and (b) markers re-mounted along its normal, at
/// 25-75 % of the session (2400 s), 0.05-0.3 mm: one `tool_change` named, with `t_s` within
/// `TIME_TOLERANCE_INTERVALS` pose intervals, held out <= `HELD_OUT_BAR` x the floor.
#[test]
fn knocked_tools_and_remounted_markers_are_named_with_their_time() {
    let dir = tempfile::tempdir().unwrap();
    // (label, seed, offset in the flange frame, change time s, noise mm)
    let cases = [
        ("tool", 21, Vector3::new(0.24, -0.18, 0.0), 1205.0, 0.01),
        ("tool", 22, Vector3::new(-0.06, 0.08, 0.0), 1805.0, 0.015),
        ("tool", 23, Vector3::new(0.08, 0.06, 0.0), 605.0, 0.01),
        ("marker", 24, Vector3::new(0.0, 0.0, 0.15), 1205.0, 0.02),
        ("marker", 25, Vector3::new(0.0, 0.0, -0.3), 605.0, 0.01),
        ("marker", 26, Vector3::new(0.0, 0.0, 0.05), 1805.0, 0.01),
    ];
    let mut failures = Vec::new();
    for (label, seed, offset, t_true, noise_mm) in cases {
        write_set(dir.path(), seed, Change::Tool(offset), t_true, noise_mm);
        let d = diagnose(dir.path(), noise_mm);
        let named = changes_named(&d);
        let dt = named
            .iter()
            .map(|t| (t - t_true).abs())
            .fold(f64::INFINITY, f64::min);
        let held_out = d["floor"]["validation_over_floor"]
            .as_f64()
            .unwrap_or(f64::NAN);
        let what = format!(
            "{label} seed {seed}, {:.2} mm at {t_true} s: changes at {named:?}, held out \
             {held_out:.3}x: {}",
            offset.norm(),
            table(&d)
        );
        record_push(&format!("{label}_time_error_intervals"), dt / INTERVAL_S);
        record_push(&format!("{label}_held_out_over_floor"), held_out);
        record_push(&format!("{label}_changes_named"), named.len() as u64);
        // one change happened: one named (a second, spurious one at the first's neighbour stood
        // in for a wrongly placed first)
        if dt > TIME_TOLERANCE_INTERVALS * INTERVAL_S || held_out > HELD_OUT_BAR || named.len() != 1
        {
            failures.push(what);
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// (c) the instrument bumped at 30-75 % of the session: no candidate describes it. Asserted on
/// every set: `diagnose` does not end at the floor with nothing said: the probe's change-point
/// scan reports a step, within `TIME_TOLERANCE_INTERVALS` pose intervals of its time.
#[test]
fn a_bumped_instrument_is_seen_by_the_probe() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (27, Vector3::new(0.08, 0.0, -0.05), 1205.0),
        (28, Vector3::new(0.0, -0.1, 0.06), 705.0),
        (29, Vector3::new(-0.06, 0.06, 0.04), 1805.0),
    ];
    let mut failures = Vec::new();
    let mut near = 0u64;
    for (seed, shift, t_true) in cases {
        write_set(dir.path(), seed, Change::Instrument(shift), t_true, 0.01);
        let d = diagnose(dir.path(), 0.01);
        let t = d["probe"]["change_point"]["t_s"]
            .as_f64()
            .unwrap_or(f64::NAN);
        let dt = (t - t_true).abs();
        if dt <= TIME_TOLERANCE_INTERVALS * INTERVAL_S {
            near += 1;
        }
        record_push("instrument_time_error_intervals", dt / INTERVAL_S);
        let note = d["unexplained"]["note"].as_str().unwrap_or("");
        if !t.is_finite()
            || !note.contains("something changed at t =")
            || dt > TIME_TOLERANCE_INTERVALS * INTERVAL_S
        {
            failures.push(format!(
                "seed {seed}: change point {} vs {t_true}: {}",
                d["probe"]["change_point"],
                table(&d)
            ));
        }
    }
    record("instrument_sets", cases.len() as u64);
    record("instrument_near", near);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The same sets without a change over `NO_CHANGE_SEEDS` seeds (half at 0.01 mm, half at 0.02
/// mm): a false alarm is a set where a change is named or the probe reports a step.
#[test]
fn sets_without_a_change_false_alarm_rate() {
    const NO_CHANGE_SEEDS: u64 = 400;
    let dir = tempfile::tempdir().unwrap();
    let mut alarms = Vec::new();
    for seed in 100..100 + NO_CHANGE_SEEDS {
        let noise_mm = if seed % 2 == 0 { 0.01 } else { 0.02 };
        write_set(dir.path(), seed, Change::None, f64::INFINITY, noise_mm);
        let d = diagnose(dir.path(), noise_mm);
        let named = changes_named(&d);
        if !named.is_empty() || d["probe"].get("change_point").is_some() {
            alarms.push(format!(
                "seed {seed}: changes {named:?}, change point {}",
                d["probe"]["change_point"]
            ));
        }
    }
    record("no_change_seeds", NO_CHANGE_SEEDS);
    record("no_change_false_alarms", alarms.len() as u64);
    // at most one in ten: the selection's level is p < 0.001 per round after a Bonferroni
    // correction, so more than that is a defect, not chance
    assert!(
        alarms.len() as u64 * 10 <= NO_CHANGE_SEEDS,
        "{} of {NO_CHANGE_SEEDS}: {alarms:#?}",
        alarms.len()
    );
}
