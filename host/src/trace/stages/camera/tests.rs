//! The camera fit on synthetic marks: scans, tilted photos with distortion, an off-centre lens,
//! outlying ring dots.

use super::*;

fn truth() -> CameraModel {
    let h = Matrix3::new(9.5, 2.1, 2000.0, -1.8, 10.2, 1500.0, 0.0011, -0.0007, 1.0);
    CameraModel::new(h, -0.07, 0.01, [1650.0, 1820.0], 2500.0).expect("invertible")
}

#[test]
fn jacobian_matches_finite_differences() {
    let m = truth();
    let s = [63.0, -41.0];
    let (_, j) = m.project_with_jacobian(s);
    let p0 = m.params();
    for k in 0..NP {
        let step = 1e-6 * p0[k].abs().max(1e-6);
        let mut pp = p0;
        pp[k] += step;
        let mut pm = p0;
        pm[k] -= step;
        let a = m.with_params(&pp).expect("p").to_px(s);
        let b = m.with_params(&pm).expect("m").to_px(s);
        for r in 0..2 {
            let fd = (a[r] - b[r]) / (2.0 * step);
            let tol = 1e-5 * fd.abs().max(j[(r, k)].abs()).max(1e-3);
            assert!(
                (fd - j[(r, k)]).abs() < tol,
                "param {k} row {r}: {fd} vs {}",
                j[(r, k)]
            );
        }
    }
}

#[test]
fn fit_recovers_distortion_and_inverts() {
    let m = truth();
    let (marks, px) = marks_seen_by(&m, |_| 0.0);
    let (fit, q) =
        CameraModel::fit(&marks, &px, [4000.0, 3000.0], &CameraParams::default()).expect("fit");
    // Exact marks: what is left is the prior's pull on the centre (475 px off the image
    // centre here), a thousandth of a pixel at the marks.
    assert!(q.rms_mm < 2e-4, "{q:?} {fit:?}");
    assert!(
        (fit.k1 - m.k1).abs() < 1e-4 && (fit.k2 - m.k2).abs() < 1e-4,
        "{fit:?}"
    );
    assert!(
        (fit.centre_px[0] - 1650.0).abs() < 1.0 && (fit.centre_px[1] - 1820.0).abs() < 1.0,
        "{fit:?}"
    );
    let s = [12.5, 77.0];
    let back = fit.to_mm(m.to_px(s));
    assert!((back[0] - s[0]).abs() < 1e-3 && (back[1] - s[1]).abs() < 1e-3);
    assert!(m
        .to_mm(m.to_px(s))
        .iter()
        .zip(s)
        .all(|(a, b)| (a - b).abs() < 1e-9));
}

/// The sheet-v2 marks (ring dots, corner fiducials, orientation dot) and their pixels through
/// `m`, mark `i` moved by `scatter_px(i)` in a direction that turns by 2.399 rad per mark.
fn marks_seen_by(
    m: &CameraModel,
    scatter_px: impl Fn(usize) -> f64,
) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
    let mut marks = crate::sheet::ring_dots_mm(180.0);
    marks.extend(crate::sheet::fiducial_centres_mm(180.0));
    let px = marks
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let p = m.to_px(*s);
            let (a, r) = (2.399 * i as f64, scatter_px(i));
            [p[0] + r * a.cos(), p[1] + r * a.sin()]
        })
        .collect();
    (marks, px)
}

/// The worst sheet error (mm) of `fit` over a 5 mm grid inside the ring of marks, for pixels
/// made by `truth`.
fn worst_inside_mm(fit: &CameraModel, truth: &CameraModel) -> f64 {
    let mut worst: f64 = 0.0;
    for i in -16..=16 {
        for j in -16..=16 {
            let s = [5.0 * i as f64, 5.0 * j as f64];
            let q = fit.to_mm(truth.to_px(s));
            worst = worst.max((q[0] - s[0]).hypot(q[1] - s[1]));
        }
    }
    worst
}

/// A photo cropped off its centre: the lens's axis 600 px from the image centre. Marks
/// located to 0.2 px; the inside of the ring must come out right, not only the marks.
#[test]
fn fit_finds_an_off_centre_distortion_centre() {
    let h = Matrix3::new(9.5, 2.1, 2000.0, -1.8, 10.2, 1500.0, 0.0011, -0.0007, 1.0);
    for (k1, c) in [(-0.08, [2450.0, 1100.0]), (0.06, [1480.0, 1750.0])] {
        let m = CameraModel::new(h, k1, 0.0, c, 2500.0).expect("invertible");
        let (marks, px) = marks_seen_by(&m, |_| 0.2);
        let (fit, _) =
            CameraModel::fit(&marks, &px, [4000.0, 3000.0], &CameraParams::default()).expect("fit");
        let worst = worst_inside_mm(&fit, &m);
        assert!(worst < 0.02, "k1 {k1}: {worst} mm inside the ring, {fit:?}");
        // The same marks fitted about the image centre (the model before) bend the inside.
        let fixed =
            CameraModel::new(fit.h, fit.k1, fit.k2, [2000.0, 1500.0], 2500.0).expect("invertible");
        let about_image_centre = {
            let all: Vec<usize> = (0..px.len()).collect();
            lm(fixed, &marks, &px, &all, None).expect("fit")
        };
        assert!(
            worst_inside_mm(&about_image_centre, &m) > 3.0 * worst,
            "k1 {k1}: the test does not tell the centres apart"
        );
    }
}

/// Distortion about the image centre, marks located to 0.2 px: two more parameters would fit
/// the marks' scatter, so the centre is held where it is.
#[test]
fn centre_is_held_when_the_marks_do_not_ask_for_it() {
    let h = Matrix3::new(9.5, 2.1, 2000.0, -1.8, 10.2, 1500.0, 0.0011, -0.0007, 1.0);
    let m = CameraModel::new(h, -0.06, 0.0, [2000.0, 1500.0], 2500.0).expect("invertible");
    let (marks, px) = marks_seen_by(&m, |i| 0.2 * (0.5 + (0.618 * i as f64).fract()));
    let (fit, _) =
        CameraModel::fit(&marks, &px, [4000.0, 3000.0], &CameraParams::default()).expect("fit");
    assert_eq!(fit.centre_px, [2000.0, 1500.0], "{fit:?}");
    assert!(worst_inside_mm(&fit, &m) < 0.02);
}

/// A flatbed scan: no distortion, so nothing determines the centre; it stays at the image
/// centre and the fit is the homography.
#[test]
fn scan_keeps_the_centre_at_the_image_centre() {
    let h = Matrix3::new(23.6, 0.4, 2480.0, 0.4, -23.6, 3500.0, 0.0, 0.0, 1.0);
    let m = CameraModel::new(h, 0.0, 0.0, [2480.0, 3508.0], 4300.0).expect("invertible");
    let (marks, px) = marks_seen_by(&m, |_| 0.0);
    let (fit, q) =
        CameraModel::fit(&marks, &px, [4960.0, 7016.0], &CameraParams::default()).expect("fit");
    assert!(q.rms_mm < 1e-6, "{q:?}");
    assert!(fit.k1.abs() < 1e-9 && fit.k2.abs() < 1e-9, "{fit:?}");
    assert!(
        (fit.centre_px[0] - 2480.0).abs() < 1e-3 && (fit.centre_px[1] - 3508.0).abs() < 1e-3,
        "{fit:?}"
    );
}
