//! Tests of the measured set and its components.

use super::*;
use crate::model::katana450;
use nalgebra::DMatrix;

fn sample(t: f64, dev_u: f64, dev_n: f64) -> FusedSample {
    FusedSample {
        t_s: t,
        q_deg: vec![-90.0 + t, 60.0, -60.0, 10.0, 90.0],
        nominal_mm: Vector3::new(100.0, -200.0, 150.0),
        dev_u_mm: dev_u,
        u: Vector3::new(1.0, 0.0, 0.0),
        dev_n_mm: dev_n,
        n: Vector3::new(0.0, 0.6, 0.8),
    }
}

/// A fused sample measures exactly its two deviations; the along-path component of any
/// vector is projected out; full positions concatenated keep all three axes.
#[test]
fn partial_measurements_project_out_the_path_direction() {
    let model = katana450(330.0).unwrap();
    let s: Vec<FusedSample> = (0..5).map(|k| sample(k as f64 * 0.01, 0.1, -0.2)).collect();
    let d = MeasuredSet::from_fused(&s)
        .unwrap()
        .with_inertial_moments(&model)
        .unwrap();
    assert!(d.is_serial());
    assert_eq!(d.n_residuals(), 10);
    assert_eq!(d.measured_dims(), 2);
    let e = d.poses.xyz_mm[0] - s[0].nominal_mm;
    let c = d.components(0, &e);
    assert!(
        (c[0] - 0.1).abs() < 1e-12 && (c[1] + 0.2).abs() < 1e-12,
        "{c:?}"
    );
    let along = Vector3::new(0.0, 0.8, -0.6);
    assert!(d.measured_part(0, &along).norm() < 1e-12);
    let j = DMatrix::from_row_slice(3, 1, &[0.0, 0.8, -0.6]);
    assert!(d.jacobian_rows(0, &j).norm() < 1e-12);
    let full = MeasuredSet::from_poses(PosePoints {
        q_deg: vec![vec![0.0; 5]],
        xyz_mm: vec![Vector3::new(1.0, 2.0, 3.0)],
    });
    let both = d.concat(full);
    assert_eq!(both.len(), 6);
    assert_eq!(both.n_residuals(), 13);
    assert_eq!(both.measured_dims(), 3);
    assert_eq!(both.measured_part(5, &along), along);
    assert!(both.t_s.is_none());
    let m = both.moments_kgfm.as_ref().unwrap();
    assert_eq!(m.len(), 6);
    assert!(m[5].len() == 5 && m[5].iter().all(|v| v.norm() == 0.0));
    let sub = both.subset(&[5, 0]);
    assert_eq!(sub.rows(0), 3);
    assert_eq!(sub.rows(1), 2);
}

/// Several points per pose come out pose by pose, slots in order; leaving out measured
/// components keeps the others' directions and drops a pose with none left; the residual of
/// a full and of a partial pose is taken along its measured directions.
#[test]
fn points_components_and_residuals() {
    let p = |x: f64| Vector3::new(x, 0.0, 0.0);
    let mut set = MeasuredSet::from_poses(PosePoints {
        q_deg: vec![vec![0.0], vec![1.0]],
        xyz_mm: vec![p(1.0), p(2.0)],
    });
    set.further_mm = vec![vec![p(10.0), p(11.0)], vec![p(20.0), p(21.0)]];
    set.markers = vec![0, 2, 3];
    let pts: Vec<(usize, usize, f64)> =
        set.points().map(|m| (m.pose, m.slot, m.xyz_mm.x)).collect();
    assert_eq!(
        pts,
        vec![
            (0, 0, 1.0),
            (0, 1, 10.0),
            (0, 2, 11.0),
            (1, 0, 2.0),
            (1, 1, 20.0),
            (1, 2, 21.0)
        ]
    );
    assert_eq!((set.n_slots(), set.n_points()), (3, 6));
    assert_eq!(set.row_blocks(), vec![9, 9]);
    assert_eq!(set.as_poses().len(), 6);
    assert_eq!(set.offset_name(2, 1), "marker4_y_mm");
    assert_eq!(set.subset(&[1]).further_mm, vec![vec![p(20.0), p(21.0)]]);

    let h = std::f64::consts::FRAC_1_SQRT_2;
    let (u, n) = (Vector3::new(h, h, 0.0), Vector3::new(0.0, 0.0, 1.0));
    set.further_mm.clear();
    set.directions = Some(vec![Vec::new(), vec![u, n]]);
    assert_eq!(set.n_residuals(), 5);
    let off = Vector3::new(1.0, 2.0, 3.0);
    assert_eq!(
        set.residual(0, &(set.poses.xyz_mm[0] + off)),
        vec![1.0, 2.0, 3.0]
    );
    let r1 = set.residual(1, &(set.poses.xyz_mm[1] + off));
    assert!(
        (r1[0] - 3.0 * h).abs() < 1e-12 && (r1[1] - 3.0).abs() < 1e-12,
        "{r1:?}"
    );
    let e1 = set.error_mm(1, &(set.poses.xyz_mm[1] + Vector3::new(1.0, -1.0, 0.0)));
    assert!(
        e1.norm() < 1e-12,
        "along-path error is not measured: {e1:?}"
    );
    let kept = set.keep_components(&[true, false, true, false, false]);
    assert_eq!(kept.len(), 1);
    assert_eq!(kept.directions_at(0), vec![Vector3::x(), Vector3::z()]);
    assert_eq!(kept.n_residuals(), 2);
    let kept = set.keep_components(&[true, true, true, false, true]);
    assert_eq!((kept.len(), kept.rows(0), kept.rows(1)), (2, 3, 1));
    assert_eq!(kept.directions_at(1), vec![n]);
}

