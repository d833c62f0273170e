//! The ISO 9283 calibration sequence and the reachability of the thesis's circle.

use nalgebra::Vector3;
use rigctl::model::ik::{solve, IkTilt};
use rigctl::model::{katana450, Tilt};
use rigctl::sim::iso9283::{Cube, ISO_POSE_COUNT};
use rigctl::sim::paths::{Circle, Path};
use rigctl::sim::plan::{iso_calibration_sequence, KATANA_SEED_DEG};

#[test]
fn iso_sequence_has_118_reachable_poses_changing_every_joint() {
    let model = katana450(200.0).unwrap();
    let cube = Cube::thesis_frontal();
    let seq = iso_calibration_sequence(&model, &cube).unwrap();
    assert_eq!(seq.len(), ISO_POSE_COUNT);
    assert_eq!(seq[0].id, "P1");
    assert_eq!(seq[ISO_POSE_COUNT - 1].id, "P1");
    let limits = model.joint_limits();
    let mut smallest_change = f64::INFINITY;
    for (k, p) in seq.iter().enumerate() {
        // the commanded joints put the rigid tool at the target, inside the cube
        let at = model.position_mm(&p.q_deg, Tilt::Off).unwrap();
        assert!((at - p.target.position_mm).norm() < 1e-9, "{}", p.id);
        let rel = (at - cube.centre_mm) / cube.side_mm;
        assert!(rel.amax() <= 0.4 + 1e-9, "{} outside the inset cube", p.id);
        for (v, l) in p.q_deg.iter().zip(&limits) {
            assert!(*v >= l[0] && *v <= l[1], "{}: {v} outside {l:?}", p.id);
        }
        if k > 0 {
            let change = seq[k - 1]
                .q_deg
                .iter()
                .zip(&p.q_deg)
                .map(|(a, b)| (a - b).abs())
                .fold(f64::INFINITY, f64::min);
            smallest_change = smallest_change.min(change);
        }
    }
    eprintln!("smallest joint change between consecutive poses: {smallest_change:.3} deg");
    assert!(
        smallest_change > 5.0,
        "some move leaves a joint (almost) still: {smallest_change} deg"
    );
}

/// Which of 72 samples of the thesis's circle (tool normal to the plane) are reachable.
fn circle_reachability(tool_mm: f64) -> Vec<bool> {
    let model = katana450(tool_mm).unwrap();
    let circle = Circle::thesis(Vector3::zeros());
    (0..72)
        .map(|k| {
            solve(
                &model,
                &circle.at(k as f64 / 72.0),
                &KATANA_SEED_DEG,
                IkTilt::Off,
            )
            .is_ok()
        })
        .collect()
}

/// Finding (reported): with the tool exactly normal to the 45-degree plane, the thesis's circle
/// is only partly reachable within the joint limits of table 3.1, for both tool lengths. The
/// binding limits are q2 <= 102 and |q4| <= 112 (the tool is at right angles to the roll axis).
#[test]
fn thesis_circle_with_normal_tool_is_only_partly_reachable() {
    for (tool, lo, hi) in [(200.0, 30, 60), (330.0, 20, 50)] {
        let ok = circle_reachability(tool);
        let n = ok.iter().filter(|b| **b).count();
        eprintln!(
            "d5 = {tool} mm: {n}/72 circle samples reachable: {}",
            ok.iter()
                .map(|b| if *b { '#' } else { '.' })
                .collect::<String>()
        );
        assert!((lo..=hi).contains(&n), "d5 = {tool}: {n}/72 reachable");
    }
}
