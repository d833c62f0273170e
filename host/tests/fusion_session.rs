//! The fusion on simulated sessions, without the scanner: the pencil's true path on the paper
//! stands in for the traced curve, so the fused components can be checked against the truth.

use nalgebra::Vector3;
use rigctl::calib::projected::{calibrate_projected, ProjectedData, SampleTilt};
use rigctl::calib::identifiability::{analyse, DEFAULT_RTOL};
use rigctl::calib::projected::projected_jacobian;
use rigctl::calib::{default_selection, CalibrateOptions};
use rigctl::fusion::curve::TracedCurve;
use rigctl::fusion::pot::TravelSeries;
use rigctl::fusion::{fuse, FuseOptions, Fused, JointSamples, PotCalibration};
use rigctl::model::{katana450, Model, KATANA_PENCIL_TOOL_MM};
use rigctl::sim::session::{simulate_session, Session, SessionConfig, SessionPath};

fn run(path: SessionPath, seed: u64) -> (Model, SessionConfig, Session, Fused) {
    let declared = katana450(KATANA_PENCIL_TOOL_MM).unwrap();
    let cfg = SessionConfig { path, seed, ..SessionConfig::default() };
    let s = simulate_session(&declared, &cfg).unwrap();
    let cal = PotCalibration::fit(&s.jig, 1).unwrap();
    let pot = TravelSeries::new(&s.pot_samples(), |r| cal.travel_mm(r));
    let curve = TracedCurve::new(s.pencil_mm.clone(), 2.0).unwrap();
    let joints = JointSamples { t_s: s.t_s.clone(), q_deg: s.q_deg.clone() };
    let fused = fuse(&declared, &joints, &pot, &curve, &s.placement, &FuseOptions::default()).unwrap();
    (declared, cfg, s, fused)
}

#[test]
fn fused_components_match_the_truth_and_the_clock_offset_is_recovered() {
    for path in [SessionPath::Circle, SessionPath::Line] {
        let (_, cfg, s, fused) = run(path, 3);
        let a = &fused.alignment;
        let err_ms = (a.board_s(5.0) - (5.0 + cfg.clock_offset_s)) * 1e3;
        eprintln!(
            "{path:?}: {} samples, skipped {:?}, offset error {err_ms:.4} ms, drift {:.2} ppm, markers {}",
            fused.samples.len(),
            fused.skipped,
            a.drift_ppm,
            a.markers.len()
        );
        for m in &a.markers {
            eprintln!("  {m:?} err {:.4} ms", (m.offset_s - cfg.clock_offset_s) * 1e3);
        }
        assert!(err_ms.abs() < 1.0, "clock offset error {err_ms} ms");
        assert_eq!(a.markers.len(), 2);
        let (mut worst_u, mut worst_n, mut rms_dev) = (0.0f64, 0.0f64, 0.0);
        for f in &fused.samples {
            let k = s.t_s.iter().position(|&t| (t - f.t_s).abs() < 1e-9).unwrap();
            let e: Vector3<f64> = s.truth_mm[k] - f.nominal_mm;
            worst_u = worst_u.max((f.u.dot(&e) - f.dev_u_mm).abs());
            if (f.u.dot(&e) - f.dev_u_mm).abs() > 0.02 {
                eprintln!("  t {:.2} u err {:+.3} n err {:+.3}", f.t_s, f.u.dot(&e) - f.dev_u_mm, f.n.dot(&e) - f.dev_n_mm);
            }
            worst_n = worst_n.max((f.n.dot(&e) - f.dev_n_mm).abs());
            rms_dev += f.dev_u_mm.powi(2) + f.dev_n_mm.powi(2);
            // u lies in the sheet, across the path
            assert!(f.u.dot(&f.n).abs() < 1e-12);
        }
        rms_dev = (rms_dev / fused.samples.len() as f64).sqrt();
        eprintln!("{path:?}: worst |u error| {worst_u:.4} mm, |n error| {worst_n:.4} mm, rms measured deviation {rms_dev:.3} mm");
        // pot: 1 count = 0.0026 mm noise; the trace stand-in is the tip path sampled every
        // 0.05 mm; the along-path error e_t (up to ~2 mm here) bends the across-path reading by
        // e_t^2 / 2R (0.02 mm on the circle)
        assert!(worst_n < 0.015, "{worst_n}");
        assert!(worst_u < 0.05, "{worst_u}");
        assert!(rms_dev > 0.05, "the truth errors should be visible ({rms_dev})");
    }
}

#[test]
fn projected_calibration_on_two_sheets_reduces_the_error() {
    let (declared, _, s1, f1) = run(SessionPath::Circle, 5);
    let (_, _, s2, f2) = run(SessionPath::Line, 5);
    let samples: Vec<_> = f1.samples.iter().chain(&f2.samples).cloned().collect();
    let data = ProjectedData::from_fused(&samples).with_dynamic_moments(&declared).unwrap();
    let out = calibrate_projected(&declared, &data, SampleTilt::Dynamic, &CalibrateOptions::default()).unwrap();
    let r = &out.report;
    eprintln!(
        "measured |dP| mean {:.4} -> {:.4} mm (standard {:.4}); unidentifiable {:?}; rank {}",
        r.calibration.before.mean_mm, r.calibration.after.mean_mm, r.standard.calibration.mean_mm,
        r.unidentifiable, r.rank
    );
    // The truth expressed with the unidentifiable members at their nominal values: moving along
    // each null direction (coefficients c, fixed member 1) until the fixed member is nominal.
    let sel = default_selection(&declared, false);
    let jac = projected_jacobian(&declared, &data, &sel, SampleTilt::Dynamic).unwrap();
    let id = analyse(&jac, DEFAULT_RTOL);
    let mut eq: Vec<f64> = sel.iter().map(|&c| s1.truth.params()[c].value).collect();
    for comb in &id.combinations {
        let t = eq[comb.fixed] - declared.params()[sel[comb.fixed]].value;
        for &(m, c) in &comb.members {
            eq[m] -= c * t;
        }
    }
    let mut worst = 0.0f64;
    for (k, &c) in sel.iter().enumerate() {
        let name = &declared.params()[c].name;
        let fit = r.parameters.get(name).unwrap();
        match r.sigma.get(name) {
            Some(sig) => {
                let z = (fit - eq[k]) / sig;
                worst = worst.max(z.abs());
                eprintln!("{name:6} fit {fit:+.5} truth {:+.5} equivalent {:+.5} sigma {sig:.5} z {z:+.2}",
                    s1.truth.params()[c].value, eq[k]);
            }
            None => eprintln!("{name:6} fixed at {fit:+.5} (truth {:+.5})", s1.truth.params()[c].value),
        }
    }
    let _ = s2;
    for tilt in [SampleTilt::Off, SampleTilt::Static, SampleTilt::Dynamic] {
        let e = rigctl::calib::projected::measured_errors(&s1.truth, &data, tilt).unwrap();
        let st = rigctl::calib::Stats::from_errors(&e);
        eprintln!("truth model with {tilt:?}: mean {:.4} rms {:.4} max {:.4}", st.mean_mm, st.rms_mm, st.max_mm);
    }
    assert!(r.calibration.after.mean_mm < 0.3 * r.calibration.before.mean_mm);
}
