//! Which parameters a set of measurements can identify.
//!
//! The identification Jacobian `J` (residuals x parameters) is first scaled to unit column norms,
//! so that degrees and millimetres compare. Its SVD gives the rank (singular values above
//! `rtol * s_max`) and the null space: each null vector is a combination of parameters that
//! leaves every measured position unchanged (to first order). For the Katana with position-only
//! data two such directions exist: `be5` alone (it turns the tool about its own length) and
//! `dth5` with `be4` (both turn the wrist about the same axis; MODEL.md).
//!
//! To fix a basis of the null space, one parameter per null direction is chosen to be *fixed*
//! (kept at its nominal value, removed from the fitted set): greedily the parameter with the
//! **last** column (in the caller's order) whose remaining null-space component is at least
//! [`PIVOT_SHARE`] of the largest, so callers list the parameters they would rather fit first
//! (the instrument frame and the tool point before the joint offsets, encoder offsets before
//! twists) and a confounded set keeps the earlier ones fitted.
//! The null basis is then reduced so that each vector is 1 on its fixed parameter and 0 on the
//! other fixed ones; its other members name the combination, e.g. `"dth5+be4"`.

use nalgebra::{DMatrix, DVector};

/// Relative singular-value threshold below which a direction counts as unidentifiable: a
/// condition number above 1e4 of the column-scaled Jacobian means a combination the data barely
/// sees (on the UR5 laser-tracker grid, `dth5+a5` and `d5+al5` drift by degrees / tens of mm
/// with sigmas as large as their values at 1e-7).
pub const DEFAULT_RTOL: f64 = 1e-4;

/// A column whose norm is below this fraction of the largest column norm counts as zero (the
/// parameter has no effect; its entries are round-off).
pub const ZERO_COLUMN_RTOL: f64 = 1e-10;

/// The fixed member of a null direction is the **last** column (in the caller's preference
/// order) whose share of the direction is at least this fraction of the largest share: among
/// confounded parameters the later ones are fixed whenever they take a real part in the
/// direction, so the earlier ones (the instrument frame, the tool point) are the ones fitted.
pub const PIVOT_SHARE: f64 = 0.2;

/// A null-space member smaller than this (scaled, relative to the fixed member = 1) is left out
/// of a combination's name.
const MEMBER_TOL: f64 = 0.05;

/// One unidentifiable direction: a combination of parameters that does not change the
/// measurements.
#[derive(Debug, Clone, PartialEq)]
pub struct Combination {
    /// The column fixed at its nominal value for this direction.
    pub fixed: usize,
    /// Members `(column, coefficient)` in column order, the fixed one included (coefficient 1);
    /// coefficients are in the units of the unscaled columns (a change `c_i * t` of every member
    /// leaves the measurements unchanged).
    pub members: Vec<(usize, f64)>,
}

impl Combination {
    /// Name of the combination: member names joined by `+` in column order (`"dth5+be4"`), or the
    /// single name for a parameter that has no influence at all (`"be5"`).
    pub fn name(&self, names: &[&str]) -> String {
        self.members
            .iter()
            .map(|&(c, _)| names.get(c).copied().unwrap_or("?"))
            .collect::<Vec<_>>()
            .join("+")
    }
}

/// Result of [`analyse`].
#[derive(Debug, Clone, PartialEq)]
pub struct Identifiability {
    /// Numerical rank of the column-scaled Jacobian.
    pub rank: usize,
    /// Singular values of the column-scaled Jacobian, descending.
    pub singular_values: Vec<f64>,
    /// Condition number `s_max / s_min` of the column-scaled Jacobian restricted to the
    /// identifiable (kept) columns.
    pub condition_number: f64,
    /// Columns that stay in the fitted set, in column order.
    pub kept: Vec<usize>,
    /// Columns to fix at their nominal value, in column order.
    pub fixed: Vec<usize>,
    /// One combination per null direction.
    pub combinations: Vec<Combination>,
}

impl Identifiability {
    /// The analysis of a Jacobian without columns.
    fn empty() -> Self {
        Identifiability {
            rank: 0,
            singular_values: Vec::new(),
            condition_number: 1.0,
            kept: Vec::new(),
            fixed: Vec::new(),
            combinations: Vec::new(),
        }
    }
}

/// What [`scaled_svd`] returns: the column norms, the singular values (descending) and the
/// right singular vectors (columns).
pub type ScaledSvd = (DVector<f64>, Vec<f64>, DMatrix<f64>);

