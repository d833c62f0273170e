//! Tests of the folds and the paired gain.
use super::*;

#[test]
fn folds_are_balanced_and_seeded() {
    let f = fold_assignment(118, 5, 7);
    for g in 0..5 {
        let c = f.iter().filter(|&&x| x == g).count();
        assert!(c == 23 || c == 24, "fold {g}: {c}");
    }
    assert_eq!(f, fold_assignment(118, 5, 7));
    assert_ne!(f, fold_assignment(118, 5, 8));
}

#[test]
fn paired_gain_of_a_clear_improvement() {
    let e0: Vec<f64> = (0..50).map(|k| 1.0 + 0.01 * k as f64).collect();
    let e1: Vec<f64> = e0
        .iter()
        .enumerate()
        .map(|(k, e)| 0.5 * e + 0.001 * (k % 3) as f64)
        .collect();
    let (_, _, rel, t) = paired_gain(&e0, &e1, false);
    assert!(rel > 0.45 && t > 10.0, "{rel} {t}");
}
