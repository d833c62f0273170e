//! Recursive Newton-Euler on the Katana: the static case equals the model's statics, and the
//! inertial terms match hand-derived values at q = 0.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigctl::model::dynamics::{moments_kgfm, Inertia};
use rigctl::model::rnea::G_M_S2;
use rigctl::model::{katana450, Tilt};
use rigctl::sim::paths::{Line, Path};
use rigctl::sim::trajectory::{joint_trajectory, positions_in_motion};

#[test]
fn at_rest_rnea_equals_the_statics_moments() {
    let mut model = katana450(200.0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for case in 0..3 {
        // plain, with a payload, with a payload and a tilted base (gravity in robot coordinates)
        if case == 1 {
            model.set_param("payload_kg", 0.35).unwrap();
        }
        if case == 2 {
            model.set_param("base_rx", 1.5).unwrap();
            model.set_param("base_ry", -0.7).unwrap();
        }
        for _ in 0..50 {
            let q: Vec<f64> = model
                .joint_limits()
                .iter()
                .map(|l| rng.gen_range(l[0]..l[1]))
                .collect();
            let stat = model.moments_kgfm(&q).unwrap();
            for inertia in [Inertia::PointMass, Inertia::SlenderRod] {
                let dynm = moments_kgfm(&model, &q, &[0.0; 5], &[0.0; 5], inertia).unwrap();
                for (a, b) in stat.iter().zip(&dynm) {
                    assert!(
                        (a - b).norm() < 1e-9,
                        "case {case} q {q:?}: statics {a} vs rnea {b}"
                    );
                }
            }
        }
    }
}

/// COGs at q = 0 relative to joint frame 1's origin (m), from MODEL.md's chain and table 4.2:
/// link 2 at x = 100; link 3 at x = 190 + 104; link 4 at x = 329, 80 up (Tz after Rx(-90) of
/// the vertical roll axis); link 5 at x = 329, z = 147.3, 70 along the tool (-y).
const COGS_M: [(f64, [f64; 3]); 4] = [
    (1.03, [0.100, 0.0, 0.0]),
    (0.90, [0.294, 0.0, 0.0]),
    (1.00, [0.329, 0.0, 0.080]),
    (0.80, [0.329, -0.070, 0.1473]),
];

#[test]
fn joint1_acceleration_moment_is_sum_m_rho2_alpha() {
    let model = katana450(200.0).unwrap();
    let alpha_deg = 30.0;
    let q = [0.0; 5];
    let stat = model.moments_kgfm(&q).unwrap();
    let dynm = moments_kgfm(
        &model,
        &q,
        &[0.0; 5],
        &[alpha_deg, 0.0, 0.0, 0.0, 0.0],
        Inertia::PointMass,
    )
    .unwrap();
    let i_zz: f64 = COGS_M
        .iter()
        .map(|(m, c)| m * (c[0] * c[0] + c[1] * c[1]))
        .sum();
    let want = -i_zz * alpha_deg.to_radians() / G_M_S2;
    let got = dynm[0].z - stat[0].z;
    assert!((got - want).abs() < 1e-12, "eta1_z {got} vs {want} kgf.m");
}

#[test]
fn joint1_spin_adds_the_centrifugal_moments() {
    let model = katana450(200.0).unwrap();
    let w_deg = 90.0;
    let q = [0.0; 5];
    let stat = model.moments_kgfm(&q).unwrap();
    let dynm = moments_kgfm(
        &model,
        &q,
        &[w_deg, 0.0, 0.0, 0.0, 0.0],
        &[0.0; 5],
        Inertia::PointMass,
    )
    .unwrap();
    // d'Alembert force m w^2 (cx, cy, 0) outwards at c: moment c x F = m w^2 (-cz cy, cz cx, 0)
    let w2 = w_deg.to_radians().powi(2);
    let want: Vector3<f64> = COGS_M
        .iter()
        .map(|(m, c)| Vector3::new(-c[2] * c[1], c[2] * c[0], 0.0) * (m * w2 / G_M_S2))
        .sum();
    let got = dynm[0] - stat[0];
    assert!((got - want).norm() < 1e-12, "{got} vs {want}");
}

#[test]
fn slender_rods_add_rotational_inertia_to_joint5() {
    // q5 accelerating at q = 0: link 5 is a rod from the wrist along the tool (-y) of length
    // 140 mm, turning about the vertical roll axis: I = m L^2/3 = m (L^2/12 + (L/2)^2).
    let model = katana450(200.0).unwrap();
    let a_deg = 100.0;
    let q = [0.0; 5];
    let stat = model.moments_kgfm(&q).unwrap();
    let acc = [0.0, 0.0, 0.0, 0.0, a_deg];
    let point = moments_kgfm(&model, &q, &[0.0; 5], &acc, Inertia::PointMass).unwrap();
    let rod = moments_kgfm(&model, &q, &[0.0; 5], &acc, Inertia::SlenderRod).unwrap();
    let a = a_deg.to_radians();
    let (m, l) = (0.8, 0.140);
    assert!(((point[4].z - stat[4].z) - (-m * 0.07f64.powi(2) * a / G_M_S2)).abs() < 1e-12);
    assert!(((rod[4].z - stat[4].z) - (-m * l * l / 3.0 * a / G_M_S2)).abs() < 1e-12);
}

#[test]
fn trajectory_along_a_line_is_smooth_and_tilting_follows_the_moments() {
    let model = katana450(200.0).unwrap();
    let line = Line {
        start_mm: Vector3::new(-80.0, -300.0, 139.29),
        end_mm: Vector3::new(80.0, -300.0, 139.29),
        tool_axis: -Vector3::z(),
    };
    let traj = joint_trajectory(&model, &line, 4.0, 81, &[-90.0, 60.0, -60.0, 0.0, 90.0]).unwrap();
    // rest to rest, and the rates agree with central differences of the samples in time
    for j in 0..5 {
        for k in [0, 80] {
            assert_eq!(traj.qd_deg_s[k][j], 0.0);
            assert_eq!(traj.qdd_deg_s2[k][j], 0.0);
        }
        for k in 1..80 {
            let dt = traj.t_s[k + 1] - traj.t_s[k];
            let fd = (traj.q_deg[k + 1][j] - traj.q_deg[k - 1][j]) / (2.0 * dt);
            let fdd =
                (traj.q_deg[k + 1][j] - 2.0 * traj.q_deg[k][j] + traj.q_deg[k - 1][j]) / (dt * dt);
            assert!(
                (fd - traj.qd_deg_s[k][j]).abs() < 0.05,
                "qd {fd} vs {}",
                traj.qd_deg_s[k][j]
            );
            assert!(
                (fdd - traj.qdd_deg_s2[k][j]).abs() < 0.5,
                "qdd {fdd} vs {}",
                traj.qdd_deg_s2[k][j]
            );
        }
    }
    // every sample is on the line (rigid model)
    for (k, q) in traj.q_deg.iter().enumerate() {
        let (s, _, _) = rigctl::sim::paths::quintic_profile(traj.t_s[k], 4.0);
        let p = model.position_mm(q, Tilt::Off).unwrap();
        assert!((p - line.at(s).position_mm).norm() < 1e-9);
    }
    // with motion the inertial torques change the moments (and can flip the backlash side), so
    // the tilted positions differ from the static-tilt ones by up to the order of the whole
    // tilting effect (thesis fig. 5.10: about 1 mm), not more
    let moving = positions_in_motion(&model, &traj, Inertia::SlenderRod).unwrap();
    let mut max_diff: f64 = 0.0;
    for (q, p) in traj.q_deg.iter().zip(&moving) {
        let stat = model.position_mm(q, Tilt::Static).unwrap();
        max_diff = max_diff.max((p - stat).norm());
    }
    eprintln!("dynamic vs static tilting: max difference {max_diff:.4} mm");
    assert!(
        max_diff > 1e-3 && max_diff < 2.0,
        "dynamic vs static tilting differ by {max_diff} mm"
    );
    // at the ends (at rest) they are the static ones
    for k in [0, 80] {
        let stat = model.position_mm(&traj.q_deg[k], Tilt::Static).unwrap();
        assert!((moving[k] - stat).norm() < 1e-12);
    }
}