/// The largest over the smallest of the singular values `s` (descending); infinite when the
/// smallest is zero.
fn condition_of(s: &[f64]) -> f64 {
    let lo = s.last().copied().unwrap_or(0.0);
    if lo > 0.0 {
        s[0] / lo
    } else {
        f64::INFINITY
    }
}

/// Column norms (1 for a zero column) and the singular values (descending) and right singular
/// vectors `V` (columns) of `jac` with unit-norm columns.
pub fn scaled_svd(jac: &DMatrix<f64>) -> ScaledSvd {
    let n = jac.ncols();
    if jac.nrows() == 0 || n == 0 || jac.iter().any(|v| !v.is_finite()) {
        // nothing to decompose (no rows, or values that are not numbers): no direction is
        // identifiable; the callers report rank 0 instead of the SVD panicking
        return (
            DVector::from_element(n, 1.0),
            vec![0.0; n],
            DMatrix::identity(n, n),
        );
    }
    let raw: Vec<f64> = (0..n).map(|j| jac.column(j).norm()).collect();
    let top = raw.iter().copied().fold(0.0, f64::max);
    let mut js = jac.clone();
    let norms = DVector::from_iterator(
        n,
        (0..n).map(|j| {
            if raw[j] > ZERO_COLUMN_RTOL * top {
                raw[j]
            } else {
                1.0
            }
        }),
    );
    for j in 0..n {
        if raw[j] > ZERO_COLUMN_RTOL * top {
            js.column_mut(j).unscale_mut(norms[j]);
        } else {
            // Round-off of an exactly ineffective parameter: scaling it up would fake an effect.
            js.column_mut(j).fill(0.0);
        }
    }
    // QR first when tall: the SVD then works on the small n x n factor.
    let small = if js.nrows() > n { js.qr().r() } else { js };
    let svd = small.svd(false, true);
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let s: Vec<f64> = order.iter().map(|&i| svd.singular_values[i]).collect();
    let v = match svd.v_t {
        Some(v_t) => {
            let v = v_t.transpose();
            DMatrix::from_fn(n, order.len(), |r, c| v[(r, order[c])])
        }
        None => DMatrix::identity(n, n),
    };
    (norms, s, v)
}

/// Rank, condition number and unidentifiable combinations of the Jacobian `jac`
/// (rows = residuals, columns = parameters), with threshold `rtol` (see [`DEFAULT_RTOL`]).
pub fn analyse(jac: &DMatrix<f64>, rtol: f64) -> Identifiability {
    if jac.ncols() == 0 {
        return Identifiability::empty();
    }
    analyse_svd(jac, rtol, scaled_svd(jac))
}

