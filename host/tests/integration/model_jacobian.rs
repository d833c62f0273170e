//! The analytic Jacobians against central finite differences of `Model::fk`'s position, on
//! random poses of perturbed models, relative tolerance 1e-6 per column.

use nalgebra::{Matrix3xX, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigctl::model::{katana450, ur5, GammaLaw, Model, Tilt, Wrt};

use crate::common::record::record;

/// Relative tolerance of a column: |analytic - fd| <= REL * |fd| + ABS.
const REL: f64 = 1e-6;
/// Floor for columns that are (near) zero, mm per unit.
const ABS: f64 = 1e-9;

/// A Katana with every kind of parameter away from its nominal value, so that no moment
/// component sits on a sign step of the tilt law.
fn perturbed_katana(rng: &mut ChaCha8Rng) -> Model {
    let mut m = katana450(200.0).unwrap();
    let names: Vec<String> = m.param_names().map(str::to_string).collect();
    for name in names {
        let v = m.param(&name).unwrap();
        let dv = if name.starts_with("enc_") {
            rng.gen_range(-0.02..0.02)
        } else if name.starts_with("stiffness") {
            rng.gen_range(-5.0..5.0)
        } else if name.starts_with("clearance") || name.starts_with("backlash") {
            rng.gen_range(-0.005..0.005)
        } else if name == "payload_kg" {
            0.3
        } else if name == "scale_ppm" {
            40.0
        } else if name.starts_with("tool_") {
            rng.gen_range(3.0..8.0)
        } else if name.starts_with("base_r") {
            rng.gen_range(0.1..0.4)
        } else if name.starts_with("a") && !name.starts_with("al")
            || name.starts_with('d') && !name.starts_with("dth")
        {
            rng.gen_range(-0.3..0.3)
        } else {
            rng.gen_range(-0.08..0.08)
        };
        m.set_param(&name, v + dv).unwrap();
    }
    m
}

fn random_q(m: &Model, rng: &mut ChaCha8Rng) -> Vec<f64> {
    m.joint_limits()
        .iter()
        .map(|[lo, hi]| rng.gen_range(lo * 0.9..hi * 0.9))
        .collect()
}

/// Finite-difference derivative of the position wrt one coordinate.
fn fd_column(m: &Model, q: &[f64], tilt: Tilt<'_>, wrt: Wrt) -> Vector3<f64> {
    let eval = |delta: f64| {
        let mut m2 = m.clone();
        let mut q2 = q.to_vec();
        match wrt {
            Wrt::Joint(j) => q2[j] += delta,
            Wrt::Param(i) => {
                let v = m2.params()[i].value;
                m2.set_param_at(i, v + delta).unwrap();
            }
            Wrt::Lateral(j) => {
                let c = m2.lateral_compliance_at(j);
                m2.set_lateral_compliance(j, c + delta).unwrap();
            }
        }
        m2.fk(&q2, tilt).unwrap().position_mm
    };
    let h = match wrt {
        Wrt::Param(i) if m.params()[i].name == "scale_ppm" => 1.0,
        Wrt::Param(i) if m.params()[i].name.starts_with("stiffness") => 1e-2,
        _ => 1e-3,
    };
    // Richardson-extrapolated central differences (error O(h^4)).
    let d = |h: f64| (eval(h) - eval(-h)) / (2.0 * h);
    (d(h / 2.0) * 4.0 - d(h)) / 3.0
}

fn check(m: &Model, q: &[f64], tilt: Tilt<'_>, what: &str) -> usize {
    let wrt: Vec<Wrt> = (0..m.n_joints())
        .map(Wrt::Joint)
        .chain((0..m.params().len()).map(Wrt::Param))
        .collect();
    let (fk, jac): (_, Matrix3xX<f64>) = m.position_jacobian(q, tilt, &wrt).unwrap();
    assert!((fk.position_mm - m.fk(q, tilt).unwrap().position_mm).norm() == 0.0);
    let mut nonzero = 0;
    for (c, &w) in wrt.iter().enumerate() {
        let fd = fd_column(m, q, tilt, w);
        let an = jac.column(c).into_owned();
        let name = match w {
            Wrt::Joint(j) => format!("q{}", j + 1),
            Wrt::Param(i) => m.params()[i].name.clone(),
            Wrt::Lateral(j) => format!("lateral_j{}", j + 1),
        };
        assert!(
            (an - fd).norm() <= REL * fd.norm() + ABS,
            "{what}: column {name} at q = {q:?}: analytic {an:?} vs finite difference {fd:?}"
        );
        if fd.norm() > 1e-6 {
            nonzero += 1;
        }
    }
    nonzero
}

/// Every moment component away from the sign step (|x| >= 1e-9) by a wide margin, so the
/// finite differences do not straddle it.
fn clear_of_sign_steps(m: &Model, q: &[f64]) -> bool {
    m.moments_kgfm(q)
        .unwrap()
        .iter()
        .all(|eta| eta.iter().all(|c| c.abs() > 1e-4))
}

#[test]
fn katana_jacobian_matches_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut checked = 0;
    for round in 0..12 {
        let mut m = perturbed_katana(&mut rng);
        if round % 2 == 1 {
            m.set_gamma_law(GammaLaw::Atan2);
        }
        let q = random_q(&m, &mut rng);
        let n_off = check(&m, &q, Tilt::Off, "tilt off");
        // Off: joints, chain, base, tool, encoder harmonics and scale move the tool; tilting
        // values and payload do not.
        assert!(n_off >= 5 + 19 + 5 + 3, "only {n_off} non-zero columns");
        if !clear_of_sign_steps(&m, &q) {
            continue;
        }
        let n_static = check(&m, &q, Tilt::Static, "static tilt");
        assert!(
            n_static > n_off,
            "tilting values and payload must act with tilt on"
        );
        let ext: Vec<Vector3<f64>> = (0..5)
            .map(|_| {
                Vector3::new(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                )
            })
            .collect();
        check(&m, &q, Tilt::Moments(&ext), "external moments");
        // static moments plus fixed extra (inertial) ones: the static part is differentiated
        let extra: Vec<Vector3<f64>> = ext.iter().map(|e| e * 0.02).collect();
        let total_clear = m
            .moments_kgfm(&q)
            .unwrap()
            .iter()
            .zip(&extra)
            .all(|(s, e)| (s + e).iter().all(|c| c.abs() > 1e-4));
        if total_clear {
            let n_plus = check(&m, &q, Tilt::StaticPlus(&extra), "static plus extra");
            assert!(
                n_plus > n_off,
                "tilting values and payload act through the static part"
            );
            let (a, b) = (
                m.fk(&q, Tilt::StaticPlus(&extra)).unwrap(),
                m.fk(&q, Tilt::Static).unwrap(),
            );
            for ((ma, mb), e) in a.moments_kgfm.iter().zip(&b.moments_kgfm).zip(&extra) {
                assert!((ma - mb - e).norm() < 1e-12);
            }
        }
        checked += 1;
    }
    assert!(checked >= 8, "only {checked} poses clear of the sign steps");
    record("relative_tolerance", REL);
}

#[test]
fn ur5_jacobian_matches_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for _ in 0..8 {
        let mut m = ur5().unwrap();
        for name in [
            "tool_dy",
            "tool_dz",
            "base_rx",
            "enc_j2_h1_sin",
            "enc_j6_h3_cos",
            "scale_ppm",
        ] {
            m.set_param(name, rng.gen_range(0.01..30.0)).unwrap();
        }
        let q = random_q(&m, &mut rng);
        check(&m, &q, Tilt::Off, "ur5");
    }
}

#[test]
fn jacobian_rejects_bad_indices() {
    let m = katana450(200.0).unwrap();
    let q = [0.0; 5];
    assert!(m
        .position_jacobian(&q, Tilt::Off, &[Wrt::Joint(5)])
        .is_err());
    assert!(m
        .position_jacobian(&q, Tilt::Off, &[Wrt::Param(m.params().len())])
        .is_err());
    assert!(m
        .position_jacobian(&q[..4], Tilt::Off, &[Wrt::Joint(0)])
        .is_err());
}
