//! Captions true to their plots: each claim a caption makes ("stays near zero", "at most
//! 0.012 mm", "no trend remains") is computed from the values the chart draws, which the
//! [`super::Figure`] keeps (`series`) so that a test can check the words against them.

use crate::plot::summary::fmt_mm;

/// "Near zero": the calibrated values' largest stays within this share of the nominal's.
pub const NEAR_ZERO_SHARE: f64 = 0.1;

/// |r| below which a scatter shows no trend.
pub const NO_TREND_R: f64 = 0.3;

/// A pose whose error is over this many times the median error is in the tail.
pub const TAIL_X_MEDIAN: f64 = 3.0;

fn min_max(v: &[f64]) -> Option<(f64, f64)> {
    let f = v.iter().copied().filter(|x| x.is_finite());
    let lo = f.clone().reduce(f64::min)?;
    let hi = f.reduce(f64::max)?;
    Some((lo, hi))
}

/// Whether `after` stays near zero against `before` ([`NEAR_ZERO_SHARE`]).
pub fn near_zero(before: &[f64], after: &[f64]) -> bool {
    match (min_max(before), min_max(after)) {
        (Some((_, b)), Some((_, a))) => a <= NEAR_ZERO_SHARE * b,
        _ => false,
    }
}

/// The path-error chart's words: where the calibrated curve lies against the nominal one.
pub fn path_error_words(before: &[f64], after: &[f64]) -> String {
    let (Some((b0, b1)), Some((a0, a1))) = (min_max(before), min_max(after)) else {
        return "no finite value to compare".to_string();
    };
    if near_zero(before, after) {
        format!(
            "the calibrated curve stays near zero, at most {} mm (the nominal one up to {} mm)",
            fmt_mm(a1),
            fmt_mm(b1)
        )
    } else {
        format!(
            "the calibrated curve lies between {} and {} mm, not near zero (the nominal one between {} and {} mm){}",
            fmt_mm(a0),
            fmt_mm(a1),
            fmt_mm(b0),
            fmt_mm(b1),
            if a1 < b0 {
                ": below the nominal one all along, with an error the calibrated model does not remove"
            } else {
                ""
            }
        )
    }
}

/// The per-pose bars' words: how long the red (after) bars are against the before ones.
pub fn pose_bars_words(before: &[f64], after: &[f64]) -> String {
    let (Some((_, b1)), Some((_, a1))) = (min_max(before), min_max(after)) else {
        return "no finite value to compare".to_string();
    };
    if near_zero(before, after) {
        format!(
            "the red bars (after) are short: at most {} mm (before up to {} mm)",
            fmt_mm(a1),
            fmt_mm(b1)
        )
    } else {
        format!(
            "the red bars (after) reach {} mm (before up to {} mm)",
            fmt_mm(a1),
            fmt_mm(b1)
        )
    }
}

/// The number of values over [`TAIL_X_MEDIAN`] times their median.
pub fn tail_count(v: &[f64]) -> usize {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return 0;
    }
    s.sort_by(f64::total_cmp);
    let median = s[s.len() / 2];
    s.iter().filter(|x| **x > TAIL_X_MEDIAN * median).count()
}

/// The histogram's words: the largest error after and the tail.
pub fn histogram_words(before: &[f64], after: &[f64]) -> String {
    let (Some((_, b1)), Some((_, a1))) = (min_max(before), min_max(after)) else {
        return "no finite value to compare".to_string();
    };
    let tail = tail_count(after);
    format!(
        "after calibration the errors reach {} mm at most (before {} mm); {}",
        fmt_mm(a1),
        fmt_mm(b1),
        match tail {
            0 => format!(
                "no pose after is over {TAIL_X_MEDIAN} x their median (no tail of outliers)"
            ),
            1 => format!("1 pose after is over {TAIL_X_MEDIAN} x their median (a tail)"),
            k => format!("{k} poses after are over {TAIL_X_MEDIAN} x their median (a tail)"),
        }
    )
}

/// The scatter's words: the correlation left after calibration, `r_after`.
pub fn scatter_words(joint: usize, r_after: Option<f64>) -> String {
    match r_after {
        Some(r) if r.abs() < NO_TREND_R => {
            format!("after calibration r = {r:.2} with q{joint}: no trend remains")
        }
        Some(r) => format!("after calibration r = {r:.2} with q{joint}: a trend remains"),
        None => format!("after calibration the error does not vary with q{joint}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_curve_far_from_zero_is_not_called_near_zero() {
        let before = [2.0, 3.0, 2.5];
        let after = [1.2, 1.45, 1.3];
        let w = path_error_words(&before, &after);
        assert!(!w.contains("stays near zero"), "{w}");
        assert!(w.contains("between 1.200 and 1.450 mm"), "{w}");
        let w = path_error_words(&before, &[0.01, 0.02]);
        assert!(w.contains("stays near zero, at most 0.0200 mm"), "{w}");
    }

    #[test]
    fn the_tail_is_counted_against_the_median() {
        assert_eq!(tail_count(&[1.0, 1.0, 1.1, 0.9, 5.0]), 1);
        assert!(histogram_words(&[3.0; 5], &[1.0, 1.0, 1.1, 0.9, 5.0]).contains("1 pose after"));
    }
}