/// [`analyse`] of `jac` given its [`scaled_svd`] `svd` (computed once by a caller that also
/// needs it, e.g. for the sigmas). When every column is kept, the condition number is that of
/// the same decomposition (the sub-Jacobian of the kept columns is `jac` itself).
pub fn analyse_svd(jac: &DMatrix<f64>, rtol: f64, svd: ScaledSvd) -> Identifiability {
    let n = jac.ncols();
    if n == 0 {
        return Identifiability::empty();
    }
    let (norms, s, v) = svd;
    let s_max = s.first().copied().unwrap_or(0.0);
    let cut = rtol * s_max;
    let rank = s.iter().filter(|&&x| x > cut && x > 0.0).count();
    // Null basis: columns of V past the rank (plus missing ones when m < n).
    let mut null = DMatrix::zeros(n, n - rank);
    let mut k = 0;
    for c in rank..v.ncols() {
        null.column_mut(k).copy_from(&v.column(c));
        k += 1;
    }
    if k < n - rank {
        // Wide Jacobian: complete the basis by Gram-Schmidt against V's columns.
        for e in 0..n {
            if k == n - rank {
                break;
            }
            let mut u = DVector::zeros(n);
            u[e] = 1.0;
            for c in 0..v.ncols().min(rank) {
                let vc = v.column(c);
                u -= vc * vc.dot(&u);
            }
            for c in 0..k {
                let nc = null.column(c).into_owned();
                u -= &nc * nc.dot(&u);
            }
            if u.norm() > 1e-8 {
                null.column_mut(k).copy_from(&(u.normalize()));
                k += 1;
            }
        }
    }
    // Greedy pivots on the rows of the null basis.
    let d = n - rank;
    let mut work = null.clone();
    let mut pivots = Vec::with_capacity(d);
    for _ in 0..d {
        let row_norm = |i: usize| work.row(i).norm();
        let best = (0..n)
            .filter(|i| !pivots.contains(i))
            .map(row_norm)
            .fold(0.0, f64::max);
        let Some(p) = (0..n)
            .rev()
            .find(|&i| !pivots.contains(&i) && row_norm(i) >= best * PIVOT_SHARE)
        else {
            break;
        };
        pivots.push(p);
        // Project row p's direction out of the remaining rows' null components.
        let rp = work.row(p).transpose().normalize();
        let proj = &work * &rp;
        work -= proj * rp.transpose();
    }
    // Reduced basis: N' = N (N[pivots, :])^-1, so N'[pivots, :] = I.
    let np = DMatrix::from_fn(pivots.len(), d, |r, c| null[(pivots[r], c)]);
    let reduced = match np.clone().try_inverse() {
        Some(inv) => &null * inv,
        None => null.clone(),
    };
    let mut combinations: Vec<Combination> = pivots
        .iter()
        .enumerate()
        .map(|(k, &p)| {
            let members = (0..n)
                .filter(|&i| {
                    i == p || (!pivots.contains(&i) && reduced[(i, k)].abs() >= MEMBER_TOL)
                })
                .map(|i| {
                    (
                        i,
                        if i == p {
                            1.0
                        } else {
                            reduced[(i, k)] * norms[p] / norms[i]
                        },
                    )
                })
                .collect();
            Combination { fixed: p, members }
        })
        .collect();
    combinations.sort_by_key(|c| c.fixed);
    let mut fixed: Vec<usize> = pivots.clone();
    fixed.sort_unstable();
    let kept: Vec<usize> = (0..n).filter(|i| !fixed.contains(i)).collect();
    let condition_number = if kept.is_empty() {
        1.0
    } else if kept.len() == n {
        condition_of(&s)
    } else {
        let sub = DMatrix::from_fn(jac.nrows(), kept.len(), |r, c| jac[(r, kept[c])]);
        condition_of(&scaled_svd(&sub).1)
    };
    Identifiability {
        rank,
        singular_values: s,
        condition_number,
        kept,
        fixed,
        combinations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Columns: a, b = -2 a (confounded), c independent, z all-zero; rows random-ish.
    fn jac() -> DMatrix<f64> {
        let rows = 12;
        DMatrix::from_fn(rows, 4, |r, c| {
            let t = r as f64;
            let a = (0.7 * t).sin() + 0.1 * t;
            match c {
                0 => a,
                1 => -2.0 * a,
                2 => (1.3 * t).cos() * 50.0,
                _ => 0.0,
            }
        })
    }

    #[test]
    fn finds_the_confounded_pair_and_the_dead_column() {
        let id = analyse(&jac(), DEFAULT_RTOL);
        assert_eq!(id.rank, 2);
        assert_eq!(id.fixed, vec![1, 3]);
        assert_eq!(id.kept, vec![0, 2]);
        let names = ["a", "b", "c", "z"];
        let got: Vec<String> = id.combinations.iter().map(|c| c.name(&names)).collect();
        assert_eq!(got, ["a+b", "z"]);
        // b -> b + t, a -> a + 2t leaves J unchanged: coefficient of a is 2 (unscaled units).
        let ab = &id.combinations[0];
        assert_eq!(ab.members[0].0, 0);
        assert!((ab.members[0].1 - 2.0).abs() < 1e-9, "{:?}", ab.members);
        assert!(id.condition_number.is_finite() && id.condition_number >= 1.0);
    }

    #[test]
    fn full_rank_has_no_combination() {
        let j = DMatrix::from_fn(10, 3, |r, c| {
            ((r * (c + 2)) as f64).sin() + if r == c { 1.0 } else { 0.0 }
        });
        let id = analyse(&j, DEFAULT_RTOL);
        assert_eq!(id.rank, 3);
        assert!(id.fixed.is_empty() && id.combinations.is_empty());
        assert_eq!(id.kept, vec![0, 1, 2]);
    }

    #[test]
    fn column_scaling_makes_units_irrelevant() {
        let mut j = jac();
        j.column_mut(2).scale_mut(1e-6);
        let a = analyse(&jac(), DEFAULT_RTOL);
        let b = analyse(&j, DEFAULT_RTOL);
        assert_eq!(a.fixed, b.fixed);
        assert!((a.condition_number - b.condition_number).abs() < 1e-6 * a.condition_number);
    }
}
