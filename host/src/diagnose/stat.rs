//! Small statistics helpers: the F-test p-value (regularised incomplete beta function), the
//! Bayesian information criterion of a least-squares fit, and the expected mean Euclidean length
//! of isotropic Gaussian noise.

/// `ln Gamma(x)` for `x > 0` (Lanczos approximation, g = 7, 9 terms; relative error < 1e-13).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Gamma(x) Gamma(1 - x) = pi / sin(pi x).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).abs().ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Continued fraction of the incomplete beta function (modified Lentz).
fn beta_continued_fraction(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    const EPS: f64 = 1e-15;
    let fix = |v: f64| if v.abs() < TINY { TINY } else { v };
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 / fix(1.0 - qab * x / qap);
    let mut h = d;
    for m in 1..500 {
        let m = f64::from(m);
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 / fix(1.0 + aa * d);
        c = fix(1.0 + aa / c);
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 / fix(1.0 + aa * d);
        c = fix(1.0 + aa / c);
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    h
}

/// Regularised incomplete beta function `I_x(a, b)`, `a, b > 0`, `0 <= x <= 1`.
pub fn incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    if x < (a + 1.0) / (a + b + 2.0) {
        ln_front.exp() * beta_continued_fraction(a, b, x) / a
    } else {
        1.0 - ln_front.exp() * beta_continued_fraction(b, a, 1.0 - x) / b
    }
}

/// Upper-tail probability `P(F > f)` of the F distribution with `(d1, d2)` degrees of freedom.
pub fn f_test_p_value(f: f64, d1: f64, d2: f64) -> f64 {
    if !(f.is_finite() && d1 > 0.0 && d2 > 0.0) {
        return if f == f64::INFINITY { 0.0 } else { 1.0 };
    }
    if f <= 0.0 {
        return 1.0;
    }
    incomplete_beta(d2 / 2.0, d1 / 2.0, d2 / (d2 + d1 * f)).clamp(0.0, 1.0)
}

/// Nested-model F-test of a least-squares fit: adding `added` parameters lowers the residual
/// sum of squares from `rss0` to `rss1`, with `dof1` residual degrees of freedom after. Returns
/// `(F, p)`.
pub fn nested_f_test(rss0: f64, rss1: f64, added: usize, dof1: usize) -> (f64, f64) {
    if added == 0 || dof1 == 0 {
        return (0.0, 1.0);
    }
    let (d1, d2) = (added as f64, dof1 as f64);
    let f = if rss1 > 0.0 {
        ((rss0 - rss1).max(0.0) / d1) / (rss1 / d2)
    } else {
        f64::INFINITY
    };
    (f, f_test_p_value(f, d1, d2))
}

/// Change of the Bayesian information criterion `m ln(RSS/m) + k ln m` when `added`
/// parameters lower the RSS of `m` residuals from `rss0` to `rss1` (negative = better).
pub fn delta_bic(m: usize, rss0: f64, rss1: f64, added: usize) -> f64 {
    let mf = m as f64;
    if rss0 <= 0.0 || rss1 <= 0.0 {
        return 0.0;
    }
    mf * (rss1 / rss0).ln() + added as f64 * mf.ln()
}

/// Mean length of a 3-D isotropic Gaussian vector of standard deviation `sigma` per
/// coordinate: `sigma sqrt(8 / pi)` (Maxwell distribution).
pub fn expected_mean_norm(sigma: f64) -> f64 {
    sigma * (8.0 / std::f64::consts::PI).sqrt()
}

/// Mean length of a `dims`-dimensional isotropic Gaussian vector of standard deviation `sigma`
/// per coordinate: `sigma sqrt(2) Gamma((dims + 1) / 2) / Gamma(dims / 2)` (chi distribution;
/// `sigma sqrt(pi / 2)` for the two measured components of a traced sample, and
/// [`expected_mean_norm`] for 3).
pub fn expected_mean_norm_dims(sigma: f64, dims: usize) -> f64 {
    let k = dims.max(1) as f64;
    sigma * std::f64::consts::SQRT_2 * (ln_gamma((k + 1.0) / 2.0) - ln_gamma(k / 2.0)).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln_gamma_matches_factorials() {
        // Gamma(n) = (n - 1)!; Gamma(1/2) = sqrt(pi).
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
        assert!((ln_gamma(11.0) - 3_628_800f64.ln()).abs() < 1e-10);
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-12);
    }

    #[test]
    fn f_critical_values_of_printed_tables() {
        // 5 % critical values of F (standard tables): F(1, 10) = 4.96, F(2, 20) = 3.49,
        // F(3, 60) = 2.76; 0.1 %: F(1, 30) = 13.29.
        for (f, d1, d2, p) in [
            (4.9646, 1.0, 10.0, 0.05),
            (3.4928, 2.0, 20.0, 0.05),
            (2.7581, 3.0, 60.0, 0.05),
            (13.293, 1.0, 30.0, 0.001),
        ] {
            let got = f_test_p_value(f, d1, d2);
            assert!(
                (got - p).abs() < 2e-3 * p.max(0.01),
                "F({d1},{d2}) = {f}: p {got}, table {p}"
            );
        }
        assert_eq!(f_test_p_value(0.0, 2.0, 10.0), 1.0);
    }

    #[test]
    fn incomplete_beta_closed_forms() {
        // I_x(1, 1) = x; I_x(a, 1) = x^a.
        assert!((incomplete_beta(1.0, 1.0, 0.3) - 0.3).abs() < 1e-12);
        assert!((incomplete_beta(2.5, 1.0, 0.6) - 0.6f64.powf(2.5)).abs() < 1e-12);
    }

    #[test]
    fn bic_and_noise_mean() {
        assert!(delta_bic(300, 2.0, 1.0, 1) < 0.0);
        assert!(delta_bic(300, 1.0, 0.999, 1) > 0.0);
        assert!((expected_mean_norm(1.0) - 1.595_769).abs() < 1e-6);
        assert!((expected_mean_norm_dims(1.0, 3) - expected_mean_norm(1.0)).abs() < 1e-12);
        // Rayleigh mean sqrt(pi / 2); half-normal mean sqrt(2 / pi)
        assert!((expected_mean_norm_dims(2.0, 2) - 2.0 * 1.253_314_137).abs() < 1e-8);
        assert!((expected_mean_norm_dims(1.0, 1) - 0.797_884_561).abs() < 1e-8);
    }
}
