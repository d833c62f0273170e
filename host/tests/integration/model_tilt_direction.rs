//! `Model::set_tilt_direction_frozen`, the Jacobian `rigctl plan` designs on: the position is
//! unchanged, only the slope of the clearance tilt's contact direction (MODEL.md eq. 5.16) is
//! dropped. Without clearance it is the exact Jacobian; on random poses it differs from the
//! exact one by a small share of a column; where a joint's moment vanishes the exact slope
//! explodes and the frozen one stays at the size of the geometry's.

use nalgebra::Matrix3xX;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigctl::model::{katana450, Model, Tilt, Wrt, KATANA_TOOL_MM};

fn all_params(m: &Model) -> Vec<Wrt> {
    (0..m.params().len()).map(Wrt::Param).collect()
}

fn jac(m: &Model, q: &[f64], frozen: bool) -> Matrix3xX<f64> {
    let mut m = m.clone();
    m.set_tilt_direction_frozen(frozen);
    m.position_jacobian(q, Tilt::Static, &all_params(&m))
        .unwrap()
        .1
}

fn random_q(m: &Model, rng: &mut ChaCha8Rng) -> Vec<f64> {
    m.joint_limits()
        .iter()
        .map(|[lo, hi]| rng.gen_range(lo * 0.95..hi * 0.95))
        .collect()
}

#[test]
fn position_unchanged_and_exact_without_clearance() {
    let declared = katana450(KATANA_TOOL_MM).unwrap();
    let mut frozen = declared.clone();
    frozen.set_tilt_direction_frozen(true);
    let mut no_clearance = declared.clone();
    for j in 1..=5 {
        no_clearance
            .set_param(&format!("clearance_j{j}"), 0.0)
            .unwrap();
    }
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..50 {
        let q = random_q(&declared, &mut rng);
        let a = declared.position_mm(&q, Tilt::Static).unwrap();
        let b = frozen.position_mm(&q, Tilt::Static).unwrap();
        assert_eq!(a, b, "the position does not depend on the flag");
        let (e, f) = (jac(&no_clearance, &q, false), jac(&no_clearance, &q, true));
        let diff = (&e - &f).abs().max();
        assert!(
            diff <= 1e-12 * e.abs().max(),
            "without clearance the frozen Jacobian is the exact one: {diff}"
        );
    }
}

#[test]
fn small_share_on_random_poses_bounded_where_a_moment_vanishes() {
    let declared = katana450(KATANA_TOOL_MM).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let mut shares = Vec::new();
    for _ in 0..200 {
        let q = random_q(&declared, &mut rng);
        let (e, f) = (jac(&declared, &q, false), jac(&declared, &q, true));
        // share of the geometric columns (the 12 identified: dth, al, be) on this pose
        for name in ["dth2", "dth3", "al2", "al3", "al4", "be3"] {
            let k = declared.param_index(name).unwrap();
            let share = (e.column(k) - f.column(k)).norm() / f.column(k).norm().max(1e-3);
            shares.push(share);
        }
    }
    shares.sort_by(f64::total_cmp);
    let median = shares[shares.len() / 2];
    eprintln!(
        "share of the contact-direction slope: median {median:.2e}, p90 {:.2e}",
        shares[shares.len() * 9 / 10]
    );
    assert!(median < 0.01, "median share {median}");
    // joints 2 and 3 sum to zero: the moment of joint 3's clearance plane nearly vanishes
    let q = [
        -126.347152299,
        0.091753272,
        -0.064405103,
        -49.344948689,
        89.952589096,
    ];
    let k = declared.param_index("al2").unwrap();
    let (e, f) = (jac(&declared, &q, false), jac(&declared, &q, true));
    let (ne, nf) = (e.column(k).norm(), f.column(k).norm());
    eprintln!("al2 column at a vanishing moment: exact {ne:.1} mm/deg, frozen {nf:.2} mm/deg");
    assert!(ne > 20.0 * nf, "exact {ne} frozen {nf}");
    let mut no_clearance = declared.clone();
    for j in 1..=5 {
        no_clearance
            .set_param(&format!("clearance_j{j}"), 0.0)
            .unwrap();
    }
    let g = jac(&no_clearance, &q, false);
    let ng = g.column(k).norm();
    assert!(
        (nf - ng).abs() <= 0.2 * ng + 0.05,
        "frozen {nf} vs the geometry without clearance {ng}"
    );
}
