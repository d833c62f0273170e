//! The probe's smooth functions of the joint angles: a constant, additive per-joint terms and
//! pairwise interaction terms, each a small block of Legendre polynomials of the joint angle
//! scaled to its observed range.
//!
//! For joint `i` observed over `[lo_i, hi_i]` (deg), `x_i = 2 (q_i - lo_i) / (hi_i - lo_i) - 1`,
//! clamped to `[-1, 1]` (a prediction outside the observed range is held at its edge, never
//! extrapolated). A main term `q<i>` is `P_1(x_i) .. P_MAIN_ORDER(x_i)`; a pair term `q<i>:q<j>`
//! is `P_a(x_i) P_b(x_j)` for `a, b = 1 ..= PAIR_ORDER` (the interaction alone: the main effects
//! are separate terms). Every basis function is vector-valued through its three coefficients
//! (x, y, z of frame R, mm).

use serde::Serialize;

/// Polynomial order of a main (one-joint) term.
pub const MAIN_ORDER: usize = 4;
/// Polynomial order in each joint of a pair term.
pub const PAIR_ORDER: usize = 2;
/// A joint whose observed range is narrower than this (deg) gets no term.
pub const MIN_RANGE_DEG: f64 = 1e-3;

/// One term of the probe's additive model (joints 0-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Term {
    /// A constant offset.
    Const,
    /// A smooth function of one joint.
    Main(usize),
    /// A smooth interaction of two joints (`i < j`).
    Pair(usize, usize),
}

impl Term {
    /// The FORMATS.md name: `q2`, `q1:q3` (1-based); `const` for the offset.
    pub fn name(&self) -> String {
        match self {
            Term::Const => "const".to_string(),
            Term::Main(i) => format!("q{}", i + 1),
            Term::Pair(i, j) => format!("q{}:q{}", i + 1, j + 1),
        }
    }

    /// The words of the sentence: `q2`, `q1 with q3`.
    pub fn phrase(&self) -> String {
        match self {
            Term::Const => "a constant offset".to_string(),
            Term::Main(i) => format!("q{}", i + 1),
            Term::Pair(i, j) => format!("q{} with q{}", i + 1, j + 1),
        }
    }

    /// Number of scalar basis functions.
    pub fn n_basis(&self) -> usize {
        match self {
            Term::Const => 1,
            Term::Main(_) => MAIN_ORDER,
            Term::Pair(..) => PAIR_ORDER * PAIR_ORDER,
        }
    }

    /// Names of its basis functions (`P2(x3)`, `P1(x1)P2(x3)`).
    pub fn basis_names(&self) -> Vec<String> {
        match *self {
            Term::Const => vec!["1".to_string()],
            Term::Main(i) => (1..=MAIN_ORDER)
                .map(|a| format!("P{a}(x{})", i + 1))
                .collect(),
            Term::Pair(i, j) => (1..=PAIR_ORDER)
                .flat_map(|a| (1..=PAIR_ORDER).map(move |b| (a, b)))
                .map(|(a, b)| format!("P{a}(x{})P{b}(x{})", i + 1, j + 1))
                .collect(),
        }
    }

    /// The joints it involves.
    pub fn joints(&self) -> Vec<usize> {
        match *self {
            Term::Const => Vec::new(),
            Term::Main(i) => vec![i],
            Term::Pair(i, j) => vec![i, j],
        }
    }
}

/// Legendre polynomials `P_0 ..= P_order` at `x`.
pub fn legendre(x: f64, order: usize) -> Vec<f64> {
    let mut p = Vec::with_capacity(order + 1);
    p.push(1.0);
    if order >= 1 {
        p.push(x);
    }
    for n in 1..order {
        let nf = n as f64;
        let next = ((2.0 * nf + 1.0) * x * p[n] - nf * p[n - 1]) / (nf + 1.0);
        p.push(next);
    }
    p
}