/// A tree's set: slot k on tip k, an unmeasured point left out of the measured points (and of
/// their count), kept through `subset` and `concat`, the points of one tip seen by its chain
/// with the joints of its path; a chain's identification refuses the set.
#[test]
fn a_tree_set_has_tips_and_unmeasured_points() {
    let p = |x: f64| Vector3::new(x, 0.0, 0.0);
    let q = vec![
        vec![1.0, 2.0, 3.0],
        vec![4.0, 5.0, 6.0],
        vec![7.0, 8.0, 9.0],
    ];
    let points = vec![
        vec![Some(p(1.0)), Some(p(10.0))],
        vec![None, Some(p(20.0))],
        vec![Some(p(3.0))],
    ];
    let set = MeasuredSet::from_tip_points(q, points);
    assert_eq!(
        (set.len(), set.n_slots(), set.tips.clone()),
        (3, 2, vec![0, 1])
    );
    assert_eq!((set.tip(0), set.tip(1)), (0, 1));
    let of = |s: &MeasuredSet, k: usize| -> Vec<(usize, f64)> {
        s.measured_of(k).map(|m| (m.slot, m.xyz_mm.x)).collect()
    };
    assert_eq!(of(&set, 0), vec![(0, 1.0), (1, 10.0)]);
    assert_eq!(of(&set, 1), vec![(1, 20.0)]);
    assert_eq!(of(&set, 2), vec![(0, 3.0)]);
    assert_eq!(set.n_measured_points(), 4);
    assert!(set.has_tips());
    assert!(matches!(
        set.chain_only("poses"),
        Err(crate::calib::error::CalibError::NotChainSet { .. })
    ));

    let sub = set.subset(&[1, 2]);
    assert_eq!(of(&sub, 0), vec![(1, 20.0)]);
    assert_eq!(sub.n_measured_points(), 2);

    // tip 1's chain: joints 0 and 2 of the tree, the poses where tip 1 was measured
    let view = set.tip_view(1, &[0, 2]);
    assert_eq!(view.poses.q_deg, vec![vec![1.0, 3.0], vec![4.0, 6.0]]);
    assert_eq!(view.poses.xyz_mm, vec![p(10.0), p(20.0)]);
    assert!(!view.has_tips());
    assert!(view.chain_only("tip").is_ok());

    let both = set.clone().concat(set.subset(&[1]));
    assert_eq!((both.len(), both.n_slots()), (4, 2));
    assert_eq!(of(&both, 3), vec![(1, 20.0)]);
    assert_eq!(both.n_measured_points(), 5);

    // a chain's set: no tips, every point measured, nothing added by concat
    let chain = MeasuredSet::from_points(vec![vec![0.0]; 2], vec![p(1.0), p(2.0)]);
    let chain = chain.clone().concat(chain);
    assert!(!chain.has_tips() && chain.present.is_none());
    assert_eq!(chain.n_measured_points(), chain.n_points());
}

/// The pre-fit check of every chain identification refuses a tree's set with a typed error.
#[test]
fn a_chain_identification_refuses_a_tree_set() {
    let model = katana450(330.0).unwrap();
    let q = vec![vec![-90.0, 60.0, -60.0, 10.0, 90.0]; 12];
    let xyz: Vec<Option<Vector3<f64>>> = vec![Some(Vector3::new(100.0, -200.0, 150.0))];
    let mut set = MeasuredSet::from_tip_points(q, vec![xyz; 12]);
    for what in ["tips", "unmeasured"] {
        let err = crate::calib::plausible::check_set(&model, &set, what).unwrap_err();
        assert!(
            matches!(&err, crate::calib::error::CalibError::NotChainSet { what: w } if w == what),
            "{err}"
        );
        assert_eq!(
            crate::error::Classify::kind(&err),
            crate::error::ErrorKind::BadInput
        );
        set.tips.clear();
        set.present = Some(vec![vec![true]; 12]);
    }
}
