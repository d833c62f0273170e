//! Acceptance tests of `rigctl::diagnose` on simulated sessions (`rigctl::sim`): one undeclared
//! effect per FORMATS.md family, magnitudes a few times the noise effect, noise 0.01 mm.
//! Each must be named first, and the held-out mean error after the diagnosis must come within
//! 1.5x of the noise floor (the held-out mean error of the true model, i.e. the mean length of
//! the validation noise).

use rigctl::diagnose::{DiagnoseOptions, Diagnosis};
use rigctl::model::katana450;
use rigctl::sim::effects::parse_effect;
use rigctl::sim::simulate::{simulate, SimConfig};

use crate::common::record::record_push;

struct Run {
    diag: Diagnosis,
    /// Held-out mean error of the true model (mm).
    floor_mm: f64,
}

fn run(effects: &[&str], seed: u64) -> Run {
    let declared = katana450(200.0).unwrap();
    let cfg = SimConfig {
        seed,
        effects: effects.iter().map(|e| parse_effect(e).unwrap()).collect(),
        ..SimConfig::default()
    };
    let out = simulate(&declared, &cfg).unwrap();
    let floor_mm = crate::common::held_out_noise_mm(&out);
    let diag = crate::common::diagnose_sim(&declared, &out, &DiagnoseOptions::default());
    Run { diag, floor_mm }
}

fn ids(r: &Run) -> Vec<String> {
    r.diag.report.effects.iter().map(|e| e.id.clone()).collect()
}

fn final_val(r: &Run) -> f64 {
    r.diag.report.final_.validation.mean_mm
}

/// The effect is named first and the held-out error ends within `ratio` x the noise floor.
fn assert_found(effect: &str, expected_id: &str, ratio: f64) -> Run {
    let r = run(&[effect], 1);
    let got = ids(&r);
    assert_eq!(
        got.first().map(String::as_str),
        Some(expected_id),
        "{effect}: effects {got:?}\n{}",
        r.diag.report.table()
    );
    assert!(
        final_val(&r) <= ratio * r.floor_mm,
        "{effect}: validation mean {:.4} mm > {ratio} x floor {:.4} mm\n{}",
        final_val(&r),
        r.floor_mm,
        r.diag.report.table()
    );
    assert!(
        r.diag.report.declared.validation.mean_mm > 1.5 * r.floor_mm,
        "{effect}: too small to test ({})",
        r.diag.report.table()
    );
    record_push("named_first", effect);
    record_push("final_over_floor", final_val(&r) / r.floor_mm);
    r
}

fn param(r: &Run, name: &str) -> f64 {
    r.diag.report.effects[0]
        .parameters
        .get(name)
        .unwrap_or(f64::NAN)
}

#[test]
fn clean_data_adds_nothing() {
    let r = run(&[], 1);
    assert!(ids(&r).is_empty(), "{}", r.diag.report.table());
    assert!(
        !r.diag.report.unexplained.structured,
        "{}",
        r.diag.report.unexplained.note
    );
    assert!(final_val(&r) <= 1.5 * r.floor_mm);
    crate::common::record::record("clean_final_over_floor", final_val(&r) / r.floor_mm);
}

#[test]
fn link_lengths_a2_a3_d5() {
    for (e, id, v) in [
        ("link_length:a2=0.1", "link_length:a2", 0.1),
        ("link_length:a3=-0.1", "link_length:a3", -0.1),
        ("link_length:d5=0.1", "link_length:d5", 0.1),
    ] {
        let r = assert_found(e, id, 1.5);
        assert!(
            (param(&r, "delta_mm") - v).abs() < 0.02,
            "{e}: {}",
            param(&r, "delta_mm")
        );
    }
}

/// d4 moves the tool along joint 5's axis, which the declared geometric parameters already
/// reproduce: it is not an effect the declared model lacks, so nothing is added and the declared
/// fit alone reaches the noise floor.
#[test]
fn link_length_d4_is_absorbed_by_the_declared_parameters() {
    let r = run(&["link_length:d4=0.1"], 1);
    assert!(ids(&r).is_empty(), "{}", r.diag.report.table());
    assert!(
        r.diag.report.declared.validation.mean_mm <= 1.5 * r.floor_mm,
        "{}",
        r.diag.report.table()
    );
}

#[test]
fn encoder_harmonics_on_three_joints() {
    for (e, id, a, phi) in [
        (
            "encoder_harmonic:j2:h1=0.03,40",
            "encoder_harmonic:j2:h1",
            0.03,
            40.0,
        ),
        (
            "encoder_harmonic:j3:h2=0.03,-60",
            "encoder_harmonic:j3:h2",
            0.03,
            -60.0,
        ),
        (
            "encoder_harmonic:j1:h3=0.03,10",
            "encoder_harmonic:j1:h3",
            0.03,
            10.0,
        ),
    ] {
        let r = assert_found(e, id, 1.5);
        assert!(
            (param(&r, "A") - a).abs() < 0.005,
            "{e}: A {}",
            param(&r, "A")
        );
        assert!(
            (param(&r, "phi") - phi).abs() < 10.0,
            "{e}: phi {}",
            param(&r, "phi")
        );
    }
}

/// tool_dx aliases the declared dth5 (both move the tip along x of the last frame) and tool_dy
/// aliases d4 (absorbed by the declared parameters, see above): only dz is separable. The
/// effect is still named, with the aliased components reported as unidentifiable combinations.
#[test]
fn tool_offset() {
    let r = assert_found("tool_offset=0.1,0.1,-0.1", "tool_offset", 1.5);
    assert!(
        (param(&r, "dz") + 0.1).abs() < 0.02,
        "dz {}",
        param(&r, "dz")
    );
    assert!(!r.diag.report.effects[0].unidentifiable.is_empty());
}

