//! Unit tests of `session.rs`.

use super::*;

#[test]
fn timeline_is_continuous_and_has_two_dips() {
    let cfg = SessionConfig::default();
    let total = session_duration_s(&cfg);
    let mut prev = timeline(&cfg, 0.0);
    let mut minima = 0;
    let mut was_low = false;
    for k in 1..=(total * 1000.0) as usize {
        let cur = timeline(&cfg, k as f64 * 1e-3);
        assert!(
            (cur.0 - prev.0).abs() < 1e-3 && (cur.1 - prev.1).abs() < 0.05,
            "{k}"
        );
        let low = cur.1 < -0.5 * cfg.dip_mm;
        if low && !was_low {
            minima += 1;
        }
        was_low = low;
        prev = cur;
    }
    assert_eq!(minima, 2);
    assert_eq!(timeline(&cfg, total), (1.0, cfg.lift_mm));
}