/// Observed range of every joint, deg (`(lo, hi)`; `(0, 0)` for no poses).
pub fn joint_ranges_deg(q_deg: &[Vec<f64>]) -> Vec<(f64, f64)> {
    let nj = q_deg.first().map_or(0, Vec::len);
    (0..nj)
        .map(|j| {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for q in q_deg {
                if let Some(v) = q.get(j).copied().filter(|v| v.is_finite()) {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
            if lo.is_finite() {
                (lo, hi)
            } else {
                (0.0, 0.0)
            }
        })
        .collect()
}

/// Every candidate term for joints with these ranges: the constant, one main term per joint that
/// moves, one pair term per two joints that move.
pub fn candidate_terms(ranges_deg: &[(f64, f64)]) -> Vec<Term> {
    let moving: Vec<usize> = ranges_deg
        .iter()
        .enumerate()
        .filter(|(_, (lo, hi))| hi - lo >= MIN_RANGE_DEG)
        .map(|(j, _)| j)
        .collect();
    let mut terms = vec![Term::Const];
    terms.extend(moving.iter().map(|&j| Term::Main(j)));
    for (a, &i) in moving.iter().enumerate() {
        for &j in &moving[a + 1..] {
            terms.push(Term::Pair(i, j));
        }
    }
    terms
}

/// The scaled, clamped coordinate of joint `j` at `q`.
fn scaled(ranges_deg: &[(f64, f64)], q_deg: &[f64], j: usize) -> f64 {
    let (lo, hi) = ranges_deg.get(j).copied().unwrap_or((0.0, 0.0));
    let v = q_deg.get(j).copied().unwrap_or(lo);
    if hi - lo < MIN_RANGE_DEG || !v.is_finite() {
        return 0.0;
    }
    (2.0 * (v - lo) / (hi - lo) - 1.0).clamp(-1.0, 1.0)
}

/// Appends the values of `term`'s basis functions at `q_deg` to `out`.
pub fn push_values(term: Term, ranges_deg: &[(f64, f64)], q_deg: &[f64], out: &mut Vec<f64>) {
    match term {
        Term::Const => out.push(1.0),
        Term::Main(i) => {
            let p = legendre(scaled(ranges_deg, q_deg, i), MAIN_ORDER);
            out.extend_from_slice(&p[1..]);
        }
        Term::Pair(i, j) => {
            let pi = legendre(scaled(ranges_deg, q_deg, i), PAIR_ORDER);
            let pj = legendre(scaled(ranges_deg, q_deg, j), PAIR_ORDER);
            for a in &pi[1..] {
                for b in &pj[1..] {
                    out.push(a * b);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The recurrence gives the closed forms; terms are laid out as documented.
    #[test]
    fn legendre_closed_forms_and_term_layout() {
        for x in [-1.0, -0.3, 0.0, 0.7, 1.0] {
            let p = legendre(x, 4);
            assert!((p[2] - (3.0 * x * x - 1.0) / 2.0).abs() < 1e-12);
            assert!((p[3] - (5.0 * x * x * x - 3.0 * x) / 2.0).abs() < 1e-12);
            let p4 = (35.0 * x.powi(4) - 30.0 * x * x + 3.0) / 8.0;
            assert!((p[4] - p4).abs() < 1e-12);
        }
        let ranges = [(0.0, 10.0), (5.0, 5.0), (-90.0, 90.0)];
        let terms = candidate_terms(&ranges);
        assert_eq!(
            terms,
            vec![Term::Const, Term::Main(0), Term::Main(2), Term::Pair(0, 2)]
        );
        assert_eq!(Term::Pair(0, 2).name(), "q1:q3");
        assert_eq!(Term::Pair(0, 2).phrase(), "q1 with q3");
        let mut v = Vec::new();
        push_values(Term::Pair(0, 2), &ranges, &[10.0, 5.0, 400.0], &mut v);
        // x1 = 1, x3 clamped to 1: every product is 1
        assert_eq!(v.len(), 4);
        assert!(v.iter().all(|x| (x - 1.0).abs() < 1e-12), "{v:?}");
        assert_eq!(Term::Main(2).basis_names().len(), Term::Main(2).n_basis());
    }
}
