use nalgebra::Vector3;

use crate::model::{katana450, ur5, Model, Tilt, Wrt, KATANA_TOOL_MM};

const Q_UR5: [f64; 6] = [20.0, -65.0, 80.0, -40.0, 55.0, 30.0];

fn with_lateral(mut m: Model, values: &[(usize, f64)]) -> Model {
    for &(j, c) in values {
        m.set_lateral_compliance(j, c).unwrap();
    }
    m
}

/// The bend sits where the declared tilting's does: the chain with `Rx(c eta_x) Ry(c eta_y)` at
/// joint frame i (`Model::frames` with those tilts, the moments of the untilted chain).
#[test]
fn the_bend_is_the_tilt_at_the_joint_frame_from_the_untilted_moments() {
    let m = with_lateral(ur5().unwrap(), &[(1, 0.03), (2, 0.05)]);
    let eta = m.moments_kgfm(&Q_UR5).unwrap();
    let tilts: Vec<Vector3<f64>> = (0..6)
        .map(|j| Vector3::new(eta[j].x, eta[j].y, 0.0) * m.lateral_compliance_at(j))
        .collect();
    assert!(
        tilts[1].norm() > 1e-3 && tilts[2].norm() > 1e-3,
        "{tilts:?}"
    );
    let frames = m.frames(&Q_UR5, Some(&tilts)).unwrap();
    let p = m.position_mm(&Q_UR5, Tilt::Off).unwrap();
    assert!(
        (p - frames.tool_mm()).norm() < 1e-9,
        "{p} {}",
        frames.tool_mm()
    );
    let rigid = ur5().unwrap().position_mm(&Q_UR5, Tilt::Off).unwrap();
    assert!((p - rigid).norm() > 0.05, "{}", (p - rigid).norm());
}

/// Every analytic column (joints, parameters, the lateral compliances themselves) of a model
/// with lateral compliance, with and without the declared tilting, matches central differences.
#[test]
fn the_analytic_jacobian_matches_central_differences() {
    let ur = with_lateral(ur5().unwrap(), &[(1, 0.03), (2, 0.05)]);
    let mut kat = with_lateral(katana450(KATANA_TOOL_MM).unwrap(), &[(1, 0.04), (3, 0.02)]);
    kat.set_param("payload_kg", 0.3).unwrap();
    let q_kat = [30.0, 40.0, -50.0, 20.0, 35.0];
    for (m, q, tilt) in [
        (&ur, &Q_UR5[..], Tilt::Off),
        (&kat, &q_kat[..], Tilt::Static),
        (&kat, &q_kat[..], Tilt::Off),
    ] {
        let n = m.n_joints();
        let mut wrt: Vec<Wrt> = (0..n).map(Wrt::Joint).collect();
        wrt.extend((0..n).map(Wrt::Lateral));
        for name in ["base_rx", "base_ry", "tool_dz", "payload_kg", "dth2", "a3"] {
            // a base tilt gives joint 1 an axis torque where it has none: the declared
            // tilting's backlash sign step (MODEL.md eq. 5.19) sits at zero
            let sign_step = name.starts_with("base_r") && matches!(tilt, Tilt::Static);
            if let Some(i) = m.param_index(name).filter(|_| !sign_step) {
                wrt.push(Wrt::Param(i));
            }
        }
        let (_, jac) = m.position_jacobian(q, tilt, &wrt).unwrap();
        for (c, w) in wrt.iter().enumerate() {
            let h = match w {
                Wrt::Lateral(_) => 1e-4,
                _ => 1e-5,
            };
            let at = |s: f64| {
                let mut mm = m.clone();
                let mut qq = q.to_vec();
                match *w {
                    Wrt::Joint(j) => qq[j] += s,
                    Wrt::Lateral(j) => {
                        let c0 = mm.lateral_compliance_at(j);
                        mm.set_lateral_compliance(j, c0 + s).unwrap();
                    }
                    Wrt::Param(i) => {
                        let v = mm.params()[i].value;
                        mm.set_param_at(i, v + s).unwrap();
                    }
                }
                mm.position_mm(&qq, tilt).unwrap()
            };
            let fd = (at(h) - at(-h)) / (2.0 * h);
            let an = jac.column(c).into_owned();
            assert!(
                (fd - an).norm() < 1e-5 * (1.0 + fd.norm()),
                "{} {w:?} ({tilt:?}): analytic {an} finite differences {fd}",
                m.name()
            );
        }
    }
}

/// The column of a lateral compliance at zero is the one at any value (the prediction is linear
/// in it to first order), and all zeros leave the model the rigid one bit for bit.
#[test]
fn zero_lateral_compliance_is_the_rigid_model_and_still_has_its_column() {
    let rigid = ur5().unwrap();
    let zero = with_lateral(ur5().unwrap(), &[(2, 0.0)]);
    let wrt = [Wrt::Joint(1), Wrt::Param(rigid.param_index("a2").unwrap())];
    let (f0, j0) = rigid.position_jacobian(&Q_UR5, Tilt::Off, &wrt).unwrap();
    let (f1, j1) = zero.position_jacobian(&Q_UR5, Tilt::Off, &wrt).unwrap();
    assert_eq!(f0.position_mm, f1.position_mm);
    assert_eq!(j0, j1);
    let (_, col) = zero
        .position_jacobian(&Q_UR5, Tilt::Off, &[Wrt::Lateral(2)])
        .unwrap();
    let h = 1e-4;
    let p = |c: f64| {
        with_lateral(ur5().unwrap(), &[(2, c)])
            .position_mm(&Q_UR5, Tilt::Off)
            .unwrap()
    };
    let fd = (p(h) - p(-h)) / (2.0 * h);
    assert!(
        (fd - col.column(0)).norm() < 1e-6 * (1.0 + fd.norm()),
        "{fd} {col}"
    );
    assert!(fd.norm() > 1.0, "{fd}");
}

#[test]
fn a_joint_beyond_the_chain_or_a_non_finite_value_is_refused() {
    let mut m = ur5().unwrap();
    assert!(m.set_lateral_compliance(6, 0.01).is_err());
    assert!(m.set_lateral_compliance(1, f64::NAN).is_err());
    assert!(m
        .position_jacobian(&Q_UR5, Tilt::Off, &[Wrt::Lateral(6)])
        .is_err());
}

/// A model file holds the values (`[[joint]] lateral_compliance_deg_per_kgfm`) and reads back
/// the identical model; without link masses the key is refused.
#[test]
fn model_files_hold_lateral_compliance_and_need_masses() {
    let m = with_lateral(ur5().unwrap(), &[(2, 0.05)]);
    let text = m.to_toml_string();
    assert!(
        text.contains("lateral_compliance_deg_per_kgfm = 0.05"),
        "{text}"
    );
    let back = Model::from_toml_str(&text, "t").unwrap();
    assert_eq!(back.lateral_compliance(), m.lateral_compliance());
    assert_eq!(
        back.position_mm(&Q_UR5, Tilt::Off).unwrap(),
        m.position_mm(&Q_UR5, Tilt::Off).unwrap()
    );
    let rigid = ur5().unwrap().to_toml_string();
    assert!(!rigid.contains("lateral"), "{rigid}");
    let no_masses: String = text.split("\n[[mass]]").next().unwrap().to_string();
    let err = Model::from_toml_str(&no_masses, "t")
        .unwrap_err()
        .to_string();
    assert!(err.contains("link masses"), "{err}");
}