/// `tool_length` (the effect table's `tool_dz` alone) moves the Katana's tool point along the
/// last frame's z, exactly as its declared tool length `d5` does: the simulated length change is
/// found, named as one of the two, with the other reported `equivalent` (never as two effects).
#[test]
fn tool_length_is_named_with_its_equivalent_link_length() {
    let r = run(&["tool_length=0.1"], 1);
    let got = ids(&r);
    assert_eq!(got.len(), 1, "{got:?}\n{}", r.diag.report.table());
    let e = &r.diag.report.effects[0];
    let pair = ["link_length:d5", "tool_length"];
    assert!(pair.contains(&e.id.as_str()), "{got:?}");
    let other = pair.iter().find(|i| **i != e.id).unwrap();
    assert!(
        e.equivalent.iter().any(|i| i == other),
        "{}: equivalent {:?}",
        e.id,
        e.equivalent
    );
    let (v, s) = (
        param(&r, "delta_mm"),
        e.sigma.get("delta_mm").flatten().unwrap(),
    );
    assert!((v - 0.1).abs() < 3.0 * s + 0.005, "delta {v} +- {s}");
    assert!(
        final_val(&r) <= 1.5 * r.floor_mm,
        "{}",
        r.diag.report.table()
    );
}

#[test]
fn base_offset() {
    let r = assert_found("base_offset=0.1,-0.1,0.1", "base_offset", 1.5);
    assert!(
        (param(&r, "dz") - 0.1).abs() < 0.02,
        "dz {}",
        param(&r, "dz")
    );
}

/// A base tilt gives joint 1 a gravity torque about its axis, which switches its declared
/// backlash (sign(eta_z) b, MODEL.md eq. 5.19) on with pose-dependent signs: the fit objective
/// has steps, at which the Levenberg-Marquardt refit stops (rx 0.0269, 2.2x the floor without
/// the polish); the derivative-free polish (`rigctl::diagnose::polish`) carries the fit across
/// them to the 1.5x acceptance and to within 10 % of the true tilt.
#[test]
fn base_tilt() {
    let r = assert_found("base_tilt=0.03,-0.02", "base_tilt", 1.5);
    assert!(
        (param(&r, "rx") - 0.03).abs() < 0.003 && (param(&r, "ry") + 0.02).abs() < 0.002,
        "{:?}",
        r.diag.report.effects[0].parameters
    );
}

#[test]
fn payload_and_scale() {
    let r = assert_found("payload=2", "payload", 1.5);
    assert!((param(&r, "mass_kg") - 2.0).abs() < 0.2);
    let r = assert_found("scale=300", "scale", 1.5);
    assert!((param(&r, "ppm") - 300.0).abs() < 20.0);
}

#[test]
fn tilting_values_stiffness_backlash_clearance() {
    let r = assert_found("stiffness:j2=-40", "stiffness:j2", 1.5);
    assert!((param(&r, "delta_kgfm_per_deg") + 40.0).abs() < 5.0);
    let r = assert_found("backlash:j3=0.05", "backlash:j3", 1.5);
    assert!((param(&r, "delta_deg") - 0.05).abs() < 0.005);
    let r = assert_found("clearance:j2=0.05", "clearance:j2", 1.5);
    assert!((param(&r, "delta_deg") - 0.05).abs() < 0.005);
}

#[test]
fn time_drift() {
    let r = assert_found("time_drift=0.3,-0.2,0.4", "time_drift", 1.5);
    assert!((param(&r, "vz_mm_per_h") - 0.4).abs() < 0.05);
}

#[test]
fn two_effects_are_both_found() {
    let r = run(&["encoder_harmonic:j2:h1=0.03,40", "scale=300"], 2);
    let mut got = ids(&r);
    got.sort();
    assert_eq!(
        got,
        ["encoder_harmonic:j2:h1", "scale"],
        "{}",
        r.diag.report.table()
    );
    assert!(
        final_val(&r) <= 1.5 * r.floor_mm,
        "{}",
        r.diag.report.table()
    );
    // Validation numbers are reported step by step and chain up.
    let e = &r.diag.report.effects;
    assert!((e[0].validation_mean_mm_after - e[1].validation_mean_mm_before).abs() < 1e-12);
    assert!((e[1].validation_mean_mm_after - final_val(&r)).abs() < 1e-12);
}

/// Regressions of the selection rule on other seeds: a first encoder harmonic that a second one
/// nearly aliases over joint 2's range (settled by cross-validation, then by simplicity), and a
/// base tilt that the linear screen cannot see because it switches on joint 1's backlash (found
/// by the sign-onset probe).
#[test]
fn near_aliases_and_sign_onsets_on_other_seeds() {
    let cases = [
        (
            "encoder_harmonic:j2:h1=0.03,40",
            "encoder_harmonic:j2:h1",
            7,
        ),
        ("base_tilt=0.03,-0.02", "base_tilt", 2),
        ("base_tilt=0.03,-0.02", "base_tilt", 3),
        ("base_tilt=0.03,-0.02", "base_tilt", 4),
    ];
    for (effect, id, seed) in cases {
        let r = run(&[effect], seed);
        let got = ids(&r);
        assert_eq!(
            got.first().map(String::as_str),
            Some(id),
            "{effect} seed {seed}: effects {got:?}\n{}",
            r.diag.report.table()
        );
        assert!(
            final_val(&r) <= 1.5 * r.floor_mm,
            "{effect} seed {seed}: validation mean {:.4} mm > 1.5 x floor {:.4} mm\n{}",
            final_val(&r),
            r.floor_mm,
            r.diag.report.table()
        );
    }
}
