//! The extra effects every model carries (FORMATS.md effect ids), checked against hand
//! computations at simple poses.

use nalgebra::Vector3;
use rigctl::model::{harmonic_amplitude_phase, katana450, sign_1e9, Tilt};

#[test]
fn payload_adds_its_moment_at_the_tool_point() {
    let mut m = katana450(200.0).unwrap();
    let q = [0.0; 5];
    let before = m.moments_kgfm(&q).unwrap();
    m.set_param("payload_kg", 0.5).unwrap();
    let after = m.moments_kgfm(&q).unwrap();
    // q = 0: tool at (384, -145, 348.8), joint 1 origin (55, 55, 201.5), joint frame 1 = R;
    // (c - o) x (0, 0, -m) = (-m r_y, m r_x, 0) with r = (0.329, -0.2, ..) m.
    let d = after[0] - before[0];
    assert!(
        (d - Vector3::new(0.5 * 0.2, 0.5 * 0.329, 0.0)).norm() < 1e-12,
        "{d:?}"
    );
}

#[test]
fn base_tilt_moves_gravity_into_joint_1() {
    let mut m = katana450(200.0).unwrap();
    let q = [30.0, 40.0, 20.0, 10.0, 5.0];
    assert!(m.moments_kgfm(&q).unwrap()[0].z.abs() < 1e-12);
    m.set_param("base_rx", 0.5).unwrap();
    assert!(m.moments_kgfm(&q).unwrap()[0].z.abs() > 1e-4);
}

#[test]
fn scale_is_about_the_origin_of_r() {
    let mut m = katana450(200.0).unwrap();
    let q = [10.0, 20.0, 30.0, 40.0, 50.0];
    let p0 = m.position_mm(&q, Tilt::Off).unwrap();
    m.set_param("scale_ppm", 100.0).unwrap();
    let p1 = m.position_mm(&q, Tilt::Off).unwrap();
    assert!((p1 - p0 * (1.0 + 100e-6)).norm() < 1e-12);
}

#[test]
fn encoder_harmonic_is_a_joint_angle_error() {
    let mut m = katana450(200.0).unwrap();
    let q = [10.0, 20.0, 30.0, 40.0, 50.0];
    // 0.02 sin(2 q3) + 0.01 cos(2 q3) at q3 = 30 deg shifts joint 3 by that many degrees.
    m.set_param("enc_j3_h2_sin", 0.02).unwrap();
    m.set_param("enc_j3_h2_cos", 0.01).unwrap();
    let shift = 0.02 * 60f64.to_radians().sin() + 0.01 * 60f64.to_radians().cos();
    let p = m.position_mm(&q, Tilt::Off).unwrap();
    let nominal = katana450(200.0).unwrap();
    let p_shift = nominal
        .position_mm(&[10.0, 20.0, 30.0 + shift, 40.0, 50.0], Tilt::Off)
        .unwrap();
    assert!((p - p_shift).norm() < 1e-12);
    // A sin(2 q + phi) form.
    let (a, phi) = harmonic_amplitude_phase(0.02, 0.01);
    assert!((a * (60f64 + phi).to_radians().sin() - shift).abs() < 1e-15);
}

#[test]
fn tool_offset_is_in_the_last_frame() {
    let mut m = katana450(200.0).unwrap();
    let q = [0.0; 5];
    m.set_param("tool_dz", 10.0).unwrap();
    // q = 0: the last frame's z is -y of R (al5 = 90 after al4 = -90 after al2 = 90).
    let p = m.position_mm(&q, Tilt::Off).unwrap();
    assert!(
        (p - Vector3::new(384.0, -155.0, 348.8)).norm() < 1e-9,
        "{p:?}"
    );
}

#[test]
fn sign_has_the_declared_threshold() {
    assert_eq!(sign_1e9(0.99e-9), 0.0);
    assert_eq!(sign_1e9(-0.99e-9), 0.0);
    assert_eq!(sign_1e9(1.0e-9), 1.0);
    assert_eq!(sign_1e9(-2e-3), -1.0);
}

#[test]
fn tilt_needs_tilt_data_and_right_lengths() {
    let ur = rigctl::model::ur5().unwrap();
    assert!(ur.fk(&[0.0; 6], Tilt::Static).is_err());
    let k = katana450(200.0).unwrap();
    assert!(k.fk(&[0.0; 4], Tilt::Off).is_err());
    assert!(k
        .fk(&[0.0; 5], Tilt::Moments(&[Vector3::zeros(); 4]))
        .is_err());
    assert!(k.clone().set_param("stiffness_j2", 0.0).is_err());
    assert!(k.clone().set_param("dth2", f64::NAN).is_err());
}
