//! Whether the sheet lay flat: what the camera model leaves on the printed marks, read as a
//! pattern. A sheet that is not flat (a bow, a lifted edge) moves every mark by its height
//! times the slope of the ray through it; the homography and the lens terms absorb part of that,
//! and the rest is a smooth pattern over the sheet, while a flat sheet leaves only each mark's
//! own scatter. So a smooth vector field (each component a polynomial of degree 3 in the sheet
//! coordinates) is fitted to the marks' residuals (measured mark mapped to the sheet, minus its
//! printed place), and its RMS over the marks is the sheet's departure from flat as the marks see
//! it. Above `max_bend_pattern_mm` ([`super::TraceOptions`]), and explaining far more than the
//! scatter (an F test), the run is refused: the trace inside the ring would be off by several
//! times that pattern, which the marks on the ring cannot tell.

use nalgebra::{DMatrix, DVector};

/// The residual pattern of the printed marks under the camera model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Flatness {
    /// RMS over the marks of the smooth field fitted to their residuals, mm.
    pub pattern_mm: f64,
    /// Largest length of that field at a mark, mm.
    pub pattern_max_mm: f64,
    /// RMS of what the field leaves (the marks' own scatter), mm.
    pub scatter_mm: f64,
    /// F statistic of the field against the scatter.
    pub f_stat: f64,
    /// Marks used.
    pub marks: usize,
}

/// F statistic above which a pattern is taken as real, not scatter (F(20, 70) is 2.9 at
/// p = 0.001).
pub const PATTERN_F: f64 = 4.0;

/// Degree of the polynomial field.
const DEGREE: usize = 3;

fn monomials(p: [f64; 2]) -> Vec<f64> {
    // Sheet mm over 100: values of order one on the ring of marks.
    let (x, y) = (p[0] / 100.0, p[1] / 100.0);
    let mut out = Vec::with_capacity(10);
    for d in 0..=DEGREE {
        for i in 0..=d {
            out.push(x.powi((d - i) as i32) * y.powi(i as i32));
        }
    }
    out
}

/// The pattern of `residual_mm[i]` (measured minus printed, sheet mm) at the printed places
/// `sheet_mm[i]`; `None` with too few marks for the field.
pub fn measure(sheet_mm: &[[f64; 2]], residual_mm: &[[f64; 2]]) -> Option<Flatness> {
    let n = sheet_mm.len().min(residual_mm.len());
    let terms = monomials([0.0, 0.0]).len();
    if n < terms + 8 {
        return None;
    }
    let a = DMatrix::from_fn(n, terms, |i, j| monomials(sheet_mm[i])[j]);
    let svd = a.clone().svd(true, true);
    let mut fitted = vec![[0.0; 2]; n];
    for c in 0..2 {
        let b = DVector::from_fn(n, |i, _| residual_mm[i][c]);
        let coef = svd.solve(&b, 1e-9).ok()?;
        let f = &a * coef;
        for i in 0..n {
            fitted[i][c] = f[i];
        }
    }
    let mut field2 = 0.0;
    let mut left2 = 0.0;
    let mut total2 = 0.0;
    let mut field_max: f64 = 0.0;
    for i in 0..n {
        let f = fitted[i][0].hypot(fitted[i][1]);
        let r = residual_mm[i];
        let l = (r[0] - fitted[i][0]).hypot(r[1] - fitted[i][1]);
        field2 += f * f;
        left2 += l * l;
        total2 += r[0] * r[0] + r[1] * r[1];
        field_max = field_max.max(f);
    }
    let dof_field = (2 * terms) as f64;
    let dof_left = (2 * n - 2 * terms) as f64;
    let f_stat = ((total2 - left2).max(0.0) / dof_field) / (left2 / dof_left).max(1e-18);
    Some(Flatness {
        pattern_mm: (field2 / n as f64).sqrt(),
        pattern_max_mm: field_max,
        scatter_mm: (left2 / n as f64).sqrt(),
        f_stat,
        marks: n,
    })
}

impl Flatness {
    /// Whether the pattern says the sheet was not flat, against the limit `max_pattern_mm`.
    pub fn is_bent(&self, max_pattern_mm: f64) -> bool {
        self.pattern_mm > max_pattern_mm && self.f_stat > PATTERN_F
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring() -> Vec<[f64; 2]> {
        let mut v = Vec::new();
        for i in -5..=5 {
            let t = f64::from(i) * 16.0;
            v.extend([[t, 90.0], [t, -90.0], [90.0, t], [-90.0, t]]);
        }
        v
    }

    #[test]
    fn a_smooth_pattern_is_told_from_scatter() {
        let s = ring();
        // Scatter only: a hash-like sequence of +-0.01 mm.
        let scatter: Vec<[f64; 2]> = (0..s.len())
            .map(|i| {
                let a = (i as f64 * 12.9898).sin() * 43_758.545;
                let b = (i as f64 * 78.233).sin() * 12_543.12;
                [0.01 * (a.fract() - 0.5), 0.01 * (b.fract() - 0.5)]
            })
            .collect();
        let flat = measure(&s, &scatter).expect("measured");
        assert!(!flat.is_bent(0.01), "{flat:?}");
        // A cubic pattern of 0.05 mm on top.
        let bent: Vec<[f64; 2]> = s
            .iter()
            .zip(&scatter)
            .map(|(p, e)| {
                let x = p[0] / 90.0;
                [e[0] + 0.05 * x * x * x, e[1] + 0.03 * x * x]
            })
            .collect();
        let b = measure(&s, &bent).expect("measured");
        assert!(b.is_bent(0.01) && b.pattern_mm > 0.02, "{b:?}");
    }
}
