//! Calibration of the real UR5 laser-tracker data (shared/data/real/ur5_laser_tracker): 1000
//! grid poses fit, 20 random poses held out. Published (P. Jacobi 2025, hybrid MDH + neural
//! network): mean 2.5664 mm before, 0.1549 mm after on the 20 test poses.

use crate::common;
use crate::common::record::record;

use rigctl::calib::{calibrate, CalibrateOptions, Method};

#[test]
fn ur5_held_out_mean_beats_the_published_value() {
    let Some((model, cal, val)) =
        common::ur5_tracker("ur5_held_out_mean_beats_the_published_value")
    else {
        return;
    };
    assert_eq!((cal.len(), val.len()), (1000, 20));
    let opts = CalibrateOptions {
        method: Method::Standard,
        base: true,
        ..Default::default()
    };
    let out = calibrate(&model, &cal, Some(&val), &opts).unwrap();
    let v = out.report.validation.unwrap();
    eprintln!(
        "UR5 held-out mean {:.4} -> {:.4} mm (published 2.5664 -> 0.1549)",
        v.before.mean_mm, v.after.mean_mm
    );
    record("before_mm", v.before.mean_mm);
    record("after_mm", v.after.mean_mm);
    // The nominal model with the SMR offset reproduces the published "before".
    assert!(
        (v.before.mean_mm - 2.5664).abs() < 0.01,
        "before {}",
        v.before.mean_mm
    );
    assert!(v.after.mean_mm < 0.1549, "after {}", v.after.mean_mm);
    assert!(out.report.converged);
    // Parallel joints 2-4: their d offsets only act as a sum.
    assert!(
        out.report.unidentifiable.iter().any(|u| u == "d2+d3"),
        "{:?}",
        out.report.unidentifiable
    );
}
