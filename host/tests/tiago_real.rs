//! TIAGo real data (FIGAROH examples): calibration levels fitted on the training session and
//! scored on the validation session, against the published held-out numbers (norm RMSE of the
//! BL point, mm; data README): registration 3.37 / 4.87, joint offsets 2.88 / 4.23, full
//! parameters 1.64 / 3.07 (training / validation). The geometric constants alone, selected on
//! the training data, reach 3.19 mm; adding gravity-compliance terms (chosen by training
//! cross-validation) goes below FIGAROH's 3.07 mm.

mod common;

use rigctl::tiago::levels::{run_level, run_selected, Level, TiagoData, MARKER};
use rigctl::tiago::markers::fit_markers;

fn data() -> Option<TiagoData> {
    let dir = common::shared_file("TIAGo data", rigctl::tiago::levels::DATA_DIR)?;
    Some(TiagoData::load(&dir).expect("the shared TIAGo data loads"))
}

#[test]
fn levels_reproduce_figaroh_and_selection_improves() {
    let Some(d) = data() else { return };
    assert_eq!((d.training.len(), d.validation.len()), (37, 62));
    let train = d.training.poses(MARKER);
    let valid = d.validation.poses(MARKER);
    let reg = run_level(&d.model, &train, &valid, Level::Registration).unwrap();
    let off = run_level(&reg.fit.model, &train, &valid, Level::JointOffsets).unwrap();
    let full = run_level(&off.fit.model, &train, &valid, Level::Full).unwrap();
    let (sel, added) = run_selected(&off, &train, &valid).unwrap();
    for r in [&reg, &off, &full, &sel] {
        println!(
            "{:>14}: {} params, training {:.3} mm, validation {:.3} mm (per coordinate {:.3}, max {:.2})",
            r.level.name(),
            r.fit.fitted.len(),
            r.training.stats.rms_mm,
            r.validation.stats.rms_mm,
            r.validation.coordinate_rms_mm,
            r.validation.stats.max_mm
        );
    }
    let names: Vec<&str> = d.model.param_names().collect();
    println!(
        "selected: {:?}",
        added.iter().map(|&i| names[i]).collect::<Vec<_>>()
    );
    // FIGAROH's published values (2 decimals) for the two levels defined identically.
    assert_eq!(reg.fit.fitted.len(), 9);
    assert!((reg.training.stats.rms_mm - 3.37).abs() < 0.01);
    assert!((reg.validation.stats.rms_mm - 4.87).abs() < 0.01);
    assert_eq!(off.fit.fitted.len(), 14);
    assert!((off.training.stats.rms_mm - 2.88).abs() < 0.01);
    assert!((off.validation.stats.rms_mm - 4.23).abs() < 0.01);
    // The PRESS-selected level generalises better than both the offsets and the full level.
    assert!(sel.validation.stats.rms_mm < off.validation.stats.rms_mm);
    assert!(sel.validation.stats.rms_mm < full.validation.stats.rms_mm);
    // Not reached: FIGAROH's 3.07 mm (see the helper's report); keep it visible.
    if sel.validation.stats.rms_mm >= 3.07 {
        eprintln!(
            "NOTE: validation RMS {:.3} mm does not beat FIGAROH's full_params 3.07 mm",
            sel.validation.stats.rms_mm
        );
    }
}

#[test]
fn four_marker_fit_recovers_the_rigid_body_geometry() {
    let Some(d) = data() else { return };
    let lm = rigctl::calib::lm::LmConfig::default();
    let sel = rigctl::tiago::levels::selection(&d.model, Level::JointOffsets);
    let f = fit_markers(&d.model, &d.training, &sel, &lm, 1e-4).unwrap();
    // Data README: |BL-BR| = 158.24 mm, |BL-TR| = 165.65 mm (mocap rigid body definition).
    let bl_br = (f.markers_mm[0] - f.markers_mm[1]).norm();
    let bl_tr = (f.markers_mm[0] - f.markers_mm[2]).norm();
    assert!((bl_br - 158.24).abs() < 0.5, "{bl_br}");
    assert!((bl_tr - 165.65).abs() < 0.5, "{bl_tr}");
}

/// Joint terms (gravity compliance, backlash sign) and encoder harmonics next to the chain
/// constants: each candidate pool is selected on the training postures, and the pool is chosen
/// by nested leave-one-posture-out cross-validation on the training postures alone.
#[test]
fn non_geometric_terms_chosen_on_training_only() {
    use rigctl::calib::lm::LmConfig;
    use rigctl::tiago::terms::{cross_validated_rms, fit_terms, select_terms, Pools, Torques};
    let Some(d) = data() else { return };
    let train = d.training.poses(MARKER);
    let valid = d.validation.poses(MARKER);
    let reg = run_level(&d.model, &train, &valid, Level::Registration).unwrap();
    let off = run_level(&reg.fit.model, &train, &valid, Level::JointOffsets).unwrap();
    let torques = Torques::new(&d.mass_model).expect("the URDF has link masses");
    let lm = LmConfig {
        max_iterations: 200,
        ..LmConfig::default()
    };
    let g = Pools {
        geometric: true,
        ..Pools::default()
    };
    let variants = [
        ("geometric", g),
        (
            "geometric+compliance",
            Pools {
                compliance: true,
                ..g
            },
        ),
        ("geometric+encoder", Pools { encoder: true, ..g }),
        (
            "geometric+backlash",
            Pools {
                backlash: true,
                ..g
            },
        ),
        (
            "all",
            Pools {
                geometric: true,
                encoder: true,
                compliance: true,
                backlash: true,
            },
        ),
    ];
    let rms = |e: &[nalgebra::Vector3<f64>]| {
        (e.iter().map(|v| v.norm_squared()).sum::<f64>() / e.len() as f64).sqrt()
    };
    let mut results = Vec::new();
    for (name, pools) in variants {
        let start = &off.fit.model;
        let sel = select_terms(start, &train, &off.fit.fitted, pools, &torques).unwrap();
        let fit = fit_terms(start, &train, &sel.cols, &sel.terms, &torques, &lm).unwrap();
        let cv = cross_validated_rms(start, &train, &off.fit.fitted, pools, &torques, &lm).unwrap();
        let t = rms(&fit.errors(&train).unwrap());
        let v = rms(&fit.errors(&valid).unwrap());
        println!(
            "{name:>22}: training {t:.3} mm, training LOO-CV {cv:.3} mm, validation {v:.3} mm; added {:?} coef {:?}",
            sel.added, fit.coef
        );
        results.push((name, cv, t, v));
    }
    let best = results.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
    println!(
        "chosen by training CV: {} (validation {:.3} mm)",
        best.0, best.3
    );
    // The choice uses the training postures only; the validation number is then what it is.
    let geometric_cv = results[0].1;
    assert!(
        best.1 < geometric_cv,
        "a non-geometric pool must win on training CV"
    );
    // FIGAROH's full-parameter held-out norm RMSE is 3.07 mm; the training-chosen model beats it.
    assert!(best.3 < 3.07, "validation {:.3} mm", best.3);
}
