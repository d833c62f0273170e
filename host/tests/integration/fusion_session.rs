//! The fusion and the projected calibration on simulated sessions, without the scanner: the
//! pencil tip's true path on the paper stands in for the traced curve, so the fused components
//! can be checked against the truth. (The scanner is in `tests/tests/e2e/session_e2e.rs`.)

use nalgebra::Vector3;
use rigctl::calib::calibrate_general::{calibrate_poses, GeneralOptions};
use rigctl::calib::identifiability::DEFAULT_RTOL;
use rigctl::calib::lm::LmConfig;
use rigctl::calib::projected::{fit_projected, measured_errors, SampleTilt};
use rigctl::calib::{default_selection, CalibrateOptions, MeasuredSet, Stats};
use rigctl::fusion::curve::TracedCurve;
use rigctl::fusion::pot::TravelSeries;
use rigctl::fusion::{fuse, FuseOptions, Fused, JointSamples, PotCalibration};
use rigctl::model::{katana450, Model, KATANA_PENCIL_TOOL_MM};
use rigctl::sim::session::{simulate_session, Session, SessionConfig, SessionPath};

fn run(path: SessionPath, seed: u64) -> (Model, SessionConfig, Session, Fused) {
    let declared = katana450(KATANA_PENCIL_TOOL_MM).unwrap();
    let cfg = SessionConfig {
        path,
        seed,
        ..SessionConfig::default()
    };
    let s = simulate_session(&declared, &cfg).unwrap();
    let cal = PotCalibration::fit(&s.jig, 1).unwrap();
    let pot = TravelSeries::new(&s.pot_samples(), |r| cal.travel_mm(r));
    let curve = TracedCurve::new(s.pencil_mm.clone(), 2.0).unwrap();
    let joints = JointSamples {
        t_s: s.t_s.clone(),
        q_deg: s.q_deg.clone(),
    };
    let fused = fuse(
        &declared,
        &joints,
        &pot,
        &curve,
        &s.placement,
        &FuseOptions::default(),
    )
    .unwrap();
    (declared, cfg, s, fused)
}

#[test]
fn fused_components_match_the_truth_and_the_clock_offset_is_recovered() {
    for path in [SessionPath::Circle, SessionPath::Line] {
        let (_, cfg, s, fused) = run(path, 3);
        let a = &fused.alignment;
        let err_ms = (a.board_s(5.0) - (5.0 + cfg.clock_offset_s)) * 1e3;
        eprintln!(
            "{path:?}: {} samples, skipped {:?}, offset error {err_ms:.4} ms, drift {:.2} ppm",
            fused.samples.len(),
            fused.skipped,
            a.drift_ppm
        );
        assert!(err_ms.abs() < 1.0, "clock offset error {err_ms} ms");
        // the two dips (each merged with the descent or the lift)
        assert_eq!(a.markers.len(), 2);
        let (mut worst_u, mut worst_n, mut rms_dev) = (0.0f64, 0.0f64, 0.0);
        for f in &fused.samples {
            let k = s
                .t_s
                .iter()
                .position(|&t| (t - f.t_s).abs() < 1e-9)
                .unwrap();
            let e: Vector3<f64> = s.truth_mm[k] - f.nominal_mm;
            worst_u = worst_u.max((f.u.dot(&e) - f.dev_u_mm).abs());
            worst_n = worst_n.max((f.n.dot(&e) - f.dev_n_mm).abs());
            rms_dev += f.dev_u_mm.powi(2) + f.dev_n_mm.powi(2);
            // u lies in the sheet
            assert!(f.u.dot(&f.n).abs() < 1e-12);
        }
        rms_dev = (rms_dev / fused.samples.len() as f64).sqrt();
        eprintln!(
            "{path:?}: worst |u error| {worst_u:.4} mm, |n error| {worst_n:.4} mm, rms measured \
             deviation {rms_dev:.3} mm"
        );
        // n: pot noise 1 count = 0.0026 mm (3.5 sigma over ~600 samples = 0.009 mm);
        // u: the stand-in trace is the tip path every 0.05 mm; the along-path error e_t bends the
        // across-path reading by e_t^2 / 2R
        assert!(worst_n < 0.012, "{worst_n}");
        assert!(worst_u < 0.01, "{worst_u}");
        assert!(
            rms_dev > 0.05,
            "the truth errors should be visible ({rms_dev})"
        );
    }
}

#[test]
fn projected_calibration_on_two_sheets_recovers_the_identifiable_parameters() {
    let (declared, _, s1, f1) = run(SessionPath::Circle, 21);
    let (_, _, _, f2) = run(SessionPath::Line, 21);
    let samples: Vec<_> = f1.samples.iter().chain(&f2.samples).cloned().collect();
    let data = MeasuredSet::from_fused(&samples)
        .and_then(|d| d.with_inertial_moments(&declared))
        .unwrap();
    let out = calibrate_poses(
        &declared,
        &data,
        None,
        &CalibrateOptions::default(),
        &GeneralOptions::default(),
    )
    .unwrap();
    let r = &out.outcome.report;
    eprintln!(
        "measured |dP| mean {:.4} -> {:.4} mm (standard {:.4}); unidentifiable {:?}; rank {}; \
         {} outliers",
        r.calibration.before.mean_mm,
        r.calibration.after.mean_mm,
        r.standard.calibration.mean_mm,
        r.unidentifiable,
        r.rank,
        out.rejected
    );
    assert_eq!(
        r.unidentifiable,
        vec!["dth5+be4".to_string(), "be5".to_string()]
    );
    assert!(r.calibration.after.mean_mm < 0.02 * r.calibration.before.mean_mm);
    // the truth in the fitted parametrisation: the same identification on the truth's own exact
    // projections at these samples (its moments on its own chain)
    let truth_moments = data.clone().with_inertial_moments(&s1.truth).unwrap();
    let mut exact = truth_moments.clone();
    for k in 0..exact.len() {
        exact.poses.xyz_mm[k] = s1
            .truth
            .position_mm(
                &data.poses.q_deg[k],
                SampleTilt::Dynamic.at(&truth_moments, k),
            )
            .unwrap();
    }
    let sel = default_selection(&declared, false);
    let best = fit_projected(
        &declared,
        &exact,
        &sel,
        SampleTilt::Dynamic,
        &LmConfig::default(),
        DEFAULT_RTOL,
    )
    .unwrap();
    for &c in &sel {
        let name = &declared.params()[c].name;
        let fit = r.parameters.get(name).unwrap();
        let eq = best.model.params()[c].value;
        // a kept parameter's sigma is null in the JSON (NaN here)
        match r.sigma.get(name).filter(|s| s.is_finite()) {
            Some(sig) => {
                let z = (fit - eq) / sig;
                eprintln!(
                    "{name:6} fit {fit:+.5} truth {:+.5} equivalent {eq:+.5} sigma {sig:.5} z {z:+.2}",
                    s1.truth.params()[c].value
                );
                assert!(z.abs() < 3.0, "{name}: {fit} vs {eq} (sigma {sig})");
            }
            None => eprintln!(
                "{name:6} fixed at {fit:+.5} (truth {:+.5})",
                s1.truth.params()[c].value
            ),
        }
    }
    let e = measured_errors(&s1.truth, &truth_moments, SampleTilt::Dynamic).unwrap();
    let st = Stats::from_errors(&e);
    eprintln!(
        "truth model on the fused data: mean {:.4} rms {:.4} max {:.4} mm",
        st.mean_mm, st.rms_mm, st.max_mm
    );
}
