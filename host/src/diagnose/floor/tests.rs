//! Unit tests of the independent floor.

use super::*;
use crate::calib::measured::PosePoints;
use nalgebra::Vector3;

#[test]
fn chi2_tail_matches_known_quantiles() {
    // chi2(100): 99.9 % quantile 149.449, median 99.334
    assert!((chi2_upper_p(149.449, 100.0) - 1e-3).abs() < 2e-4);
    assert!((chi2_upper_p(99.334, 100.0) - 0.5).abs() < 5e-3);
}

#[test]
fn repeatability_pools_repeated_poses() {
    let q = vec![
        vec![1.0, 2.0],
        vec![1.0, 2.0],
        vec![3.0, 4.0],
        vec![5.0, 6.0],
    ];
    let xyz = vec![
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(0.2, 0.0, 0.0),
        Vector3::zeros(),
        Vector3::zeros(),
    ];
    let d = MeasuredSet::from_poses(PosePoints {
        q_deg: q,
        xyz_mm: xyz,
    });
    let (s, dof) = repeatability_mm(&d).expect("one repeated pose");
    assert_eq!(dof, 3);
    // deviations +-0.1 on x: ss = 0.02 over 3 dof
    assert!((s - (0.02f64 / 3.0).sqrt()).abs() < 1e-12);
    let none = d.subset(&[0, 2, 3]);
    assert!(repeatability_mm(&none).is_none());
}

/// The groups by the definition: every later pose that is no member yet, compared with
/// the one opening the group (quadratic, for the test).
fn groups_by_definition(data: &MeasuredSet) -> Vec<Vec<usize>> {
    let n = data.len();
    let mut member = vec![false; n];
    let mut out = Vec::new();
    for i in 0..n {
        if member[i] {
            continue;
        }
        let mut g = vec![i];
        g.extend((i + 1..n).filter(|&k| !member[k] && same_pose(data, i, k)));
        if g.len() > 1 {
            for &m in &g {
                member[m] = true;
            }
            out.push(g);
        }
    }
    out
}

#[test]
fn repeat_groups_are_those_of_the_definition() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(129);
    for case in 0..40 {
        let n = rng.gen_range(1..300);
        let base: Vec<Vec<f64>> = (0..rng.gen_range(1..40))
            .map(|_| (0..5).map(|_| rng.gen_range(-170.0..170.0)).collect())
            .collect();
        let q: Vec<Vec<f64>> = (0..n)
            .map(|_| {
                let mut v = base[rng.gen_range(0..base.len())].clone();
                // within, at and beyond the tolerance, on one joint or on several
                for x in v.iter_mut() {
                    if rng.gen_bool(0.3) {
                        *x += [0.0, 0.4e-6, 1e-6, 1.5e-6, -0.9e-6, 1e-3][rng.gen_range(0..6)];
                    }
                }
                v
            })
            .collect();
        let mut d = MeasuredSet::from_poses(PosePoints {
            q_deg: q,
            xyz_mm: (0..n).map(|_| Vector3::new(rng.gen(), 0.0, 0.0)).collect(),
        });
        if case % 2 == 0 {
            d.ids = Some(
                (0..n)
                    .map(|_| match rng.gen_range(0..4) {
                        0 => String::new(),
                        k => format!("P{k}"),
                    })
                    .collect(),
            );
        }
        assert_eq!(repeat_groups(&d), groups_by_definition(&d), "case {case}");
    }
}

/// 200 000 distinct poses and 100 000 poses measured twice: the grouping takes well under
/// a second (comparing every pair would take minutes).
#[test]
fn repeat_groups_of_many_poses_are_fast() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let n = 200_000;
    // each pose twice in a row
    let q: Vec<Vec<f64>> = (0..n / 2)
        .flat_map(|_| {
            let v: Vec<f64> = (0..5).map(|_| rng.gen_range(-170.0..170.0)).collect();
            [v.clone(), v]
        })
        .collect();
    let xyz_mm = vec![Vector3::zeros(); q.len()];
    let d = MeasuredSet::from_poses(PosePoints { q_deg: q, xyz_mm });
    let t = std::time::Instant::now();
    let (_, dof) = repeatability_mm(&d).expect("repeated poses");
    assert_eq!(dof, 3 * n / 2);
    assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
}

/// A final residual of 0.02 mm per coordinate on 100 poses, and on 30 held-out ones.
fn residual_of_0_02_mm() -> FinalResidual {
    FinalResidual {
        rss_mm2: 300.0 * 0.02f64.powi(2),
        n_residuals: 300,
        n_params: 0,
        tau: 1.0,
        n_poses: 100,
        val_ss_mm2: 90.0 * 0.02f64.powi(2),
        val_residuals: 90,
    }
}

#[test]
fn judge_uses_the_larger_floor_and_flags_excess() {
    let r = residual_of_0_02_mm();
    let f = judge(&r, Some(0.01), None);
    assert_eq!(f.used, "instrument");
    assert!((f.final_over_floor - 2.0).abs() < 1e-9 && f.above);
    let g = judge(&r, Some(0.02), Some((0.01, 20)));
    assert_eq!(g.used, "instrument");
    assert!(!g.above, "{g:?}");
    assert!(g.note.contains("is below it"), "{}", g.note);
    let h = judge(&r, None, None);
    assert_eq!(h.used, "residual");
    assert!(!h.above && (h.final_over_floor - 1.0).abs() < 1e-12);
}

#[test]
fn too_few_repeats_fall_back_in_order_and_say_why() {
    let r = residual_of_0_02_mm();
    // one pose measured twice: 3 degrees of freedom
    let few = Some((0.03, 3));
    let a = judge(&r, Some(0.01), few);
    assert_eq!(a.used, "instrument", "{a:?}");
    assert!(
        a.note.contains("too uncertain") && a.note.contains("3 degrees"),
        "{}",
        a.note
    );
    assert_eq!(a.repeatability_dof, Some(3));
    let b = judge(&r, None, few);
    assert_eq!(b.used, "residual", "{b:?}");
    assert!(b.note.contains("too uncertain"), "{}", b.note);
    // enough repeats: the repeatability is the floor, with its degrees of freedom
    let c = judge(&r, None, Some((0.02, 30)));
    assert_eq!(c.used, "repeatability");
    assert!(c.note.contains("30 degrees of freedom"), "{}", c.note);
    // larger than the instrument: the robot's repeatability sets the floor
    let d = judge(&r, Some(0.01), Some((0.02, 30)));
    assert_eq!(d.used, "repeatability");
}
